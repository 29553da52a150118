"""Shared test set-up.  The problems here are small (n <= ~1000): BLAS threads only add contention
on a 2-core machine, so tests run single-threaded unless the caller says otherwise."""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import matplotlib  # noqa: E402

matplotlib.use("Agg")
