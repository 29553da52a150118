"""Coordinate frames of a test geometry (UFF dataset 2420): rectangular, cylindrical, spherical.

A frame is a rotation ``R`` (3, 3) whose rows are its x, y, z axes in the global frame and an
``origin`` (3,); a point's local Cartesian coordinates c map to global g = c R + origin (UFF 2420
records 5-7 are the rows of R, record 8 the origin, as SDynPy's ``global_coord`` reads them).

- rectangular (type 0): c = (x, y, z);
- cylindrical (type 1): (r, theta [deg], z) -> c = (r cos theta, r sin theta, z);
- spherical (type 2): (r, theta [deg] from the local z axis, phi [deg] azimuth) ->
  c = r (sin theta cos phi, sin theta sin phi, cos theta).

A node's displacement frame sets what its UFF 55/58 direction codes 1, 2, 3 mean at that node:
the frame's axes (rectangular), (e_r, e_theta, e_z) (cylindrical) or (e_theta, e_phi, e_r)
(spherical, the I-DEAS order as IMAT and SDynPy's ``global_deflection`` read it), each at the
node's position.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError

KINDS = ("rectangular", "cylindrical", "spherical")


@dataclass(frozen=True)
class CoordinateFrame:
    """One test coordinate frame: ``id`` (UFF label; 0 is the global frame), ``kind`` (one of
    ``KINDS``), ``rotation`` (3, 3) rows = axes in global, ``origin`` (3,) [m]."""

    id: int
    kind: str
    rotation: np.ndarray
    origin: np.ndarray


GLOBAL = CoordinateFrame(0, "rectangular", np.eye(3), np.zeros(3))


def checked_frame(label, kind, matrix, where: str, metres: float = 1.0) -> CoordinateFrame:
    """A ``CoordinateFrame`` from a 2420-style (4, 3) matrix (rows: x, y, z axes, origin in
    file units, times ``metres``); its axes must be orthonormal and right-handed to 1e-6."""
    m = np.asarray(matrix, dtype=float)
    if m.shape != (4, 3) or not np.all(np.isfinite(m)):
        raise BayesUpdateError(f"{where}: frame {label}: give 4 rows of 3 numbers (axes, origin)")
    if kind not in KINDS:
        raise BayesUpdateError(f"{where}: frame {label}: kind {kind!r}; use one of {KINDS}")
    R = m[:3]
    if np.abs(R @ R.T - np.eye(3)).max() > 1e-6 or np.linalg.det(R) < 0:
        raise BayesUpdateError(
            f"{where}: frame {label}: its axes are not orthonormal and right-handed; "
            "give the rows of a rotation matrix"
        )
    return CoordinateFrame(int(label), kind, R, m[3] * metres)


def to_global(frame: CoordinateFrame, local) -> np.ndarray:
    """Global coordinates (n, 3) of points given in ``frame`` (n, 3): lengths in metres,
    angles in degrees."""
    p = np.atleast_2d(np.asarray(local, dtype=float))
    if frame.kind == "cylindrical":
        t = np.radians(p[:, 1])
        p = np.column_stack([p[:, 0] * np.cos(t), p[:, 0] * np.sin(t), p[:, 2]])
    elif frame.kind == "spherical":
        t, f = np.radians(p[:, 1]), np.radians(p[:, 2])
        st = np.sin(t)
        p = p[:, :1] * np.column_stack([st * np.cos(f), st * np.sin(f), np.cos(t)])
    return p @ frame.rotation + frame.origin


def to_local(frame: CoordinateFrame, points) -> np.ndarray:
    """Coordinates (n, 3) in ``frame`` of global points (n, 3): the inverse of ``to_global``
    (angles in degrees)."""
    c = (np.atleast_2d(np.asarray(points, dtype=float)) - frame.origin) @ frame.rotation.T
    if frame.kind == "cylindrical":
        return np.column_stack([np.hypot(c[:, 0], c[:, 1]), _deg(c[:, 1], c[:, 0]), c[:, 2]])
    if frame.kind == "spherical":
        r = np.linalg.norm(c, axis=1)
        theta = _deg(np.hypot(c[:, 0], c[:, 1]), c[:, 2])
        return np.column_stack([r, theta, _deg(c[:, 1], c[:, 0])])
    return c


def _deg(y, x):
    return np.degrees(np.arctan2(y, x))


def displacement_axes(frame: CoordinateFrame, points) -> np.ndarray:
    """(n, 3, 3): row k of [i] is the global unit vector of direction code k + 1 at global
    point i in ``frame`` (module docstring)."""
    p = np.atleast_2d(np.asarray(points, dtype=float))
    n = len(p)
    if frame.kind == "rectangular":
        return np.broadcast_to(frame.rotation, (n, 3, 3)).copy()
    local = to_local(frame, p)
    f = np.radians(local[:, 1] if frame.kind == "cylindrical" else local[:, 2])
    cf, sf, zero, one = np.cos(f), np.sin(f), np.zeros(n), np.ones(n)
    if frame.kind == "cylindrical":
        rows = [(cf, sf, zero), (-sf, cf, zero), (zero, zero, one)]
    else:
        t = np.radians(local[:, 1])
        ct, st = np.cos(t), np.sin(t)
        rows = [(ct * cf, ct * sf, -st), (-sf, cf, zero), (st * cf, st * sf, ct)]
    axes = np.stack([np.stack(r, axis=-1) for r in rows], axis=1)  # (n, 3, 3) local Cartesian
    return axes @ frame.rotation
