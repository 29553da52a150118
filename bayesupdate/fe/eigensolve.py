"""Free-free generalized eigenproblem K u = lambda M u (seed eqs 1-2), first elastic modes.

Default method ("krylov"): shift-invert block Krylov with Rayleigh-Ritz (Ericsson & Ruhe 1980;
Bathe, *Finite Element Procedures*, 2014, sec. 11.5-11.6), using a banded Cholesky factor of
K - sigma M (sigma < 0, so the factor exists for a free body) in a bandwidth-reducing ordering
(reverse Cuthill-McKee).  The start block contains the rigid-body motions, so the six zero modes
are exact from the first step.  Blocks are added until the residual of every wanted elastic mode
is small (see ``_block_krylov``).  "dense": LAPACK on the full matrices, for checks.

Rigid-body modes are detected by a scale-free test: the share of a mode's kinetic energy that lies
in the span of the rigid-body motions (> 0.5 = rigid-shaped) and a zero eigenvalue, i.e. strain +
spring energy zero to solver precision against the elastic scale (free body: exactly six).  A
body on soft springs to ground (bungees, as in a ground vibration test) keeps only its truly free
motions as rigid modes: its suspension modes store energy in the springs, so they are elastic
modes, numbered with the others (as MSC Nastran without SUPORT, OpenSees and any other modal
solver report them).
"""

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sl
from scipy.linalg.lapack import dpbtrf as _dpbtrf
from scipy.linalg.lapack import dpbtrs as _dpbtrs
from scipy.linalg.lapack import dtrtri as _dtrtri
from scipy.sparse.csgraph import reverse_cuthill_mckee

from bayesupdate.errors import BayesUpdateError

#: shift [rad^2/s^2] of the shift-invert; (2 pi 1 Hz)^2 keeps K - sigma M well conditioned for
#: structures whose modes of interest are from ~1 Hz upwards, and does not depend on unit scaling.
DEFAULT_SHIFT = -((2 * np.pi * 1.0) ** 2)


@dataclass(frozen=True)
class ModalSolution:
    """Elastic modes of a structure.

    frequencies_hz : (m,) [Hz]; eigenvalues : (m,) lambda = omega^2 [rad^2/s^2];
    shapes : (n_dof, m) mass-normalized (phi^T M phi = 1); n_rigid : rigid-body modes removed;
    rigid_frequencies_hz : (n_rigid,) their frequencies (~0 for a free body) [Hz].
    """

    frequencies_hz: np.ndarray
    eigenvalues: np.ndarray
    shapes: np.ndarray
    n_rigid: int
    rigid_frequencies_hz: np.ndarray


class BandedShiftInvert:
    """Precomputed ordering and band layout for a fixed sparse pattern (rows, cols, indptr)."""

    def __init__(self, n: int, rows: np.ndarray, cols: np.ndarray, indptr: np.ndarray):
        import scipy.sparse as sp

        pattern = sp.csr_matrix((np.ones(rows.size), cols, indptr), shape=(n, n))
        self.n = n
        self.perm = reverse_cuthill_mckee(pattern, symmetric_mode=True).astype(np.intp)
        self.inv_perm = np.empty(n, dtype=np.intp)
        self.inv_perm[self.perm] = np.arange(n)
        pr = self.inv_perm[rows]
        pc = self.inv_perm[cols]
        lower = pr >= pc
        self.lower_mask = lower
        self.bandwidth = int(np.max(pr[lower] - pc[lower]))
        # lower banded storage of LAPACK: ab[i - j, j] = a[i, j]
        self.band_pos = (pr[lower] - pc[lower]) * n + pc[lower]

    def factor(self, data_K: np.ndarray, data_M: np.ndarray, shift: float):
        band = np.bincount(
            self.band_pos,
            (data_K - shift * data_M)[self.lower_mask],
            minlength=(self.bandwidth + 1) * self.n,
        ).reshape(self.bandwidth + 1, self.n)
        # LAPACK directly: scipy's checking wrappers cost more than the factorization here
        chol, info = _dpbtrf(band, lower=1)
        if info != 0:
            raise BayesUpdateError(
                "the stiffness matrix is not positive semi-definite (a negative stiffness or "
                "property); check the parameter values"
            )
        return chol

    def solve(self, chol, rhs: np.ndarray) -> np.ndarray:
        x, _ = _dpbtrs(chol, rhs[self.perm], lower=1)
        return x[self.inv_perm]


def _rigid_share(shapes, M, rigid_basis):
    """Share of each (M-normalized) mode's M-norm inside span(rigid_basis), (m,) in [0, 1]."""
    MR = M @ rigid_basis
    G = rigid_basis.T @ MR
    c = MR.T @ shapes
    return np.einsum("im,im->m", c, np.linalg.solve(G, c))


def solve_modes(
    K,
    M,
    n_modes: int,
    rigid_basis: np.ndarray,
    banded: BandedShiftInvert | None = None,
    method: str = "krylov",
    tol: float = 1e-4,
    shift: float = DEFAULT_SHIFT,
    n_rigid_max: int = 6,
    remove_rigid: bool = True,
) -> ModalSolution:
    """First ``n_modes`` elastic modes of K u = lambda M u.

    K, M : (n, n) sparse (CSR) matrices; rigid_basis : (n, 6) rigid-body motions;
    banded : precomputed ``BandedShiftInvert`` for the pattern (needed for "krylov").
    remove_rigid : drop the zero-energy rigid-body modes; False keeps every mode.  Suspension
    modes on springs to ground are elastic modes either way (module docstring).
    """
    n = K.shape[0]
    n_want = min(n_modes + n_rigid_max, n)
    if n_modes > n:
        raise BayesUpdateError(f"asked for {n_modes} modes but the model has only {n} DOFs")
    if method == "krylov" and n <= 3 * (n_want + 8):
        method = "dense"  # a Krylov space would span nearly everything: LAPACK is cheaper
    lam, phi, share = _lowest_pairs(K, M, n_want, rigid_basis, banded, method, tol, shift)
    rigid = np.zeros(lam.size, bool)
    if remove_rigid:
        if share is None:
            share = _rigid_share(phi, M, rigid_basis)
        rigid = _rigid_modes(lam, share)
    n_rigid = int(rigid.sum())
    if n_rigid > n_rigid_max:
        raise BayesUpdateError(
            f"found {n_rigid} rigid-body modes (a free body has {n_rigid_max}): the structure is "
            "a mechanism or disconnected; check its joints"
        )
    elastic = np.flatnonzero(~rigid)[:n_modes]
    if elastic.size < n_modes:
        raise BayesUpdateError(f"could only compute {elastic.size} elastic modes of {n_modes}")
    lam_e = lam[elastic]
    phi_e = phi[:, elastic]
    # deterministic sign: largest-magnitude component positive
    idx = np.argmax(np.abs(phi_e), axis=0)
    phi_e = phi_e * np.sign(phi_e[idx, np.arange(phi_e.shape[1])])
    with np.errstate(invalid="ignore"):
        f_rigid = np.sqrt(np.abs(lam[rigid])) / (2 * np.pi)
    return ModalSolution(
        frequencies_hz=np.sqrt(np.maximum(lam_e, 0.0)) / (2 * np.pi),
        eigenvalues=lam_e,
        shapes=phi_e,
        n_rigid=n_rigid,
        rigid_frequencies_hz=f_rigid,
    )


def _lowest_pairs(K, M, n_want, rigid_basis, banded, method, tol, shift):
    """(lam (n_want,), phi (n, n_want), rigid share or None) by dense LAPACK or block Krylov."""
    if method == "dense":
        lam, phi = sl.eigh(
            K.toarray(), M.toarray(), subset_by_index=[0, n_want - 1], check_finite=False
        )
        share = None
    elif method == "krylov":
        if banded is None:
            raise ValueError("method='krylov' needs a BandedShiftInvert")
        lam, phi, share = _block_krylov(K, M, n_want, rigid_basis, banded, tol, shift)
    else:
        raise BayesUpdateError(f"unknown eigen-solver method {method!r}; use 'krylov' or 'dense'")
    if not np.all(np.isfinite(lam)):
        raise BayesUpdateError("the eigen-solve produced non-finite eigenvalues")
    return lam, phi, share


def _rigid_modes(lam, share) -> np.ndarray:
    """(m,) bool: rigid-body modes, i.e. rigid-shaped (share > 0.5) with a zero eigenvalue: strain
    + spring energy (lambda, the modes being mass-normalized) below 1e-8 of the highest computed
    one.  A suspension mode is rigid-shaped too, but its springs store lambda of energy: at
    0.1 Hz under a 10 Hz mode it is at 1e-4, orders above the round-off of a true zero mode."""
    return (share > 0.5) & (np.abs(lam) < 1e-8 * np.abs(lam).max())


def _rayleigh_ritz(Kr, Mr, n_want):
    """Lowest ``n_want`` eigenpairs of the projected pencil (Kr, Mr).  Mr ~ I, but using it (via
    its Cholesky factor) keeps the Ritz values exact upper bounds despite round-off in V."""
    L = np.linalg.cholesky(0.5 * (Mr + Mr.T))
    Linv = _dtrtri(L, lower=1)[0]
    C = Linv @ Kr @ Linv.T
    lam, z = np.linalg.eigh(0.5 * (C + C.T))
    return lam[:n_want], Linv.T @ z[:, :n_want]


def _m_orthonormal_columns(Y, MY):
    """Y, MY scaled so that Y^T M Y = I: Cholesky QR, or an eigen-decomposition that drops
    directions with negligible M-norm when the block is (numerically) rank deficient."""
    G = Y.T @ MY
    G = 0.5 * (G + G.T)
    try:
        L = np.linalg.cholesky(G)
        if np.min(np.diag(L)) > 1e-7 * np.max(np.diag(L)):
            inv_lt = _dtrtri(L, lower=1)[0].T
            return Y @ inv_lt, MY @ inv_lt
    except np.linalg.LinAlgError:
        pass
    w, U = np.linalg.eigh(G)
    keep = w > 1e-12 * max(w.max(), 1e-300)
    scale = U[:, keep] / np.sqrt(w[keep])
    return Y @ scale, MY @ scale


def _start_block(random: np.ndarray, V: np.ndarray, KV: np.ndarray, K) -> np.ndarray:
    """The Krylov start block (n, b): ``random`` (n, b), with the rigid motions V (n, r) added
    when springs to ground hold them (K V != 0 beyond round-off: ||K V|| > 1e-14 ||K|| ||V||, the
    frame test's free body sits at 2e-18, a 1 N/m spring at 6e-12).  Their suspension modes
    then lie mostly in span(V) but are not in it, and a space grown from a block orthogonal to
    V alone reaches their correction slowly: on a 156-DOF frame with a point spring to ground
    every block up to ``max_blocks`` was built (23 ms a solve against 4 ms with V added).  A
    free body's V is an exact null space, so its start block stays the random one."""
    k_norm = np.sqrt(np.sum(K.data**2))
    if np.linalg.norm(KV) <= 1e-14 * k_norm * np.linalg.norm(V):
        return random
    return np.concatenate([random, V], axis=1)


def _block_krylov(K, M, n_want, rigid_basis, banded, tol, shift, max_blocks=12, min_blocks=4):
    """Shift-invert block Krylov + Rayleigh-Ritz.

    The rigid-body motions span the null space of a free body exactly, so they are the first
    columns of the basis and the Krylov blocks start from a random block M-orthogonal to them
    (A^-1 M keeps that orthogonality, so later blocks do not lose rank).  V, M V and K V are kept,
    so each new block costs one banded solve and two sparse products.
    """
    n = K.shape[0]
    chol = banded.factor(K.data, M.data, shift)
    # the rigid motions are exact columns already: the blocks only need the elastic modes + 2
    # (measured on the exhaust: 14-wide blocks x 4 converge with one Rayleigh-Ritz step)
    n_rigid = rigid_basis.shape[1]
    block = max(1, min(n_want - n_rigid + 2, n - n_rigid))
    V, MV = _m_orthonormal_columns(rigid_basis, M @ rigid_basis)
    KV = K @ V
    rng = np.random.default_rng(20130220)  # fixed: the solver is deterministic
    Y = banded.solve(chol, M @ _start_block(rng.standard_normal((n, block)), V, KV, K))
    lam = phi = None
    for it in range(max_blocks):
        for _ in range(2):  # classical Gram-Schmidt, twice is enough (Giraud et al. 2005)
            Y = Y - V @ (MV.T @ Y)
        Y, MY = _m_orthonormal_columns(Y, M @ Y)
        if Y.shape[1] == 0:
            break
        V = np.concatenate([V, Y], axis=1)
        MV = np.concatenate([MV, MY], axis=1)
        KV = np.concatenate([KV, K @ Y], axis=1)
        if it >= min_blocks - 1:
            lam, y = _rayleigh_ritz(V.T @ KV, V.T @ MV, n_want)
            phi = V @ y
            # Residuals r = K phi - lambda M phi of the elastic modes (rigid ones are in the start
            # block, hence exact).  K holds axial terms ~1e9 times the modal eigenvalues, so the
            # round-off floor of |r| / (lambda |M phi|) is ~1e-5; the eigenvalue error is
            # quadratic in it (Kato-Temple: |dlambda| <= |r|^2 / gap), so tol ~1e-4 already gives
            # relative eigenvalue errors ~1e-8 x lambda/gap.
            lam_abs = np.abs(lam)
            elastic = lam_abs > 1e-7 * lam_abs.max()
            y_e = y[:, elastic]
            res = np.linalg.norm(KV @ y_e - (MV @ y_e) * lam[elastic], axis=0)
            ref = lam_abs[elastic] * np.linalg.norm(MV @ y_e, axis=0)
            if np.all(res < tol * ref) or V.shape[1] + block > n:
                # V is M-orthonormal with the rigid motions as its first columns, so a Ritz
                # vector's rigid-body share is the squared norm of those coefficients
                return lam, phi, np.sum(y[:n_rigid] ** 2, axis=0)
        Y = banded.solve(chol, MY)
    if lam is None:
        raise BayesUpdateError("eigen-solve failed: the Krylov space collapsed")
    return lam, phi, np.sum(y[:n_rigid] ** 2, axis=0)
