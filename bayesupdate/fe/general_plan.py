"""The constrained pencil of a general assembler on its fixed pattern, reduced without sparse
products: the solve route of small deck models (``FEModel.small_method`` "krylov").

``Assembler.solve`` reduces K and M by the supports' and rigid elements' transformation T
(``constraints.constraint_transform``, u = T u_ind) as T^T K T, two sparse products and a
format conversion per matrix and per solve (1.3-1.6 ms CPU of the mAEWing1 v3.3 deck's solve,
756 -> 354 DOFs; 0.16-0.3 ms this way: ``benchmarks/deck_solve.py --solve-only``).  T and the
pattern of K and M (``Assembler.rows``, ``cols``: every family's and the shells' blocks) are
fixed per model, and T^T K T is linear in K's (nnz,) data:

    (T^T K T)_ab = sum_e T_{r_e a} K_e T_{c_e b}    (e over the pattern's entries (r_e, c_e)),

so a sparse S (nnz_red, nnz), built once, gives the reduced data as one product, S @ K.data, on
one reduced pattern shared by K and M (Cook et al., *Concepts and Applications of FEA*, 4th ed.,
sec. 9.2, the transformation method; the same sums in another order: equal to round-off).  The
shared pattern lets the banded block Krylov (``eigen_small``) form K - sigma M from the two data
vectors and reuse its band layout.  Everything after the reduction is ``sparse_modal``'s
(``solve_reduced_modes``: rigid set, Krylov or dense LAPACK, mechanism check).
"""

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from bayesupdate.fe.eigensolve import ModalSolution
from bayesupdate.fe.sparse_modal import ModalSettings, constrained_modes


def _row_entries(A: sp.csr_matrix, rows: np.ndarray):
    """(owner (k,), column (k,), value (k,)) of every stored entry of ``A``'s ``rows`` (m,),
    owner the position in ``rows``."""
    counts = A.indptr[rows + 1] - A.indptr[rows]
    owner = np.repeat(np.arange(rows.size), counts)
    first = np.repeat(A.indptr[rows] - (np.cumsum(counts) - counts), counts)
    idx = first + np.arange(owner.size)
    return owner, A.indices[idx], A.data[idx]


class ReductionMap:
    """T^T X T for K and M on one CSR pattern, as one sparse product of each one's data.

    T : (n_dof, n_ind) sparse transformation; rows, cols : (nnz,) the pattern's entries in CSR
    order (``Assembler.rows``, ``cols``).  ``S`` : (n_red, nnz) CSR, the reduced data on every
    entry the pattern can reach = S @ data.  Most of them hold zeros (the pattern has whole
    element blocks; a beam along a global axis has exact zeros in them): the reduced matrices
    keep the ``live`` entries only, those nonzero in K or M at some point solved so far, so
    their pattern is that of the sparse products (``ConstraintTransform.reduce``), and grows
    when a point makes another entry nonzero (checked at every call: nothing is dropped)."""

    def __init__(self, T, rows: np.ndarray, cols: np.ndarray):
        T = sp.csr_matrix(T)
        self.n = n = T.shape[1]
        e1, a, va = _row_entries(T, np.asarray(rows))  # T_{r_e a} for every entry e
        e2, b, vb = _row_entries(T, np.asarray(cols)[e1])  # T_{c_e b} for each of those
        entry, a, va = e1[e2], a[e2], va[e2]
        key = a.astype(np.int64) * n + b
        self._keys, red = np.unique(key, return_inverse=True)
        self.S = sp.csr_matrix((va * vb, (red.ravel(), entry)), shape=(self._keys.size, len(rows)))
        self.live = np.zeros(self._keys.size, bool)
        self._split()

    def _split(self):
        """S's rows of the live entries and of the others; the live entries' pattern."""
        keys = self._keys[self.live]
        indptr = np.searchsorted(keys // self.n, np.arange(self.n + 1)).astype(np.int32)
        self._pattern = ((keys % self.n).astype(np.int32), indptr)
        self._S_live, self._S_dead = self.S[self.live], self.S[~self.live]

    def reduce(self, K_data: np.ndarray, M_data: np.ndarray):
        """(T^T K T, T^T M T) (n_ind, n_ind) CSR on one pattern (equal index arrays)
        for K's and M's (nnz,) data."""
        if np.any(self._S_dead @ K_data) or np.any(self._S_dead @ M_data):
            self.live |= (self.S @ K_data != 0) | (self.S @ M_data != 0)
            self._split()
        k, m = self._S_live @ K_data, self._S_live @ M_data
        indices, indptr = self._pattern
        shape = (self.n, self.n)
        return (sp.csr_matrix((k, indices, indptr), shape=shape),
                sp.csr_matrix((m, indices, indptr), shape=shape))  # fmt: skip


class GeneralPlan:
    """What a general assembler's solve needs that its pattern and constraints fix, computed
    once: the reduction (``ReductionMap``), the independent DOFs, the allowed rigid motions
    and T to expand the shapes.  ``assembler`` : ``assembly.Assembler``."""

    def __init__(self, assembler):
        tr = assembler.transform
        self.assembler = assembler
        self.map = ReductionMap(tr.T, assembler.rows, assembler.cols)
        self.independent = tr.independent
        self.rigid = assembler.rigid
        self.T = tr.T

    def solve(self, K, M, n_modes: int, settings: ModalSettings) -> ModalSolution:
        """``Assembler.solve`` of K, M (CSR on the assembler's pattern, as ``assemble`` gives
        them): the first ``n_modes`` elastic modes, full-DOF shapes."""
        g = self.assembler
        on_pattern = all(
            np.array_equal(X.indices, g.cols) and np.array_equal(X.indptr, g.indptr) for X in (K, M)
        )
        if not on_pattern:  # not assembled on the pattern (a caller's own matrices)
            return g.solve(K, M, n_modes, settings=settings)
        settings = replace(settings, n_modes=n_modes)
        Kf, Mf = self.map.reduce(K.data, M.data)
        return constrained_modes(Kf, Mf, self.rigid, settings, self.independent, self.T)
