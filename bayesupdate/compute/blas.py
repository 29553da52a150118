"""The BLAS thread settings: the environment variables that fix how many threads a BLAS
(OpenBLAS, MKL, Apple Accelerate), OpenMP or numexpr starts, read once when the library loads.

One tuple, used twice: the CLI sets each to 1 before numpy loads (a user's own setting wins;
the linear algebra here is small, n <= ~1000 and batches of such, so BLAS threads only add
contention), and ``compute.executors.ProcessExecutor`` sets them in its spawned workers (n
processes on n cores with threaded BLAS would only oversubscribe).  This module imports nothing,
so the CLI can read it before numpy is loaded.
"""

BLAS_THREAD_VARIABLES = (
    "OPENBLAS_NUM_THREADS",
    "OMP_NUM_THREADS",
    "MKL_NUM_THREADS",
    "VECLIB_MAXIMUM_THREADS",
    "NUMEXPR_NUM_THREADS",
)
