"""Assembly of the global stiffness K and mass M, vectorised over elements, looping over the
element families (``fe.elements``).

``Assembler`` precomputes everything that depends on geometry and connectivity only (the families'
element arrays and DOF maps, the sparse pattern).  ``assemble(props)`` then builds K and M for any
element property values in one pass with no per-element Python loop: each family's element
matrices are (n_e, d, d) stacks scattered into the fixed CSR pattern by ``np.bincount``.

* The parametric families (``elements.base.ParametricFamily``: tube beams, point masses,
  springs) are computed at the property record ``ElementProperties``; between two assemblies
  only the elements whose properties changed are recomputed (a calibration changes a few parts at
  a time), and a family none of whose elements changed is not scattered again.
* The other registered families (``elements.base.ElementFamily``: general beams, rods, scalar
  masses, ...) carry no parameter: they are computed and scattered once.

Density, Young's modulus, point masses and spring stiffnesses enter K and M linearly
(``fe.model.AffineTerms`` gives the exact affine terms); wall thickness does not (area and second
moments are polynomials in t and the Timoshenko shear parameter is rational in them), so those
elements are recomputed.

``GeneralAssembler`` adds the shells (grouped by their parameters, K and M exact sums of powers of
the thickness), supports and rigid elements of a general structure to the families' assembly, on
the union of both sparse patterns, and solves the constrained modes.
"""

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.constraints import Constraints, constraint_transform
from bayesupdate.fe.eigensolve import ModalSolution
from bayesupdate.fe.elements import ElementSettings, families_of, parametric_of, shell
from bayesupdate.fe.elements.base import FamilyMatrices, rigid_mass
from bayesupdate.fe.rotations import rigid_body_basis
from bayesupdate.fe.shell_model import ShellAssembly
from bayesupdate.fe.sparse_modal import (
    ModalSettings,
    _allowed_rigid,
    rigid_motions,
    solve_reduced_modes,
    sorted_unique,
)
from bayesupdate.fe.structure import Structure


@dataclass(frozen=True)
class ElementProperties:
    """Per-element property values used by one assembly (all SI): the fields the parametric
    families read (``ParametricFamily.fields``).

    beam_thickness, beam_rho, beam_E, beam_bend_factor : (E,) - the last multiplies the B31.3 factor
    (1 = none); mass_scale : (P,) factors on point masses; spring_scale : (S,) factors on springs.
    """

    beam_thickness: np.ndarray
    beam_rho: np.ndarray
    beam_E: np.ndarray
    beam_bend_factor: np.ndarray
    mass_scale: np.ndarray
    spring_scale: np.ndarray


@dataclass(frozen=True)
class _Memo:
    """A parametric family's last assembly: its fields (k, n), matrices and their (nnz,) data."""

    key: np.ndarray
    matrices: FamilyMatrices
    K: np.ndarray | None
    M: np.ndarray | None


class Assembler:
    """Geometry-dependent precomputation for fast repeated assembly of one ``Structure``.

    parametric : {family name: ``ParametricFamily``} (tube beams, point masses, springs, in the
    order of assembly); families : the other registered families' ``FamilyMatrices``, computed
    once.
    """

    def __init__(self, structure: Structure):
        self.structure = s = structure
        self.n_dof = s.n_dof
        self._settings = settings = ElementSettings(s.shear, s.rotary_inertia)
        self.parametric = {f.family: f for f in parametric_of(s)}
        # no parameter acts on the other families: their matrices are computed once
        self.families = tuple(FamilyMatrices.of(f, s.nodes, settings) for f in families_of(s))
        self._memos: dict[str, _Memo] = {}
        self._dofs = {name: f.dofs() for name, f in self.parametric.items()}
        positions = self._build_pattern([*self._dofs.values(), *(f.dofs for f in self.families)])
        self._positions = dict(zip(self.parametric, positions, strict=False))
        self._family_K = self._scatter_families("K", positions[len(self.parametric) :])
        self._family_M = self._scatter_families("M", positions[len(self.parametric) :])

    # -- sparse pattern ------------------------------------------------------------------------
    def _build_pattern(self, blocks) -> list[np.ndarray]:
        """Set the CSR pattern of the element blocks (DOF maps (n_e, d)) and every diagonal;
        returns each block's positions in the CSR data (row-major entries)."""
        n = self.n_dof
        rows = np.concatenate([np.repeat(d, d.shape[1], axis=1).ravel() for d in blocks])
        cols = np.concatenate([np.tile(d, (1, d.shape[1])).ravel() for d in blocks])
        # every node gets its diagonal so the pattern is never structurally singular
        rows = np.concatenate([rows, np.arange(n)])
        cols = np.concatenate([cols, np.arange(n)])
        key = rows.astype(np.int64) * n + cols
        uniq, inverse = np.unique(key, return_inverse=True)
        self.nnz = uniq.size
        self.pattern_rows = (uniq // n).astype(np.int32)
        self.pattern_cols = (uniq % n).astype(np.int32)
        splits = np.cumsum([0] + [d.shape[0] * d.shape[1] ** 2 for d in blocks])
        indptr = np.zeros(n + 1, dtype=np.int32)
        np.add.at(indptr, self.pattern_rows + 1, 1)
        self.indptr = np.cumsum(indptr).astype(np.int32)
        return [inverse[a:b] for a, b in zip(splits[:-1], splits[1:], strict=True)]

    def to_csr(self, data: np.ndarray) -> sp.csr_matrix:
        """CSR matrix on the fixed pattern from its (nnz,) data."""
        return sp.csr_matrix((data, self.pattern_cols, self.indptr), shape=(self.n_dof,) * 2)

    # -- element matrices ----------------------------------------------------------------------
    def default_properties(self) -> ElementProperties:
        s = self.structure
        return ElementProperties(
            beam_thickness=s.beam_thickness.copy(),
            beam_rho=s.beam_rho.copy(),
            beam_E=s.beam_E.copy(),
            beam_bend_factor=np.ones(len(s.beam_part)),
            mass_scale=np.ones(len(s.mass_node)),
            spring_scale=np.ones(len(s.spring_part)),
        )

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

    def assemble(self, props: ElementProperties | None = None):
        """Global K and M as CSR matrices, plus every family's element matrices (for energies).

        Returns (K, M, elements): elements a tuple of ``FamilyMatrices``, the parametric
        families' at ``props`` (read-only) then the other registered families'.
        """
        props = self.default_properties() if props is None else props
        check_properties(self.structure, props)
        K = M = None
        used = []
        for family in self.parametric.values():
            memo = self._reusing(family, props)
            used.append(memo.matrices)
            K = _add(K, memo.K)
            M = _add(M, memo.M)
        K, M = _own(_add(K, self._family_K), self.nnz), _own(_add(M, self._family_M), self.nnz)
        return self.to_csr(K), self.to_csr(M), (*used, *self.families)

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
        pos = self._positions[family.family]
        data = [None if X is None else self._scatter(pos, X) for X in (K, M)]
        for X in (K, M, *data):
            if X is not None:
                X.flags.writeable = False
        mats = FamilyMatrices(family.family, self._dofs[family.family], K, M, family.part)
        memo = self._memos[family.family] = _Memo(key.copy(), mats, *data)
        return memo

    def _scatter(self, positions, element_matrices):
        """Sum element entries into the (nnz,) CSR data (float even for no elements)."""
        return np.bincount(positions, element_matrices.ravel(), self.nnz).astype(float, copy=False)

    def total_mass(self, props: ElementProperties | None = None):
        """Total mass [kg] and centre of gravity (3,) [m]: the parametric families' element
        masses (``ParametricFamily.masses``) and the other families' rigid-body mass
        (``elements.base.rigid_mass`` of their M)."""
        props = self.default_properties() if props is None else props
        xyz = self.structure.nodes
        total, moment = 0.0, np.zeros(3)
        for family in self.parametric.values():
            m, centre = family.masses(props, xyz)
            total = total + m.sum()
            moment = moment + m @ centre
        for f in self.families:
            # the rigid-body functional of ``GeneralAssembler.total_mass``: trace / 3 of the
            # translational block, the first moments from the translation-rotation coupling
            Mr = rigid_mass(f.M, f.dofs, xyz)
            total = total + np.trace(Mr[:3, :3]) / 3.0
            moment = moment + np.array([Mr[1, 5], Mr[2, 3], Mr[0, 4]])
        cog = moment / total
        return float(total), cog


def _own(data: np.ndarray | None, nnz: int) -> np.ndarray:
    """``data`` as an array the caller owns: zeros for None, a copy of a memo's (read-only)."""
    if data is None:
        return np.zeros(nnz)
    return data if data.flags.writeable else data.copy()


def _add(a: np.ndarray | None, b: np.ndarray | None) -> np.ndarray | None:
    """a + b where None is nothing (a new array: the memos' data stay untouched)."""
    if a is None:
        return b
    return a if b is None else a + b


def check_properties(structure: Structure, props: ElementProperties) -> None:
    """Raise BayesUpdateError naming the part if a property is non-physical."""
    tube = structure.beam_shape != 2  # solid bars have no wall
    checks = (
        ("thickness", props.beam_thickness[tube], structure.beam_part[tube], True),
        ("density", props.beam_rho, structure.beam_part, True),
        ("Young's modulus", props.beam_E, structure.beam_part, True),
        ("bend factor", props.beam_bend_factor, structure.beam_part, True),
        ("point-mass factor", props.mass_scale, structure.mass_part, False),
        ("spring factor", props.spring_scale, structure.spring_part, False),
    )
    for name, values, parts, strictly in checks:
        bad = ~np.isfinite(values) | ((values <= 0) if strictly else (values < 0))
        if np.any(bad):
            part = structure.parts[parts[np.flatnonzero(bad)[0]]]
            limit = "> 0" if strictly else ">= 0"
            raise BayesUpdateError(
                f"part {part!r}: {name} must be finite and {limit}, got "
                f"{values[np.flatnonzero(bad)[0]]}"
            )
    too_thick = tube & (
        2 * props.beam_thickness >= np.minimum(structure.beam_width, structure.beam_height)
    )
    if np.any(too_thick):
        i = np.flatnonzero(too_thick)[0]
        raise BayesUpdateError(
            f"part {structure.parts[structure.beam_part[i]]!r}: wall thickness "
            f"{props.beam_thickness[i]} m is not less than half the section size"
        )


class GeneralAssembler:
    """Precomputation for repeated K(theta), M(theta) of a general structure.

    shell_keys : (n_shell, k) numbers that must be equal for shells to share a parameter group
    (the FE model passes the indices of the parameters bound to each shell); None = one group
    per distinct nominal (part, t, E, rho).
    """

    def __init__(self, structure: Structure, shell_keys=None):
        s = self.structure = structure
        n = self.n_dof = s.n_dof
        self.beams = Assembler(s)
        b = self.beams
        keys = [b.pattern_rows.astype(np.int64) * n + b.pattern_cols]
        self.shells = None
        if s.shells is not None:
            n_el = s.shells.n_elements
            unit = s.shells.mesh(s.nodes, rho=np.ones(n_el))  # mass per unit density
            self.shells = ShellAssembly(unit, rotary_inertia=s.rotary_inertia)
            pat = self.shells.pattern
            keys.append(pat.rows.astype(np.int64) * n + pat.cols)
        union = sorted_unique(np.concatenate(keys))
        self.nnz = union.size
        self.rows = (union // n).astype(np.int32)
        self.cols = (union % n).astype(np.int32)
        self.indptr = np.searchsorted(self.rows, np.arange(n + 1)).astype(np.int32)
        self._pos_beam = np.searchsorted(union, keys[0])
        if self.shells is not None:
            self._pos_shell = np.searchsorted(union, keys[1])
            self._groups(np.zeros((n_el, 0)) if shell_keys is None else shell_keys)
        c = s.constraints if s.constraints is not None else Constraints()
        self.transform = constraint_transform(s.nodes, c)
        self.rigid = allowed_rigid(s.nodes, self.transform)
        self._rigid_origin = rigid_body_basis(s.nodes, centre=np.zeros(3))

    # -- shells ----------------------------------------------------------------------------------
    def _groups(self, shell_keys):
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

    # -- assembly and solution ------------------------------------------------------------------
    def csr(self, data: np.ndarray) -> sp.csr_matrix:
        return sp.csr_matrix((data, self.cols, self.indptr), shape=(self.n_dof, self.n_dof))

    def assemble(self, props: ElementProperties, shell_props=None):
        """Full (K, M) CSR at beam properties ``props`` and shell (t, E, rho) arrays, plus the
        beam assembler's element matrices (for energies)."""
        Kb, Mb, elem = self.beams.assemble(props)
        K, M = np.zeros(self.nnz), np.zeros(self.nnz)
        K[self._pos_beam] += Kb.data
        M[self._pos_beam] += Mb.data
        if self.shells is not None:
            sh = self.structure.shells
            t, E, rho = (sh.thickness, sh.E, sh.rho) if shell_props is None else shell_props
            Ks, Ms = self.shell_data(t, E, rho)
            K += Ks
            M += Ms
        K = self.csr(K)
        return K, self.csr(M), elem

    def solve(self, K, M, n_modes: int, dense: bool = False, settings=None) -> ModalSolution:
        """First ``n_modes`` elastic modes of the constrained structure (full-DOF shapes).

        settings : ``ModalSettings`` (its n_modes is replaced by ``n_modes``; its rigid_set
        "rigid_motions" for a Nastran SUPORT)."""
        tr = self.transform
        settings = replace(settings or ModalSettings(), n_modes=n_modes)
        if dense:
            settings = replace(settings, dense_below=tr.independent.size + 1, small_method="dense")
        lam, phi, Rm, lam_r = solve_reduced_modes(
            tr.reduce(K),
            tr.reduce(M),
            self.rigid,
            settings,
            tr.independent,
        )
        return ModalSolution(
            frequencies_hz=np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi),
            eigenvalues=lam,
            shapes=tr.expand(phi),
            n_rigid=Rm.shape[1],
            rigid_frequencies_hz=np.sqrt(np.abs(lam_r)) / (2 * np.pi),
        )

    def total_mass(self, M) -> tuple[float, np.ndarray]:
        """Total mass [kg] and centre of gravity (3,) [m] from the full mass matrix: the rigid
        translations give m I, the coupling with rotations about the origin m skew(c)."""
        R = self._rigid_origin
        Mr = R.T @ (M @ R)
        m = float(np.trace(Mr[:3, :3]) / 3.0)
        return m, np.array([Mr[1, 5], Mr[2, 3], Mr[0, 4]]) / m


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


def _block_keys(dofs: np.ndarray, n: int) -> np.ndarray:
    """row * n + col of every entry of element matrices with DOF maps (n_e, d), row-major."""
    d = dofs.shape[1]
    rows = np.repeat(dofs, d, axis=1).ravel().astype(np.int64)
    return rows * n + np.tile(dofs, (1, d)).ravel()


def allowed_rigid(nodes: np.ndarray, tr) -> np.ndarray:
    """(n_ind, r) rigid motions that the supports allow, in the independent DOFs of ``tr``
    (with node frames the fixed DOFs are in the nodes' own axes: w = Lambda^T u)."""
    n = 6 * nodes.shape[0]
    if tr.rotation is None:
        return _allowed_rigid(nodes, n, tr.fixed)[tr.independent]
    R = tr.rotation.T @ rigid_motions(nodes)
    if tr.fixed.size:
        s, v = np.linalg.svd(R[tr.fixed], full_matrices=True)[1:]
        rank = int(np.sum(s > 1e-9 * max(1.0, np.abs(R).max())))
        R = R @ v[rank:].T
    return R[tr.independent]
