"""Pure functions that return a modified copy of a ``Structure`` (frozen): extra point masses,
springs, or a joint spring split into a fixed part and a separately scalable bending part.
Used by the discovery layer to add a physical effect to a model."""

from dataclasses import replace

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.structure import Structure


def _part_ids(structure: Structure, part: str) -> tuple[tuple[str, ...], int]:
    parts = structure.parts if part in structure.parts else structure.parts + (part,)
    return parts, parts.index(part)


def with_point_mass(
    structure: Structure, node: int, mass: float, part: str, inertia=None, offset=(0.0, 0.0, 0.0)
) -> Structure:
    """Copy of ``structure`` with a point mass [kg] (inertia 3x3 [kg m^2]) at ``node``."""
    if not 0 <= node < structure.n_nodes:
        raise BayesUpdateError(f"node {node} does not exist")
    parts, pid = _part_ids(structure, part)
    J = np.zeros((3, 3)) if inertia is None else np.asarray(inertia, dtype=float)
    return replace(
        structure,
        parts=parts,
        mass_node=np.append(structure.mass_node, node),
        mass_value=np.append(structure.mass_value, float(mass)),
        mass_inertia=np.concatenate([structure.mass_inertia, J[None]], axis=0),
        mass_offset=np.concatenate([structure.mass_offset, np.asarray(offset, float)[None]]),
        mass_part=np.append(structure.mass_part, pid),
    )


def with_spring(
    structure: Structure,
    node_a: int,
    node_b: int | None,
    stiffness,
    part: str,
    frame=None,
    offset=None,
) -> Structure:
    """Copy with a 6-DOF spring (``node_b`` None = to ground); stiffness 6 values in ``frame``;
    offset (2, 3) [m] from node A and node B to the spring's location (``fe.elements.spring``;
    None: at the
    nodes)."""
    parts, pid = _part_ids(structure, part)
    R = np.eye(3) if frame is None else np.asarray(frame, dtype=float)
    nodes = np.array([[node_a, -1 if node_b is None else node_b]])
    off = np.zeros((2, 3)) if offset is None else np.asarray(offset, float).reshape(2, 3)
    offsets = None
    if structure.spring_offset is not None or np.any(off):
        offsets = np.concatenate([structure.spring_offsets(), off[None]])
    return replace(
        structure,
        parts=parts,
        spring_nodes=np.concatenate([structure.spring_nodes, nodes]),
        spring_k=np.concatenate([structure.spring_k, np.asarray(stiffness, float)[None]]),
        spring_frame=np.concatenate([structure.spring_frame, R[None]]),
        spring_part=np.append(structure.spring_part, pid),
        spring_offset=offsets,
    )


def split_joint_bending(structure: Structure, joint_part: str, new_part: str) -> Structure:
    """Move the two bending stiffnesses (rotations about the 2nd and 3rd spring axes) of every
    spring in ``joint_part`` into new springs of unit stiffness [N m/rad] in ``new_part``, so that
    a ``stiffness_factor`` binding on ``new_part`` *is* the joint's bending stiffness k_rot."""
    pid = structure.parts.index(joint_part) if joint_part in structure.parts else -1
    idx = np.flatnonzero(structure.spring_part == pid)
    if idx.size == 0:
        joints = sorted({p for p in structure.parts if "/" in p})
        raise BayesUpdateError(
            f"joint {joint_part!r} is not a spring joint of this model; joints are {joints}"
        )
    k = structure.spring_k.copy()
    k[idx, 4:6] = 0.0
    out = replace(structure, spring_k=k)
    for i in idx:
        a, b = structure.spring_nodes[i]
        out = with_spring(
            out,
            int(a),
            None if b < 0 else int(b),
            [0, 0, 0, 0, 1.0, 1.0],
            new_part,
            structure.spring_frame[i],
            structure.spring_offsets()[i],
        )
    return out
