"""GRID positions and displacement frames of a pyNastran model, vectorised over the grids.

A GRID's position is given in its CP system and its displacements in its CD system (MSC Nastran
Quick Reference Guide, GRID and CORD2R/C/S).  The FE structure works in the basic system, so each
grid carries R (3, 3) whose rows are its CD axes in basic coordinates; for a cylindrical or
spherical CD the axes depend on the grid's position (r, theta, z) / (r, theta, phi).
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.fe import frames


@dataclass(frozen=True)
class Grids:
    """ids (n,) GRID ids, sorted; xyz (n, 3) basic coordinates [deck length]; cd (n,) CD ids;
    frame (n, 3, 3) rows = CD axes in basic; ps (n,) permanent single-point constraints
    (component digits as str, '' for none)."""

    ids: np.ndarray
    xyz: np.ndarray
    cd: np.ndarray
    frame: np.ndarray
    ps: tuple[str, ...]

    def index(self, ids, what: str) -> np.ndarray:
        """Row of each GRID id in ``ids`` (any shape); BayesUpdateError naming ``what``."""
        from bayesupdate.errors import BayesUpdateError

        ids = np.asarray(ids, dtype=np.int64)
        pos = np.clip(np.searchsorted(self.ids, ids), 0, len(self.ids) - 1)
        bad = self.ids[pos] != ids
        if np.any(bad):
            raise BayesUpdateError(f"{what}: GRID {int(ids[bad].ravel()[0])} does not exist")
        return pos

    def is_basic(self, rows) -> np.ndarray:
        """(k,) True where the grid's CD axes are the basic axes."""
        return np.all(np.abs(self.frame[rows] - np.eye(3)) < 1e-9, axis=(1, 2))


def axes_at(coord, xyz: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rows = the axes of pyNastran coordinate system ``coord`` at basic points
    xyz (n, 3): constant for CORD2R, (e_r, e_theta, e_z) for CORD2C, (e_r, e_theta, e_phi)
    for CORD2S (theta from the local z axis, phi about it) (``fe.frames``)."""
    kind = {"R": "rectangular", "C": "cylindrical", "S": "spherical"}[coord.Type]
    beta = np.asarray(coord.beta(), dtype=float)  # rows: local i, j, k in basic
    return frames.axes_at(kind, np.asarray(coord.origin, dtype=float), beta, xyz)


def read_grids(model) -> Grids:
    """``Grids`` of a cross-referenced pyNastran model (pyNastran's vectorised CP transform)."""
    _, icp, xyz_cp, nid_cp_cd = model.get_displacement_index_xyz_cp_cd()
    ids = nid_cp_cd[:, 0].astype(np.int64)
    xyz = model.transform_xyzcp_to_xyz_cid(xyz_cp, ids, icp, cid=0)
    cd = nid_cp_cd[:, 2].astype(np.int64)
    frame = np.broadcast_to(np.eye(3), (len(ids), 3, 3)).copy()
    for cid in np.unique(cd[cd > 0]):
        rows = np.flatnonzero(cd == cid)
        frame[rows] = axes_at(model.coords[int(cid)], xyz[rows])
    ps = tuple(str(model.nodes[int(i)].ps or "") for i in ids)
    order = np.argsort(ids)
    return Grids(ids[order], xyz[order], cd[order], frame[order], tuple(ps[i] for i in order))
