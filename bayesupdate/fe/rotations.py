"""Small-rotation algebra shared by rigid offsets, rigid elements and rigid-body modes."""

import numpy as np


def skew(v: np.ndarray) -> np.ndarray:
    """(..., 3) -> (..., 3, 3) with skew(v) @ w = v x w (a rigid offset's rotation coupling)."""
    s = np.zeros(v.shape[:-1] + (3, 3))
    s[..., 0, 1], s[..., 0, 2] = -v[..., 2], v[..., 1]
    s[..., 1, 0], s[..., 1, 2] = v[..., 2], -v[..., 0]
    s[..., 2, 0], s[..., 2, 1] = -v[..., 1], v[..., 0]
    return s


def rigid_body_basis(nodes: np.ndarray, centre=None) -> np.ndarray:
    """(6N, 6) rigid-body motions of all nodes: 3 translations and 3 rotations about ``centre``."""
    n = nodes.shape[0]
    c = nodes.mean(axis=0) if centre is None else np.asarray(centre, dtype=float)
    R = np.zeros((n, 6, 6))
    R[:, :3, :3] = np.eye(3)
    R[:, 3:, 3:] = np.eye(3)
    R[:, :3, 3:] = -skew(nodes - c)
    return R.reshape(6 * n, 6)
