"""Rigid-body mass properties of a structure from its mass matrix: mass, centre of gravity and
inertia tensor about the centre of gravity.

With R (n_dof, 6) the rigid-body motions about the origin (3 translations, 3 small rotations
theta with u = theta x x: ``assembly.rigid_body_basis(nodes, centre=0)``), the rigid-body mass
matrix is M_r = R^T M R (6, 6), which MSC Nastran's grid point weight generator prints as [MO]
about its reference point (MSC Nastran Linear Static Analysis User's Guide, "Grid Point Weight
Generator"; PARAM GRDPNT):

    M_r = [[ m I,          -m skew(c) ],
           [ m skew(c),     J_o       ]],

so m = trace(M_r[:3, :3]) / 3, m c = (M_r[1, 5], M_r[2, 3], M_r[0, 4]) and the inertia tensor
about the centre of gravity follows from the one about the origin by the parallel-axis theorem,
J_cg = J_o - m (|c|^2 I - c c^T).  Products of inertia are reported as Nastran writes them on
CONM2 (I21, I31, I32) and in the weight generator's I(S): I_xy = integral of x y dm about the
centre of gravity, so J = [[Ixx, -Ixy, -Ixz], [-Ixy, Iyy, -Iyz], [-Ixz, -Iyz, Izz]].

Values are in the model's own consistent units (SI for built-in models; a Nastran deck's own,
e.g. lbf s^2/in, in and lbf s^2 in for an inch-lbf-s deck).
"""

from collections.abc import Mapping
from dataclasses import dataclass, replace
from itertools import combinations

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.rotations import rigid_body_basis

#: component names of a ``MassProperties``, in ``MassProperties.vector`` order
COMPONENTS = ("mass", "cg_x", "cg_y", "cg_z", "ixx", "iyy", "izz", "ixy", "ixz", "iyz")


@dataclass(frozen=True)
class MassProperties:
    """Rigid-body mass properties.

    mass : total mass [model mass unit].  cg : (3,) centre of gravity in the model's frame
    [model length unit].  inertia : (3, 3) inertia tensor about the centre of gravity, axes
    parallel to the model's [mass x length^2] (off-diagonals are minus the products of inertia).
    """

    mass: float
    cg: np.ndarray
    inertia: np.ndarray

    @property
    def products(self) -> np.ndarray:
        """(Ixy, Ixz, Iyz): integrals of x y, x z, y z dm about the centre of gravity."""
        J = self.inertia
        return -np.array([J[0, 1], J[0, 2], J[1, 2]])

    def inertia_about(self, point) -> np.ndarray:
        """(3, 3) inertia tensor about axes through ``point`` (3,) parallel to the model's,
        by the parallel-axis theorem J_p = J_cg + m (|d|^2 I - d d^T), d = cg - point."""
        d = np.asarray(self.cg, dtype=float) - np.asarray(point, dtype=float)
        return self.inertia + self.mass * (d @ d * np.eye(3) - np.outer(d, d))

    def vector(self) -> np.ndarray:
        """(10,) values in ``COMPONENTS`` order."""
        J = self.inertia
        return np.concatenate([[self.mass], self.cg, np.diag(J), self.products])

    def as_dict(self) -> dict[str, float]:
        """{component: value} in ``COMPONENTS`` order."""
        return dict(zip(COMPONENTS, map(float, self.vector()), strict=True))


def rigid_body_mass_matrix(M, nodes: np.ndarray) -> np.ndarray:
    """(6, 6) rigid-body mass matrix about the origin, R^T M R.

    M : (6N, 6N) mass matrix (dense or sparse) of N nodes with 6 DOFs each, in the global frame,
    before supports and rigid elements are applied.  nodes : (N, 3) node coordinates."""
    nodes = np.asarray(nodes, dtype=float)
    if M.shape != (6 * len(nodes), 6 * len(nodes)):
        raise BayesUpdateError(
            f"mass properties: a mass matrix {M.shape} for {len(nodes)} nodes (needs 6 per node)"
        )
    R = rigid_body_basis(nodes, centre=np.zeros(3))
    return np.asarray(R.T @ (M @ R))


def from_rigid_mass(Mr: np.ndarray) -> MassProperties:
    """``MassProperties`` of a (6, 6) rigid-body mass matrix about the origin (module
    docstring).  A mass that is not > 0 is an error (no centre of gravity)."""
    Mr = np.asarray(Mr, dtype=float)
    m = float(np.trace(Mr[:3, :3]) / 3.0)
    if not m > 0:
        raise BayesUpdateError(f"mass properties: the total mass is {m:g}; it must be > 0")
    c = np.array([Mr[1, 5], Mr[2, 3], Mr[0, 4]]) / m
    J_o = 0.5 * (Mr[3:, 3:] + Mr[3:, 3:].T)
    J = J_o - m * (c @ c * np.eye(3) - np.outer(c, c))
    return MassProperties(m, c, J)


def model_mass_properties(model, params: Mapping[str, float] | None = None) -> MassProperties:
    """``MassProperties`` of an FE model (anything with ``matrices(params)`` and a
    ``structure``) at ``params`` (name -> value; missing names take the defaults)."""
    M = model.matrices(params)[1]
    return from_rigid_mass(rigid_body_mass_matrix(M, model.structure.nodes))


#: relative tolerance of the affine check of ``RigidMassTerms`` (round-off of an assembly)
AFFINE_TOL = 1e-9


@dataclass(frozen=True)
class RigidMassTerms:
    """M_r(theta) = M_r0 + sum_i d_i D_i + sum_(i,j) in pairs d_i d_j C_ij, d = theta - theta0:
    the rigid-body mass matrix of a model whose mass matrix is affine in each parameter, so
    that mass properties cost a 6 x 6 sum instead of an assembly.  Additive parameters
    (densities, point masses, non-structural mass, beam section fields on their own elements)
    need no pair; a product of two (a density times a section field of the same beams, as in a
    lumped beam's twist inertia rho (I1 + I2) L / 2) is one C_ij.  names (d,); theta0 (d,);
    Mr0 (6, 6); D (d, 6, 6); pairs ((i, j), ...) with i < j and C (n_pairs, 6, 6), empty for
    an additive model."""

    names: tuple[str, ...]
    theta0: np.ndarray
    Mr0: np.ndarray
    D: np.ndarray
    pairs: tuple[tuple[int, int], ...] = ()
    C: np.ndarray | None = None
    #: (d,) the model's defaults, where they are not theta0 (``rigid_mass_terms``): the values
    #: of names a call leaves out
    defaults: np.ndarray | None = None

    def __call__(self, params: Mapping[str, float] | None = None) -> MassProperties:
        return from_rigid_mass(self.rigid_mass(params))

    def rigid_mass(self, params: Mapping[str, float] | None = None) -> np.ndarray:
        """(6, 6) M_r about the origin at ``params`` (missing names: theta0)."""
        return _affine(self, params)


def _affine(terms: RigidMassTerms, params: Mapping[str, float] | None) -> np.ndarray:
    """M_r at ``params`` (missing names: theta0) from the affine and pair terms."""
    values = params or {}
    missing = terms.theta0 if terms.defaults is None else terms.defaults
    theta = np.array([float(values.get(n, t)) for n, t in zip(terms.names, missing,
                      strict=True)])  # fmt: skip
    d = theta - terms.theta0
    Mr = terms.Mr0 + np.tensordot(d, terms.D, axes=1)
    if terms.pairs:
        i, j = np.array(terms.pairs).T
        Mr = Mr + np.tensordot(d[i] * d[j], terms.C, axes=1)
    return Mr


def _rigid(model, values: Mapping[str, float]) -> np.ndarray:
    return rigid_body_mass_matrix(model.matrices(values)[1], model.structure.nodes)


def _agrees(predicted: np.ndarray, exact: np.ndarray, Mr0: np.ndarray) -> bool:
    """Entry-wise within ``AFFINE_TOL`` of sqrt(|M_ii M_jj|) (the bound of a PSD matrix's
    off-diagonal) and of the entry itself."""
    d = np.sqrt(np.abs(np.diag(Mr0)))
    scale = np.abs(exact) + np.outer(d, d)
    return bool(np.all(np.abs(predicted - exact) <= AFFINE_TOL * scale))


def _pair_terms(model, terms: RigidMassTerms, steps: list[float]) -> RigidMassTerms:
    """``terms`` with the pairs whose mixed difference
    M_r(theta0 + h_i e_i + h_j e_j) - M_r0 - h_i D_i - h_j D_j = h_i h_j C_ij (exact for a
    bilinear dependence) is not round-off (d (d - 1) / 2 assemblies)."""
    theta0 = dict(zip(terms.names, terms.theta0, strict=True))
    pairs, C = [], []
    for i, j in combinations(range(len(terms.names)), 2):
        (a, ha), (b, hb) = (terms.names[i], steps[i]), (terms.names[j], steps[j])
        corner = _rigid(model, {**theta0, a: theta0[a] + ha, b: theta0[b] + hb})
        mixed = corner - terms.Mr0 - ha * terms.D[i] - hb * terms.D[j]
        if not _agrees(mixed, np.zeros((6, 6)), terms.Mr0):
            pairs.append((i, j))
            C.append(mixed / (ha * hb))
    return replace(terms, pairs=tuple(pairs), C=np.array(C) if C else None)


def rigid_mass_terms(model) -> RigidMassTerms | None:
    """``RigidMassTerms`` of an FE model about its default parameters, or None where its mass
    matrix is not affine in some parameter, or not bilinear over them (or a step leaves the
    physical range).

    Each D_i is a forward difference with a 25 % step (exact for an affine dependence), checked
    by a second step of twice the size and, for all parameters moved at once by 15-25 %, by the
    exact M_r there (2 d + 2 assemblies).  Where that check fails (a product of two parameters:
    a density and a section field of the same beams), the pair terms C_ij are each one mixed
    difference (``_pair_terms``) and the same point checks the bilinear sum; a product of three
    parameters still fails it (None).  A model the affine check accepts keeps no pairs, so its
    terms are the affine ones exactly.

    A model whose matrices at the defaults are not those of its parameters written there (a
    Nastran DESVAR whose relations set cards that hold values the relations do not give, its
    default the mean x: the deck's own matrices at the defaults, the relations' everywhere
    else; a study's absolute binding of that kind is refused, ``nastran.bindings``) fails
    the checks about the defaults; the terms are then built about a point off them (every
    parameter moved by a tenth of its step) and hold everywhere but at the defaults
    themselves, where they give the written parameters' limit."""
    theta0 = model.default_parameters()
    bounds = model.default_bounds()
    steps = {n: 0.25 * (abs(t) if t != 0 else bounds[n][1] - bounds[n][0])
             for n, t in theta0.items()}  # fmt: skip
    try:
        terms = _terms_about(model, theta0, steps)
        if terms is None and theta0:
            off = {n: t + 0.1 * steps[n] for n, t in theta0.items()}
            terms = _terms_about(model, off, steps)
            if terms is not None:
                terms = replace(terms, defaults=np.array(list(theta0.values())))
    except BayesUpdateError:
        return None
    return terms


def _terms_about(model, theta0: dict, steps: dict) -> RigidMassTerms | None:
    """``rigid_mass_terms`` about ``theta0`` with the steps ``steps`` ({name: h}), or None."""
    names = tuple(theta0)
    Mr0 = _rigid(model, theta0)
    D = []
    for name in names:
        t0, h = theta0[name], steps[name]
        one = _rigid(model, {**theta0, name: t0 + h}) - Mr0
        two = _rigid(model, {**theta0, name: t0 + 2.0 * h}) - Mr0
        if not _agrees(2.0 * one, two, Mr0):
            return None
        D.append(one / h)
    terms = RigidMassTerms(names, np.array([theta0[n] for n in names]), Mr0, np.array(D))
    if not names:
        return terms
    moved = {n: theta0[n] + (0.6 + 0.4 * k / len(names)) * steps[n] for k, n in enumerate(names)}
    exact = _rigid(model, moved)
    if _agrees(_affine(terms, moved), exact, Mr0):
        return terms
    terms = _pair_terms(model, terms, [steps[n] for n in names])
    if not terms.pairs or not _agrees(_affine(terms, moved), exact, Mr0):
        return None
    return terms
