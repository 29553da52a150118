"""Timing helper shared by the benchmarks: the median wall time of repeated calls."""

import time

import numpy as np


def time_median(fn, repeats: int):
    """(median wall time [s] over ``repeats`` calls of ``fn()``, the last call's result)."""
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out
