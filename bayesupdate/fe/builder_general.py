"""Builder steps for shells, supports and rigid elements (the ``StructureBuilder`` methods
``add_shells``, ``add_support``, ``add_rbe2``, ``add_rbe3`` delegate here), and their arrays for
the frozen ``Structure`` (``general_parts``).

Shell points that lie within ``merge_tol`` of an existing node reuse that node, so shell faces
built separately, or a shell and the beams on its edge, share DOFs (6 per node everywhere).
"""

import numpy as np
from scipy.spatial import cKDTree

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.constraints import Constraints
from bayesupdate.fe.shell_model import WARP_LIMIT, ShellElements, shell_mesh


def add_shells(
    builder,
    points,
    quads,
    trias,
    thickness,
    material,
    part: str,
    offset=0.0,
    offset_ratio=0.0,
    nsm=0.0,
    merge_tol: float = 1e-6,
    warp_limit: float = WARP_LIMIT,
) -> np.ndarray:
    """Add shell elements to ``builder``.

    points (n, 3) [m]; quads (nq, 4) / trias (nt, 3) indices into ``points``; thickness [m],
    offset [m], offset_ratio, nsm [kg/m^2]: scalars or one per element (quads first);
    material : ``Material``.  The elements are checked on their own (``shell_mesh``: repeated
    nodes, zero area, order, warp, properties; errors name the element of this call).
    Returns (n,) the structure node number of each point.
    """
    try:
        mesh = shell_mesh(
            points,
            quads,
            trias,
            thickness=thickness,
            E=material.youngs_modulus,
            nu=material.poisson,
            rho=material.density,
            offset=offset,
            offset_ratio=offset_ratio,
            nsm=nsm,
            warp_limit=warp_limit,
        )
    except BayesUpdateError as exc:
        raise BayesUpdateError(f"shells of part {part!r}: {exc}") from None
    ids = _merge_points(builder, mesh.nodes, merge_tol)
    builder._shell_blocks.append(  # noqa: SLF001 - the builder's own store
        dict(mesh=mesh, ids=ids, part=builder._part(part))  # noqa: SLF001
    )
    return ids


def _merge_points(builder, points: np.ndarray, tol: float) -> np.ndarray:
    """Node numbers for points (n, 3): an existing node within ``tol`` or a new node."""
    existing = np.array(builder._nodes, dtype=float).reshape(-1, 3)  # noqa: SLF001
    ids = np.full(len(points), -1)
    if len(existing):
        dist, near = cKDTree(existing).query(points, distance_upper_bound=tol)
        hit = np.isfinite(dist)
        ids[hit] = near[hit]
    new = np.flatnonzero(ids < 0)
    ids[new] = len(existing) + np.arange(new.size)
    builder._nodes.extend(map(tuple, points[new].tolist()))  # noqa: SLF001 - checked finite
    return ids


def _shell_elements(builder) -> ShellElements | None:
    blocks = builder._shell_blocks  # noqa: SLF001
    if not blocks:
        return None
    quads = [b["ids"][b["mesh"].quads] for b in blocks]
    trias = [b["ids"][b["mesh"].trias] for b in blocks]
    names = ("thickness", "E", "nu", "rho", "offset", "offset_ratio", "nsm")

    def per_element(get):
        q = [get(b)[: len(b["mesh"].quads)] for b in blocks]
        t = [get(b)[len(b["mesh"].quads) :] for b in blocks]
        return np.concatenate(q + t)

    props = {n: per_element(lambda b, n=n: getattr(b["mesh"], n)) for n in names}
    part = per_element(lambda b: np.full(b["mesh"].n_elements, b["part"]))
    return ShellElements(
        quads=np.concatenate(quads).reshape(-1, 4),
        trias=np.concatenate(trias).reshape(-1, 3),
        part=part.astype(int),
        **props,
    )


def _constraints(builder) -> Constraints | None:
    sup, r2, r3 = builder._supports, builder._rbe2, builder._rbe3  # noqa: SLF001
    if not (sup or r2 or r3):
        return None
    legs2 = [(e, ind, d, c) for e, (ind, deps, c) in enumerate(r2) for d in deps]
    legs3 = [
        (e, n, w, nc)
        for e, (_, _, ns, ws, nc) in enumerate(r3)
        for n, w in zip(ns, ws, strict=True)
    ]
    return Constraints(
        fixed_node=np.array([n for n, _ in sup], dtype=int),
        fixed_components=np.array([c for _, c in sup], dtype=bool).reshape(-1, 6),
        rbe2_element=np.array([leg[0] for leg in legs2], dtype=int),
        rbe2_independent=np.array([leg[1] for leg in legs2], dtype=int),
        rbe2_dependent=np.array([leg[2] for leg in legs2], dtype=int),
        rbe2_components=np.array([leg[3] for leg in legs2], dtype=bool).reshape(-1, 6),
        rbe3_reference=np.array([r[0] for r in r3], dtype=int),
        rbe3_ref_components=np.array([r[1] for r in r3], dtype=bool).reshape(-1, 6),
        rbe3_element=np.array([leg[0] for leg in legs3], dtype=int),
        rbe3_node=np.array([leg[1] for leg in legs3], dtype=int),
        rbe3_weight=np.array([leg[2] for leg in legs3], dtype=float),
        rbe3_components=np.array([leg[3] for leg in legs3], dtype=bool).reshape(-1, 6),
    )


def general_parts(builder) -> dict:
    """``shells`` and ``constraints`` fields of the ``Structure`` being built."""
    return dict(shells=_shell_elements(builder), constraints=_constraints(builder))
