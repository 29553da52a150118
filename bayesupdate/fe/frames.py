"""Coordinate frames for the DOFs of a node (a Nastran GRID's CD system): rectangular,
cylindrical or spherical, vectorized over points.

A frame is an origin and three orthonormal axes (rows of ``axes``, global coordinates).  At a
point x its local DOF directions are (MSC Nastran Quick Reference Guide, CORD2R/C/S):

* rectangular: the frame's axes, everywhere;
* cylindrical (r, theta, z): e_r = cos(theta) e_1 + sin(theta) e_2, e_theta = -sin(theta) e_1 +
  cos(theta) e_2, e_z = e_3, with theta = atan2(x_2, x_1) of the local position;
* spherical (r, theta, phi), theta measured from the local z axis and phi about it:
  e_r = (sin t cos p, sin t sin p, cos t), e_theta = (cos t cos p, cos t sin p, -sin t),
  e_phi = (-sin p, cos p, 0), in local axes.

On the axis (cylindrical) or at the origin (spherical) the angles are taken as 0 (atan2(0, 0)).
A node with a frame has its DOFs (supports, rigid-element components, output) in these axes;
``constraints`` applies them as an exact orthogonal change of variables, u = Lambda w.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError

KINDS = ("rectangular", "cylindrical", "spherical")


@dataclass(frozen=True)
class CoordinateFrame:
    """kind : one of ``KINDS``; origin (3,) [m]; axes (3, 3) rows = the frame's unit x, y, z
    axes in global coordinates."""

    kind: str
    origin: tuple
    axes: tuple

    def __post_init__(self):
        if self.kind not in KINDS:
            raise BayesUpdateError(
                f"coordinate frame: kind must be one of {KINDS}, got {self.kind!r}"
            )
        R = np.asarray(self.axes, dtype=float)
        o = np.asarray(self.origin, dtype=float)
        if R.shape != (3, 3) or o.shape != (3,) or not np.all(np.isfinite(R)):
            raise BayesUpdateError("coordinate frame: origin must be 3 numbers and axes 3 x 3")
        if not np.allclose(R @ R.T, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
            raise BayesUpdateError("coordinate frame: axes must be a right-handed rotation")

    @classmethod
    def from_points(cls, kind: str, origin, z_point, xz_point) -> "CoordinateFrame":
        """Nastran CORD2R/C/S style: the origin A, a point B on the local z axis, a point C in
        the local x-z plane (global coordinates [m])."""
        a, b, c = (np.asarray(p, dtype=float).reshape(3) for p in (origin, z_point, xz_point))
        z = b - a
        x = c - a
        y = np.cross(z, x)
        if np.linalg.norm(z) == 0 or np.linalg.norm(y) <= 1e-12 * np.linalg.norm(
            z
        ) * np.linalg.norm(x):
            raise BayesUpdateError(
                "coordinate frame: the three points must not be collinear (A, B on the z axis, "
                "C in the x-z plane)"
            )
        z, y = z / np.linalg.norm(z), y / np.linalg.norm(y)
        return cls.from_axes(kind, a, np.stack([np.cross(y, z), y, z]))

    @classmethod
    def from_axes(cls, kind: str, origin, axes) -> "CoordinateFrame":
        """From an origin (3,) and axes (3, 3) rows x, y, z in global coordinates."""
        R = np.asarray(axes, dtype=float).reshape(3, 3)
        return cls(kind, tuple(np.asarray(origin, float).reshape(3).tolist()),
                   tuple(map(tuple, R.tolist())))  # fmt: skip

    def axes_at(self, xyz) -> np.ndarray:
        """(n, 3, 3) rows = the local DOF directions at global points xyz (n, 3) [m]."""
        return axes_at(self.kind, np.asarray(self.origin, float), np.asarray(self.axes, float), xyz)


def axes_at(kind: str, origin: np.ndarray, axes: np.ndarray, xyz) -> np.ndarray:
    """(n, 3, 3) local DOF axes (rows, global) of a ``kind`` frame at points xyz (n, 3)."""
    xyz = np.atleast_2d(np.asarray(xyz, dtype=float))
    n = len(xyz)
    if kind == "rectangular":
        return np.broadcast_to(axes, (n, 3, 3)).copy()
    local = (xyz - origin) @ axes.T
    p = np.arctan2(local[:, 1], local[:, 0])
    c, s = np.cos(p), np.sin(p)
    zero, one = np.zeros(n), np.ones(n)
    if kind == "cylindrical":
        rows = [
            np.stack([c, s, zero], 1),
            np.stack([-s, c, zero], 1),
            np.stack([zero, zero, one], 1),
        ]
    else:
        t = np.arctan2(np.linalg.norm(local[:, :2], axis=1), local[:, 2])
        ct, st = np.cos(t), np.sin(t)
        rows = [
            np.stack([st * c, st * s, ct], 1),
            np.stack([ct * c, ct * s, -st], 1),
            np.stack([-s, c, zero], 1),
        ]
    return np.stack(rows, axis=1) @ axes
