"""Parameter-separable (affine) decomposition of K(theta), M(theta) for the reduced model.

Every beam, point mass and spring is grouped by the parameters bound to it
(``FEModel.affine_terms``).  Density, Young's modulus (and its factor), point-mass and spring
factors enter M or K exactly linearly: such a group contributes ``value * X_unit`` (X_unit
assembled with the value 1).  Wall thickness and bend factor do not (A, I are polynomials in t,
the Timoshenko shear parameter is rational, the ASME B31.3 elbow factor max(1, 1.65/h) has a
kink): their group matrices are interpolated in log(value) by barycentric Lagrange interpolation
on Chebyshev points of the second kind (``reduced.interpolation``), piecewise between the kinks of
the B31.3 factor and tensor-product when two such parameters act on the same beams.  The degree
is raised until the element matrices are reproduced to ``interp_tol`` (relative, checked between
the nodes), so the interpolation is exact to far below the frequency tolerance.

The registered element families (general beams, rods, scalar masses: ``fe.elements.base``) carry
no parameter: their K and M join the constant term.  Shells (``FEModel.general``) need no
interpolation:
shell K and M are exact polynomials in the thickness and linear in modulus and density
(``reduced.shell_terms``), hence the features theta^2 and theta^3.
"""

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.assembly import ElementProperties
from bayesupdate.fe.elements.base import PARAMETRIC
from bayesupdate.fe.model import AffineTerms, FEModel
from bayesupdate.fe.reduced.interpolation import (
    barycentric_weights_columns,
    piecewise_nodes,
    tensor_weights,
)
from bayesupdate.fe.reduced.shell_terms import (
    SparsePart,
    general_terms,
    pattern_parts,
    shell_parameters,
)

#: 1-D interpolation degrees tried in turn for each non-linear parameter
DEGREES = (4, 6, 8, 12, 16, 24, 32)
#: seed of the test points between the interpolation nodes (fixed: the build is deterministic)
TEST_SEED = 7
N_TEST = 12


@dataclass(frozen=True)
class InterpolatedGroup:
    """Beams with the same bound parameters.  ``nonaffine``: parameter indices interpolated in
    log(value) (breakpoints ``pieces`` in log, one ``degrees`` entry each); ``k_scale`` /
    ``m_scale``: parameter index whose value multiplies K / M (or -1)."""

    elements: np.ndarray
    nonaffine: tuple[int, ...]
    pieces: tuple[np.ndarray, ...]
    degrees: tuple[int, ...]
    k_scale: int
    m_scale: int

    @property
    def n_nodes(self) -> int:
        """Interpolation nodes (tensor grid size; 1 without non-linear parameters)."""
        sizes = [(p.size - 1) * (d + 1) for p, d in zip(self.pieces, self.degrees, strict=True)]
        return int(np.prod(sizes))


@dataclass(frozen=True, eq=False)
class AffineDecomposition:
    """theta -> K(theta), M(theta) as sums coefficient(theta) x fixed element-matrix stacks.

    ``k_stacks`` / ``m_stacks``: per term, the parts (dofs (n_e, d), mats (n_e, d, d)) or
    ``SparsePart`` summed into it; ``coefficients(theta)`` -> (B, n_terms) with the term order of
    the stacks.  Term 0 is the constant part (coefficient 1).  A term's coefficient is
    F[:, a] * F[:, b] * c over the features F = [1, theta, theta^2, theta^3, interpolation
    weights of every group], (a, b, c) = ``k_gather`` / ``m_gather``; ``one_d`` batches the
    groups interpolated in one parameter by (degree, piece count): (group indices, parameter
    indices, stacked log breakpoints (G, P + 1), degree).
    """

    names: tuple[str, ...]
    groups: tuple[InterpolatedGroup, ...]
    k_stacks: tuple
    m_stacks: tuple
    k_gather: tuple[np.ndarray, np.ndarray, np.ndarray]
    m_gather: tuple[np.ndarray, np.ndarray, np.ndarray]
    one_d: tuple

    @property
    def has_terms(self) -> bool:
        """False for a coefficient map read from the cache (``coefficient_map``): no stacks."""
        return bool(self.k_stacks)

    def coefficients(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(B, n_k_terms), (B, n_m_terms) coefficients at theta (B, n_params) (all names, SI)."""
        weights: list = [None] * len(self.groups)
        for groups, params, pieces, degree in self.one_d:
            w = barycentric_weights_columns(np.log(theta[:, params]), pieces, degree)
            for c, g in enumerate(groups):
                weights[g] = w[:, c]
        for g, group in enumerate(self.groups):
            if weights[g] is None:
                cols = theta[:, list(group.nonaffine)]
                weights[g] = tensor_weights(cols, group.pieces, group.degrees)
        F = np.concatenate(
            [np.ones((theta.shape[0], 1)), theta, theta**2, theta**3, *weights], axis=1
        )
        return tuple(F[:, a] * F[:, b] * c for a, b, c in (self.k_gather, self.m_gather))

    @staticmethod
    def project(V: np.ndarray, stacks) -> np.ndarray:
        """(n_terms, r, r) projections V^T X_term V of the term stacks, V (n_dof, r)."""
        r = V.shape[1]
        out = np.zeros((len(stacks), r, r))
        for t, parts in enumerate(stacks):
            for part in parts:
                if isinstance(part, SparsePart):
                    out[t] += part.project(V)
                    continue
                dofs, mats = part
                if mats.shape[0]:
                    Vd = V[dofs]
                    out[t] += np.einsum("eir,eij,ejs->rs", Vd, mats, Vd, optimize=True)
        return 0.5 * (out + out.transpose(0, 2, 1))


def decompose(
    fe: FEModel, bounds: Mapping[str, tuple[float, float]], interp_tol: float
) -> AffineDecomposition:
    """The decomposition of ``fe`` (beams, point masses, springs, shells, general beams, rods) over
    the box ``bounds`` (name -> (low, high), SI).  Raises ``BayesUpdateError`` when two
    parameters set the same property of an element or an interpolation does not reach
    ``interp_tol``."""
    names = fe.parameter_names
    low = np.array([bounds[n][0] for n in names])
    high = np.array([bounds[n][1] for n in names])
    terms = fe.affine_terms()
    keys = _beam_keys(terms, len(fe.structure.beam_part))
    k_stacks, m_stacks, k_entries, m_entries = _fixed_terms(fe, terms, keys)
    # shell terms are stored at their size at the box centre (coefficient 1 there): the term
    # compression (``basis.compress_terms``) cuts relative to the largest term
    centre = 0.5 * (low + high)
    f_ref = np.concatenate([[1.0], centre, centre**2, centre**3])
    for stacks, entries, parts in zip(
        (k_stacks, m_stacks), (k_entries, m_entries), general_terms(fe, terms, f_ref), strict=True
    ):
        for (a, b), part in parts.items():
            if (a, b) == (0, 0):
                stacks[0].append(part)
            else:
                stacks.append([part])
                entries.append((a, b, 1.0 / (f_ref[a] * f_ref[b])))
    groups = []
    # features before the first group's weights: [1, theta, theta^2, theta^3]
    offset = 1 + 3 * len(names)
    for key in sorted({k for k in keys if k}):
        elements = np.array([i for i, k in enumerate(keys) if k == key], dtype=int)
        group, Kn, Mn = _interpolated_group(fe, terms, elements, key, (low, high), interp_tol)
        dofs = fe.beam_assembler.parametric["beam"].dofs()[elements]
        k_col = 1 + group.k_scale if group.k_scale >= 0 else 0
        m_col = 1 + group.m_scale if group.m_scale >= 0 else 0
        for n in range(Kn.shape[0]):
            k_stacks.append([(dofs, Kn[n])])
            k_entries.append((offset + n, k_col, 1.0))
            m_stacks.append([(dofs, Mn[n])])
            m_entries.append((offset + n, m_col, 1.0))
        groups.append(group)
        offset += group.n_nodes
    for group, k_parts, m_parts in _line_groups(fe, bounds, interp_tol):
        for n, (k_part, m_part) in enumerate(zip(k_parts, m_parts, strict=True)):
            k_stacks.append([k_part])
            k_entries.append((offset + n, 0, 1.0))
            m_stacks.append([m_part])
            m_entries.append((offset + n, 0, 1.0))
        groups.append(group)
        offset += group.n_nodes
    return AffineDecomposition(
        names,
        tuple(groups),
        tuple(k_stacks),
        tuple(m_stacks),
        _gather(k_entries),
        _gather(m_entries),
        _one_d_batches(groups),
    )


def check_separable(fe: FEModel, terms: AffineTerms) -> None:
    """Raise the ``BayesUpdateError`` of ``decompose`` when two parameters set the same property
    of one element (beam, shell) or scale the same point mass or spring: the checks that need no
    element matrix (the cache key of a basis is computed without decomposing)."""
    _beam_keys(terms, len(fe.structure.beam_part))
    if fe.structure.shells is not None:
        shell_parameters(terms, fe.structure.shells.n_elements)


def _line_groups(fe: FEModel, bounds, interp_tol: float) -> list:
    """[(``InterpolatedGroup``, K parts, M parts)] of a deck's line-element fields that do not
    enter K and M linearly (``NastranModel.line_groups``): their change from the deck's values
    interpolated in log(theta) on Chebyshev tensor nodes, one ``SparsePart`` per node."""
    out = []
    for line in getattr(fe, "line_groups", lambda *_: ())(bounds, interp_tol):
        params = tuple(fe.parameter_names.index(n) for n in line.names)
        group = InterpolatedGroup(np.zeros(0, int), params, line.log_pieces, line.degrees, -1, -1)
        k_parts = pattern_parts(fe.general, line.dK)
        m_parts = pattern_parts(fe.general, line.dM)
        out.append((group, k_parts, m_parts))
    return out


def _beam_keys(terms: AffineTerms, n_beams: int) -> list[tuple[int, ...]]:
    """Per beam, the indices of the parameters acting on it (ascending); raises when two of them
    set the same property, or two scale the same point mass or spring."""
    keys: list[list[int]] = [[] for _ in range(n_beams)]
    for j, term in enumerate(terms.parameters):
        if term.family == "beam":
            for e in term.elements:
                keys[e].append(j)
    for key in keys:
        fields = [terms.parameters[j].field for j in key]
        if len(set(fields)) != len(fields):
            raise BayesUpdateError(
                "reduced model: two parameters set the same property of one beam; "
                "use the full model (--full)"
            )
    for family in (c for c in PARAMETRIC.values() if c.linear):
        for kind in family.linear:
            idx = np.concatenate(
                [t.elements for t in terms.parameters
                 if t.family == family.family and t.enters == kind] + [np.zeros(0, int)]
            )  # fmt: skip
            if np.unique(idx).size != idx.size:
                raise BayesUpdateError(
                    f"reduced model: two parameters scale the same {family.family}'s {kind}; "
                    "use the full model (--full)"
                )
    return [tuple(k) for k in keys]


def _fixed_terms(fe: FEModel, terms: AffineTerms, keys):
    """The constant term and one linear term per parameter of a linear parametric family
    (``ParametricFamily.linear``: point masses, springs): (k_stacks, m_stacks, k_entries,
    m_entries), entries (feature a, feature b, factor c) as in ``AffineDecomposition``.  The
    constant term holds the tube beams without parameters at the defaults, the elements of the
    linear families that no parameter scales, and every other registered family (no parameter
    acts on them, ``fe.elements.base``)."""
    a = fe.beam_assembler
    free_beams = np.array([i for i, k in enumerate(keys) if not k], dtype=int)
    beams = a.parametric["beam"]
    K0, M0 = (
        a.matrices("beam", terms.defaults, free_beams)
        if free_beams.size
        else (np.zeros((0, 12, 12)),) * 2
    )
    dofs = beams.dofs()[free_beams]
    k_stacks, m_stacks = [[(dofs, K0)]], [[(dofs, M0)]]
    k_entries, m_entries = [(0, 0, 1.0)], [(0, 0, 1.0)]
    for family in a.parametric.values():
        for kind in family.linear:
            stacks, entries = (k_stacks, k_entries) if kind == "K" else (m_stacks, m_entries)
            _linear_family(a, family, kind, (terms, fe.parameter_names), stacks, entries)
    for f in a.families:
        k_stacks[0].append((f.dofs, f.K))
        m_stacks[0].append((f.dofs, f.M))
    return k_stacks, m_stacks, k_entries, m_entries


def _linear_family(a, family, kind: str, described, stacks: list, entries: list) -> None:
    """Append the ``kind`` ("K" or "M") matrices of the linear ``family``'s elements that no
    parameter scales in that matrix (at the defaults) to the constant term of ``stacks``, and
    one term (its elements at factor 1, coefficient theta_j x scale) per parameter j entering
    that matrix on it, in place; ``described`` = (``AffineTerms``, the parameter names: a
    term's j is its name's place, a further family's term following the parameters).  A
    family linear in both (solids: E in K, rho in M) is called once per matrix."""
    terms, names = described
    bound = [(names.index(t.name), t) for t in terms.parameters
             if t.family == family.family and t.enters == kind]  # fmt: skip
    taken = np.concatenate([t.elements for _, t in bound] + [np.zeros(0, int)])
    free = np.setdiff1d(np.arange(family.n_elements), taken)
    which = 0 if kind == "K" else 1
    X0 = a.matrices(family.family, terms.defaults)[which]
    X_unit = a.matrices(family.family, terms.unit)[which]
    dofs = family.dofs()
    stacks[0].append((dofs[free], X0[free]))
    for j, t in bound:
        stacks.append([(dofs[t.elements], X_unit[t.elements])])
        entries.append((1 + j, 0, t.scale))


def _gather(entries) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    a, b, c = zip(*entries, strict=True)
    return np.array(a), np.array(b), np.array(c)


def _one_d_batches(groups) -> tuple:
    """Groups interpolated in one parameter, batched by (degree, piece count) (see
    ``AffineDecomposition``)."""
    batches: dict[tuple[int, int], list[int]] = {}
    for g, group in enumerate(groups):
        if len(group.nonaffine) == 1:
            batches.setdefault((group.degrees[0], group.pieces[0].size), []).append(g)
    return tuple(
        (
            gs,
            [groups[g].nonaffine[0] for g in gs],
            np.array([groups[g].pieces[0] for g in gs]),
            degree,
        )
        for (degree, _), gs in batches.items()
    )


# -- interpolated beam groups ---------------------------------------------------------------------
def b31_kinks(structure, elements: np.ndarray, low: float, high: float) -> list[float]:
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


@dataclass(frozen=True)
class _GroupMatrices:
    """Element matrices of one group's beams at values of its non-linear parameters: the
    ``AffineTerms.unit`` properties with each non-linear parameter's ``field`` set to its value
    on the group's beams."""

    fe: FEModel
    unit: ElementProperties
    elements: np.ndarray
    fields: tuple[str, ...]

    def __call__(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """points (n, len(fields)) -> K, M (n, n_e, 12, 12)."""
        Ks, Ms = [], []
        for row in points:
            K, M = self.fe.beam_assembler.matrices("beam", self._props(row), self.elements)
            Ks.append(K)
            Ms.append(M)
        return np.array(Ks), np.array(Ms)

    def _props(self, row) -> ElementProperties:
        u = self.unit
        arrays = {
            "beam_thickness": u.beam_thickness.copy(),
            "beam_rho": u.beam_rho.copy(),
            "beam_E": u.beam_E.copy(),
            "beam_bend_factor": u.beam_bend_factor.copy(),
        }
        for field, value in zip(self.fields, row, strict=True):
            arrays[field][self.elements] = value
        return ElementProperties(**arrays, mass_scale=u.mass_scale, spring_scale=u.spring_scale)

    def interp_error(
        self, log_pieces, degrees, nodes, test, test_cols
    ) -> tuple[float, np.ndarray, np.ndarray]:
        """Largest relative entry error of the interpolant on ``nodes`` (n, len(fields)) at
        ``test`` (k, len(fields)); the weights are taken at ``test_cols`` (k, len(degrees)), the
        interpolated columns of ``test``.  Returns (error, node K, node M)."""
        Kn, Mn = self(nodes)
        Kt, Mt = self(test)
        w = tensor_weights(test_cols, log_pieces, degrees)
        err = max(
            _rel_err(np.einsum("bn,neij->beij", w, Kn), Kt),
            _rel_err(np.einsum("bn,neij->beij", w, Mn), Mt),
        )
        return err, Kn, Mn


def _interpolated_group(fe, terms: AffineTerms, elements, key, box, interp_tol: float):
    """The group of ``elements`` (beams acting with the parameters ``key``) and its node matrices
    K, M (n_nodes, n_e, 12, 12).  ``box``: (low, high) of all parameters."""
    params = terms.parameters
    nonaffine = tuple(j for j in key if params[j].enters == "nonlinear")
    k_scale = next((j for j in key if params[j].enters == "K"), -1)
    m_scale = next((j for j in key if params[j].enters == "M"), -1)
    fields = tuple(params[j].field for j in nonaffine)
    matrices = _GroupMatrices(fe, terms.unit, elements, fields)
    if not nonaffine:
        Kn, Mn = matrices(np.zeros((1, 0)))
        return InterpolatedGroup(elements, (), (), (), k_scale, m_scale), Kn, Mn
    low, high = box
    pieces = []
    for j in nonaffine:
        if low[j] <= 0:
            raise BayesUpdateError(
                f"reduced model: the lower bound of {params[j].name} must be > 0, got {low[j]}"
            )
        thickness = params[j].property == "thickness"
        kinks = b31_kinks(fe.structure, elements, low[j], high[j]) if thickness else []
        pieces.append(np.array([low[j], *kinks, high[j]]))
    # interpolate in log(parameter): thickness enters through rational functions with poles at
    # t = 0 (B31.3 factor ~ 1/t), which map to -infinity in log t, so the degree stays low
    log_pieces = tuple(np.log(p) for p in pieces)
    rng = np.random.default_rng(TEST_SEED)
    search = _DegreeSearch(matrices, nonaffine, log_pieces, low, high, interp_tol, params)
    degrees = [search.axis_degree(i, rng) for i in range(len(nonaffine))]
    degrees, Kn, Mn = search.tensor(degrees, rng)
    group = InterpolatedGroup(elements, nonaffine, log_pieces, degrees, k_scale, m_scale)
    return group, Kn, Mn


@dataclass(frozen=True)
class _DegreeSearch:
    """The interpolation degrees of one group: each parameter alone (the others mid-range), then
    the tensor product, raised until the element matrices are reproduced to ``tol``."""

    matrices: _GroupMatrices
    nonaffine: tuple[int, ...]
    log_pieces: tuple[np.ndarray, ...]
    low: np.ndarray
    high: np.ndarray
    tol: float
    params: tuple

    def _test_values(self, j: int, rng) -> np.ndarray:
        return np.exp(rng.uniform(np.log(self.low[j]), np.log(self.high[j]), N_TEST))

    def axis_degree(self, i: int, rng) -> int:
        """Smallest of ``DEGREES`` reaching the tolerance in parameter ``nonaffine[i]``."""
        j = self.nonaffine[i]
        others = [float(np.sqrt(self.low[q] * self.high[q])) for q in self.nonaffine]
        test = np.tile(others, (N_TEST, 1))
        test[:, i] = self._test_values(j, rng)
        for degree in DEGREES:
            n_nodes = (len(self.log_pieces[i]) - 1) * (degree + 1)
            nodes = np.tile(others, n_nodes).reshape(-1, len(others))
            nodes[:, i] = np.exp(piecewise_nodes(self.log_pieces[i], degree))
            pieces = (self.log_pieces[i],)
            err = self.matrices.interp_error(pieces, (degree,), nodes, test, test[:, i : i + 1])
            err = err[0]
            if err < self.tol:
                return degree
        raise BayesUpdateError(
            f"reduced model: interpolation in {self.params[j].name} does not reach "
            f"{self.tol:g} at degree {DEGREES[-1]}; use the full model (--full)"
        )

    def tensor(self, degrees: list[int], rng) -> tuple[tuple[int, ...], np.ndarray, np.ndarray]:
        """Tensor-product degrees from the 1-D ones (raised by 4 up to 3 times): (degrees,
        node K, node M)."""
        test = np.column_stack([self._test_values(j, rng) for j in self.nonaffine])
        for _ in range(4):  # the tensor product may need a little more than each 1-D degree
            axes = [
                np.exp(piecewise_nodes(p, d)) for p, d in zip(self.log_pieces, degrees, strict=True)
            ]
            grid = np.stack([m.ravel() for m in np.meshgrid(*axes, indexing="ij")], axis=1)
            err, Kn, Mn = self.matrices.interp_error(
                self.log_pieces, tuple(degrees), grid, test, test
            )
            if err < self.tol:
                return tuple(degrees), Kn, Mn
            degrees = [d + 4 for d in degrees]
        names = [self.params[j].name for j in self.nonaffine]
        raise BayesUpdateError(
            f"reduced model: tensor interpolation in {names} has error {err:.1e} > "
            f"{self.tol:g}; use the full model (--full)"
        )


def _rel_err(approx: np.ndarray, exact: np.ndarray) -> float:
    """Largest entry error of each element matrix relative to its largest entry."""
    scale = np.abs(exact).max(axis=(-2, -1))
    return float(np.max(np.abs(approx - exact).max(axis=(-2, -1)) / np.maximum(scale, 1e-300)))


# -- the coefficient map alone (a cached basis) ---------------------------------------------------
def coefficient_arrays(d: AffineDecomposition) -> dict[str, np.ndarray]:
    """The arrays ``coefficients`` needs (groups, gathers), for storage (``coefficient_map``
    reads them back); the term stacks are left out."""
    out = {"names": np.array(d.names, dtype=str), "n_groups": np.array(len(d.groups))}
    for which, (a, b, c) in (("k", d.k_gather), ("m", d.m_gather)):
        out[f"{which}_gather_ab"] = np.array([a, b], dtype=np.int64).reshape(2, -1)
        out[f"{which}_gather_c"] = np.asarray(c, float)
    for g, group in enumerate(d.groups):
        out[f"group_{g}_elements"] = np.asarray(group.elements, np.int64)
        out[f"group_{g}_ints"] = np.array(
            [group.k_scale, group.m_scale, len(group.nonaffine), *group.nonaffine, *group.degrees],
            dtype=np.int64,
        )
        for i, piece in enumerate(group.pieces):
            out[f"group_{g}_piece_{i}"] = np.asarray(piece, float)
    return out


def coefficient_map(arrays) -> AffineDecomposition:
    """The ``AffineDecomposition`` stored by ``coefficient_arrays``: its ``coefficients`` are the
    stored decomposition's, its ``k_stacks`` / ``m_stacks`` empty (``has_terms`` False: whoever
    needs the terms decomposes again).  Raises KeyError / ValueError on a malformed entry."""
    groups = []
    for g in range(int(arrays["n_groups"])):
        ints = [int(v) for v in arrays[f"group_{g}_ints"]]
        k_scale, m_scale, n = ints[:3]
        nonaffine, degrees = tuple(ints[3 : 3 + n]), tuple(ints[3 + n : 3 + 2 * n])
        if len(degrees) != n:
            raise ValueError(f"group {g}: {n} parameters, {len(degrees)} degrees")
        pieces = tuple(np.asarray(arrays[f"group_{g}_piece_{i}"], float) for i in range(n))
        elements = np.asarray(arrays[f"group_{g}_elements"], int)
        groups.append(InterpolatedGroup(elements, nonaffine, pieces, degrees, k_scale, m_scale))
    gathers = []
    for which in ("k", "m"):
        ab, c = arrays[f"{which}_gather_ab"], np.asarray(arrays[f"{which}_gather_c"], float)
        if ab.shape != (2, c.size):
            raise ValueError(f"{which} gather of shape {ab.shape} for {c.size} terms")
        gathers.append((ab[0].astype(int), ab[1].astype(int), c))
    names = tuple(str(n) for n in arrays["names"])
    return AffineDecomposition(names, tuple(groups), (), (), *gathers, _one_d_batches(groups))
