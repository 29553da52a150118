"""Shear panels (Nastran CSHEAR + PSHEAR): four-node panels that carry shear alone, vectorized
over elements.

The panel is Garvey's (NASTRAN Theoretical Manual, NASA SP-221, sec. 5.3; the COSMIC NASTRAN
source, read to learn which of its cases applies where, is NASA's NASTRAN-95 ``shears.f``).  In
the panel's plane (normal k along the cross product of the diagonals, x along side 1-2 projected
on it, corners at (0, 0), (x2, 0), (x3, y3), (x4, y4)) the shear flow that keeps a panel whose
sides are not parallel in equilibrium varies across it, as 1 / p^2 with p the distance from the
points where opposite sides meet; its one deformation mode moves the corners along the
diagonals, and

    K = g g^T / (2 Z)   on the corners' translations (12 of the 24 DOFs; no rotation),

g_i = a_i e_i with e_i the unit diagonal through corner i (1 and 3 along 1-3, 2 and 4 along
2-4) and a_i the corner factors (a_3 = -a_1, a_4 = -a_2), and Z [m/N x m^2] the panel's
flexibility: the complementary energy of the assumed stress field per unit generalized force,
Z = A / (2 G t) (1 + 2 D^2 / (1 + nu)) for a parallelogram (D its skew), with closed forms for a
panel with one pair of parallel sides and for the general quadrilateral (the manual's
logarithmic integral).  A pair of sides counts as parallel within ``PARALLEL`` of their
directions, MSC's tolerance (NASTRAN-95's is 0.01): found on MSC's own solution of 141 panels
(``studies/msc_cshear.py``: its shear stresses to 2.6e-6 of their scale, median, 1e-4 at most;
with 0.01 the panels whose sides are between the two tolerances miss by up to 18 %).

The corner shear stresses of a displacement u are tau_i = r_i s, s = -g . u / (2 Z t), r =
(p2 / p1, p1 / p2, p1 p2 / p3^2, p1 p2 / p4^2) (``panel_stresses``: MSC's stress output, the
average and the largest of the four).  The mass is lumped at the corners, translational:
corner i carries (rho t + nsm) (A_i + A) / 6, A_i the triangle of corner i and its two
neighbours, A the panel's projected area (NASTRAN-95 ``emastq.f``; MSC's own not checked).
Extensional stiffness (PSHEAR F1-F4) is not modelled (the reader refuses it).  SI units.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.fe.elements.base import ElementSettings, in_elements, register

#: sides closer to parallel than this (the sine of the angle between them, as the manual's
#: ratio of cross to dot products) are parallel (MSC's tolerance, module docstring)
PARALLEL = 1e-3


@dataclass(frozen=True)
class PanelModes:
    """The one deformation mode of n panels: g (n, 4, 3) the corner vectors (a_i e_i, global
    axes), z (n,) the flexibility Z times G t [m^2], p (n, 4) the corner distances p_i [m]."""

    g: np.ndarray
    z: np.ndarray
    p: np.ndarray


def _frames(x):
    """(k, i, j unit vectors (n, 3), projected area (n,), local corners x2, x3, y3, x4, y4)."""
    d13, d24 = x[:, 2] - x[:, 0], x[:, 3] - x[:, 1]
    kn = np.cross(d13, d24)
    area = 0.5 * np.linalg.norm(kn, axis=1)
    k = kn / np.linalg.norm(kn, axis=1)[:, None]
    s12 = x[:, 1] - x[:, 0]
    p12 = s12 - np.einsum("ni,ni->n", s12, k)[:, None] * k
    x2 = np.linalg.norm(p12, axis=1)
    i = p12 / x2[:, None]
    j = np.cross(k, i)
    s14 = x[:, 3] - x[:, 0]
    dot = lambda a, b: np.einsum("ni,ni->n", a, b)  # noqa: E731
    return k, i, j, area, (x2, dot(i, d13), dot(j, d13), dot(i, s14), dot(j, s14))


def convex(x: np.ndarray) -> np.ndarray:
    """(n,) True where the panel x (n, 4, 3) [m] has every interior angle below 180 degrees
    (the manual's four tests in the panel's plane)."""
    with np.errstate(divide="ignore", invalid="ignore"):  # a degenerate panel: NaN, False
        *_, (x2, x3, y3, x4, y4) = _frames(x)
        return ((y3 > 0) & (y4 > 0) & (x3 > y3 * x4 / y4)
                & (x4 < x2 - (x2 - x3) * y4 / y3))  # fmt: skip


def panel_modes(x: np.ndarray, nu: np.ndarray, parallel: float = PARALLEL) -> PanelModes:
    """``PanelModes`` of panels with corners x (n, 4, 3) [m] and Poisson ratio nu (n,); sides
    within ``parallel`` of parallel are parallel (MSC's tolerance by default)."""
    k, i, j, area, (x2, x3, y3, x4, y4) = _frames(x)
    X = np.stack([np.zeros_like(x2), x2, x3, x4], 1)
    Y = np.stack([np.zeros_like(x2), np.zeros_like(x2), y3, y4], 1)
    par34 = np.abs(y3 - y4) < parallel * np.abs(x3 - x4)
    par23 = np.abs(y4 * (x3 - x2) - y3 * x4) < parallel * np.abs(x4 * (x3 - x2) + y4 * y3)
    nuc = 2.0 / 3.0 / (1.0 + nu)
    p = np.ones((len(x2), 4))
    z = np.empty(len(x2))
    with np.errstate(divide="ignore", invalid="ignore"):  # each case where it applies
        both = par34 & par23
        skew = -0.5 * (x4 / y4 + (x3 - x2) / y3 + (y3 - y4) / (x3 - x4))
        z[both] = (0.5 * area * (1 + 3 * nuc * skew**2))[both]
        for case, (pc, zc) in (
            (par34 & ~par23, _trapezoid_12(x2, x3, y3, x4, y4, Y, area, nuc)),
            (par23 & ~par34, _trapezoid_14(x2, x3, y3, x4, y4, X, Y, area, nuc)),
            (~par34 & ~par23, _general(x2, x3, y3, x4, y4, X, Y, area, nuc)),
        ):
            p[case], z[case] = pc[case], zc[case]
    l13, l24 = np.hypot(x3, y3), np.hypot(x4 - x2, y4)
    e13 = (x3 / l13)[:, None] * i + (y3 / l13)[:, None] * j
    e24 = ((x4 - x2) / l24)[:, None] * i + (y4 / l24)[:, None] * j
    den = x4 * y3 - x3 * y4
    a1 = -0.5 * x2 * y4 * l13 / den
    a2 = 0.5 * x2 * y3 * l24 / (den - x2 * (y3 - y4))
    g = np.stack([a1[:, None] * e13, a2[:, None] * e24, -a1[:, None] * e13,
                  -a2[:, None] * e24], 1)  # fmt: skip
    return PanelModes(g, z, p)


def _trapezoid_12(x2, x3, y3, x4, y4, Y, area, nuc):
    """(p, Z G t) of panels whose side 3-4 is parallel to 1-2 (the manual's first case)."""
    den = y3 * x4 - y4 * (x3 - x2)
    yp, xp = x2 * y3 * y4 / den, x2 * y3 * x4 / den
    p = yp[:, None] - Y
    sa, c = (x2 - xp) / yp, -xp / yp
    ratio = p[:, 0] * p[:, 1] / (p[:, 2] * p[:, 3])
    return p, 0.5 * ratio * area * (1 + nuc * (sa**2 + sa * c + c**2))


def _trapezoid_14(x2, x3, y3, x4, y4, X, Y, area, nuc):
    """(p, Z G t) of panels whose side 1-4 is parallel to 2-3."""
    d = -0.5 * (x4 / y4 + (x3 - x2) / y3)
    xq = x4 - y4 * (x3 - x4) / (y3 - y4)
    p = (xq[:, None] - X - d[:, None] * Y) / np.sqrt(1 + d**2)[:, None]
    b = ((xq - x4) * d + y4) / ((xq - x4) - y4 * d)
    ratio = p[:, 0] * p[:, 1] / (p[:, 2] * p[:, 3])
    return p, 0.5 * ratio * area * (1 + nuc * (b**2 + b * d + d**2))


def _general(x2, x3, y3, x4, y4, X, Y, area, nuc):
    """(p, Z G t) of panels with no parallel sides: the manual's logarithmic integral of the
    stress field's complementary energy, in the corners' slopes a, b, c, d seen from the meeting
    point of sides 1-2 and 3-4."""
    xq = x4 - (x3 - x4) / (y3 - y4) * y4
    den = y3 * x4 - y4 * (x3 - x2)
    xp, yp = x2 * y3 * x4 / den, x2 * y3 * y4 / den
    xl = np.hypot(xq - xp, yp)
    d = (xq - xp) / yp
    p = (yp / xl)[:, None] * (xq[:, None] - X - d[:, None] * Y)
    c = xl / p[:, 0] - d
    b = xl / p[:, 3] - c
    a = xl / p[:, 1] - d

    def log_term(u, v):
        return (u + v + 2 / 3 * (u**3 + v**3) + 0.2 * (u**5 + v**5)) * np.log(np.abs(u + v))

    f = 0.5 * p.prod(axis=1) / xl**2 * (
        log_term(a, b) + log_term(c, d) - log_term(b, c) - log_term(d, a)
        + 0.1 * ((a**2 - c**2) * (b**3 - d**3) + (b**2 - d**2) * (a**3 - c**3))
        - 0.2 * ((a - c) * (b**4 - d**4) + (b - d) * (a**4 - c**4))
    )  # fmt: skip
    ratio = p[:, 0] * p[:, 1] / (p[:, 2] * p[:, 3])
    return p, 0.5 * ratio * (area + 6 * nuc * (f - 2 / 3 * area))


def panel_stresses(modes: PanelModes, G, u: np.ndarray) -> np.ndarray:
    """(n, 4) corner shear stresses [Pa] of panels with ``PanelModes`` ``modes`` and shear
    modulus G [Pa] (n,) under corner displacements u (n, 4, 3) [m] (module docstring; MSC
    prints their average and the largest magnitude): s = -g . u / (2 Z t) = -G g . u / (2 z)."""
    s = -G * np.einsum("nki,nki->n", modes.g, u) / (2 * modes.z)
    p = modes.p
    r = np.stack([p[:, 1] / p[:, 0], p[:, 0] / p[:, 1], p[:, 0] * p[:, 1] / p[:, 2] ** 2,
                  p[:, 0] * p[:, 1] / p[:, 3] ** 2], 1)  # fmt: skip
    return r * s[:, None]


def corner_areas(x: np.ndarray) -> np.ndarray:
    """(n, 4) (A_i + A) / 6 of panels x (n, 4, 3): each corner's share of the lumped mass per
    unit mass per area [m^2] (module docstring); the four sum to A for a flat panel."""
    prev, nxt = np.roll(x, 1, axis=1), np.roll(x, -1, axis=1)
    tri = 0.5 * np.linalg.norm(np.cross(nxt - x, prev - x), axis=2)
    quad = 0.5 * np.linalg.norm(np.cross(x[:, 2] - x[:, 0], x[:, 3] - x[:, 1]), axis=1)
    return (tri + quad[:, None]) / 6.0


@register
@dataclass(frozen=True)
class ShearPanels:
    """n shear panels: nodes (n, 4) (corners in order around the panel), part (n,), G [Pa], nu,
    thickness t [m], rho [kg/m^3], nsm [kg/m^2] (n,).  An ``elements.base.ElementFamily`` held
    in ``Structure.elements``."""

    #: registry name (a plain class attribute: not a dataclass field)
    family = "shear_panel"

    nodes: np.ndarray
    part: np.ndarray
    G: np.ndarray
    nu: np.ndarray
    thickness: np.ndarray
    rho: np.ndarray
    nsm: np.ndarray

    @property
    def n_elements(self) -> int:
        return int(self.nodes.shape[0])

    def dofs(self) -> np.ndarray:
        """(n, 24) global DOF numbers, six per corner."""
        return (6 * self.nodes[:, :, None] + np.arange(6)).reshape(-1, 24)

    def has_mass(self) -> bool:
        return bool(np.any(self.rho * self.thickness + self.nsm > 0))

    def matrices(self, xyz: np.ndarray, settings: ElementSettings):
        """Global (K, M) (n, 24, 24) on nodes xyz (N, 3) [m]: K = G t g g^T / (2 Z G t) on the
        translations, M lumped (module docstring); the settings play no part."""
        x = xyz[self.nodes]
        modes = panel_modes(x, self.nu)
        g = modes.g.reshape(-1, 12)
        Kt = (self.G * self.thickness / (2 * modes.z))[:, None, None] * g[:, :, None] * g[:, None]
        trans = (6 * np.arange(4)[:, None] + np.arange(3)).ravel()
        K = np.zeros((self.n_elements, 24, 24))
        K[:, trans[:, None], trans] = Kt
        m = (self.rho * self.thickness + self.nsm)[:, None] * corner_areas(x)
        M = np.zeros_like(K)
        M[:, trans, trans] = np.repeat(m, 3, axis=1)
        return K, M

    @classmethod
    def of(cls, structure) -> "ShearPanels | None":
        return in_elements(cls, structure)
