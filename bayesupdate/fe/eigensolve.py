"""Free-free generalized eigenproblem K u = lambda M u (seed eqs 1-2), first elastic modes.

Default method ("krylov"): shift-invert block Krylov with Rayleigh-Ritz (Ericsson & Ruhe 1980;
Bathe, *Finite Element Procedures*, 2014, sec. 11.5-11.6), using a banded Cholesky factor of
K - sigma M (sigma < 0, so the factor exists for a free body) in a bandwidth-reducing ordering (reverse
Cuthill-McKee).  The start block contains the rigid-body motions, so the six zero modes are exact
from the first step.  Convergence is checked by the residual ||K phi - lambda M phi||, and blocks are
added until every wanted mode meets the tolerance.  "dense": LAPACK on the full matrices, for checks.

Rigid-body modes are detected by a scale-free test: the share of a mode's kinetic energy that lies
in the span of the rigid-body motions (> 0.5 = rigid).  A free connected body has exactly six;
springs to ground turn them into suspension modes, which are still rigid in shape and are removed.
"""

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sl
from scipy.sparse.csgraph import reverse_cuthill_mckee

from bayesupdate.errors import BayesUpdateError

#: shift [rad^2/s^2] of the shift-invert; (2 pi 1 Hz)^2 keeps K - sigma M well conditioned for
#: structures whose modes of interest are from ~1 Hz upwards, and does not depend on unit scaling.
DEFAULT_SHIFT = -((2 * np.pi * 1.0) ** 2)


@dataclass(frozen=True)
class ModalSolution:
    """Elastic modes of a structure.

    frequencies_hz : (m,) [Hz]; eigenvalues : (m,) lambda = omega^2 [rad^2/s^2];
    shapes : (n_dof, m) mass-normalised (phi^T M phi = 1); n_rigid : rigid-body modes removed;
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
        try:
            return sl.cholesky_banded(band, lower=True, check_finite=False)
        except np.linalg.LinAlgError as exc:
            raise BayesUpdateError(
                "the stiffness matrix is not positive semi-definite (a negative stiffness or "
                "property); check the parameter values"
            ) from exc

    def solve(self, chol, rhs: np.ndarray) -> np.ndarray:
        x = sl.cho_solve_banded((chol, True), rhs[self.perm], check_finite=False)
        return x[self.inv_perm]


def _m_orthonormalize(Y, M, V_blocks):
    """Orthogonalize Y against the M-orthonormal blocks (twice, classical Gram-Schmidt), then
    M-orthonormalize Y itself; directions with negligible M-norm are dropped."""
    for _ in range(2):
        for V in V_blocks:
            Y = Y - V @ (V.T @ (M @ Y))
    G = Y.T @ (M @ Y)
    w, U = np.linalg.eigh(0.5 * (G + G.T))
    keep = w > 1e-12 * max(w.max(), 1e-300)
    return Y @ (U[:, keep] / np.sqrt(w[keep]))


def _rigid_share(shapes, M, rigid_basis):
    """Share of each (M-normalised) mode's M-norm inside span(rigid_basis), (m,) in [0, 1]."""
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
    tol: float = 1e-9,
    shift: float = DEFAULT_SHIFT,
    n_rigid_max: int = 6,
) -> ModalSolution:
    """First ``n_modes`` elastic modes of K u = lambda M u.

    K, M : (n, n) sparse (CSR) matrices; rigid_basis : (n, 6) rigid-body motions;
    banded : precomputed ``BandedShiftInvert`` for the pattern (needed for "krylov").
    """
    n = K.shape[0]
    n_want = n_modes + n_rigid_max
    if n_want > n:
        raise BayesUpdateError(
            f"asked for {n_modes} elastic modes but the model has only {n} DOFs "
            f"({n - n_rigid_max} elastic modes at most)"
        )
    if method == "krylov" and n <= 3 * (n_want + 8):
        method = "dense"  # a Krylov space would span nearly everything: LAPACK is cheaper
    if method == "dense":
        lam, phi = sl.eigh(
            K.toarray(), M.toarray(), subset_by_index=[0, n_want - 1], check_finite=False
        )
    elif method == "krylov":
        if banded is None:
            raise ValueError("method='krylov' needs a BandedShiftInvert")
        lam, phi = _block_krylov(K, M, n_want, rigid_basis, banded, tol, shift)
    else:
        raise BayesUpdateError(f"unknown eigen-solver method {method!r}; use 'krylov' or 'dense'")
    if not np.all(np.isfinite(lam)):
        raise BayesUpdateError("the eigen-solve produced non-finite eigenvalues")
    share = _rigid_share(phi, M, rigid_basis)
    rigid = share > 0.5
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


def _block_krylov(K, M, n_want, rigid_basis, banded, tol, shift, max_blocks=12):
    """Shift-invert block Krylov + Rayleigh-Ritz; V, M V and K V are kept so that each new block
    costs one banded solve and two sparse products."""
    n = K.shape[0]
    chol = banded.factor(K.data, M.data, shift)
    block = min(n_want + 8, n)
    rng = np.random.default_rng(20130220)  # fixed: the solver is deterministic
    start = np.concatenate(
        [rigid_basis, rng.standard_normal((n, block - rigid_basis.shape[1]))], axis=1
    )
    V = np.zeros((n, 0))
    MV = np.zeros((n, 0))
    KV = np.zeros((n, 0))
    Y = banded.solve(chol, M @ start)
    lam = phi = lam_prev = None
    for it in range(max_blocks):
        for _ in range(2):  # classical Gram-Schmidt, twice is enough (Giraud et al. 2005)
            Y = Y - V @ (MV.T @ Y)
        MY = M @ Y
        G = Y.T @ MY
        w, U = np.linalg.eigh(0.5 * (G + G.T))
        keep = w > 1e-12 * max(w.max(), 1e-300)
        if not np.any(keep):
            break
        scale = U[:, keep] / np.sqrt(w[keep])
        Y, MY = Y @ scale, MY @ scale
        V = np.concatenate([V, Y], axis=1)
        MV = np.concatenate([MV, MY], axis=1)
        KV = np.concatenate([KV, K @ Y], axis=1)
        if it >= 1:
            Kr = V.T @ KV
            Mr = V.T @ MV  # ~I; using it keeps Rayleigh-Ritz exact despite round-off in V
            lam, y = sl.eigh(
                0.5 * (Kr + Kr.T),
                0.5 * (Mr + Mr.T),
                subset_by_index=[0, n_want - 1],
                check_finite=False,
            )
            phi = V @ y
            # Ritz values decrease monotonically to the eigenvalues as the space grows
            # (Courant-Fischer); stop when the wanted ones no longer move.  Residual norms are
            # no good here: K holds axial terms ~1e9 times the modal eigenvalues, so their
            # round-off floor sits far above the accuracy the Ritz values reach.
            if lam_prev is not None:
                # rigid-body eigenvalues are round-off noise around 0: judge the elastic ones
                elastic = np.abs(lam) > 1e-7 * np.abs(lam).max()
                change = np.abs(lam - lam_prev)[elastic] / np.abs(lam[elastic])
                if np.all(change < tol) or V.shape[1] + block > n:
                    return lam, phi
            lam_prev = lam
        Y = banded.solve(chol, MY)
    if lam is None:
        raise BayesUpdateError("eigen-solve failed: the Krylov space collapsed")
    return lam, phi
