"""Certified parametric reduced basis for the free-free eigenproblem K(theta) u = lambda M(theta) u.

Offline (``ReducedFEModel.build``):

1. *Parameter-separable terms.*  Every beam, point mass and spring is grouped by the parameters
   bound to it.  Density, Young's modulus (and its factor), point-mass and spring factors enter M or
   K exactly linearly: such a group contributes ``value * X_unit`` (X_unit assembled with the value
   1).  Wall thickness and bend factor do not (A, I are polynomials in t, the Timoshenko shear
   parameter is rational, the ASME B31.3 elbow factor max(1, 1.65/h) has a kink): their group
   matrices are interpolated in log(value) by barycentric Lagrange interpolation on Chebyshev
   points of the second kind (Berrut & Trefethen, SIAM Rev. 46, 2004), piecewise between the kinks
   of the B31.3 factor and tensor-product when two such parameters act on the same beams.  The
   degree is raised until the element matrices are reproduced to ``interp_tol`` (relative, checked
   between the nodes), so the interpolation is exact to far below the frequency tolerance.
   Interpolation weights are linear in the interpolated matrices, so projecting the node matrices
   once gives the reduced matrices for every theta.
2. *Basis.*  Elastic mode shapes (n_modes + ``extra_modes``) at seeded scrambled-Sobol points of
   the box (snapshots), rigid-body part removed, compressed by POD in the energy (K) norm of the
   box centre with each snapshot scaled to unit strain energy: the discarded POD energy then
   estimates the relative eigenvalue error of Rayleigh-Ritz (Quarteroni, Manzoni & Negri,
   *Reduced Basis Methods for PDEs*, 2016, ch. 6).  The six rigid-body motions are kept exactly
   as the first basis vectors.
3. *Certification.*  Reduced frequencies are Rayleigh-Ritz values, hence upper bounds of the full
   ones (Courant-Fischer); the relative error is one-sided, so a reduced value *below* a full one
   can only come from the interpolation, and is treated as such (the degree is raised).  Fresh
   seeded validation points are solved in full; while the largest relative frequency error exceeds
   ``tol`` the validation shapes join the snapshots, the POD threshold is lowered and a new
   validation set is drawn.  If ``max_size`` is reached first, the model warns and falls back to
   full solves.

Online (``predict_frequencies_batch``): reduced K and M for all points by one matrix product each,
the rigid-body coordinates eliminated exactly (K R = 0 for a free body, so the elastic pencil is
K_ww x = lambda (M_ww - M_wr M_rr^-1 M_rw) x), then stacked Cholesky + ``eigvalsh`` for all points,
the batch split over threads (``fe.batched_eigen``).
"""

import copy
import warnings
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.linalg.lapack import dsygvd as _dsygvd
from scipy.stats import qmc

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.assembly import ElementProperties
from bayesupdate.fe.batched_eigen import batched_elastic_eigenvalues
from bayesupdate.fe.model import FEModel
from bayesupdate.model_protocol import Prediction

_NON_AFFINE = ("thickness", "bend_factor")
_BEAM_K_LINEAR = ("youngs_modulus", "modulus_factor")
_BEAM_M_LINEAR = ("density",)


# -- interpolation --------------------------------------------------------------------------------
def chebyshev_nodes(low: float, high: float, degree: int) -> np.ndarray:
    """(degree + 1,) Chebyshev points of the second kind on [low, high], ascending."""
    k = np.arange(degree + 1)
    return low + (high - low) * 0.5 * (1.0 - np.cos(np.pi * k / degree))


def barycentric_weights(x: np.ndarray, pieces: np.ndarray, degree: int) -> np.ndarray:
    """Lagrange basis values of a piecewise Chebyshev interpolant.

    x : (B,) points; pieces : (P + 1,) ascending breakpoints.  Returns (B, P * (degree + 1)): the
    weight of each piece's node values, zero outside the piece holding x (Berrut & Trefethen 2004,
    eq. 4.2 with the second-kind weights (-1)^j, halved at the ends).
    """
    x = np.asarray(x, dtype=float).reshape(-1, 1)
    return barycentric_weights_columns(x, np.asarray(pieces, dtype=float)[None, :], degree)[:, 0]


def barycentric_weights_columns(x: np.ndarray, pieces: np.ndarray, degree: int) -> np.ndarray:
    """``barycentric_weights`` for G interpolants of the same degree and piece count at once:
    x (B, G), pieces (G, P + 1) -> (B, G, P * (degree + 1)).  Vectorised over points, columns
    and pieces: it runs in every likelihood call."""
    B, G = x.shape
    n = degree + 1
    P = pieces.shape[1] - 1
    w = (-1.0) ** np.arange(n)
    w[0] *= 0.5
    w[-1] *= 0.5
    which = np.empty((B, G), dtype=int)
    for g in range(G):  # G is the number of interpolated parameters (a handful)
        which[:, g] = np.searchsorted(pieces[g], x[:, g], side="right") - 1
    np.clip(which, 0, P - 1, out=which)
    cols = np.arange(G)[None, :]
    low, high = pieces[cols, which], pieces[cols, which + 1]
    unit = 0.5 * (1.0 - np.cos(np.pi * np.arange(n) / degree))
    d = x[..., None] - (low[..., None] + (high - low)[..., None] * unit)  # (B, G, n)
    exact = d == 0.0
    q = w / np.where(exact, 1.0, d)
    lag = q / q.sum(axis=-1, keepdims=True)
    hit = exact.any(axis=-1)
    if np.any(hit):
        lag[hit] = exact[hit].astype(float)
    out = np.zeros((B, G, P * n))
    np.put_along_axis(out, which[..., None] * n + np.arange(n), lag, axis=-1)
    return out


def _b31_kinks(structure, elements: np.ndarray, low: float, high: float) -> list[float]:
    """Thicknesses in (low, high) where the B31.3 factor max(1, 1.65/h), h = t R / r^2,
    r = (D - t)/2, switches branch: 1.65 t^2 - (3.3 D + 4 R) t + 1.65 D^2 = 0."""
    s = structure
    e = elements[s.beam_elbow[elements] & (s.beam_bend_radius[elements] > 0)]
    kinks = []
    for D, R in {(float(s.beam_width[i]), float(s.beam_bend_radius[i])) for i in e}:
        for t in np.roots([1.65, -(3.3 * D + 4 * R), 1.65 * D**2]).real:
            if low < t < high:
                kinks.append(float(t))
    return sorted(set(kinks))


# -- parameter-separable decomposition ------------------------------------------------------------
@dataclass(frozen=True)
class _Group:
    """Beams with the same bound parameters.  ``nonaffine``: parameter indices interpolated in
    log(value) (breakpoints ``pieces`` in log, one ``degrees`` entry each); ``k_scale`` /
    ``m_scale``: parameter index whose value multiplies K / M (or -1)."""

    elements: np.ndarray
    nonaffine: tuple[int, ...]
    pieces: tuple[np.ndarray, ...]
    degrees: tuple[int, ...]
    k_scale: int
    m_scale: int


class _Decomposition:
    """theta -> K(theta), M(theta) as sums coefficient(theta) x fixed element-matrix stacks.

    ``k_stacks`` / ``m_stacks``: list of (dofs (n_e, d), mats (n_e, d, d)); ``k_coef(theta)`` /
    ``m_coef(theta)`` -> (B, n_terms) with the term order of the stacks.  Term 0 is the constant
    part (coefficient 1).
    """

    def __init__(self, fe: FEModel, bounds: Mapping[str, tuple[float, float]], interp_tol: float):
        self.fe = fe
        self.names = fe.parameter_names
        self.low = np.array([bounds[n][0] for n in self.names])
        self.high = np.array([bounds[n][1] for n in self.names])
        self.interp_tol = interp_tol
        s, a = fe.structure, fe.assembler
        props0 = fe.element_properties(fe.default_parameters())
        prop_of = {n: fe.bindings[n].property for n in self.names}
        masks = fe._masks  # noqa: SLF001 - same masks the FE model uses, so the terms agree with it
        n_beams = len(s.beam_part)
        beam_params = [[] for _ in range(n_beams)]
        point_terms, spring_terms = [], []
        for j, name in enumerate(self.names):
            prop = prop_of[name]
            if prop in ("mass", "mass_factor"):
                point_terms.append((j, np.flatnonzero(masks[name])))
            elif prop == "stiffness_factor":
                spring_terms.append((j, np.flatnonzero(masks[name])))
            else:
                for e in np.flatnonzero(masks[name]):
                    beam_params[e].append(j)
        self._check_unique(beam_params, prop_of, point_terms, spring_terms)
        # constant parts: beams without parameters at the defaults, unbound masses and springs
        unit = ElementProperties(
            props0.beam_thickness.copy(),
            props0.beam_rho.copy(),
            props0.beam_E.copy(),
            props0.beam_bend_factor.copy(),
            np.ones_like(props0.mass_scale),
            np.ones_like(props0.spring_scale),
        )
        self.props0 = props0
        self.unit = unit
        keys = [tuple(p) for p in beam_params]
        free_beams = np.array([i for i, k in enumerate(keys) if not k], dtype=int)
        bound_masses = np.concatenate([m for _, m in point_terms] + [np.zeros(0, int)])
        bound_springs = np.concatenate([m for _, m in spring_terms] + [np.zeros(0, int)])
        free_masses = np.setdiff1d(np.arange(len(s.mass_node)), bound_masses)
        free_springs = np.setdiff1d(np.arange(len(s.spring_part)), bound_springs)
        mM = a.mass_matrices(props0)
        sK = a.spring_matrices(props0)
        mM_unit = a.mass_matrices(unit)
        sK_unit = a.spring_matrices(unit)
        bK0, bM0 = (
            a.beam_matrices(props0, elements=free_beams)
            if free_beams.size
            else (np.zeros((0, 12, 12)),) * 2
        )
        self.k_stacks = [
            [(a.beam_dofs[free_beams], bK0), (a.spring_dofs[free_springs], sK[free_springs])]
        ]
        self.m_stacks = [
            [(a.beam_dofs[free_beams], bM0), (a.mass_dofs[free_masses], mM[free_masses])]
        ]
        self._k_rules = [("const",)]
        self._m_rules = [("const",)]
        for j, idx in point_terms:
            self.m_stacks.append([(a.mass_dofs[idx], mM_unit[idx])])
            per = 1.0 / s.mass_value[idx].sum() if prop_of[self.names[j]] == "mass" else 1.0
            self._m_rules.append(("linear", j, per))
        for j, idx in spring_terms:
            self.k_stacks.append([(a.spring_dofs[idx], sK_unit[idx])])
            self._k_rules.append(("linear", j, 1.0))
        self.groups = []
        for key in sorted({k for k in keys if k}):
            elements = np.array([i for i, k in enumerate(keys) if k == key], dtype=int)
            self._add_group(elements, key, prop_of)

    def _check_unique(self, beam_params, prop_of, point_terms, spring_terms):
        for params in beam_params:
            props = [prop_of[self.names[j]] for j in params]
            if len(set(props)) != len(props):
                raise BayesUpdateError(
                    "reduced model: two parameters set the same property of one beam; "
                    "use the full model (--full)"
                )
        for terms in (point_terms, spring_terms):
            idx = np.concatenate([m for _, m in terms] + [np.zeros(0, int)])
            if np.unique(idx).size != idx.size:
                raise BayesUpdateError(
                    "reduced model: two parameters scale the same point mass or spring; "
                    "use the full model (--full)"
                )

    def _add_group(self, elements, key, prop_of):
        s, a = self.fe.structure, self.fe.assembler
        nonaffine = tuple(j for j in key if prop_of[self.names[j]] in _NON_AFFINE)
        k_scale = next((j for j in key if prop_of[self.names[j]] in _BEAM_K_LINEAR), -1)
        m_scale = next((j for j in key if prop_of[self.names[j]] in _BEAM_M_LINEAR), -1)
        pieces = []
        for j in nonaffine:
            lo, hi = self.low[j], self.high[j]
            if lo <= 0:
                raise BayesUpdateError(
                    f"reduced model: the lower bound of {self.names[j]} must be > 0, got {lo}"
                )
            kinks = _b31_kinks(s, elements, lo, hi) if prop_of[self.names[j]] == "thickness" else []
            pieces.append(np.array([lo, *kinks, hi]))

        def unit_props(values: dict) -> ElementProperties:
            t = self.unit.beam_thickness.copy()
            rho = self.unit.beam_rho.copy()
            E = self.unit.beam_E.copy()
            bend = self.unit.beam_bend_factor.copy()
            base_E = self.fe._base.beam_E  # noqa: SLF001 - nominal E for modulus_factor
            for j in key:
                prop, v = prop_of[self.names[j]], values.get(j, 1.0)
                if prop == "thickness":
                    t[elements] = v
                elif prop == "bend_factor":
                    bend[elements] = v
                elif prop == "density":
                    rho[elements] = 1.0
                elif prop == "youngs_modulus":
                    E[elements] = 1.0
                elif prop == "modulus_factor":
                    E[elements] = base_E[elements]
            return ElementProperties(t, rho, E, bend, self.unit.mass_scale, self.unit.spring_scale)

        # interpolate in log(parameter): thickness enters through rational functions with poles at
        # t = 0 (B31.3 factor ~ 1/t), which map to -infinity in log t, so the degree stays low
        log_pieces = [np.log(p) for p in pieces]
        mid = {j: float(np.sqrt(self.low[j] * self.high[j])) for j in nonaffine}

        def axis_nodes(i, degree):
            p = log_pieces[i]
            return np.exp(
                np.concatenate([chebyshev_nodes(p[k], p[k + 1], degree) for k in range(p.size - 1)])
            )

        def matrices(points):
            Ks, Ms = [], []
            for row in points:
                K, M = a.beam_matrices(
                    unit_props(dict(zip(nonaffine, row, strict=True))), elements=elements
                )
                Ks.append(K)
                Ms.append(M)
            return np.array(Ks), np.array(Ms)

        def interp_error(group, nodes, test):
            Kn, Mn = matrices(nodes)
            Kt, Mt = matrices(test)
            w = self._interp_weights(group, test[:, : len(group.nonaffine)])
            err = max(
                _rel_err(np.einsum("bn,neij->beij", w, Kn), Kt),
                _rel_err(np.einsum("bn,neij->beij", w, Mn), Mt),
            )
            return err, Kn, Mn

        rng = np.random.default_rng(7)
        degrees = []
        for i, j in enumerate(nonaffine):  # 1-D degree of each parameter, the others mid-range
            others = [mid[q] for q in nonaffine]
            test_1d = np.tile(others, (12, 1))
            test_1d[:, i] = np.exp(rng.uniform(np.log(self.low[j]), np.log(self.high[j]), 12))
            for degree in (4, 6, 8, 12, 16, 24, 32):
                nodes_1d = np.tile(others, (len(pieces[i]) - 1) * (degree + 1)).reshape(
                    -1, len(others)
                )
                nodes_1d[:, i] = axis_nodes(i, degree)
                g1 = _Group(elements, (j,), (log_pieces[i],), (degree,), k_scale, m_scale)
                Kn1, Mn1 = matrices(nodes_1d)
                Kt1, Mt1 = matrices(test_1d)
                w = self._interp_weights(g1, test_1d[:, i : i + 1])
                err = max(
                    _rel_err(np.einsum("bn,neij->beij", w, Kn1), Kt1),
                    _rel_err(np.einsum("bn,neij->beij", w, Mn1), Mt1),
                )
                if err < self.interp_tol:
                    break
            else:
                raise BayesUpdateError(
                    f"reduced model: interpolation in {self.names[j]} does not reach "
                    f"{self.interp_tol:g} at degree 32; use the full model (--full)"
                )
            degrees.append(degree)
        if nonaffine:
            test = np.column_stack(
                [
                    np.exp(rng.uniform(np.log(self.low[j]), np.log(self.high[j]), 12))
                    for j in nonaffine
                ]
            )
            for _ in range(4):  # the tensor product may need a little more than each 1-D degree
                axes = [axis_nodes(i, d) for i, d in enumerate(degrees)]
                grid = np.stack([m.ravel() for m in np.meshgrid(*axes, indexing="ij")], axis=1)
                group = _Group(
                    elements, nonaffine, tuple(log_pieces), tuple(degrees), k_scale, m_scale
                )
                err, Kn, Mn = interp_error(group, grid, test)
                if err < self.interp_tol:
                    break
                degrees = [d + 4 for d in degrees]
            else:
                raise BayesUpdateError(
                    f"reduced model: tensor interpolation in {[self.names[j] for j in nonaffine]} "
                    f"has error {err:.1e} > {self.interp_tol:g}; use the full model (--full)"
                )
        else:
            group = _Group(elements, (), (), (), k_scale, m_scale)
            Kn, Mn = matrices(np.zeros((1, 0)))
        gi = len(self.groups)
        self.groups.append(group)
        dofs = a.beam_dofs[elements]
        for n in range(Kn.shape[0]):
            self.k_stacks.append([(dofs, Kn[n])])
            self._k_rules.append(("group", gi, n, "k"))
            self.m_stacks.append([(dofs, Mn[n])])
            self._m_rules.append(("group", gi, n, "m"))

    @staticmethod
    def _interp_weights(group: _Group, theta_cols: np.ndarray) -> np.ndarray:
        """(B, n_nodes) tensor-product interpolation weights of ``group`` at (B, len(nonaffine))."""
        if not group.nonaffine:
            return np.ones((theta_cols.shape[0], 1))
        w = None
        for i, p in enumerate(group.pieces):
            wi = barycentric_weights(np.log(theta_cols[:, i]), p, group.degrees[i])
            w = wi if w is None else np.einsum("bi,bj->bij", w, wi).reshape(wi.shape[0], -1)
        return w

    def _gather_indices(self, rules) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Each term's coefficient is F[:, a] * F[:, b] * c over the features
        F = [1, theta, interpolation weights of every group] (see ``coefficients``)."""
        d = len(self.names)
        offsets = np.cumsum([1 + d] + [self._n_nodes(g) for g in self.groups])
        entries = []
        for rule in rules:
            if rule[0] == "const":
                entries.append((0, 0, 1.0))
            elif rule[0] == "linear":
                entries.append((1 + rule[1], 0, rule[2]))
            else:
                g = self.groups[rule[1]]
                scale = g.k_scale if rule[3] == "k" else g.m_scale
                entries.append((offsets[rule[1]] + rule[2], 1 + scale if scale >= 0 else 0, 1.0))
        a, b, c = zip(*entries, strict=True)
        return np.array(a), np.array(b), np.array(c)

    @staticmethod
    def _n_nodes(g: _Group) -> int:
        return int(
            np.prod([(p.size - 1) * (d + 1) for p, d in zip(g.pieces, g.degrees, strict=True)])
        )

    def _one_d_batches(self) -> list[tuple[list[int], list[int], np.ndarray, int]]:
        """Groups interpolated in one parameter, batched by (degree, piece count): (group
        indices, parameter indices, stacked log breakpoints (G, P + 1), degree)."""
        batches: dict[tuple[int, int], list[int]] = {}
        for g, group in enumerate(self.groups):
            if len(group.nonaffine) == 1:
                key = (group.degrees[0], group.pieces[0].size)
                batches.setdefault(key, []).append(g)
        return [
            (
                gs,
                [self.groups[g].nonaffine[0] for g in gs],
                np.array([self.groups[g].pieces[0] for g in gs]),
                degree,
            )
            for (degree, _), gs in batches.items()
        ]

    def coefficients(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(B, n_k_terms), (B, n_m_terms) coefficients at theta (B, n_params) (all names)."""
        if not hasattr(self, "_k_gather"):
            self._k_gather = self._gather_indices(self._k_rules)
            self._m_gather = self._gather_indices(self._m_rules)
        if not hasattr(self, "_one_d"):
            self._one_d = self._one_d_batches()
        weights: list = [None] * len(self.groups)
        for groups, params, pieces, degree in self._one_d:
            w = barycentric_weights_columns(np.log(theta[:, params]), pieces, degree)
            for c, g in enumerate(groups):
                weights[g] = w[:, c]
        for g, group in enumerate(self.groups):
            if weights[g] is None:
                weights[g] = self._interp_weights(group, theta[:, list(group.nonaffine)])
        F = np.concatenate([np.ones((theta.shape[0], 1)), theta, *weights], axis=1)
        return tuple(F[:, a] * F[:, b] * c for a, b, c in (self._k_gather, self._m_gather))

    def project(self, V: np.ndarray, stacks) -> np.ndarray:
        """(n_terms, r, r) projections V^T X_term V of the term stacks, V (n_dof, r)."""
        r = V.shape[1]
        out = np.zeros((len(stacks), r, r))
        for t, parts in enumerate(stacks):
            for dofs, mats in parts:
                if mats.shape[0]:
                    Vd = V[dofs]
                    out[t] += np.einsum("eir,eij,ejs->rs", Vd, mats, Vd, optimize=True)
        return 0.5 * (out + out.transpose(0, 2, 1))


def _compress_terms(terms: np.ndarray, rel: float = 1e-14) -> tuple[np.ndarray, np.ndarray]:
    """(n_terms, r*r) projected terms -> (C (n_terms, k), B (k, r*r)) with terms ~= C @ B.

    The interpolation nodes of one part give nearly dependent matrices (smooth in the
    parameter), so k is about 40 % of n_terms; dropping singular values below ``rel`` times the
    largest changes reduced entries by < 1e-14 ||K_r||, far below the certified tolerance (and
    the certification is run on the compressed terms)."""
    U, sv, Vt = np.linalg.svd(terms, full_matrices=False)
    k = max(1, int(np.sum(sv > rel * sv[0])))
    return U[:, :k] * sv[:k], Vt[:k]


def _rel_err(approx: np.ndarray, exact: np.ndarray) -> float:
    """Largest entry error of each element matrix relative to its largest entry."""
    scale = np.abs(exact).max(axis=(-2, -1))
    return float(np.max(np.abs(approx - exact).max(axis=(-2, -1)) / np.maximum(scale, 1e-300)))


# -- batched eigen-solve --------------------------------------------------------------------------
def sygvd_elastic_eigenvalues(K_ww: np.ndarray, M_full: np.ndarray, n_rigid: int, n_modes: int):
    """Reference path for ``batched_eigen.batched_elastic_eigenvalues`` (eigenvalues only): the
    Schur complement S formed explicitly, then LAPACK dsygvd (Cholesky of S, reduction to
    standard form, divide and conquer) per point.  Kept for the benchmark and the tests: it
    shares no code with the threaded path."""
    nr = n_rigid
    M_full = 0.5 * (M_full + M_full.transpose(0, 2, 1))
    M_rw = M_full[:, :nr, nr:]
    S = M_full[:, nr:, nr:] - M_rw.transpose(0, 2, 1) @ np.linalg.solve(M_full[:, :nr, :nr], M_rw)
    lam = np.empty((K_ww.shape[0], n_modes))
    for i in range(K_ww.shape[0]):
        out = _dsygvd(K_ww[i], S[i], jobz="N")  # (w, [a,] info)
        w, info = out[0], out[-1]
        if info != 0:
            raise np.linalg.LinAlgError(f"reduced pencil not definite (LAPACK info {info})")
        lam[i] = w[:n_modes]
    return lam


# -- the reduced model ----------------------------------------------------------------------------
@dataclass(frozen=True)
class Certificate:
    """What the certification found: largest relative frequency error over ``n_points`` full solves
    (validation set plus checked points), the smallest signed error (>= ~0 by Rayleigh-Ritz)."""

    max_rel_error: float
    min_signed_error: float
    n_points: int


class ReducedFEModel:
    """A certified reduced-basis surrogate of an ``FEModel`` (see the module docstring).

    Same ``parameter_names``, defaults and bounds as the wrapped model; implements
    ``ParametricModel`` and ``BatchParametricModel``.  Attributes after ``build``: ``size`` (basis
    vectors incl. 6 rigid), ``max_rel_error`` (certified on full solves), ``certified`` (False ->
    every prediction is a full solve), ``tol``, ``n_modes``.
    """

    def __init__(
        self,
        fe_model: FEModel,
        bounds: Mapping[str, tuple[float, float]] | None = None,
        n_modes: int = 12,
        tol: float = 1e-4,
        seed: int = 0,
        n_snapshots: int = 32,
        n_validation: int = 32,
        extra_modes: int = 4,
        max_size: int = 120,
        max_rounds: int = 6,
        interp_tol: float = 1e-9,
        outer=None,
    ):
        self.fe = fe_model
        self.name = f"{fe_model.name} (reduced)"
        self.parameter_names = fe_model.parameter_names
        b = dict(fe_model.default_bounds(), **dict(bounds or {}))
        self.bounds = {k: (float(b[k][0]), float(b[k][1])) for k in self.parameter_names}
        for k, (lo, hi) in self.bounds.items():
            if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
                raise BayesUpdateError(f"reduced model: bounds of {k} must be finite, low < high")
        self.n_modes, self.tol, self.seed = int(n_modes), float(tol), int(seed)
        self.n_snapshots, self.n_validation = int(n_snapshots), int(n_validation)
        self.extra_modes, self.max_size, self.max_rounds = extra_modes, max_size, max_rounds
        self.interp_tol = interp_tol
        self.outer = fe_model if outer is None else outer
        self.low = np.array([self.bounds[k][0] for k in self.parameter_names])
        self.high = np.array([self.bounds[k][1] for k in self.parameter_names])
        self.certified = False
        self.max_rel_error = np.inf
        self.size = 0
        self.history: list[dict] = []
        self.certificate = Certificate(np.inf, 0.0, 0)
        self._warned = False

    # -- protocol ------------------------------------------------------------------------------
    def default_parameters(self) -> dict[str, float]:
        return self.fe.default_parameters()

    def default_bounds(self) -> dict[str, tuple[float, float]]:
        return self.fe.default_bounds()

    def __str__(self) -> str:
        state = "certified" if self.certified else "NOT certified: full solves are used"
        return (
            f"reduced basis of {self.fe.name}: size {self.size} (6 rigid + {self.size - 6} "
            f"elastic), {self.n_modes} modes, max relative frequency error "
            f"{self.max_rel_error:.2e} over {self.certificate.n_points} full solves "
            f"(tol {self.tol:g}); {state}"
        )

    def summary(self) -> dict:
        """JSON-ready {"size", "max_rel_error", "certified", "tol", "n_modes"}."""
        return {
            "size": int(self.size),
            "max_rel_error": float(self.max_rel_error),
            "certified": bool(self.certified),
            "tol": self.tol,
            "n_modes": self.n_modes,
        }

    # -- offline ------------------------------------------------------------------------------
    def build(self) -> "ReducedFEModel":
        """Decompose, snapshot, compress, certify, enrich (module docstring).  Returns self."""
        fe = self.fe
        K0 = fe.assembler.assemble(fe.element_properties(self._mapping(self._centre())))[0]
        R = fe.rigid_basis
        if np.abs(K0 @ R).max() > 1e-8 * np.abs(K0.data).max():
            raise BayesUpdateError(
                "reduced model: the structure is not free-free (rigid motions strain it, e.g. "
                "springs to ground); use the full model (--full)"
            )
        self.decomp = _Decomposition(fe, self.bounds, self.interp_tol)
        dim = len(self.parameter_names)
        sobol = qmc.Sobol(dim, scramble=True, seed=self.seed)
        snap_theta = self._scale(sobol.random(self.n_snapshots))
        snaps = self._full_shapes(snap_theta, self.n_modes + self.extra_modes)[1]
        pod_tol = 0.5 * self.tol
        val_round = 0
        checked: list[tuple[np.ndarray, np.ndarray]] = []
        for rnd in range(self.max_rounds):
            self._compress(snaps, pod_tol)
            if self.size > self.max_size:
                break
            vs = qmc.Sobol(dim, scramble=True, seed=self.seed + 1000 + val_round)
            val_round += 1
            theta_v = self._scale(vs.random(self.n_validation))
            f_full, shapes_v = self._full_shapes(theta_v, self.n_modes)
            cert = self._compare(theta_v, f_full)
            self.history.append(
                dict(round=rnd, size=self.size, max_rel_error=cert.max_rel_error, pod_tol=pod_tol)
            )
            self.certificate = cert
            if cert.min_signed_error < -0.1 * self.tol:
                raise BayesUpdateError(
                    f"reduced model: reduced frequencies fall {-cert.min_signed_error:.1e} below "
                    "full ones (Rayleigh-Ritz forbids it): the parameter interpolation is too "
                    "coarse; lower interp_tol or use the full model (--full)"
                )
            if cert.max_rel_error <= self.tol:
                self.certified = True
                self.max_rel_error = cert.max_rel_error
                checked.append((theta_v, f_full))
                break
            snaps = np.concatenate([snaps, shapes_v], axis=1)
            pod_tol *= 0.25
        if not self.certified:
            self._fail()
        self._checked = checked
        return self

    def _fail(self):
        self.certified = False
        cert = getattr(self, "certificate", None)
        self.max_rel_error = cert.max_rel_error if cert else np.inf
        warnings.warn(
            f"reduced model of {self.fe.name}: tolerance {self.tol:g} not reached within size "
            f"{self.max_size} (best {self.max_rel_error:.2e} at size {self.size}); "
            "falling back to full solves",
            RuntimeWarning,
            stacklevel=3,
        )

    def _centre(self) -> np.ndarray:
        d = np.array([self.fe.default_parameters()[k] for k in self.parameter_names])
        inside = np.all((d >= self.low) & (d <= self.high))
        return d if inside else 0.5 * (self.low + self.high)

    def _scale(self, u: np.ndarray) -> np.ndarray:
        return self.low + u * (self.high - self.low)

    def _mapping(self, row) -> dict[str, float]:
        return dict(zip(self.parameter_names, map(float, row), strict=True))

    def _full_shapes(self, theta: np.ndarray, n_modes: int):
        """Full solves: (B, n_modes) frequencies (NaN rows on failure) and (n_dof, k) shapes."""
        freqs = np.full((theta.shape[0], n_modes), np.nan)
        shapes = []
        for i, row in enumerate(theta):
            try:
                sol = self.fe.solve(self._mapping(row), n_modes).modes
            except (BayesUpdateError, np.linalg.LinAlgError):
                # a snapshot whose eigen-solve fails is left out (its row stays NaN); the
                # certification then runs on the points that solved
                continue
            freqs[i] = sol.frequencies_hz
            shapes.append(sol.shapes)
        return freqs, np.concatenate(shapes, axis=1)

    def _compress(self, snaps: np.ndarray, pod_tol: float):
        """POD of the rigid-free snapshots in the K-norm of the centre (unit strain energy each);
        keep the smallest rank whose discarded energy per snapshot (on average) is <= pod_tol:
        that is about the relative eigenvalue error, twice the relative frequency error."""
        fe = self.fe
        props = fe.element_properties(self._mapping(self._centre()))
        K0, M0, _ = fe.assembler.assemble(props)
        R = fe.rigid_basis
        MR = M0 @ R
        Rr = R @ np.linalg.inv(np.linalg.cholesky(R.T @ MR)).T  # M0-orthonormal rigid motions
        Y = snaps - Rr @ (Rr.T @ (M0 @ snaps))
        energy = np.einsum("ik,ik->k", Y, K0 @ Y)
        Y = Y / np.sqrt(energy)
        G = Y.T @ (K0 @ Y)
        w, U = np.linalg.eigh(0.5 * (G + G.T))
        w, U = w[::-1], U[:, ::-1]
        tail = np.concatenate([np.cumsum(w[::-1])[::-1][1:], [0.0]])
        numerical = int(np.sum(w > 1e-10 * w[0]))
        rank = int(np.argmax(tail <= pod_tol * Y.shape[1])) + 1
        rank = min(max(rank, self.n_modes), numerical)
        W = Y @ U[:, :rank]
        # M0-orthonormal elastic basis (well-conditioned reduced M)
        W = W - Rr @ (Rr.T @ (M0 @ W))
        g = W.T @ (M0 @ W)
        s, Q = np.linalg.eigh(0.5 * (g + g.T))
        W = W @ (Q / np.sqrt(s))
        V = np.concatenate([Rr, W], axis=1)
        self.V = V
        # sensor read-out is linear in the shape: sensor shapes of a reduced solution y are
        # V_sensor @ y, so a batch of shapes costs (n_sensors x r x n_modes) per point
        self._V_sensor = fe.sensor_shapes(V)
        self.size = V.shape[1]
        self._n_rigid = Rr.shape[1]
        nr = self._n_rigid
        Kt = self.decomp.project(V, self.decomp.k_stacks)[:, nr:, nr:]
        Mt = self.decomp.project(V, self.decomp.m_stacks)
        self._K_terms = _compress_terms(Kt.reshape(Kt.shape[0], -1))
        self._M_terms = _compress_terms(Mt.reshape(Mt.shape[0], -1))

    # -- online --------------------------------------------------------------------------------
    def reduced_matrices(self, theta_full: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Reduced pencils at theta_full (B, n_params) (all parameters, SI): the elastic block of
        K (B, r_e, r_e) and the whole M (B, r, r), the first ``n_rigid`` coordinates being the
        rigid-body motions.  Two matrix products over the projected affine terms."""
        cK, cM = self.decomp.coefficients(theta_full)
        r, nr = self.size, self._n_rigid
        K = ((cK @ self._K_terms[0]) @ self._K_terms[1]).reshape(-1, r - nr, r - nr)
        M = ((cM @ self._M_terms[0]) @ self._M_terms[1]).reshape(-1, r, r)
        return K, M

    @property
    def n_rigid(self) -> int:
        return self._n_rigid

    def _reduced_eigenvalues(self, theta_full: np.ndarray, n_modes: int, vectors: bool = False):
        K, M = self.reduced_matrices(theta_full)
        return batched_elastic_eigenvalues(K, M, self._n_rigid, n_modes, vectors=vectors)

    def _compare(self, theta: np.ndarray, f_full: np.ndarray) -> Certificate:
        ok = np.all(np.isfinite(f_full), axis=1)
        lam = self._reduced_eigenvalues(theta[ok], self.n_modes)
        f_rom = np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)
        signed = f_rom / f_full[ok] - 1.0
        return Certificate(float(np.max(np.abs(signed))), float(np.min(signed)), int(ok.sum()))

    def _theta_full(self, theta: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
        if names == self.parameter_names:  # the sampler's case: no defaults to fill in
            return np.array(theta, dtype=float)
        unknown = [n for n in names if n not in self.parameter_names]
        if unknown:
            raise BayesUpdateError(
                f"unknown parameters {unknown} for model {self.fe.name}; "
                f"parameters are {list(self.parameter_names)}"
            )
        d = self.fe.default_parameters()
        full = np.tile([d[n] for n in self.parameter_names], (theta.shape[0], 1))
        for c, n in enumerate(names):
            full[:, self.parameter_names.index(n)] = theta[:, c]
        return full

    def predict_frequencies_batch(
        self, theta: np.ndarray, names: tuple[str, ...] | None = None, n_modes: int | None = None
    ) -> np.ndarray:
        """(B, n_modes) elastic frequencies [Hz] at theta (B, len(names)) (SI).

        Points inside the box of the basis: reduced solve (all at once).  Points outside it, more
        modes than certified, or an uncertified model: full solves.  Non-physical rows: NaN."""
        names = tuple(self.parameter_names if names is None else names)
        n_modes = self.n_modes if n_modes is None else int(n_modes)
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        full = self._theta_full(theta, names)
        if not self.certified or n_modes > self.n_modes:
            if not self.certified and not self._warned:
                self._warned = True
                warnings.warn(f"{self}", RuntimeWarning, stacklevel=2)
            return self.fe.predict_frequencies_batch(full, self.parameter_names, n_modes)
        out = np.full((theta.shape[0], n_modes), np.nan)
        finite = np.all(np.isfinite(full), axis=1)
        inside = finite & np.all((full >= self.low) & (full <= self.high), axis=1)
        if np.any(inside):
            lam = self._reduced_eigenvalues(full[inside], n_modes)
            out[inside] = np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)
        outside = finite & ~inside
        if np.any(outside):
            out[outside] = self.outer.predict_frequencies_batch(
                full[outside], self.parameter_names, n_modes
            )
        return out

    @property
    def sensor_labels(self) -> tuple[str, ...]:
        return tuple(self.fe.structure.sensor_labels)

    def predict_batch_with_shapes(
        self, theta: np.ndarray, names: tuple[str, ...] | None = None, n_modes: int | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Frequencies (B, n_modes) [Hz] and sensor shapes (B, n_sensors, n_modes) at theta
        (B, len(names)), rows on ``sensor_labels``; shapes are not normalised (MAC ignores scale).

        Reduced points: one batched solve with eigenvectors, phi_sensors = V_sensor @ y (no
        full-size shape is formed).  Points outside the box, more modes than certified or an
        uncertified model: full solves (``predict``) one by one.  Failed points: NaN."""
        names = tuple(self.parameter_names if names is None else names)
        n_modes = self.n_modes if n_modes is None else int(n_modes)
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        full = self._theta_full(theta, names)
        usable = self.certified and n_modes <= self.n_modes
        if usable and np.all((full >= self.low) & (full <= self.high)):
            # every point inside the box (the sampler's usual batch): one batched solve
            lam, y = self._reduced_eigenvalues(full, n_modes, vectors=True)
            return np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi), self._V_sensor @ y
        n_s = len(self.sensor_labels)
        freqs = np.full((theta.shape[0], n_modes), np.nan)
        shapes = np.full((theta.shape[0], n_s, n_modes), np.nan)
        finite = np.all(np.isfinite(full), axis=1)
        inside = finite & np.all((full >= self.low) & (full <= self.high), axis=1) & usable
        if np.any(inside):
            lam, y = self._reduced_eigenvalues(full[inside], n_modes, vectors=True)
            freqs[inside] = np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)
            shapes[inside] = self._V_sensor @ y  # (s, r) @ (B, r, m): BLAS, unlike einsum
        model = self.outer if self.certified else self.fe
        for i in np.flatnonzero(finite & ~inside):
            try:
                pred = model.predict(self._mapping(full[i]), n_modes)
            except BayesUpdateError:
                continue
            freqs[i] = pred.frequencies_hz
            shapes[i] = pred.shapes
        return freqs, shapes

    def predict(self, params: Mapping[str, float] | None = None, n_modes: int = 12) -> Prediction:
        """Prediction with reduced frequencies and shapes (full solve outside the certified use)."""
        p = self.fe.full_parameters(params)
        row = np.array([[p[k] for k in self.parameter_names]])
        if (
            not self.certified
            or n_modes > self.n_modes
            or np.any(row < self.low)
            or np.any(row > self.high)
        ):
            return (self.fe if not self.certified else self.outer).predict(p, n_modes)
        props = self.fe.element_properties(p)  # validates the values
        lam, y = self._reduced_eigenvalues(row, n_modes, vectors=True)
        phi = self.V @ y[0]
        idx = np.argmax(np.abs(phi), axis=0)
        phi = phi * np.sign(phi[idx, np.arange(phi.shape[1])])
        mass, _ = self.fe.assembler.total_mass(props)
        freqs = np.sqrt(np.maximum(lam[0], 0.0)) / (2 * np.pi)
        return Prediction(freqs, self.fe.sensor_shapes(phi), self.fe.structure.sensor_labels, mass)

    def coarsened(
        self, tol: float = 5e-3, n_train: int = 128, n_check: int = 64, min_size: int | None = None
    ) -> "ReducedFEModel":
        """A smaller reduced model for screening proposals (delayed-acceptance sampling), built
        without any full solve: a second Rayleigh-Ritz level inside this basis.

        Elastic reduced eigenvectors of this model at ``n_train`` seeded Sobol points of the box,
        each scaled to unit strain energy at the box centre, are compressed by POD in that
        energy norm; the smallest rank whose frequencies stay within ``tol`` (relative) of this
        model's on ``n_check`` fresh points is kept (``min_size`` elastic vectors at least,
        default ``n_modes``).  The affine terms are projected once more, so an evaluation costs
        an eigen-solve of size 6 + m.  Its values are Rayleigh-Ritz values of this model's
        pencils: upper bounds of this model's frequencies, hence of the full ones.
        ``max_rel_error`` of the result is the measured error against this model (its own
        error against full solves adds to it).  Raises ``BayesUpdateError`` on an uncertified
        model."""
        if not self.certified:
            raise BayesUpdateError("coarsened: the reduced model is not certified")
        nr, re = self._n_rigid, self.size - self._n_rigid
        dim = len(self.parameter_names)
        train = self._scale(qmc.Sobol(dim, scramble=True, seed=self.seed + 77).random(n_train))
        check = self._scale(qmc.Sobol(dim, scramble=True, seed=self.seed + 78).random(n_check))
        _, y = self._reduced_eigenvalues(train, self.n_modes, vectors=True)
        lam_check = self._reduced_eigenvalues(check, self.n_modes)
        Y = np.moveaxis(y[:, nr:, :], 1, 0).reshape(re, -1)  # (r_e, n_train * n_modes)
        Kc = self.reduced_matrices(self._centre()[None, :])[0][0]
        G = np.linalg.cholesky(0.5 * (Kc + Kc.T))  # energy norm ||x||^2 = |G^T x|^2
        Z = G.T @ Y
        Z = Z / np.linalg.norm(Z, axis=0)
        U = np.linalg.svd(Z, full_matrices=False)[0]
        start = self.n_modes if min_size is None else int(min_size)
        best = None
        for m in range(min(start, re), re + 1, 2):
            Q = np.linalg.qr(np.linalg.solve(G.T, U[:, :m]))[0]  # same span, orthonormal
            coarse = self._projected(Q)
            lam = coarse._reduced_eigenvalues(check, self.n_modes)
            err = float(np.max(np.abs(np.sqrt(lam / lam_check) - 1.0)))
            best = (coarse, err)
            if err <= tol:
                break
        coarse, err = best
        coarse.max_rel_error = err
        coarse.tol = float(tol)
        coarse.name = f"{self.fe.name} (reduced, screening)"
        return coarse

    def _projected(self, Q: np.ndarray) -> "ReducedFEModel":
        """A copy restricted to the elastic subspace Q (r_e, m) of this basis (rigid kept)."""
        nr, re = self._n_rigid, self.size - self._n_rigid
        m = Q.shape[1]
        Qf = np.zeros((self.size, nr + m))
        Qf[:nr, :nr] = np.eye(nr)
        Qf[nr:, nr:] = Q
        BK = self._K_terms[1].reshape(-1, re, re)
        BM = self._M_terms[1].reshape(-1, self.size, self.size)
        out = copy.copy(self)
        out._K_terms = (self._K_terms[0], (Q.T @ BK @ Q).reshape(BK.shape[0], -1))
        out._M_terms = (self._M_terms[0], (Qf.T @ BM @ Qf).reshape(BM.shape[0], -1))
        out.V = self.V @ Qf
        out._V_sensor = self._V_sensor @ Qf
        out.size = nr + m
        out.history = list(self.history)
        out._checked = list(self._checked)
        return out

    def localized(
        self, samples: np.ndarray, names: tuple[str, ...] | None = None, widen: float = 0.5, **kw
    ) -> "ReducedFEModel":
        """A smaller, faster certified model on the box of ``samples`` (k, len(names)) (e.g. a
        pilot chain), widened by ``widen`` times its width on each side and clipped to this
        model's box; points outside it are predicted by this model (``outer``).  Parameters not in
        ``names`` keep this model's bounds.  Same tol, seed and n_modes unless given in ``kw``."""
        names = tuple(self.parameter_names if names is None else names)
        samples = np.atleast_2d(np.asarray(samples, dtype=float))
        bounds = dict(self.bounds)
        for c, n in enumerate(names):
            lo, hi = np.min(samples[:, c]), np.max(samples[:, c])
            pad = widen * max(hi - lo, 1e-6 * abs(hi))
            bounds[n] = (max(lo - pad, self.bounds[n][0]), min(hi + pad, self.bounds[n][1]))
        options = dict(n_modes=self.n_modes, tol=self.tol, seed=self.seed, outer=self)
        options.update(kw)
        return ReducedFEModel(self.fe, bounds, **options).build()

    def certify_at(
        self, theta: np.ndarray, names: tuple[str, ...] | None = None, enrich: bool = True
    ) -> float:
        """Check the reduced frequencies against full solves at extra points (e.g. the posterior
        mean), theta (k, len(names)).  If the error there exceeds ``tol`` and ``enrich``, their
        shapes join the basis and all checked points are re-verified; if the tolerance still fails
        (or the size limit is hit), the model falls back to full solves with a warning.
        Returns the largest relative error at the points; updates ``max_rel_error``."""
        names = tuple(self.parameter_names if names is None else names)
        full = self._theta_full(np.atleast_2d(np.asarray(theta, dtype=float)), names)
        full = full[np.all((full >= self.low) & (full <= self.high), axis=1)]
        if not self.certified or full.shape[0] == 0:
            return float("nan")
        f_full, shapes = self._full_shapes(full, self.n_modes)
        cert = self._compare(full, f_full)
        if cert.max_rel_error > self.tol and enrich:
            extra = self._full_shapes(full, self.n_modes + self.extra_modes)[1]
            self._compress(np.concatenate([self.V[:, self._n_rigid :], extra], axis=1), 0.0)
            errors = [self._compare(t, f) for t, f in [*self._checked, (full, f_full)]]
            cert = self._compare(full, f_full)
            worst = max(c.max_rel_error for c in errors)
            self.max_rel_error = max(self.max_rel_error, worst)
            if worst > self.tol or self.size > self.max_size:
                self._fail()
                return cert.max_rel_error
            self.max_rel_error = worst
        else:
            self.max_rel_error = max(self.max_rel_error, cert.max_rel_error)
        self._checked.append((full, f_full))
        self.certificate = Certificate(
            self.max_rel_error,
            min(self.certificate.min_signed_error, cert.min_signed_error),
            self.certificate.n_points + cert.n_points,
        )
        return cert.max_rel_error


def reduced_model_for(
    fe_model,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    tol: float = 1e-4,
    seed: int = 0,
    n_modes: int = 12,
    **options,
):
    """A built, certified ``ReducedFEModel`` of ``fe_model``; the model itself (with a warning)
    when it is not an ``FEModel`` or has no reduced form (not free-free, overlapping bindings).
    An uncertified reduced model (size limit) is returned too: it falls back to full solves."""
    if not isinstance(fe_model, FEModel):
        return fe_model
    try:
        return ReducedFEModel(fe_model, bounds, n_modes, tol, seed, **options).build()
    except BayesUpdateError as exc:
        warnings.warn(f"{exc}; using full solves", RuntimeWarning, stacklevel=2)
        return fe_model
