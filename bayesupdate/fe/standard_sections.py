"""General beam cross-sections: arbitrary properties and the common standard shapes.

A ``BeamSection`` holds the properties the beam element needs, about the section's centroid in
the element's local axes (x along the beam, y and z across; SI: m^2, m^4):

* area A; iy = int z^2 dA (bending about y, deflection along z), iz = int y^2 dA, iyz = int y z dA;
* torsion: Saint-Venant torsion constant J;
* shear_y, shear_z: shear-area factors k (effective shear area k A for shear along y and z);
  0 means rigid in shear (Euler-Bernoulli in that plane).

Nastran names (PBAR/PBEAM): I1 = iz, I2 = iy, I12 = iyz, K1 = shear_y, K2 = shear_z.

Standard shapes (``width`` along local y, ``height`` along local z; thin-walled results use the
wall mid-lines where stated):

* ``rod_section`` (solid circle, diameter d): A = pi d^2/4, I = pi d^4/64, J = 2 I; shear factor
  of Cowper (1966), k = 6 (1 + nu) / (7 + 6 nu).
* ``tube_section`` (outer diameter D, wall t): exact annulus, J = 2 I; Cowper's hollow circle,
  k = 6 (1 + nu)(1 + m^2)^2 / ((7 + 6 nu)(1 + m^2)^2 + (20 + 12 nu) m^2), m = r_i / r_o.
* ``bar_section`` (solid rectangle b x h): A = b h, iy = b h^3 / 12, iz = h b^3 / 12;
  J = a c^3 [1/3 - 0.21 (c / a)(1 - c^4 / (12 a^4))] with a = max(b, h), c = min(b, h) (Roark's
  Formulas for Stress and Strain, 7th ed., Table 10.7 case 4); Cowper's rectangle
  k = 10 (1 + nu) / (12 + 11 nu) on both axes.
* ``box_section`` (outer b x h, side walls t_w along z, top and bottom walls t_f along y):
  A = b h - b_i h_i, I by outer minus inner rectangle (b_i = b - 2 t_w, h_i = h - 2 t_f);
  J = 2 t_w t_f (b - t_w)^2 (h - t_f)^2 / (b t_w + h t_f - t_w^2 - t_f^2) (Bredt-Batho on the
  mid-line rectangle, Roark Table 10.7 case 16); Cowper's thin-walled box for shear along z
  (the webs' direction), k = 10 (1 + nu)(1 + 3 m)^2 / [(12 + 72 m + 150 m^2 + 90 m^3)
  + nu (11 + 66 m + 135 m^2 + 90 m^3) + 10 n^2 ((3 + nu) m + 3 m^2)], m = b t_f / (h t_w),
  n = b / h (b, h of the mid-line rectangle), and the same with the walls' roles exchanged for
  shear along y.
* ``i_section`` (height h along z, flange width b along y, web t_w, flanges t_f, symmetric):
  iy = (b h^3 - (b - t_w)(h - 2 t_f)^3) / 12, iz = (2 t_f b^3 + (h - 2 t_f) t_w^3) / 12;
  J = (2 b t_f^3 + (h - t_f) t_w^3) / 3 (open thin-walled section, Roark Table 10.7 case 26);
  shear along z (web): Cowper's thin-walled I, k = 10 (1 + nu)(1 + 3 m)^2 / [(12 + 72 m
  + 150 m^2 + 90 m^3) + nu (11 + 66 m + 135 m^2 + 90 m^3) + 30 n^2 (m + m^2) + 5 nu n^2
  (8 m + 9 m^2)], m = 2 b t_f / (h t_w), n = b / h (h between the flanges' mid-lines) (Cowper,
  J. Appl. Mech. 33 (1966) 335, Table 1); shear along y (flanges): the flanges as two
  rectangles, k A = 10 (1 + nu) / (12 + 11 nu) x 2 b t_f.
* ``tee_section`` (height h along z, one flange b along y, t_f thick, web t_w): about the
  centroid, J = (b t_f^3 + (h - t_f/2) t_w^3) / 3, shear areas web along z, flange along y.
* ``channel_section`` (height h along z, flange width b along y including the web, web t_w,
  flanges t_f): properties about the centroid (the centroid lies off the web, at y_c from the
  web's outer face); J = (2 (b - t_w/2) t_f^3 + (h - t_f) t_w^3) / 3; shear areas as the usual
  thin-walled approximation (Pilkey, *Formulas for Stress, Strain, and Structural Matrices*,
  2nd ed., sec. 2.3): web area (h - 2 t_f) t_w along z, flange area 2 (b - t_w) t_f along y.
  The shear centre lies off the centroid; the bending-torsion coupling this causes is not
  modelled (the element's axis is the centroid line).
"""

from dataclasses import dataclass, replace

import numpy as np

from bayesupdate.errors import BayesUpdateError


@dataclass(frozen=True)
class BeamSection:
    """Section properties about the centroid in local axes (module docstring).  SI units."""

    area: float
    iy: float
    iz: float
    torsion: float
    iyz: float = 0.0
    shear_y: float = 0.0
    shear_z: float = 0.0
    name: str = "general"

    def __post_init__(self):
        check_section(self)

    def swap_yz(self) -> "BeamSection":
        """The same section turned by 90 degrees: y and z exchanged (iyz keeps its value)."""
        return replace(self, iy=self.iz, iz=self.iy, shear_y=self.shear_z, shear_z=self.shear_y)


def check_section(s: BeamSection) -> None:
    """BayesUpdateError naming the section and the field for a non-physical property.  The
    area must be > 0; iy, iz and the torsion constant may be 0 (no stiffness in that plane or
    twist, as MSC's PBAR allows: I1, I2 >= 0), a product iyz needs iy iz > iyz^2."""
    if not (np.isfinite(s.area) and s.area > 0):
        raise BayesUpdateError(f"section {s.name!r}: area must be finite and > 0, got {s.area}")
    for name, v in dict(iy=s.iy, iz=s.iz, torsion=s.torsion).items():
        if not (np.isfinite(v) and v >= 0):
            raise BayesUpdateError(f"section {s.name!r}: {name} must be finite and >= 0, got {v}")
    for name in ("shear_y", "shear_z"):
        v = getattr(s, name)
        if not (np.isfinite(v) and v >= 0):
            raise BayesUpdateError(
                f"section {s.name!r}: {name} must be >= 0 (0: rigid in shear), got {v}"
            )
    if not (np.isfinite(s.iyz) and (s.iyz == 0 or s.iy * s.iz - s.iyz**2 > 0)):
        raise BayesUpdateError(
            f"section {s.name!r}: needs iy iz > iyz^2 (a positive definite inertia), got "
            f"iy={s.iy}, iz={s.iz}, iyz={s.iyz}"
        )


def general_section(area, iy, iz, torsion, iyz=0.0, shear_y=0.0, shear_z=0.0, name="general"):
    """A section from its properties (SI); shear factors 0 = rigid in shear."""
    return BeamSection(*(float(v) for v in (area, iy, iz, torsion, iyz, shear_y, shear_z)), name)


def _positive(name, **dims):
    for k, v in dims.items():
        if not (np.isfinite(v) and v > 0):
            raise BayesUpdateError(f"{name}: {k} must be a finite positive length in m, got {v}")


def _cowper_rectangle(nu):
    return 10 * (1 + nu) / (12 + 11 * nu)


def rod_section(diameter: float, poisson: float = 0.3) -> BeamSection:
    """Solid circle of ``diameter`` [m]."""
    _positive("rod_section", diameter=diameter)
    r = 0.5 * diameter
    a = np.pi * r**2
    i = np.pi / 4.0 * r**4
    k = 6 * (1 + poisson) / (7 + 6 * poisson)
    return BeamSection(a, i, i, 2 * i, 0.0, k, k, "rod")


def tube_section(outer_diameter: float, thickness: float, poisson: float = 0.3) -> BeamSection:
    """Round tube: outer diameter and wall [m]."""
    _positive("tube_section", outer_diameter=outer_diameter, thickness=thickness)
    if 2 * thickness >= outer_diameter:
        raise BayesUpdateError("tube_section: wall must be less than half the outer diameter")
    ro = 0.5 * outer_diameter
    ri = ro - thickness
    a = np.pi * (ro**2 - ri**2)
    i = np.pi / 4.0 * (ro**4 - ri**4)
    m, n = ri / ro, poisson
    k = 6 * (1 + n) * (1 + m**2) ** 2 / ((7 + 6 * n) * (1 + m**2) ** 2 + (20 + 12 * n) * m**2)
    return BeamSection(a, i, i, 2 * i, 0.0, k, k, "tube")


def bar_section(width: float, height: float, poisson: float = 0.3) -> BeamSection:
    """Solid rectangle: ``width`` along local y, ``height`` along local z [m]."""
    _positive("bar_section", width=width, height=height)
    a, c = max(width, height), min(width, height)
    J = a * c**3 * (1 / 3 - 0.21 * (c / a) * (1 - c**4 / (12 * a**4)))
    k = _cowper_rectangle(poisson)
    A = width * height
    return BeamSection(A, width * height**3 / 12, height * width**3 / 12, J, 0.0, k, k, "bar")


def _cowper_box(m, n, nu):
    num = 10 * (1 + nu) * (1 + 3 * m) ** 2
    den = (12 + 72 * m + 150 * m**2 + 90 * m**3) + nu * (11 + 66 * m + 135 * m**2 + 90 * m**3)
    return num / (den + 10 * n**2 * ((3 + nu) * m + 3 * m**2))


def box_section(
    width: float, height: float, web: float, flange: float, poisson: float = 0.3
) -> BeamSection:
    """Rectangular hollow section: outer ``width`` (y) x ``height`` (z), side walls ``web`` and
    top/bottom walls ``flange`` thick [m]."""
    _positive("box_section", width=width, height=height, web=web, flange=flange)
    if 2 * web >= width or 2 * flange >= height:
        raise BayesUpdateError("box_section: walls must be thinner than half the outer size")
    bi, hi = width - 2 * web, height - 2 * flange
    A = width * height - bi * hi
    iy = (width * height**3 - bi * hi**3) / 12
    iz = (height * width**3 - hi * bi**3) / 12
    bm, hm = width - web, height - flange  # mid-line rectangle
    J = 2 * web * flange * bm**2 * hm**2 / (width * web + height * flange - web**2 - flange**2)
    kz = _cowper_box(bm * flange / (hm * web), bm / hm, poisson)
    ky = _cowper_box(hm * web / (bm * flange), hm / bm, poisson)
    return BeamSection(A, iy, iz, J, 0.0, ky, kz, "box")


def i_section(
    height: float, width: float, web: float, flange: float, poisson: float = 0.3
) -> BeamSection:
    """Doubly symmetric I: ``height`` along z, flanges ``width`` along y, ``web`` and
    ``flange`` thicknesses [m]."""
    _positive("i_section", height=height, width=width, web=web, flange=flange)
    if 2 * flange >= height or web >= width:
        raise BayesUpdateError("i_section: needs 2 flange < height and web < width")
    hw = height - 2 * flange
    A = 2 * width * flange + hw * web
    iy = (width * height**3 - (width - web) * hw**3) / 12
    iz = (2 * flange * width**3 + hw * web**3) / 12
    J = (2 * width * flange**3 + (height - flange) * web**3) / 3
    hm = height - flange  # between the flanges' mid-lines
    m, n, nu = 2 * width * flange / (hm * web), width / hm, poisson
    num = 10 * (1 + nu) * (1 + 3 * m) ** 2
    den = (12 + 72 * m + 150 * m**2 + 90 * m**3) + nu * (11 + 66 * m + 135 * m**2 + 90 * m**3)
    kz = num / (den + 30 * n**2 * (m + m**2) + 5 * nu * n**2 * (8 * m + 9 * m**2))
    ky = _cowper_rectangle(nu) * 2 * width * flange / A
    return BeamSection(A, iy, iz, J, 0.0, ky, kz, "I")


def channel_section(height: float, width: float, web: float, flange: float) -> BeamSection:
    """Channel (C): ``height`` along z, flanges ``width`` along y (web included), ``web`` and
    ``flange`` thicknesses [m]; properties about the centroid."""
    _positive("channel_section", height=height, width=width, web=web, flange=flange)
    if 2 * flange >= height or web >= width:
        raise BayesUpdateError("channel_section: needs 2 flange < height and web < width")
    hw = height - 2 * flange
    bf = width - web
    A = 2 * width * flange + hw * web
    iy = (width * height**3 - bf * hw**3) / 12
    # y from the web's outer face: web (area hw tw at tw/2) + flanges (2 b tf at b/2)
    yc = (hw * web * web / 2 + 2 * width * flange * width / 2) / A
    iz = (
        hw * web**3 / 12
        + hw * web * (web / 2 - yc) ** 2
        + 2 * (flange * width**3 / 12 + width * flange * (width / 2 - yc) ** 2)
    )
    J = (2 * (width - web / 2) * flange**3 + (height - flange) * web**3) / 3
    return BeamSection(A, iy, iz, J, 0.0, 2 * bf * flange / A, hw * web / A, "channel")


def tee_section(height: float, width: float, web: float, flange: float) -> BeamSection:
    """T: one flange ``width`` (y) x ``flange`` thick at an end of a ``web`` thick web, the whole
    ``height`` along z [m]; properties about the centroid (the same for the flange at either
    end: Nastran's T and T2).  J = (b t_f^3 + (h - t_f/2) t_w^3) / 3 (open thin-walled section
    on the walls' mid-lines, Roark Table 10.7, as ``i_section`` and ``channel_section``); shear
    areas the web's along z and the flange's along y, the wall rule MSC's PBEAML BOX uses
    (``nastran.cards.beams``)."""
    _positive("tee_section", height=height, width=width, web=web, flange=flange)
    if flange >= height or web >= width:
        raise BayesUpdateError("tee_section: needs flange < height and web < width")
    hw = height - flange
    a_web, a_flange = hw * web, width * flange
    A = a_web + a_flange
    # z from the flange's outer face: flange centre at flange/2, web centre at flange + hw/2
    zc = (a_flange * flange / 2 + a_web * (flange + hw / 2)) / A
    iy = (
        width * flange**3 / 12
        + a_flange * (flange / 2 - zc) ** 2
        + web * hw**3 / 12
        + a_web * (flange + hw / 2 - zc) ** 2
    )
    iz = (flange * width**3 + hw * web**3) / 12
    J = (width * flange**3 + (height - flange / 2) * web**3) / 3
    return BeamSection(A, iy, iz, J, 0.0, a_flange / A, a_web / A, "T")


def from_tube(section, poisson: float = 0.3) -> BeamSection:
    """The ``BeamSection`` of a ``sections.Section`` (tube, oval tube or solid round) with the
    same area, second moments, torsion constant and shear areas."""
    p = section.properties(poisson)
    return BeamSection(
        p["A"], p["Iy"], p["Iz"], p["J"], 0.0, p["Asy"] / p["A"], p["Asz"] / p["A"], section.shape
    )
