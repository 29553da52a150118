"""A test's geometry as data: node ids, coordinates [m], displacement frames, trace lines.

``TestGeometry`` is what every reader returns (``uff.read_uff_geometry``,
``csv_io.read_csv_geometry``): coordinates in the test's global frame, in metres (the file's
unit converted, ``units``); ``frames`` are the coordinate frames its nodes' displacement
directions refer to (``frames``); ``trace_lines`` the UFF 82 lines (node sequences, 0 = move);
``declared`` the DOFs a CSV file gives with a direction vector of their own (``dofs``).
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.testgeom.frames import GLOBAL, CoordinateFrame, displacement_axes


@dataclass(frozen=True)
class DeclaredDof:
    """A test DOF with its own direction: ``label`` (as the test data name it), ``node``,
    ``vector`` (3,) in the node's displacement frame (not normalized)."""

    label: str
    node: int
    vector: tuple[float, float, float]


@dataclass(frozen=True)
class TestGeometry:
    """node_ids (n,) int; xyz (n, 3) [m] in the test's global frame; disp_frame (n,) id of each
    node's displacement frame (0 = global); frames: the frames named (``CoordinateFrame``);
    trace_lines: tuples of node ids (0 = move to the next node); declared: ``DeclaredDof``s;
    unit: the length unit the source was written in; source: its file name."""

    __test__ = False  # not a pytest class

    node_ids: np.ndarray
    xyz: np.ndarray
    disp_frame: np.ndarray
    frames: tuple[CoordinateFrame, ...] = ()
    trace_lines: tuple[tuple[int, ...], ...] = ()
    declared: tuple[DeclaredDof, ...] = ()
    unit: str = "m"
    source: str = "test geometry"

    def index(self, node: int, what: str) -> int:
        """Row of test node ``node``; a one-line error naming ``what`` when it is missing."""
        hits = np.flatnonzero(self.node_ids == int(node))
        if hits.size == 0:
            ids = self.node_ids
            have = f"{ids.min()}..{ids.max()}" if ids.size else "none"
            raise BayesUpdateError(
                f"{what}: node {node} is not in {self.source} (its nodes: {len(ids)}, ids "
                f"{have}); add the node to the geometry or drop the DOF"
            )
        return int(hits[0])

    def frame(self, frame_id: int) -> CoordinateFrame:
        if int(frame_id) == 0:
            return GLOBAL
        return next(f for f in self.frames if f.id == int(frame_id))

    def axes(self, row: int) -> np.ndarray:
        """(3, 3) rows = global unit vectors of direction codes 1, 2, 3 at node row ``row``."""
        return displacement_axes(self.frame(self.disp_frame[row]), self.xyz[row])[0]


def make_geometry(
    node_ids,
    xyz,
    disp_frame=None,
    frames=(),
    trace_lines=(),
    declared=(),
    unit="m",
    source="test geometry",
) -> TestGeometry:
    """A checked ``TestGeometry``: each node once, finite coordinates, every displacement frame
    defined, every trace-line and declared node present (one-line errors naming ``source``)."""
    ids = np.asarray(node_ids, dtype=np.int64).ravel()
    xyz = np.asarray(xyz, dtype=float).reshape(-1, 3)
    disp = np.zeros(len(ids), np.int64) if disp_frame is None else np.asarray(disp_frame, int)
    if ids.size == 0:
        raise BayesUpdateError(f"{source}: no test nodes in it; give node coordinates")
    unique, counts = np.unique(ids, return_counts=True)
    if (counts > 1).any():
        raise BayesUpdateError(
            f"{source}: node {unique[counts > 1][0]} appears twice; give each node once"
        )
    if len(xyz) != len(ids) or not np.all(np.isfinite(xyz)):
        raise BayesUpdateError(f"{source}: every node needs three finite coordinates")
    known = {0} | {f.id for f in frames}
    missing = [(n, f) for n, f in zip(ids, disp, strict=True) if int(f) not in known]
    if missing:
        n, f = missing[0]
        raise BayesUpdateError(
            f"{source}: node {n} names coordinate frame {f}, which is not defined in it; "
            "add the frame (UFF 2420 or a CSV frame row)"
        )
    geometry = TestGeometry(ids, xyz, disp, tuple(frames), tuple(trace_lines),
                            tuple(declared), unit, str(source))  # fmt: skip
    for line in geometry.trace_lines:
        for n in line:
            if n != 0:
                geometry.index(n, f"{source}: trace line")
    for dof in geometry.declared:
        geometry.index(dof.node, f"{source}: DOF {dof.label!r}")
    return geometry
