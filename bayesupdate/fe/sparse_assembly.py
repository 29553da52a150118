"""Assembly and modal solution of a general ``Structure``: beams, point masses and springs (the
beam ``Assembler``, unchanged) together with shells, supports and rigid elements.

* One CSR pattern, the union of the beam pattern and the shell pattern; each re-assembly adds the
  beam data and the shell data into it at precomputed positions.
* Shells are grouped by the parameters acting on them (and their nominal E, rho and, where the
  thickness is not a parameter, t).  Within a group K and M are exact sums over powers of the
  common thickness (``shell.power_matrices``):
  K = (E / E0) sum_p t^p K_p,  M = M_nsm + rho sum_p t^p M_p  (M_p per unit density),
  so a new parameter point costs a few vector operations per group and no element computation.
* The registered element families (``fe.elements.base``: general beams, rods, scalar masses)
  carry no parameters: the beam ``Assembler`` assembles them once into its pattern and adds them
  to every re-assembly.
* Supports, rigid elements and node frames: u = T u_ind (``constraints``; T includes the
  frames' rotation), K_r = T^T K T, M_r = T^T M T, solved
  by ``sparse_modal.solve_reduced_modes`` (shift-invert Lanczos with a negative shift, the
  rigid-body modes the supports allow found exactly, mechanisms reported with their DOFs;
  dense LAPACK below ``ModalSettings.dense_below`` DOFs).
* Springs to ground: their suspension modes are elastic modes, as on the beam path
  (``fe.eigensolve``); with ``ModalSettings.rigid_set = "rigid_motions"`` (MSC Nastran's SUPORT)
  every allowed rigid motion is a rigid mode (``n_rigid``, ``rigid_frequencies_hz``) instead.
"""

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from bayesupdate.fe.assembly import Assembler, ElementProperties
from bayesupdate.fe.constraints import Constraints, constraint_transform
from bayesupdate.fe.eigensolve import ModalSolution
from bayesupdate.fe.elements import shell
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
