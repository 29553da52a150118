"""Every route to the 20 lowest elastic modes of the bound mAEWing1 v3.3 deck, side by side.

The matrices are the solve path's own: ``NastranModel.matrices`` at a parameter point, reduced
by the RBE2 transformation (``GeneralAssembler.transform``: 756 DOFs, 354 independent), the six
rigid motions of its SUPORT as the rigid set (``ModalSettings.rigid_set = "rigid_motions"``),
M singular on 31 massless DOFs.  Bound: ``PBEAM 1003 I1``, ``PBEAM 1004 I1``, ``PBEAM 1005 A``
(as ``benchmarks/deck_solve.py``), at the deck's values times (1.1, 0.9, 1.25), (0.6, 1.8,
0.7) and (1.9, 0.55, 1.4).  Printed for each route: the median CPU (process) time over
``--repeats`` runs [ms] and the largest relative difference of its 20 frequencies from dense
LAPACK (the package's solver before ``fe.eigen_small``), at each point.  Routes:

* dense LAPACK on the M-orthogonal complement of the rigid motions (``sparse_modal``'s:
  Householder projection, then ``eigh`` with a subset), its parts (the projection; ``eigh``
  drivers gvx, gvd; the standard form through a Cholesky factor with evr / evx), and the same
  after condensing the massless DOFs out exactly (static condensation);
* the package's beam-path block Krylov (``fe.eigensolve``, banded shift-invert, tol 1e-4):
  unconstrained (the rigid motions as start block), so it solves another problem wherever a
  rigid motion carries energy (three of this deck's six do: its springs to ground), shown for
  its speed;
* ARPACK shift-invert Lanczos (``sparse_modal._lanczos_modes``, bordered) with SuperLU;
* LOBPCG (scipy) on the shift-inverted pencil with the banded factor of K - sigma M as
  preconditioner and the SUPORT constraint;
* the banded shift-invert block Krylov of ``fe.eigen_small`` (cold: a seeded random block),
  and warm-started from the modes of a point 1 % away (1.01, 0.99, 1.02 times the point), as
  block Krylov and as subspace iteration (X <- op(X), Rayleigh-Ritz, same residual test);
* the parts of the cold block Krylov: factorization (as a sparse sum K - sigma M, and as the
  solve forms it from K's and M's data on their shared pattern, ``fe.general_plan``; the band
  layout it finds once per pattern), operator per block, orthonormalization per block, one
  Rayleigh-Ritz step at its converged size, and its residual by basis size (the sum uses the
  solve's factorization).
* the band solve with the factor of K - sigma M alone, 8 and 20 right-hand sides: LAPACK's
  dpbtrs (one triangular band solve per column, as the package calls it) and, only where numba
  is installed beside the package (it is none of its dependencies), a compiled loop with the
  right-hand sides innermost: what a compiled kernel would buy on the solve's largest part.

Accuracy: every eigenvalue is also compared with the extended-precision (numpy longdouble)
Rayleigh quotient of the dense route's own vector, which shows the dense answer's round-off.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/deck_eigen_routes.py [--repeats 20]
"""

import argparse
import os
import time
import warnings
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import scipy.linalg as sl  # noqa: E402
import scipy.sparse as sp  # noqa: E402
import scipy.sparse.linalg as spla  # noqa: E402
from scipy.linalg.lapack import dpbtrs  # noqa: E402

from bayesupdate.fe import eigen_small as es  # noqa: E402
from bayesupdate.fe import eigensolve, sparse_modal  # noqa: E402
from bayesupdate.fe.general_plan import GeneralPlan  # noqa: E402
from bayesupdate.nastran import load_nastran_model  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DECKS = [up / "shared/data/gvt_maewing1/fem/v3.3_hati" for up in (ROOT.parent, ROOT.parents[1])]
MAIN = "sol103_mAEWing1_Hati_FEMv3p3.bdf"
BINDS = {"i1_1003": "PBEAM 1003 I1", "i1_1004": "PBEAM 1004 I1", "a_1005": "PBEAM 1005 A"}
FACTORS = ((1.1, 0.9, 1.25), (0.6, 1.8, 0.7), (1.9, 0.55, 1.4))
NEIGHBOUR = (1.01, 0.99, 1.02)
N_MODES = 20
SIGMA = sparse_modal.ModalSettings().shift


def median_ms(fn, repeats: int) -> float:
    """Median CPU (process) time of ``fn`` [ms]."""
    times = []
    for _ in range(repeats):
        t = time.process_time()
        fn()
        times.append(time.process_time() - t)
    return 1e3 * float(np.median(times))


class Pencil:
    """The solve path's reduced (K, M) and rigid modes Rm at one parameter point."""

    def __init__(self, fe, factors):
        d = fe.default_parameters()
        p = {k: d[k] * f for k, f in zip(BINDS, factors, strict=True)}
        K, M = fe.matrices(p)
        g = fe.general
        self.K, self.M = g.transform.reduce(K), g.transform.reduce(M)
        # the solve's own reduction: one pattern for K and M (``fe.general_plan``)
        self.Ks, self.Ms = GeneralPlan(g).map.reduce(K.data, M.data)
        Rm, self.lam_r = sparse_modal._rigid_modes(self.K, self.M, g.rigid, 1e-10, "rigid_motions")
        self.Rm = Rm / np.sqrt(np.einsum("ij,ij->j", Rm, self.M @ Rm))
        self.rigid = g.rigid
        self.lam, self.phi = sparse_modal._dense_modes(self.K, self.M, self.Rm, N_MODES, SIGMA)

    def error(self, lam) -> float:
        """Largest relative frequency difference from dense LAPACK."""
        return float(np.max(np.abs(np.sqrt(np.sort(lam)[:N_MODES] / self.lam) - 1)))


# -- dense routes ---------------------------------------------------------------------------------
def projected(P: Pencil):
    """(Q^T M Q, Q^T (K - sigma M) Q) on the complement of M Rm (``sparse_modal._dense_modes``)."""
    Kd, Md = P.K.toarray(), P.M.toarray()
    (h, tau), _ = sl.qr(Md @ P.Rm, mode="raw")

    def reflect(side, trans, X):
        return sl.lapack.dormqr(side, trans, h, tau, X, lwork=max(1, 64 * X.shape[0]))[0]

    r = P.Rm.shape[1]
    A = reflect("R", "N", reflect("L", "T", Md))[r:, r:]
    B = reflect("R", "N", reflect("L", "T", Kd - SIGMA * Md))[r:, r:]
    return A, B


def dense_driver(A, B, driver):
    m = A.shape[0]
    kw = {"subset_by_index": [m - N_MODES, m - 1]} if driver == "gvx" else {}
    mu = sl.eigh(A, B, driver=driver, eigvals_only=False, check_finite=False, **kw)[0]
    return SIGMA + 1.0 / mu[::-1][:N_MODES]


def dense_standard(A, B, driver):
    m = A.shape[0]
    L = sl.cholesky(B, lower=True, check_finite=False)
    X = sl.solve_triangular(L, A, lower=True, check_finite=False)
    C = sl.solve_triangular(L, X.T, lower=True, check_finite=False)
    mu = sl.eigh(C, driver=driver, subset_by_index=[m - N_MODES, m - 1], check_finite=False)[0]
    return SIGMA + 1.0 / mu[::-1]


def condensed(P: Pencil):
    """(K_c, M_c, Rm_c, massless mask): the massless DOFs condensed out exactly,
    K_c = K_aa - K_am K_mm^-1 K_ma (M has no entries on them)."""
    Kd, Md = P.K.toarray(), P.M.toarray()
    ml = ~np.any(Md != 0, axis=0)
    a = ~ml
    Kmm = sl.cho_factor(Kd[np.ix_(ml, ml)])
    Kc = Kd[np.ix_(a, a)] - Kd[np.ix_(a, ml)] @ sl.cho_solve(Kmm, Kd[np.ix_(ml, a)])
    return Kc, Md[np.ix_(a, a)], P.Rm[a], ml


def dense_condensed(P: Pencil):
    Kc, Mc, Rc, _ = condensed(P)
    lam, _ = sparse_modal._dense_modes(sp.csr_matrix(Kc), sp.csr_matrix(Mc), Rc, N_MODES, SIGMA)
    return lam


# -- iterative routes -----------------------------------------------------------------------------
def beam_krylov(P: Pencil):
    """``fe.eigensolve``'s block Krylov (unconstrained, rigid motions in the start block):
    a function of nothing that returns its eigenvalues (the pattern work done here, once)."""
    A = (P.K - SIGMA * P.M).tocsr()
    A.sort_indices()
    rows = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
    banded = eigensolve.BandedShiftInvert(A.shape[0], rows, A.indices, A.indptr)
    K = sp.csr_matrix((P.K.toarray()[rows, A.indices], A.indices, A.indptr), shape=A.shape)
    M = sp.csr_matrix((P.M.toarray()[rows, A.indices], A.indices, A.indptr), shape=A.shape)
    return lambda: eigensolve.solve_modes(K, M, N_MODES, P.rigid, banded).eigenvalues


def arpack(P: Pencil):
    st = sparse_modal.ModalSettings(n_modes=N_MODES, dense_below=0, rigid_set="rigid_motions")
    return sparse_modal._lanczos_modes(P.K, P.M, P.Rm, st, bordered=True)[0]


def lobpcg(P: Pencil, tol=1e-9, seed=0):
    """LOBPCG on the shift-inverted pencil M x = mu (K - sigma M) x (largest mu; M itself is
    only semi-definite), preconditioned by the banded (K - sigma M)^-1, with the constraint
    Rm^T M x = 0 written as Y^T (K - sigma M) x = 0 for Y = (K - sigma M)^-1 M Rm."""
    A = (P.K - SIGMA * P.M).tocsr()
    chol = es.BandCholesky(A)
    pre = spla.LinearOperator(A.shape, matvec=chol.solve, matmat=chol.solve, dtype=float)
    X = np.random.default_rng(seed).standard_normal((A.shape[0], N_MODES + 4))
    Y = chol.solve(P.M @ P.Rm)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # LOBPCG warns where it stops unconverged
        mu = spla.lobpcg(P.M, X, B=A, M=pre, Y=Y, tol=tol, maxiter=300, largest=True)[0]
    return np.sort(SIGMA + 1.0 / mu)[:N_MODES]


def subspace_iteration(P: Pencil, start, max_it=200):
    """X <- op(X) from ``start`` with Rayleigh-Ritz on span(X) until every wanted mode's
    residual is below tol (``eigen_small``'s test); (lam, iterations)."""
    chol = es.BandCholesky((P.K - SIGMA * P.M).tocsr())
    op = es._constrained_inverse(chol, P.M, P.Rm)
    Qr = np.linalg.qr(P.M @ P.Rm)[0]
    tol, X, empty = es.KrylovSettings().tol, start, np.zeros((start.shape[0], 0))
    for it in range(1, max_it + 1):
        Y, MY = es._m_orthonormal_block(op(X), P.M, empty, empty)
        out = es._rayleigh_ritz(Y, P.K @ Y, MY, Qr, N_MODES, tol)
        if out is not None:
            return es._shift_invert_values(out[1], P.M, op, SIGMA)[0], it
        lam, z = np.linalg.eigh(Y.T @ (P.K @ Y))
        X = Y @ z
    return np.full(N_MODES, np.nan), max_it


# -- parts of the cold block Krylov ---------------------------------------------------------------
def krylov_parts(P: Pencil, repeats: int) -> str:
    st = es.KrylovSettings()
    A = (P.K - SIGMA * P.M).tocsr()
    t_factor = median_ms(lambda: es.BandCholesky((P.K - SIGMA * P.M).tocsr()), repeats)
    t_layout = median_ms(lambda: es.BandLayout(A.shape[0], A.indices, A.indptr), repeats)
    t_shared = median_ms(lambda: es.shifted(P.Ks, P.Ms, SIGMA), repeats)
    chol = es.BandCholesky(A)
    t_border = median_ms(lambda: es._constrained_inverse(chol, P.M, P.Rm), repeats)
    op = es._constrained_inverse(chol, P.M, P.Rm)
    n = A.shape[0]
    Y = np.random.default_rng(0).standard_normal((n, st.block))
    t_op = median_ms(lambda: op(Y), repeats)
    t_solve = median_ms(lambda: chol.solve(Y), repeats)
    k = int(np.ceil(st.ritz_from * N_MODES / st.block) * st.block)
    V, MV = es._m_orthonormal_block(
        np.random.default_rng(1).standard_normal((n, k)), P.M, np.zeros((n, 0)), np.zeros((n, 0))
    )
    KV = P.K @ V
    t_orth = median_ms(lambda: es._m_orthonormal_block(Y, P.M, V[:, :-8], MV[:, :-8]), repeats)
    Qr = np.linalg.qr(P.M @ P.Rm)[0]
    t_rr = median_ms(lambda: es._rayleigh_ritz(V, KV, MV, Qr, N_MODES, 1.0), repeats)
    C = V.T @ KV
    t_eigh = median_ms(lambda: np.linalg.eigh(0.5 * (C + C.T)), repeats)
    t_vals = median_ms(lambda: es._shift_invert_values(V[:, :N_MODES], P.M, op, SIGMA), repeats)
    blocks = k // st.block
    return (
        f"factor (K - sigma M as a sparse sum, its band layout kept, band Cholesky, bandwidth "
        f"{chol.factor.shape[0] - 1}) {t_factor:.2f}, from the data on the shared pattern "
        f"(the solve's, eigen_small.shifted) {t_shared:.2f}, the band layout (RCM order, "
        f"found once per pattern) {t_layout:.2f}; border (Z, S) {t_border:.2f}; operator per "
        f"block of {st.block} {t_op:.2f} (of which band solve {t_solve:.2f}); "
        f"orthonormalization per block {t_orth:.2f}; Rayleigh-Ritz at {k} vectors {t_rr:.2f} "
        f"(of which eigh {t_eigh:.2f}); "
        f"eigenvalues from the operator {t_vals:.2f} [ms]; sum for {blocks} blocks and one "
        f"Rayleigh-Ritz: "
        f"{t_shared + t_border + blocks * (t_op + t_orth) + t_rr + t_vals:.2f} ms"
    )


def _compiled_band_solve():
    """A band Cholesky solve compiled with numba (where it is installed; it is no dependency of
    the package), the right-hand sides in the innermost loop; None without numba."""
    try:
        import numba
    except ImportError:
        return None

    @numba.njit(cache=False)
    def solve(L, B):  # L: dpbtrf's (kd + 1, n) lower band; B (n, k)
        kd1, n = L.shape
        k = B.shape[1]
        X = B.copy()
        for j in range(n):  # L y = b; explicit loops: no temporary arrays
            d = 1.0 / L[0, j]
            for c in range(k):
                X[j, c] *= d
            for i in range(1, min(kd1, n - j)):
                lij = L[i, j]
                for c in range(k):
                    X[j + i, c] -= lij * X[j, c]
        for j in range(n - 1, -1, -1):  # L^T x = y
            for i in range(1, min(kd1, n - j)):
                lij = L[i, j]
                for c in range(k):
                    X[j, c] -= lij * X[j + i, c]
            d = 1.0 / L[0, j]
            for c in range(k):
                X[j, c] *= d
        return X

    return solve


def band_kernels(P: Pencil, repeats: int) -> str:
    """Median CPU [ms] of the band solve with 8 and 20 right-hand sides: LAPACK dpbtrs (one
    dtbsv per column, as ``BandCholesky.solve``) and, where numba is installed, a compiled loop
    over the right-hand sides (the same factor; its largest difference from dpbtrs relative to
    the solution's largest entry)."""
    chol = es.shifted(P.Ks, P.Ms, SIGMA)
    compiled = _compiled_band_solve()
    out = []
    for k in (8, 20):
        B = np.random.default_rng(k).standard_normal((chol.factor.shape[1], k))
        ref = dpbtrs(chol.factor, B, lower=1)[0]
        t_lapack = median_ms(lambda B=B: dpbtrs(chol.factor, B, lower=1), repeats)
        line = f"{k} columns: dpbtrs {t_lapack:.3f}"
        if compiled is not None:
            X = compiled(chol.factor, B)
            diff = np.abs(X - ref).max() / np.abs(ref).max()
            t_loop = median_ms(lambda B=B: compiled(chol.factor, B), repeats)
            line += f", compiled loop {t_loop:.3f} (difference {diff:.0e})"
        out.append(line)
    return "; ".join(out) + (
        "" if compiled is not None else " (numba not installed: no compiled loop)"
    )


def convergence(P: Pencil, blocks: int = 12) -> str:
    """The cold block Krylov's largest relative residual of the 20 wanted modes (its accept
    test) after each block: how many vectors full accuracy needs."""
    st = es.KrylovSettings()
    chol = es.BandCholesky((P.K - SIGMA * P.M).tocsr())
    op = es._constrained_inverse(chol, P.M, P.Rm)
    Qr = np.linalg.qr(P.M @ P.Rm)[0]
    n = P.K.shape[0]
    V = MV = np.zeros((n, 0))
    Y = op(np.random.default_rng(st.seed).standard_normal((n, st.block)))
    out = []
    for _ in range(blocks):
        Y, MY = es._m_orthonormal_block(Y, P.M, V, MV)
        V, MV = np.hstack([V, Y]), np.hstack([MV, MY])
        if V.shape[1] >= N_MODES + 6:
            KV = P.K @ V
            lam, z = np.linalg.eigh(0.5 * (V.T @ KV + KV.T @ V))
            y = z[:, :N_MODES]
            R = KV @ y - (MV @ y) * lam[:N_MODES]
            R = R - Qr @ (Qr.T @ R)
            rel = np.linalg.norm(R, axis=0) / (lam[:N_MODES] * np.linalg.norm(MV @ y, axis=0))
            out.append(f"{V.shape[1]}: {rel.max():.0e}")
        Y = op(Y)
    return ", ".join(out)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument(
        "--deck-dir", type=Path, default=next((d for d in DECKS if d.is_dir()), DECKS[0])
    )
    args = parser.parse_args()
    r = args.repeats
    fe = load_nastran_model(str(args.deck_dir / MAIN), {n: {"binds": b} for n, b in BINDS.items()})
    for factors in FACTORS:
        point(fe, factors, r)


def point(fe, factors, r: int) -> None:
    """Print every route at one parameter point."""
    st = es.KrylovSettings()
    P = Pencil(fe, factors)
    near = Pencil(fe, tuple(a * b for a, b in zip(factors, NEIGHBOUR, strict=True)))
    n, nm = P.K.shape[0], int(np.sum(~np.any(P.M.toarray() != 0, axis=0)))
    print(f"\npoint {factors}: {n} DOFs ({nm} massless), rigid-motion eigenvalues "
          f"{np.array2string(P.lam_r, precision=1)}")  # fmt: skip
    pl = P.phi.astype(np.longdouble)
    Kl, Ml = P.K.toarray().astype(np.longdouble), P.M.toarray().astype(np.longdouble)
    rq = np.einsum("ij,ij->j", pl, Kl @ pl) / np.einsum("ij,ij->j", pl, Ml @ pl)
    print(f"  dense LAPACK eigenvalues vs the longdouble Rayleigh quotients of its vectors: "
          f"largest relative difference {float(np.max(np.abs(P.lam / rq - 1))):.1e}")  # fmt: skip
    A, B = projected(P)
    warm = near.phi
    warm4 = np.hstack([warm, np.random.default_rng(2).standard_normal((n, 4))])
    routes = {
        "dense LAPACK, today's (projection + eigh gvx subset)": (
            lambda: sparse_modal._dense_modes(P.K, P.M, P.Rm, N_MODES, SIGMA)[0]
        ),
        "  its projection alone": lambda: projected(P) and P.lam,
        "  eigh(A, B) gvx subset, projected": lambda: dense_driver(A, B, "gvx"),
        "  eigh(A, B) gvd all, projected": lambda: dense_driver(A, B, "gvd"),
        "  Cholesky + standard eigh evr subset, projected": lambda: dense_standard(A, B, "evr"),
        "  Cholesky + standard eigh evx subset, projected": lambda: dense_standard(A, B, "evx"),
        "dense LAPACK after condensing the massless DOFs": lambda: dense_condensed(P),
        "beam-path block Krylov (fe.eigensolve, tol 1e-4)": beam_krylov(P),
        "ARPACK shift-invert + SuperLU (bordered)": lambda: arpack(P),
        "LOBPCG, shift-inverted, banded preconditioner, tol 1e-9": lambda: lobpcg(P),
        f"block Krylov, eigen_small (block {st.block}, tol {st.tol:g}), cold": (
            lambda: es.krylov_modes(P.K, P.M, P.Rm, N_MODES, SIGMA, st)[0]
        ),
        "block Krylov, eigen_small, warm (neighbour's 20 modes)": (
            lambda: es.krylov_modes(P.K, P.M, P.Rm, N_MODES, SIGMA, st, start=warm)[0]
        ),
        "block Krylov, eigen_small, warm (neighbour's 20 modes + 4)": (
            lambda: es.krylov_modes(P.K, P.M, P.Rm, N_MODES, SIGMA, st, start=warm4)[0]
        ),
        "subspace iteration, warm (neighbour's 20 modes + 4)": (
            lambda: subspace_iteration(P, warm4)[0]
        ),
    }
    for name, fn in routes.items():
        try:
            lam = fn()
        except Exception as exc:  # a route that fails is reported, not fatal
            print(f"  {name:58s} failed: {type(exc).__name__}: {str(exc)[:90]!r}")
            continue
        extra = ""
        if name.startswith("subspace"):
            extra = f" ({subspace_iteration(P, warm4)[1]} iterations)"
        print(f"  {name:58s} {median_ms(fn, r):7.2f} ms CPU, frequencies vs dense "
              f"{P.error(lam):.1e}{extra}")  # fmt: skip
    print(f"  parts of the cold block Krylov, median CPU: {krylov_parts(P, r)}")
    print(f"  its largest relative residual by basis size: {convergence(P)}")
    print(f"  band solve of K - sigma M: {band_kernels(P, r)}")


if __name__ == "__main__":
    main()
