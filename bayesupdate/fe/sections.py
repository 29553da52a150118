"""Cross-section properties of beam elements, as pure vectorized functions of the section size.

A section is described by its ``shape`` and sizes; the properties (area, second moments, torsion
constant, shear areas) follow from them so that a wall thickness can be a calibration parameter.
All lengths in m, results in m^2 and m^4.  Local axes: x along the beam, y "width", z "height".

* ``circular_tube``: annulus with outer diameter D and wall t (exact), shear coefficient of
  Cowper (1966) for hollow circles.
* ``oval_tube``: thin-walled elliptical tube (width W, height H, wall t) - muffler and catalyst
  shells. Properties by integration along the mid-line ellipse (thin-wall theory), torsion by
  Bredt-Batho J = 4 A_m^2 t / P_m.  Shear area A_s,y = t * int (dy/ds)^2 ds (exactly A/2 for a
  circle).
* ``solid_round``: solid bar of diameter d (hanger rods), Cowper's 6(1+nu)/(7+6nu).
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError

SHAPES = ("circular_tube", "oval_tube", "solid_round")
_SHAPE_CODE = {name: i for i, name in enumerate(SHAPES)}


@dataclass(frozen=True)
class Section:
    """A beam cross-section by shape and size [m].

    shape : one of ``SHAPES``.  width : outer diameter (circular/solid) or outer width W (oval).
    height : outer height H (oval; equals width otherwise).  thickness : wall t (0 for solid).
    """

    shape: str
    width: float
    height: float
    thickness: float

    def properties(self, poisson: float = 0.3) -> dict:
        """Section properties as floats: A, Iy, Iz, J, Asy, Asz (see module docstring)."""
        props = section_properties(
            np.array([_SHAPE_CODE[self.shape]]),
            np.array([self.width]),
            np.array([self.height]),
            np.array([self.thickness]),
            np.array([poisson]),
        )
        return {k: float(v[0]) for k, v in props.items()}


def circular_tube(outer_diameter: float, thickness: float) -> Section:
    """Round tube, outer diameter and wall thickness in m."""
    _check_positive("outer_diameter", outer_diameter)
    _check_positive("thickness", thickness)
    if 2 * thickness >= outer_diameter:
        raise BayesUpdateError(
            f"circular_tube: wall thickness {thickness} m must be less than half the outer "
            f"diameter {outer_diameter} m"
        )
    return Section("circular_tube", float(outer_diameter), float(outer_diameter), float(thickness))


def oval_tube(width: float, height: float, thickness: float) -> Section:
    """Thin-walled elliptical tube: outer width (local y) and height (local z), wall, in m."""
    for name, value in (("width", width), ("height", height), ("thickness", thickness)):
        _check_positive(name, value)
    if 2 * thickness >= min(width, height):
        raise BayesUpdateError(
            f"oval_tube: wall thickness {thickness} m must be less than half of "
            f"min(width, height) = {min(width, height)} m"
        )
    return Section("oval_tube", float(width), float(height), float(thickness))


def solid_round(diameter: float) -> Section:
    """Solid round bar (hanger rod) of the given diameter in m."""
    _check_positive("diameter", diameter)
    return Section("solid_round", float(diameter), float(diameter), 0.0)


def _check_positive(name, value):
    if not np.isfinite(value) or value <= 0:
        raise BayesUpdateError(f"section {name} must be a finite positive length in m, got {value}")


# Gauss-Legendre points on the quarter ellipse: thin-wall integrals of an ellipse are smooth in the
# parameter angle, so 24 points give ~1e-12 relative accuracy for aspect ratios up to 4.
_GL_X, _GL_W = np.polynomial.legendre.leggauss(24)
_PHI = (_GL_X + 1.0) * (np.pi / 4.0)  # quarter ellipse, phi in [0, pi/2]
_PHI_W = _GL_W * (np.pi / 4.0)


def section_properties(shape_code, width, height, thickness, poisson) -> dict:
    """Vectorized section properties.

    All inputs are (n,) arrays (shape_code from ``SHAPES`` order).  Returns a dict of (n,) arrays:
    A [m^2], Iy [m^4] (bending about local y, i.e. deflection along z), Iz [m^4], J [m^4],
    Asy, Asz [m^2] effective shear areas for shear along y and z.
    """
    code = np.asarray(shape_code)
    w = np.asarray(width, dtype=float)
    h = np.asarray(height, dtype=float)
    t = np.asarray(thickness, dtype=float)
    nu = np.broadcast_to(np.asarray(poisson, dtype=float), w.shape)
    A = np.empty_like(w)
    Iy = np.empty_like(w)
    Iz = np.empty_like(w)
    J = np.empty_like(w)
    Asy = np.empty_like(w)
    Asz = np.empty_like(w)

    tube = code == 0
    if np.any(tube):
        ro = 0.5 * w[tube]
        ri = ro - t[tube]
        a = _tube_area(ro, ri)
        i = np.pi / 4.0 * (ro**4 - ri**4)
        m = ri / ro
        n = nu[tube]
        # Cowper (1966), hollow circular section
        k = 6 * (1 + n) * (1 + m**2) ** 2 / ((7 + 6 * n) * (1 + m**2) ** 2 + (20 + 12 * n) * m**2)
        A[tube], Iy[tube], Iz[tube], J[tube] = a, i, i, 2 * i
        Asy[tube] = Asz[tube] = k * a

    solid = code == 2
    if np.any(solid):
        r = 0.5 * w[solid]
        a = _disc_area(r)
        i = np.pi / 4.0 * r**4
        k = 6 * (1 + nu[solid]) / (7 + 6 * nu[solid])
        A[solid], Iy[solid], Iz[solid], J[solid] = a, i, i, 2 * i
        Asy[solid] = Asz[solid] = k * a

    oval = code == 1
    if np.any(oval):
        props = _thin_oval(w[oval], h[oval], t[oval])
        A[oval], Iy[oval], Iz[oval], J[oval], Asy[oval], Asz[oval] = props
    return {"A": A, "Iy": Iy, "Iz": Iz, "J": J, "Asy": Asy, "Asz": Asz}


def section_areas(shape_code, width, height, thickness) -> np.ndarray:
    """(n,) areas A [m^2]: ``section_properties(...)["A"]`` to the bit, without the other
    properties (the total mass needs A alone, at every thickness a calibration tries)."""
    code = np.asarray(shape_code)
    w = np.asarray(width, dtype=float)
    t = np.asarray(thickness, dtype=float)
    A = np.empty_like(w)
    tube, solid, oval = code == 0, code == 2, code == 1
    ro = 0.5 * w[tube]
    A[tube] = _tube_area(ro, ro - t[tube])
    A[solid] = _disc_area(0.5 * w[solid])
    if np.any(oval):
        wq = _oval_midline(w[oval], np.asarray(height, dtype=float)[oval], t[oval])[-1]
        A[oval] = 4 * np.sum(wq, axis=1) * t[oval]
    return A


def _tube_area(outer_radius, inner_radius):
    return np.pi * (outer_radius**2 - inner_radius**2)


def _disc_area(radius):
    return np.pi * radius**2


def _oval_midline(w: np.ndarray, h: np.ndarray, t: np.ndarray) -> tuple:
    """(ay, az, dy, dz, ds, wq) of thin elliptical tubes' mid-lines: semi-axes (n, 1) [m], the
    tangent (n, 24) [m/rad], its length and the quadrature weights for arc length over the
    quarter ellipse (n, 24) [m]."""
    tt = t[:, None]
    ay = 0.5 * (w[:, None] - tt)
    az = 0.5 * (h[:, None] - tt)
    dy = -ay * np.sin(_PHI)
    dz = az * np.cos(_PHI)
    ds = np.sqrt(dy**2 + dz**2)
    return ay, az, dy, dz, ds, _PHI_W * ds


def _thin_oval(w: np.ndarray, h: np.ndarray, t: np.ndarray) -> tuple:
    """(A, Iy, Iz, J, Asy, Asz) (n,) each of thin elliptical tubes of outer width w, height h and
    wall t [m]: wall integrals by quadrature over the mid-line (Bredt's J for the torsion)."""
    tt = t[:, None]
    ay, az, dy, dz, ds, wq = _oval_midline(w, h, t)
    y = ay * np.cos(_PHI)
    z = az * np.sin(_PHI)
    perimeter = 4 * np.sum(wq, axis=1)
    area = perimeter * tt[:, 0]
    iy = 4 * tt[:, 0] * np.sum(wq * z**2, axis=1)
    iz = 4 * tt[:, 0] * np.sum(wq * y**2, axis=1)
    enclosed = np.pi * ay[:, 0] * az[:, 0]
    torsion = 4 * enclosed**2 * tt[:, 0] / perimeter
    # shear flow along the wall carries the part of the shear force parallel to the wall
    asy = 4 * tt[:, 0] * np.sum(wq * (dy / ds) ** 2, axis=1)
    asz = 4 * tt[:, 0] * np.sum(wq * (dz / ds) ** 2, axis=1)
    return area, iy, iz, torsion, asy, asz
