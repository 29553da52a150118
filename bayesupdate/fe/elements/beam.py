"""Shear-deformable (Timoshenko) 3D beam element, vectorized over elements.

Local DOFs per element (12): [u1 v1 w1 rx1 ry1 rz1  u2 v2 w2 rx2 ry2 rz2], x along the element.
Stiffness and consistent mass (translational + rotary inertia) with shear parameters
Phi_y = 12 E Iz / (G Asy L^2), Phi_z = 12 E Iy / (G Asz L^2), from Przemieniecki, *Theory of Matrix
Structural Analysis* (1968), eqs 5.116 and 11.41-11.42 (also Friedman & Kosmatka 1993).  With
Phi = 0 they reduce to the Euler-Bernoulli element with the classical 1/420 consistent mass.

All functions take (n,) arrays and return (n, 12, 12) arrays; lengths in m, E and G in Pa,
density in kg/m^3.  ``TubeBeams`` holds the exhaust's tube beams (the ``Structure``'s ``beam_*``
columns) and gives their global K and M at given wall thickness, density, modulus and bend
factor: the design parameters of ``fe.model`` act on these four arrays.
"""

from dataclasses import dataclass, field

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.elements.base import (
    Bindable,
    ElementSettings,
    check_fields,
    line_dofs,
    register_parametric,
)
from bayesupdate.fe.sections import section_areas, section_properties

# bending in the x-y plane uses (v, rz) = local DOFs 1, 5, 7, 11; x-z plane uses (w, ry) = 2, 4, 8,
# 10 with ry = -dw/dx, hence the sign pattern below.
_XY = np.array([1, 5, 7, 11])
_XZ = np.array([2, 4, 8, 10])
_XZ_SIGN = np.array([1.0, -1.0, 1.0, -1.0])


def _bending_stiffness(L, EI, phi):
    """(n, 4, 4) Timoshenko bending stiffness in (v1, rz1, v2, rz2) order."""
    c = EI / ((1.0 + phi) * L**3)
    L2 = L**2
    k = np.empty(L.shape + (4, 4))
    k[:, 0, 0] = 12
    k[:, 0, 1] = 6 * L
    k[:, 0, 2] = -12
    k[:, 0, 3] = 6 * L
    k[:, 1, 1] = (4 + phi) * L2
    k[:, 1, 2] = -6 * L
    k[:, 1, 3] = (2 - phi) * L2
    k[:, 2, 2] = 12
    k[:, 2, 3] = -6 * L
    k[:, 3, 3] = (4 + phi) * L2
    _symmetrize_upper(k)
    return k * c[:, None, None]


def _bending_mass(L, rhoA, rhoI, phi):
    """(n, 4, 4) Timoshenko consistent mass (translation + rotary inertia), (v1, rz1, v2, rz2)."""
    p, p2, L2 = phi, phi**2, L**2
    mt = np.empty(L.shape + (4, 4))
    mt[:, 0, 0] = 13 / 35 + 7 / 10 * p + 1 / 3 * p2
    mt[:, 0, 1] = (11 / 210 + 11 / 120 * p + 1 / 24 * p2) * L
    mt[:, 0, 2] = 9 / 70 + 3 / 10 * p + 1 / 6 * p2
    mt[:, 0, 3] = -(13 / 420 + 3 / 40 * p + 1 / 24 * p2) * L
    mt[:, 1, 1] = (1 / 105 + 1 / 60 * p + 1 / 120 * p2) * L2
    mt[:, 1, 2] = (13 / 420 + 3 / 40 * p + 1 / 24 * p2) * L
    mt[:, 1, 3] = -(1 / 140 + 1 / 60 * p + 1 / 120 * p2) * L2
    mt[:, 2, 2] = mt[:, 0, 0]
    mt[:, 2, 3] = -mt[:, 0, 1]
    mt[:, 3, 3] = mt[:, 1, 1]
    _symmetrize_upper(mt)
    mr = np.empty(L.shape + (4, 4))
    b = (1 / 10 - 1 / 2 * p) * L
    mr[:, 0, 0] = 6 / 5
    mr[:, 0, 1] = b
    mr[:, 0, 2] = -6 / 5
    mr[:, 0, 3] = b
    mr[:, 1, 1] = (2 / 15 + 1 / 6 * p + 1 / 3 * p2) * L2
    mr[:, 1, 2] = -b
    mr[:, 1, 3] = (-1 / 30 - 1 / 6 * p + 1 / 6 * p2) * L2
    mr[:, 2, 2] = 6 / 5
    mr[:, 2, 3] = -b
    mr[:, 3, 3] = mr[:, 1, 1]
    _symmetrize_upper(mr)
    den = (1.0 + phi) ** 2
    return mt * (rhoA * L / den)[:, None, None] + mr * (rhoI / (L * den))[:, None, None]


_UPPER = {k: np.triu_indices(k, 1) for k in (2, 4, 12)}


def _symmetrize_upper(a):
    i, j = _UPPER[a.shape[-1]]
    a[..., j, i] = a[..., i, j]


def local_beam_matrices(
    L, E, G, rho, A, Iy, Iz, J, Asy, Asz, shear=True, bend_factor=None, rotary_inertia=True
):
    """Local stiffness and consistent mass of 3D Timoshenko beams.

    L, E, G, rho, A, Iy, Iz, J, Asy, Asz : (n,) arrays (SI).  ``shear=False`` gives Euler-Bernoulli.
    ``rotary_inertia=False`` drops the rotary inertia of bending (with ``shear=False``: the
    classical Euler-Bernoulli beam).  ``bend_factor`` (n,) divides the bending stiffness EI
    (the elbow flexibility factor k of ASME B31.3).
    Returns (K, M), each (n, 12, 12), in local axes.
    """
    L = np.asarray(L, dtype=float)
    n = L.shape[0]
    flex = np.ones(n) if bend_factor is None else np.asarray(bend_factor, dtype=float)
    EIy = E * Iy / flex
    EIz = E * Iz / flex
    if shear:
        phi_y = 12 * EIz / (G * Asy * L**2)
        phi_z = 12 * EIy / (G * Asz * L**2)
    else:
        phi_y = phi_z = np.zeros(n)
    K = np.zeros((n, 12, 12))
    M = np.zeros((n, 12, 12))
    ax = np.array([0, 6])
    tor = np.array([3, 9])
    unit2 = np.array([[1.0, -1.0], [-1.0, 1.0]])
    cons2 = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6.0
    K[:, ax[:, None], ax] = (E * A / L)[:, None, None] * unit2
    K[:, tor[:, None], tor] = (G * J / L)[:, None, None] * unit2
    M[:, ax[:, None], ax] = (rho * A * L)[:, None, None] * cons2
    M[:, tor[:, None], tor] = (rho * (Iy + Iz) * L)[:, None, None] * cons2
    rot = 1.0 if rotary_inertia else 0.0
    K[:, _XY[:, None], _XY] = _bending_stiffness(L, EIz, phi_y)
    M[:, _XY[:, None], _XY] = _bending_mass(L, rho * A, rot * rho * Iz, phi_y)
    s = np.outer(_XZ_SIGN, _XZ_SIGN)
    K[:, _XZ[:, None], _XZ] = _bending_stiffness(L, EIy, phi_z) * s
    M[:, _XZ[:, None], _XZ] = _bending_mass(L, rho * A, rot * rho * Iy, phi_z) * s
    return K, M


def element_frames(x1, x2, up):
    """Rotation matrices of beam elements.

    x1, x2 : (n, 3) end coordinates [m].  up : (n, 3) reference vectors giving the local z
    ("height") direction; must not be parallel to the element.
    Returns R (n, 3, 3) whose rows are the local x, y, z unit vectors in global coordinates, and
    the lengths L (n,).
    """
    d = x2 - x1
    L = np.linalg.norm(d, axis=1)
    ex = d / L[:, None]
    ey = np.cross(up, ex)
    ny = np.linalg.norm(ey, axis=1)
    ey = ey / ny[:, None]
    ez = np.cross(ex, ey)
    return np.stack([ex, ey, ez], axis=1), L


def to_global(K_local, R):
    """Rotate (n, 12, 12) local matrices to global axes with frames R (n, 3, 3)."""
    n = R.shape[0]
    T = np.zeros((n, 12, 12))
    for b in range(4):
        T[:, 3 * b : 3 * b + 3, 3 * b : 3 * b + 3] = R
    return np.matmul(np.matmul(T.transpose(0, 2, 1), K_local), T)


def bend_elements(structure, target: str) -> np.ndarray:
    """(n,) bool: the tube beams of the bend named ``target`` (``Structure.bends``)."""
    if target not in structure.bends:
        raise BayesUpdateError(f"unknown bend {target!r}; bends are {list(structure.bends)}")
    return structure.beam_bend == structure.bends.index(target)


def bend_flexibility_factor(thickness, bend_radius, outer_diameter):
    """ASME B31.3 flexibility factor k = max(1, 1.65/h), h = t R / r^2 (r mean radius). (n,)"""
    r = 0.5 * (outer_diameter - thickness)
    h = thickness * bend_radius / r**2
    with np.errstate(divide="ignore"):
        return np.where(bend_radius > 0, np.maximum(1.0, 1.65 / h), 1.0)


@register_parametric
@dataclass(frozen=True)
class TubeBeams:
    """Tube beams (circular, oval, solid round sections: ``fe.sections``) as element arrays of
    what no design parameter changes: nodes (n, 2), part (n,), frames (n, 3, 3) (rows local x,
    y, z), lengths (n,) [m], shape (n,) section codes, width, height (n,) [m], nu (n,),
    shear_factor (n,) (> 0: the shear area is shear_factor x A; None: the sections' own), elbow
    (n,) bool (ASME B31.3 factor applies), bend_radius (n,) [m]; and the nominal values of the
    design fields: thickness (n,) [m], rho (n,) [kg/m^3], E (n,) [Pa].  An
    ``elements.base.ParametricFamily`` whose four fields (wall thickness, density, modulus, bend
    factor) are design parameters; the thickness and bend factor enter non-linearly (A, I are
    polynomials in the wall thickness, the Timoshenko shear parameter is rational and the B31.3
    elbow factor has a kink)."""

    #: registry name; the ``ElementProperties`` fields; no linear matrix
    family = "beam"
    fields = ("beam_thickness", "beam_rho", "beam_E", "beam_bend_factor")
    linear = ""
    #: the properties a parameter binds (``fe.model.Binding``), on a part's beams or a bend's
    properties = (
        Bindable("thickness", "beam_thickness", "nonlinear", unit="m",
                 acts_on="wall of the part's beams"),
        Bindable("density", "beam_rho", "M", unit="kg/m^3", acts_on="the part's beams"),
        Bindable("youngs_modulus", "beam_E", "K", unit="Pa", acts_on="the part's beams"),
        Bindable("modulus_factor", "beam_E", "K", rule="factor",
                 acts_on="factor on the nominal E of the part's beams"),
        Bindable("bend_factor", "beam_bend_factor", "nonlinear", select=bend_elements,
                 acts_on="extra factor dividing EI of a named bend"),
    )  # fmt: skip

    nodes: np.ndarray
    part: np.ndarray
    frames: np.ndarray
    lengths: np.ndarray
    shape: np.ndarray
    width: np.ndarray
    height: np.ndarray
    nu: np.ndarray
    shear_factor: np.ndarray | None
    elbow: np.ndarray
    bend_radius: np.ndarray
    thickness: np.ndarray
    rho: np.ndarray
    E: np.ndarray
    #: the last (thickness, areas): a calibration asks the mass at the same walls many times
    _areas: dict = field(default_factory=dict, compare=False, repr=False)

    @classmethod
    def of(cls, structure) -> "TubeBeams":
        s = structure
        x1, x2 = s.nodes[s.beam_nodes[:, 0]], s.nodes[s.beam_nodes[:, 1]]
        frames, lengths = element_frames(x1, x2, s.beam_up)
        return cls(
            s.beam_nodes, s.beam_part, frames, lengths, s.beam_shape, s.beam_width,
            s.beam_height, s.beam_nu, s.beam_shear_factor, s.beam_elbow, s.beam_bend_radius,
            s.beam_thickness, s.beam_rho, s.beam_E,
        )  # fmt: skip

    def nominal(self) -> dict[str, np.ndarray]:
        """The structure's wall thickness, density and modulus; bend factor 1 (none)."""
        return {
            "beam_thickness": self.thickness.copy(),
            "beam_rho": self.rho.copy(),
            "beam_E": self.E.copy(),
            "beam_bend_factor": np.ones(self.n_elements),
        }

    def check(self, props, parts: tuple[str, ...]) -> None:
        """Every field finite and > 0 (a solid bar's thickness is not read) and every wall
        thinner than half its section."""
        tube = np.flatnonzero(self.shape != 2)  # solid bars have no wall
        check_fields(
            (
                ("thickness", props.beam_thickness[tube], tube, True),
                ("density", props.beam_rho, None, True),
                ("Young's modulus", props.beam_E, None, True),
                ("bend factor", props.beam_bend_factor, None, True),
            ),
            self.part,
            parts,
        )
        t = props.beam_thickness[tube]
        too_thick = 2 * t >= np.minimum(self.width[tube], self.height[tube])
        if np.any(too_thick):
            i = np.flatnonzero(too_thick)[0]
            raise BayesUpdateError(
                f"part {parts[self.part[tube[i]]]!r}: wall thickness {t[i]} m is not less than "
                "half the section size"
            )

    @property
    def n_elements(self) -> int:
        return int(self.nodes.shape[0])

    def dofs(self) -> np.ndarray:
        """(n, 12) global DOF numbers."""
        return line_dofs(self.nodes)

    def masses(self, props, xyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n,) rho A(t) L [kg] at the element midpoints (n, 3) [m] of nodes xyz (N, 3)."""
        t = props.beam_thickness
        memo = self._areas.get("last")
        if memo is None or not np.array_equal(memo[0], t):
            memo = self._areas["last"] = (
                t.copy(),
                section_areas(self.shape, self.width, self.height, t),
            )
        mid = 0.5 * (xyz[self.nodes[:, 0]] + xyz[self.nodes[:, 1]])
        return props.beam_rho * memo[1] * self.lengths, mid

    def matrices(self, props, settings: ElementSettings, elements=None):
        """Global-axis (K, M) (n_e, 12, 12) of ``elements`` (index array, default all) at
        ``props``, any record with (n,) arrays ``beam_thickness`` [m], ``beam_rho`` [kg/m^3],
        ``beam_E`` [Pa] and ``beam_bend_factor`` (a factor dividing EI on top of the B31.3
        factor of elbows; ``fe.assembly.ElementProperties``)."""
        e = slice(None) if elements is None else elements
        t = props.beam_thickness[e]
        sec = section_properties(self.shape[e], self.width[e], self.height[e], t, self.nu[e])
        if self.shear_factor is not None:
            k = self.shear_factor[e]
            for axis in ("Asy", "Asz"):
                sec[axis] = np.where(k > 0, k * sec["A"], sec[axis])
        E = props.beam_E[e]
        G = E / (2.0 * (1.0 + self.nu[e]))
        elbow = np.where(
            self.elbow[e], bend_flexibility_factor(t, self.bend_radius[e], self.width[e]), 1.0
        )
        Kl, Ml = local_beam_matrices(
            self.lengths[e],
            E,
            G,
            props.beam_rho[e],
            sec["A"],
            sec["Iy"],
            sec["Iz"],
            sec["J"],
            sec["Asy"],
            sec["Asz"],
            shear=settings.shear,
            bend_factor=elbow * props.beam_bend_factor[e],
            rotary_inertia=settings.rotary_inertia,
        )
        R = self.frames[e]
        return to_global(Kl, R), to_global(Ml, R)
