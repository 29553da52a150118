"""Batched dense eigen-solves of small reduced free-free pencils, split over threads.

The reduced model (``fe.reduced``) gives, for a batch of B parameter points, pencils
(K_r, M_r) of size r whose first ``n_rigid`` coordinates are the rigid-body motions (K R = 0).
The rigid coordinates are eliminated exactly: the elastic pencil is K_ww x = lambda S x with the
Schur complement S = M_ww - M_wr M_rr^-1 M_rw, and S = L L^T is the trailing block of the Cholesky
factor of M_r (no separate Schur complement is formed).  Standard form C = L^-1 K_ww L^-T, then
the symmetric tridiagonal eigen-solver (LAPACK syevd via numpy's stacked ``eigvalsh`` / ``eigh``).

Why threads: numpy's stacked linear-algebra loops (Cholesky, matmul, eigvalsh, eigh) release the
GIL, so the batch split into contiguous chunks runs on all cores from one process; each matrix is
solved by the same LAPACK calls whatever the split, so the result does not depend on the thread
count (bit for bit).  The triangular inverse (LAPACK trtri, r^3/3 flops, through scipy, which
holds the GIL) is the only serial part.  Why not LAPACK sygvd per matrix: through scipy it holds
the GIL, so it cannot use the second core, and on one core it is no faster (see
``benchmarks/likelihood_speed.py``).

``BAYESUPDATE_SOLVER_THREADS`` sets the thread count; the default is 1.  On the 2-vCPU
development machine two threads gave 1.0-1.35x in wall time on the whole reduced solve over
three runs of ``benchmarks/likelihood_speed.py`` (the eigvalsh kernel alone 1.33x), for 20-50 %
more CPU time: the two vCPUs behave like SMT siblings.  On a machine with free physical cores,
set it to their number.

GPU (optional): when CuPy is installed (the ``gpu`` extra), a CUDA device is visible and the
batch holds at least ``GPU_MIN_BATCH`` points, the batch is solved on the device by the same
steps written against an array module (``solve_on``: stacked Cholesky, triangular inverse by a
stacked solve, stacked ``eigvalsh`` / ``eigh``).  Measured on an H200 against numpy's stacked
``eigvalsh`` on the same machine's CPU (float64, the lowest 20 eigenvalues agreeing to 4e-14):
r = 100, batch 1,024: 52x; batch 32: 7-11x; r = 200, batch 1,024: 12x (``docs/validation/
speed.md``).  ``BAYESUPDATE_GPU=0`` keeps every batch on the CPU.
"""

import functools
import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from scipy.linalg.lapack import dtrtri as _dtrtri

THREADS_VARIABLE = "BAYESUPDATE_SOLVER_THREADS"
GPU_VARIABLE = "BAYESUPDATE_GPU"
#: smallest batch sent to a GPU: 7-11x over the CPU already at 32 points of size 100 (module
#: docstring); below it the host-device transfer and kernel launches are not repaid
GPU_MIN_BATCH = 32
# a thread hand-off costs tens of microseconds: chunks smaller than this run in the caller
MIN_CHUNK = 4


def solver_threads() -> int:
    """Threads for batched solves: ``BAYESUPDATE_SOLVER_THREADS`` (default 1, module docstring)."""
    value = os.environ.get(THREADS_VARIABLE, "").strip()
    try:
        return max(1, int(value)) if value else 1
    except ValueError:
        return 1


@functools.cache
def _executor(n: int) -> ThreadPoolExecutor:
    """The pool of ``n`` threads, made once per process and thread count: a thread start costs
    more than a small batch's solve, so the threads are kept between calls."""
    return ThreadPoolExecutor(max_workers=n, thread_name_prefix="bayesupdate-eig")


def _triangular_inverse(L: np.ndarray) -> np.ndarray:
    """(B, n, n) inverses of lower-triangular factors (LAPACK trtri, n^3/3 flops each)."""
    out = np.empty_like(L)
    for i in range(L.shape[0]):
        out[i], info = _dtrtri(L[i], lower=1)
        if info != 0:
            raise np.linalg.LinAlgError("singular reduced mass matrix")
    return out


def _solve_chunk(K_ww: np.ndarray, M_full: np.ndarray, n_rigid: int, n_modes: int, vectors: bool):
    nr = n_rigid
    M_full = 0.5 * (M_full + M_full.transpose(0, 2, 1))
    # raises LinAlgError for an indefinite reduced mass (a non-physical parameter point)
    L = np.linalg.cholesky(M_full)[:, nr:, nr:]
    L_inv = _triangular_inverse(L)
    C = L_inv @ K_ww @ L_inv.transpose(0, 2, 1)
    C = 0.5 * (C + C.transpose(0, 2, 1))
    if not vectors:
        return np.linalg.eigvalsh(C)[:, :n_modes]
    lam, Z = np.linalg.eigh(C)
    b = L_inv.transpose(0, 2, 1) @ Z[:, :, :n_modes]
    a = -np.linalg.solve(M_full[:, :nr, :nr], M_full[:, :nr, nr:] @ b)
    return lam[:, :n_modes], np.concatenate([a, b], axis=1)


@functools.cache
def _cupy_module():
    """CuPy when it is installed and sees a CUDA device, else None (checked once per process)."""
    try:
        import cupy
    except ImportError:
        return None
    try:
        return cupy if cupy.cuda.runtime.getDeviceCount() > 0 else None
    except Exception:  # noqa: BLE001 - no driver, no device: CuPy raises its own runtime errors
        return None


def gpu_module(batch: int):
    """The array module for a batch of ``batch`` pencils: CuPy when ``_cupy_module`` finds one,
    ``BAYESUPDATE_GPU`` is not "0" and ``batch >= GPU_MIN_BATCH``; else None (the CPU path)."""
    if batch < GPU_MIN_BATCH or os.environ.get(GPU_VARIABLE, "").strip() == "0":
        return None
    return _cupy_module()


def _host(x) -> np.ndarray:
    """A device array copied to the host (CuPy's ``get``); a numpy array as it is."""
    return x.get() if hasattr(x, "get") and not isinstance(x, np.ndarray) else np.asarray(x)


def solve_on(xp, K_ww, M_full, n_rigid: int, n_modes: int, vectors: bool = False):
    """``batched_elastic_eigenvalues`` written against the array module ``xp`` (numpy or cupy):
    the same Cholesky reduction (module docstring) with the triangular inverse by a stacked
    solve against the identity, all on ``xp``'s device; the results are copied to the host.
    Shapes, units and errors as ``batched_elastic_eigenvalues``."""
    nr = n_rigid
    K = xp.asarray(K_ww)
    M = xp.asarray(M_full)
    M = 0.5 * (M + M.transpose(0, 2, 1))
    L = xp.linalg.cholesky(M)[:, nr:, nr:]
    if not bool(xp.all(xp.isfinite(L))):  # CuPy returns NaN where numpy raises
        raise np.linalg.LinAlgError("reduced mass matrix not positive definite")
    eye = xp.broadcast_to(xp.eye(L.shape[1]), L.shape).copy()
    L_inv = xp.linalg.solve(L, eye)
    C = L_inv @ K @ L_inv.transpose(0, 2, 1)
    C = 0.5 * (C + C.transpose(0, 2, 1))
    if not vectors:
        return _host(xp.linalg.eigvalsh(C)[:, :n_modes])
    lam, Z = xp.linalg.eigh(C)
    b = L_inv.transpose(0, 2, 1) @ Z[:, :, :n_modes]
    a = -xp.linalg.solve(M[:, :nr, :nr], M[:, :nr, nr:] @ b)
    return _host(lam[:, :n_modes]), _host(xp.concatenate([a, b], axis=1))


def batched_elastic_eigenvalues(
    K_ww: np.ndarray,
    M_full: np.ndarray,
    n_rigid: int,
    n_modes: int,
    vectors: bool = False,
    threads: int | None = None,
):
    """Lowest elastic eigenvalues of reduced pencils whose first ``n_rigid`` coordinates are the
    rigid-body motions (module docstring).

    K_ww : (B, r_e, r_e) elastic block of K [N/m in reduced units]; M_full : (B, r, r),
    r = n_rigid + r_e.  threads : split the batch over this many threads (default
    ``solver_threads()``; chunks of fewer than ``MIN_CHUNK`` points are not split off).
    Returns (B, n_modes) eigenvalues [rad^2/s^2] ascending and, with ``vectors``, the
    (B, r, n_modes) reduced eigenvectors, mass-normalized (y^T M_r y = 1).
    Raises ``numpy.linalg.LinAlgError`` when a reduced mass matrix is not positive definite.
    A batch of at least ``GPU_MIN_BATCH`` goes to a GPU when CuPy sees one (``gpu_module``).
    """
    B = K_ww.shape[0]
    xp = gpu_module(B)
    if xp is not None:
        return solve_on(xp, K_ww, M_full, n_rigid, n_modes, vectors)
    n = min(threads or solver_threads(), max(1, B // MIN_CHUNK))
    if n <= 1:
        return _solve_chunk(K_ww, M_full, n_rigid, n_modes, vectors)
    bounds = np.linspace(0, B, n + 1).astype(int)
    parts = list(
        _executor(n).map(
            lambda s: _solve_chunk(K_ww[s], M_full[s], n_rigid, n_modes, vectors),
            [slice(lo, hi) for lo, hi in zip(bounds[:-1], bounds[1:], strict=True)],
        )
    )
    if not vectors:
        return np.concatenate(parts)
    return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])
