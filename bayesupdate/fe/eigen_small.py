"""Lowest elastic modes of a small constrained pencil (a few hundred to ~1000 DOFs) by banded
shift-invert block Krylov, residual-checked: the general path's default between the sizes where
dense LAPACK is cheaper and ``ModalSettings.dense_below``.

The problem is that of ``sparse_modal._dense_modes``: the lowest ``n_modes`` eigenpairs of
K x = lambda M x on the M-orthogonal complement of the rigid modes Rm (M-orthonormal, (n, r)),
with M only semi-definite (massless DOFs) and Rm not necessarily eigenvectors (MSC Nastran's
SUPORT, ``ModalSettings.rigid_set = "rigid_motions"``).  Dense LAPACK spends O(n^3) on it
(projection, reduction to tridiagonal form): ~20 ms at 350 DOFs.  Here:

* A = K - sigma M (sigma < 0, positive definite) is factored once as a band Cholesky (LAPACK
  dpbtrf) in reverse Cuthill-McKee order: O(n b^2) for a bandwidth b (24 on the mAEWing1 deck);
  the order and the band positions depend on the pattern only (``BandLayout``, kept for the
  last few patterns), and where K and M share one pattern (``general_plan``) A's data is
  K's - sigma M's, without a sparse sum;
* the operator is the constrained inverse y = A^-1 (M x - M Rm mu) with Rm^T M y = 0 (a bordered
  solve: Z = A^-1 M Rm, S = Rm^T M Z once, then y = w - Z S^-1 (M Rm)^T w for w = A^-1 M x),
  the shift-invert operator of the compressed pencil, so every Krylov vector lies in the
  constraint space and the massless DOFs follow their statically condensed values;
* block Krylov (Ericsson & Ruhe, Math. Comp. 35 (1980) 1251; Bathe, *Finite Element
  Procedures*, 2014, sec. 11.5-11.6) from a seeded random block, M-orthonormalized by classical
  Gram-Schmidt twice (Giraud et al., Numer. Math. 101 (2005) 87) and the eigen-decomposition
  of each block's M-Gram matrix;
* Rayleigh-Ritz on the basis V (V^T M V = I); a Ritz pair is accepted when its residual
  r = K x - lambda M x, with its component along M Rm removed (the constraint's Lagrange
  multiplier), is below ``tol`` x |lambda| ||M x|| (the eigenvalue error is quadratic in it,
  Kato-Temple: |d lambda| <= ||r||^2 / gap);
* the eigenvalues of the accepted vectors are the Rayleigh quotients of the operator,
  theta = x^T M op(x) = 1 / (lambda - sigma), which cancel nothing (``_shift_invert_values``).

On the mAEWing1 v3.3 deck (354 DOFs after its RBE2s, 20 modes, block 8) it converges at 72
vectors (residual 5e-6) in ~8 ms CPU where dense LAPACK takes ~20 ms; its frequencies are
within 8e-9 of LAPACK's, whose own first eigenvalue is 1.3e-8 off the extended-precision
Rayleigh quotient of its vector: both carry the round-off of this deck's stiffness range
(``tests/test_fe_eigen_small.py``, ``benchmarks/deck_eigen_routes.py``).  A pencil the
iteration does not resolve (no band Cholesky, no convergence within ``max_blocks``, a block
that has lost every direction) returns None and the caller falls back to dense LAPACK, which
reports a singular K - sigma M or a mechanism as before.
"""

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import scipy.sparse as sp
from scipy.linalg.lapack import dpbtrf, dpbtrs, dtrtri
from scipy.sparse.csgraph import reverse_cuthill_mckee


@dataclass(frozen=True)
class KrylovSettings:
    """Settings of ``krylov_modes``.

    block : vectors per Krylov block (at least 1); max_blocks : blocks before giving up (None is
    returned); tol : accepted relative residual ||r|| / (|lambda| ||M x||) of every wanted mode;
    seed : of the random start block; ritz_from : basis size, in units of n_modes, of the first
    Rayleigh-Ritz step of a cold start (each step costs about as much as the blocks before it;
    later steps follow every block).
    """

    block: int = 8
    max_blocks: int = 40
    tol: float = 1e-5
    seed: int = 0
    ritz_from: float = 3.5


class BandLayout:
    """Reverse Cuthill-McKee order and band positions of a symmetric CSR pattern (n, n):
    ``band(data)`` is the (bandwidth + 1, n) lower band (LAPACK dpbtrf's layout) of a matrix
    with this pattern in that order.  Found once per pattern (``layout_of``)."""

    def __init__(self, n: int, indices: np.ndarray, indptr: np.ndarray):
        pattern = sp.csr_matrix((np.ones(indices.size), indices, indptr), shape=(n, n))
        self.n = n
        self.perm = reverse_cuthill_mckee(pattern, symmetric_mode=True).astype(np.intp)
        self.inv = np.empty(n, np.intp)
        self.inv[self.perm] = np.arange(n)
        pr = self.inv[np.repeat(np.arange(n), np.diff(indptr))]
        pc = self.inv[indices]
        self.lower = np.flatnonzero(pr >= pc)
        offset = (pr - pc)[self.lower]
        self.bandwidth = int(offset.max(initial=0))
        self.flat = offset * n + pc[self.lower]

    def band(self, data: np.ndarray) -> np.ndarray:
        """(bandwidth + 1, n) lower band of the matrix with (nnz,) ``data`` on the pattern."""
        band = np.zeros((self.bandwidth + 1) * self.n)
        band[self.flat] = data[self.lower]
        return band.reshape(self.bandwidth + 1, self.n)


@lru_cache(maxsize=8)
def _layout(n: int, indices: bytes, indptr: bytes) -> BandLayout:
    return BandLayout(n, np.frombuffer(indices, np.int64), np.frombuffer(indptr, np.int64))


def layout_of(A: sp.csr_matrix) -> BandLayout:
    """The ``BandLayout`` of A's pattern (canonical CSR: sorted, no duplicates), kept for the
    last few patterns: a model solved at many points has one."""
    return _layout(A.shape[0], A.indices.astype(np.int64).tobytes(),
                   A.indptr.astype(np.int64).tobytes())  # fmt: skip


class BandCholesky:
    """Band Cholesky factor of a sparse symmetric positive definite A (n, n) in reverse
    Cuthill-McKee order (LAPACK dpbtrf/dpbtrs), or ``ok`` False if A is not positive definite.
    layout : A's ``BandLayout`` (None: A's own, ``layout_of``)."""

    def __init__(self, A: sp.csr_matrix, layout: BandLayout | None = None):
        A = sp.csr_matrix(A)
        if layout is None:
            if not A.has_canonical_format:  # sorted, summed on a copy: the caller's A stays
                A = A.copy()
                A.sum_duplicates()
            layout = layout_of(A)
        self.perm, self.inv = layout.perm, layout.inv
        self.factor, info = dpbtrf(layout.band(A.data), lower=1)
        self.ok = info == 0

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """A^-1 rhs for rhs (n,) or (n, k)."""
        x, _ = dpbtrs(self.factor, rhs[self.perm], lower=1)
        return x[self.inv]


def shifted(Kf: sp.csr_matrix, Mf: sp.csr_matrix, sigma: float) -> BandCholesky:
    """The band Cholesky factor of Kf - sigma Mf; where Kf and Mf share one pattern
    (``general_plan.ReductionMap``) from their data on it, without a sparse sum."""
    same = np.array_equal(Kf.indptr, Mf.indptr) and np.array_equal(Kf.indices, Mf.indices)
    if not (same and Kf.has_canonical_format and Mf.has_canonical_format):
        return BandCholesky((Kf - sigma * Mf).tocsr())
    A = sp.csr_matrix((Kf.data - sigma * Mf.data, Kf.indices, Kf.indptr), shape=Kf.shape)
    return BandCholesky(A, layout_of(Kf))


def worthwhile(n: int, n_modes: int, n_rigid: int, settings: KrylovSettings) -> bool:
    """True if a pencil of n DOFs is large enough for the iteration: twice the basis it needs
    (its basis is capped at n / 2; below that dense LAPACK costs about as much)."""
    return n >= 2 * (settings.ritz_from * n_modes + n_rigid + settings.block)


def krylov_modes(Kf, Mf, Rm, n_modes: int, sigma: float, settings: KrylovSettings, start=None):
    """Lowest ``n_modes`` eigenpairs of (Kf, Mf) (n, n) sparse on the M-orthogonal complement of
    Rm (n, r) (M-orthonormal), by constrained shift-invert block Krylov (module docstring).

    sigma : shift [rad^2/s^2] (< 0); start : (n, k) start block (e.g. a neighbouring point's
    modes), else a seeded random block of ``settings.block`` columns.  Returns (lam (n_modes,)
    [rad^2/s^2] ascending, phi (n, n_modes) mass-normalized), or None where the iteration does
    not resolve the pencil."""
    Kf, Mf = sp.csr_matrix(Kf), sp.csr_matrix(Mf)
    chol = shifted(Kf, Mf, sigma)
    if not chol.ok:
        return None
    op = _constrained_inverse(chol, Mf, Rm)
    if op is None:
        return None
    MR = Mf @ Rm
    Qr = np.linalg.qr(MR)[0] if Rm.shape[1] else np.zeros((Kf.shape[0], 0))
    n = Kf.shape[0]
    rng = np.random.default_rng(settings.seed)
    Y = op(rng.standard_normal((n, settings.block)) if start is None else start)
    # a Rayleigh-Ritz step costs as much as several blocks: the first one where the basis can
    # hold the wanted modes to tol (a cold start: ~3.5 n_modes vectors on the mAEWing1 deck)
    first_check = settings.ritz_from * n_modes if start is None else 2 * Y.shape[1]
    cap = n // 2
    V, MV, KV = np.empty((n, cap)), np.empty((n, cap)), np.empty((n, cap))
    k = 0
    for _ in range(settings.max_blocks):
        Y, MY = _m_orthonormal_block(Y, Mf, V[:, :k], MV[:, :k])
        if Y is None or k + Y.shape[1] > cap:
            return None
        j, k = k, k + Y.shape[1]
        V[:, j:k], MV[:, j:k], KV[:, j:k] = Y, MY, Kf @ Y
        if k >= first_check:
            out = _rayleigh_ritz(V[:, :k], KV[:, :k], MV[:, :k], Qr, n_modes, settings.tol)
            if out is not None:
                return _shift_invert_values(out[1], Mf, op, sigma)
        Y = op(Y)
    return None


def _shift_invert_values(phi, Mf, op, sigma):
    """(lam, phi): the eigenvalues of the Ritz vectors phi (n, m) (M-orthonormal) from the
    Rayleigh quotients of the operator, theta = x^T M op(x) = 1 / (lambda - sigma).  x^T K x
    sums terms ~||K|| ||x||^2 that cancel to lambda (axial stiffness ~1e9 x the eigenvalue:
    ~5e-9 relative round-off on a 0.7 Hz suspension mode); op(x) ~ x / (lambda - sigma)
    cancels nothing, so theta keeps the backward-stable factorization's accuracy, as in
    ARPACK's shift-invert mode and dense LAPACK on M x = theta (K - sigma M) x."""
    MX = Mf @ phi
    theta = np.einsum("ij,ij->j", MX, op(phi)) / np.einsum("ij,ij->j", MX, phi)
    lam = sigma + 1.0 / theta
    order = np.argsort(lam)
    return lam[order], phi[:, order]


def _constrained_inverse(chol: BandCholesky, Mf, Rm):
    """x -> y = A^-1 (M x - M Rm mu) with Rm^T M y = 0 (n, k) -> (n, k); None if the border
    S = Rm^T M A^-1 M Rm is singular."""
    MR = Mf @ Rm
    if Rm.shape[1] == 0:
        return lambda X: chol.solve(Mf @ X)
    Z = chol.solve(MR)
    S = MR.T @ Z
    try:
        Sinv_MRt = np.linalg.solve(0.5 * (S + S.T), MR.T)
    except np.linalg.LinAlgError:
        return None

    def op(X):
        W = chol.solve(Mf @ X)
        return W - Z @ (Sinv_MRt @ W)

    return op


def _m_orthonormal_block(Y, Mf, V, MV):
    """(Y, M Y): Y made M-orthogonal to V (classical Gram-Schmidt twice) and M-orthonormal, by
    Cholesky QR where its M-Gram matrix has a condition below 1e4, else through the
    eigen-decomposition of that matrix scaled to unit diagonal, keeping its well-conditioned
    part: columns that Gram-Schmidt reduces by 1e-10 (a mode the basis already
    holds, as from a warm start) and directions below 1e-12 of the largest are dropped.  A
    block whose Gram matrix had a condition above 1e4 is orthonormalized a second time (as in
    Cholesky QR twice: Fukaya et al., SIAM J. Sci. Comput. 42 (2020) A477).  (None, None) when
    nothing is left."""
    Y0 = Y
    for _ in range(2):
        Y = Y - V @ (MV.T @ Y)
    MY = Mf @ Y
    try:  # the usual case, a well-conditioned block: Cholesky QR
        L = np.linalg.cholesky(Y.T @ MY)
        d = np.diag(L)
        if d.min() > 1e-2 * d.max():  # condition <= 1e4: orthonormal to round-off
            C = dtrtri(L, lower=1)[0].T
            return Y @ C, MY @ C
    except np.linalg.LinAlgError:
        pass
    live = np.einsum("ij,ij->j", Y, Y) > 1e-20 * np.einsum("ij,ij->j", Y0, Y0)
    Y, MY = Y[:, live], MY[:, live]
    for _ in range(2):
        if Y.shape[1] == 0:
            return None, None
        G = Y.T @ MY
        d = np.diag(G)
        if not np.all(d > 0):
            return None, None
        s = 1.0 / np.sqrt(d)
        w, U = np.linalg.eigh(G * np.outer(s, s))
        keep = w > 1e-12 * w.max()
        C = (s[:, None] * U[:, keep]) / np.sqrt(w[keep])
        Y, MY = Y @ C, MY @ C
        if w[keep].min() > 1e-4 * w.max():  # condition <= 1e4: orthonormal to round-off
            return Y, MY
        Y = Y - V @ (MV.T @ Y)
        MY = Mf @ Y
    return Y, MY


def _rayleigh_ritz(V, KV, MV, Qr, n_modes, tol):
    """(lam, phi) of the lowest n_modes Ritz pairs on V (V^T M V = I) if all are converged,
    else None.  The eigenvalues returned are refined from the operator afterwards
    (``_shift_invert_values``), so V^T M V = I to round-off is enough here."""
    C = V.T @ KV
    lam, z = np.linalg.eigh(0.5 * (C + C.T))
    lam, y = lam[:n_modes], z[:, :n_modes]
    MX = MV @ y
    R = KV @ y - MX * lam
    R = R - Qr @ (Qr.T @ R)  # the constraint's reaction M Rm mu is no residual
    res = np.linalg.norm(R, axis=0)
    if not np.all(res <= tol * np.abs(lam) * np.linalg.norm(MX, axis=0)):
        return None
    return lam, V @ y
