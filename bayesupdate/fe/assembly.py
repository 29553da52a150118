"""Assembly of the global stiffness K and mass M of a structure, looping over the element
families (``fe.elements``), and the solution of its constrained modes.

``Assembler`` precomputes everything that depends on geometry and connectivity only (the families'
element arrays and DOF maps, the shells' parameter groups, one sparse pattern for all of them,
the supports' and rigid elements' transformation).  ``assemble(props, shell_props)`` then builds K
and M for any element property values in one pass with no per-element Python loop: each family's
element matrices are (n_e, d, d) stacks scattered into the fixed CSR pattern by ``np.bincount``.

* The parametric families (``elements.base.ParametricFamily``: tube beams, point masses,
  springs, any registered one) are computed at the property record ``ElementProperties``, whose
  fields the families declare; between two assemblies only the elements whose fields changed
  are recomputed (a calibration changes a few parts at a time), and a family none of whose
  elements changed is not scattered again.
* The other registered families (``elements.base.ElementFamily``: general beams, rods, scalar
  masses, ...) carry no parameter: they are computed and scattered once.
* Shells are grouped by their parameters; each group's K and M are exact sums of powers of the
  thickness (``fe.shell_model``), so a thickness, modulus or density is a sum of stored terms.

Density, Young's modulus, point masses and spring stiffnesses enter K and M linearly
(``fe.model.AffineTerms`` gives the exact affine terms); wall thickness does not (area and second
moments are polynomials in t and the Timoshenko shear parameter is rational in them), so those
elements are recomputed.  The assembler names no family: what a family binds, its nominal values
and its limits are its own declarations (``elements.base``).
"""

from dataclasses import dataclass, replace
from functools import cached_property
from types import MappingProxyType

import numpy as np
import scipy.sparse as sp

from bayesupdate.fe.constraints import Constraints, constraint_transform
from bayesupdate.fe.eigensolve import ModalSolution
from bayesupdate.fe.elements import ElementSettings, families_of, parametric_of, shell
from bayesupdate.fe.elements.base import FamilyMatrices, rigid_mass
from bayesupdate.fe.rotations import rigid_body_basis
from bayesupdate.fe.shell_model import ShellAssembly
from bayesupdate.fe.sparse_modal import (
    ModalSettings,
    _allowed_rigid,
    constrained_modes,
    rigid_motions,
    sorted_unique,
)
from bayesupdate.fe.structure import Structure


@dataclass(frozen=True, eq=False, init=False)
class ElementProperties:
    """Per-element property values of one assembly (all SI): one (n,) array per field that a
    parametric family reads (``ParametricFamily.fields``), read as attributes.  The built-in
    families' fields: beam_thickness, beam_rho, beam_E, beam_bend_factor (E,) (the last
    multiplies the B31.3 factor, 1 = none); mass_scale (P,) factors on point masses;
    spring_scale (S,) factors on springs.

    ``ElementProperties(beam_rho=..., ...)`` or ``ElementProperties({field: array})``;
    ``dataclasses.replace(props, beam_rho=...)`` gives a copy with fields changed.
    """

    values: MappingProxyType

    def __init__(self, values=None, **fields):
        merged = {**(values or {}), **fields}
        object.__setattr__(self, "values", MappingProxyType(merged))

    def __getattr__(self, name: str) -> np.ndarray:
        if name.startswith("_"):  # copy and pickle probe for hooks before ``values`` is set
            raise AttributeError(name)
        try:
            return self.values[name]
        except KeyError:
            raise AttributeError(f"ElementProperties has no field {name!r}") from None

    def __reduce__(self):
        return ElementProperties, (dict(self.values),)


@dataclass(frozen=True)
class _Memo:
    """A parametric family's last assembly: its fields (k, n), matrices and their data at the
    CSR positions the family touches (``Assembler._touched``)."""

    key: np.ndarray
    matrices: FamilyMatrices
    K: np.ndarray | None
    M: np.ndarray | None


class Assembler:
    """Precomputation for repeated K(theta), M(theta) of one ``Structure``, and its modes.

    shell_keys : (n_shell, k) numbers that must be equal for shells to share a parameter group
    (the FE model passes the indices of the parameters bound to each shell); None = one group
    per distinct nominal (part, t, E, rho).

    parametric : {family name: ``ParametricFamily``} (in the order of assembly); families : the
    other registered families' ``FamilyMatrices``, computed once; shells : the shells'
    ``ShellAssembly`` (None: none); rows, cols, indptr : the CSR pattern (nnz entries, every
    diagonal included) of all of them; transform : the supports' and rigid elements'
    ``constraints.constraint_transform``; rigid : the rigid motions they allow.
    """

    def __init__(self, structure: Structure, shell_keys=None):
        self.structure = s = structure
        self.n_dof = s.n_dof
        self._settings = settings = ElementSettings(s.shear, s.rotary_inertia)
        self.parametric = {f.family: f for f in parametric_of(s)}
        # no parameter acts on the other families: their matrices are computed once
        self.families = tuple(FamilyMatrices.of(f, s.nodes, settings) for f in families_of(s))
        self._memos: dict[str, _Memo] = {}
        self._dofs = {name: f.dofs() for name, f in self.parametric.items()}
        self.shells = None
        if s.shells is not None:
            unit = s.shells.mesh(s.nodes, rho=np.ones(s.shells.n_elements))  # per unit density
            lumped = s.shells.lumped  # Nastran's lumped mass carries no rotary inertia
            self.shells = ShellAssembly(unit, lumped, s.rotary_inertia and not lumped)
        positions = self._build_pattern([*self._dofs.values(), *(f.dofs for f in self.families)])
        # each parametric family's data is kept at the positions it touches only: a family of a
        # few beams or masses on a shell mesh would otherwise add a whole (nnz,) array per
        # assembly (the same sums in the same order: the same bits)
        local = [_compacted(pos, self.nnz) for pos in positions[: len(self.parametric)]]
        self._touched = {name: t for name, (t, _) in zip(self.parametric, local, strict=True)}
        self._positions = {name: at for name, (_, at) in zip(self.parametric, local, strict=True)}
        self._family_K = self._scatter_families("K", positions[len(self.parametric) :])
        self._family_M = self._scatter_families("M", positions[len(self.parametric) :])
        if self.shells is not None:
            n_el = s.shells.n_elements
            self._groups(np.zeros((n_el, 0)) if shell_keys is None else shell_keys)
        if s.is_general:  # a bad support or rigid element is named when the model is built
            _ = self.transform

    @property
    def beams(self) -> "Assembler":
        """The assembler itself: the name under which the families' assembly was reached when
        it was a class of its own (deprecated; use the assembler)."""
        return self

    # -- sparse pattern ------------------------------------------------------------------------
    def _build_pattern(self, blocks) -> list[np.ndarray]:
        """Set the CSR pattern of the element blocks (DOF maps (n_e, d)), every diagonal and the
        shells' pattern; returns each block's positions in the CSR data (row-major entries)."""
        n = self.n_dof
        rows = np.concatenate([np.repeat(d, d.shape[1], axis=1).ravel() for d in blocks])
        cols = np.concatenate([np.tile(d, (1, d.shape[1])).ravel() for d in blocks])
        # every node gets its diagonal so the pattern is never structurally singular
        rows = np.concatenate([rows, np.arange(n)])
        cols = np.concatenate([cols, np.arange(n)])
        key = rows.astype(np.int64) * n + cols
        uniq, inverse = np.unique(key, return_inverse=True)
        if self.shells is not None:
            pat = self.shells.pattern
            shell_keys = pat.rows.astype(np.int64) * n + pat.cols
            union = sorted_unique(np.concatenate([uniq, shell_keys]))
            self._pos_shell = np.searchsorted(union, shell_keys)
            inverse = np.searchsorted(union, uniq)[inverse]
            uniq = union
        self.nnz = uniq.size
        self.rows = (uniq // n).astype(np.int32)
        self.cols = (uniq % n).astype(np.int32)
        self.indptr = np.searchsorted(self.rows, np.arange(n + 1)).astype(np.int32)
        splits = np.cumsum([0] + [d.shape[0] * d.shape[1] ** 2 for d in blocks])
        return [inverse[a:b] for a, b in zip(splits[:-1], splits[1:], strict=True)]

    def csr(self, data: np.ndarray) -> sp.csr_matrix:
        """CSR matrix on the fixed pattern from its (nnz,) data."""
        return sp.csr_matrix((data, self.cols, self.indptr), shape=(self.n_dof,) * 2)

    # -- element matrices ----------------------------------------------------------------------
    def default_properties(self) -> ElementProperties:
        """Every parametric family's fields at their nominal values (``nominal``)."""
        return ElementProperties(
            {k: v for f in self.parametric.values() for k, v in f.nominal().items()}
        )

    def check(self, props: ElementProperties) -> None:
        """Raise BayesUpdateError naming the part if a field of ``props`` is non-physical."""
        for family in self.parametric.values():
            family.check(props, self.structure.parts)

    def matrices(self, family: str, props: ElementProperties, elements=None):
        """Global-axis (K, M) (n_e, d, d) (None: none) of the parametric ``family``'s
        ``elements`` (index array, default all) at ``props``."""
        return self.parametric[family].matrices(props, self._settings, elements)

    def _scatter_families(self, which: str, positions) -> np.ndarray | None:
        """(nnz,) sum of the registered families' K or M (None: no family has any)."""
        data = None
        for f, pos in zip(self.families, positions, strict=True):
            mats = getattr(f, which)
            if np.any(mats):
                part = self._scatter(pos, mats)
                data = part if data is None else data + part
        if data is not None:
            data.flags.writeable = False  # added to every assembly, never changed
        return data

    def assemble(self, props: ElementProperties | None = None, shell_props=None):
        """Global K and M as CSR matrices, plus every family's element matrices (for energies).

        props : the families' fields (None: nominal); shell_props : the shells' (t [m], E [Pa],
        rho [kg/m^3]) arrays (n_shell,) (None: nominal).  Returns (K, M, elements): elements a
        tuple of ``FamilyMatrices``, the parametric families' at ``props`` (read-only) then the
        other registered families'.
        """
        props = self.default_properties() if props is None else props
        self.check(props)
        K, M = np.zeros(self.nnz), np.zeros(self.nnz)
        used = []
        for name, family in self.parametric.items():
            memo = self._reusing(family, props)
            used.append(memo.matrices)
            at = self._touched[name]
            for total, data in ((K, memo.K), (M, memo.M)):
                if data is not None:
                    total[at] += data
        for total, data in ((K, self._family_K), (M, self._family_M)):
            if data is not None:
                total += data
        if self.shells is not None:
            sh = self.structure.shells
            Ks, Ms = self.shell_data(*((sh.thickness, sh.E, sh.rho) if shell_props is None
                                       else shell_props))  # fmt: skip
            K += Ks
            M += Ms
        return self.csr(K), self.csr(M), (*used, *self.families)

    def _reusing(self, family, props: ElementProperties) -> _Memo:
        """The parametric ``family``'s matrices and scattered data at ``props``, recomputing only
        the elements whose fields differ from the previous call (none: the previous data)."""
        key = np.stack([getattr(props, name) for name in family.fields])
        memo = self._memos.get(family.family)
        if memo is not None and memo.key.shape == key.shape:
            changed = np.flatnonzero(np.any(memo.key != key, axis=0))
            if not changed.size:
                return memo
            old = memo.matrices
            K = None if old.K is None else old.K.copy()
            M = None if old.M is None else old.M.copy()
            Kc, Mc = family.matrices(props, self._settings, changed)
            if K is not None:
                K[changed] = Kc
            if M is not None:
                M[changed] = Mc
        else:
            K, M = family.matrices(props, self._settings)
        pos, n = self._positions[family.family], self._touched[family.family].size
        data = [None if X is None else self._scatter(pos, X, n) for X in (K, M)]
        for X in (K, M, *data):
            if X is not None:
                X.flags.writeable = False
        mats = FamilyMatrices(family.family, self._dofs[family.family], K, M, family.part)
        memo = self._memos[family.family] = _Memo(key.copy(), mats, *data)
        return memo

    def _scatter(self, positions, element_matrices, size: int | None = None):
        """Sum element entries into the (size,) data at ``positions`` (default: the (nnz,) CSR
        data; float even for no elements)."""
        size = self.nnz if size is None else size
        return np.bincount(positions, element_matrices.ravel(), size).astype(float, copy=False)

    def total_mass(self, props: ElementProperties | None = None):
        """Total mass [kg] and centre of gravity (3,) [m] of the element families at ``props``
        (None: nominal; shells apart: ``matrix_mass`` counts them), as ``element_mass``."""
        props = self.default_properties() if props is None else props
        return _families_mass(self.parametric.values(), self.families, self.structure.nodes, props)

    # -- shells --------------------------------------------------------------------------------
    def _groups(self, shell_keys):
        """Group the shells by ``shell_keys`` and their nominal part, E, rho and (unbound)
        thickness; keep each group's K and M power terms on the pattern (``terms``)."""
        sh = self.structure.shells
        shell_keys = np.asarray(shell_keys, dtype=float).reshape(sh.n_elements, -1)
        # the first key column is the thickness parameter (-1: none): only then does the nominal
        # thickness matter
        t_bound = shell_keys[:, 0] >= 0 if shell_keys.shape[1] else np.zeros(sh.n_elements, bool)
        t0 = np.where(t_bound, 0.0, sh.thickness)
        # a bound element's thickness is factor x the parameter: factor^p goes into its terms
        scale = np.where(t_bound, sh.factor(), 1.0)
        key = np.column_stack([shell_keys, sh.part, sh.E, sh.rho, t0])
        _, first, group = np.unique(key, axis=0, return_index=True, return_inverse=True)
        self.group_rep = first
        self.group_scale = scale[first]
        self.terms = []  # (union positions, K {p: values}, M_nsm values, M {p: values}) per group
        for g in range(first.size):
            Kp, Mp = self.shells.power_data(group.ravel() == g, scale)
            take = _nonzero_take(self.shells.pattern.nnz, (*Kp.values(), *Mp.values()))
            m0 = take(Mp.pop(0)) if 0 in Mp else np.zeros(take(self._pos_shell).size)
            self.terms.append(
                (
                    take(self._pos_shell),
                    {p: take(v) for p, v in Kp.items()},
                    m0,
                    {p: take(v) for p, v in Mp.items()},
                )
            )

    def shell_data(self, t, E, rho):
        """(K data, M data) (nnz,) of the shells with per-element thickness t [m], E [Pa], rho
        [kg/m^3] (n_shell,), uniform within each group (as the FE model's bindings make them;
        where a parameter binds the thickness, t / thickness_factor is uniform)."""
        K, M = np.zeros(self.nnz), np.zeros(self.nnz)
        rep = self.group_rep
        e_factor = E[rep] / self.structure.shells.E[rep]
        theta = t[rep] / self.group_scale
        for (pos, Kp, m0, Mp), tg, fe, rg in zip(
            self.terms, theta, e_factor, rho[rep], strict=True
        ):
            K[pos] += fe * sum(tg**p * v for p, v in Kp.items())
            M[pos] += m0 + rg * sum(tg**p * v for p, v in Mp.items())
        return K, M

    def shell_element_matrices(self, t, E, rho):
        """Direct global-axis shell element matrices [(dofs (n_e, d), K, M) per family]."""
        sh = self.structure.shells
        out = []
        for idx, dofs, f, p in self.shells.families:
            K, M = shell.direct_matrices(
                p, t[idx], rho[idx], sh.nsm[idx], sh.offset[idx], sh.offset_ratio[idx]
            )
            K = K * (E[idx] / sh.E[idx])[:, None, None]
            out.append((idx, dofs, shell.to_global(K, f.R), shell.to_global(M, f.R)))
        return out

    # -- supports and rigid elements -----------------------------------------------------------
    @cached_property
    def transform(self):
        """The supports' and rigid elements' ``constraints.constraint_transform`` (built on
        first use: a free beam structure on the banded path never needs it)."""
        s = self.structure
        c = s.constraints if s.constraints is not None else Constraints()
        return constraint_transform(s.nodes, c)

    @cached_property
    def rigid(self) -> np.ndarray:
        """(n_ind, r) rigid motions the supports allow (``allowed_rigid``), the holds of
        ``idle_dofs`` exempt."""
        return allowed_rigid(self.structure.nodes, self.transform, self.idle_dofs())

    def idle_dofs(self) -> np.ndarray:
        """Held DOFs that no stiffness couples (a zero column of K at the default properties, in
        the DOF's own axes: K Lambda e_i = 0 with a node frame Lambda) and no rigid element or
        MPC names, e.g. the rotations of a GRID that only solids join, or a membrane's bending
        rotations, which Nastran's AUTOSPC or a GRID's PS field holds.  A rigid motion of the
        structure need not vanish there: its energy does not depend on them
        (``allowed_rigid``)."""
        s = self.structure
        fixed = self.transform.fixed
        c = s.constraints if s.constraints is not None else Constraints()
        named = np.zeros(s.n_nodes, bool)
        named[np.unique(c.edges())] = True
        candidates = fixed[~named[fixed // 6]]
        if not candidates.size:
            return candidates
        K = self.assemble(self.default_properties())[0]
        rotation = self.transform.rotation  # global = rotation @ the nodes' own axes
        column = abs(K if rotation is None else K @ rotation).max(axis=0)
        column = np.asarray(column.todense()).ravel()
        return candidates[column[candidates] == 0]

    @cached_property
    def _rigid_origin(self) -> np.ndarray:
        """(n_dof, 6) rigid-body motions about the origin (``matrix_mass``)."""
        return rigid_body_basis(self.structure.nodes, centre=np.zeros(3))

    def solve(self, K, M, n_modes: int, dense: bool = False, settings=None) -> ModalSolution:
        """First ``n_modes`` elastic modes of the constrained structure (full-DOF shapes).

        settings : ``ModalSettings`` (its n_modes is replaced by ``n_modes``; its rigid_set
        "rigid_motions" for a Nastran SUPORT)."""
        tr = self.transform
        settings = replace(settings or ModalSettings(), n_modes=n_modes)
        if dense:
            settings = replace(settings, dense_below=tr.independent.size + 1, small_method="dense")
        return constrained_modes(
            tr.reduce(K), tr.reduce(M), self.rigid, settings, tr.independent, tr.T
        )

    def matrix_mass(self, M) -> tuple[float, np.ndarray]:
        """Total mass [kg] and centre of gravity (3,) [m] from the full mass matrix M (shells
        included): the rigid translations give m I, the coupling with rotations about the
        origin m skew(c)."""
        R = self._rigid_origin
        Mr = R.T @ (M @ R)
        m = float(np.trace(Mr[:3, :3]) / 3.0)
        return m, np.array([Mr[1, 5], Mr[2, 3], Mr[0, 4]]) / m


#: the name of the one ``Assembler`` when shells, supports and rigid elements had a class of
#: their own (deprecated: use ``Assembler``)
GeneralAssembler = Assembler


def element_mass(structure: Structure, props: ElementProperties | None = None):
    """Total mass [kg] and centre of gravity (3,) [m] of the structure's element families at
    ``props`` (None: nominal), shells apart, without building an ``Assembler`` (its sparse
    pattern and shell groups): the parametric families' element masses
    (``ParametricFamily.masses``) and the other families' rigid-body mass
    (``elements.base.rigid_mass`` of their M)."""
    parametric = parametric_of(structure)
    settings = ElementSettings(structure.shear, structure.rotary_inertia)
    families = [FamilyMatrices.of(f, structure.nodes, settings) for f in families_of(structure)]
    if props is None:
        props = ElementProperties({k: v for f in parametric for k, v in f.nominal().items()})
    return _families_mass(parametric, families, structure.nodes, props)


def _families_mass(parametric, families, xyz: np.ndarray, props) -> tuple[float, np.ndarray]:
    """(mass [kg], centre of gravity (3,) [m]) of parametric family instances at ``props`` and
    of ``FamilyMatrices`` on nodes xyz (N, 3) [m]."""
    total, moment = 0.0, np.zeros(3)
    for family in parametric:
        m, centre = family.masses(props, xyz)
        total = total + m.sum()
        moment = moment + m @ centre
    for f in families:
        # the rigid-body functional of ``Assembler.matrix_mass``: trace / 3 of the translational
        # block, the first moments from the translation-rotation coupling
        Mr = rigid_mass(f.M, f.dofs, xyz)
        total = total + np.trace(Mr[:3, :3]) / 3.0
        moment = moment + np.array([Mr[1, 5], Mr[2, 3], Mr[0, 4]])
    return float(total), moment / total


def check_properties(structure: Structure, props: ElementProperties) -> None:
    """Raise BayesUpdateError naming the part if a field of ``props`` is non-physical (each
    parametric family's ``check``)."""
    for family in parametric_of(structure):
        family.check(props, structure.parts)


def _nonzero_take(nnz: int, values):
    """The function v -> v[pos] for the positions pos where any of ``values`` (each (nnz,)) is
    non-zero; the identity (no copy) when that is every position (a group covering the mesh)."""
    nz = np.zeros(nnz, bool)
    for v in values:
        nz |= np.abs(v) > 0
    if nz.all():
        return lambda v: v
    pos = np.flatnonzero(nz)
    return lambda v: v[pos]


def _compacted(positions: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """(the sorted distinct ``positions`` (t,), each position's index in them): what
    ``np.unique`` and ``np.searchsorted`` give, by a mask of ``size`` and its running count in
    O(size + n) instead of a sort (a solid mesh's family touches millions of entries)."""
    mask = np.zeros(size, bool)
    mask[positions] = True
    return np.flatnonzero(mask), (np.cumsum(mask) - 1)[positions]


def _block_keys(dofs: np.ndarray, n: int) -> np.ndarray:
    """row * n + col of every entry of element matrices with DOF maps (n_e, d), row-major."""
    d = dofs.shape[1]
    rows = np.repeat(dofs, d, axis=1).ravel().astype(np.int64)
    return rows * n + np.tile(dofs, (1, d)).ravel()


def allowed_rigid(nodes: np.ndarray, tr, exempt=()) -> np.ndarray:
    """(n_ind, r) rigid motions that the supports allow, in the independent DOFs of ``tr``
    (with node frames the fixed DOFs are in the nodes' own axes: w = Lambda^T u); the held DOFs
    ``exempt`` (``Assembler.idle_dofs``) do not restrict them."""
    n = 6 * nodes.shape[0]
    fixed = np.setdiff1d(tr.fixed, np.asarray(exempt, dtype=np.int64))
    if tr.rotation is None:
        R = _allowed_rigid(nodes, n, fixed)
    else:
        R = tr.rotation.T @ rigid_motions(nodes)
        if fixed.size:
            s, v = np.linalg.svd(R[fixed], full_matrices=True)[1:]
            rank = int(np.sum(s > 1e-9 * max(1.0, np.abs(R).max())))
            R = R @ v[rank:].T
    R_ind = R[tr.independent]
    return R_ind if len(exempt) == 0 else _moving(R_ind)


def _moving(R: np.ndarray) -> np.ndarray:
    """A basis of the span of R's columns (n, r) without the combinations that vanish on all
    its rows (motions allowed only because they move exempt DOFs alone, e.g. the rotations of
    a scalar point about itself); R itself where no combination does."""
    if R.shape[1] == 0:
        return R
    s, v = np.linalg.svd(R, full_matrices=False)[1:]
    keep = s > 1e-9 * max(1.0, np.abs(R).max())
    return R if keep.sum() == R.shape[1] else R @ v[keep].T
