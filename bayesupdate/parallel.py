"""Process pool for models without batch support (e.g. a user's own model function).

``PoolEvaluator(model, n_workers)`` spawns the workers once, sends the model once (pool
initializer, so a large FE model is pickled n_workers times, not once per call) and pins BLAS to one
thread in every worker (the variables are set before the worker imports numpy: with n_workers
processes on n cores, threaded BLAS would only oversubscribe).  ``predict_frequencies_batch`` maps
the rows of a parameter batch to the workers in contiguous chunks and returns (B, n_modes)
frequencies, NaN rows for points where the model raised or returned non-finite values, so the
evaluator is itself a ``BatchParametricModel`` (emcee ``vectorize=True``).
"""

import multiprocessing as mp
import os
from collections.abc import Mapping

import numpy as np

from bayesupdate.model_protocol import Prediction

BLAS_THREAD_VARIABLES = (
    "OPENBLAS_NUM_THREADS",
    "OMP_NUM_THREADS",
    "MKL_NUM_THREADS",
    "VECLIB_MAXIMUM_THREADS",
    "NUMEXPR_NUM_THREADS",
)

_WORKER_MODEL = None


def _init_worker(model) -> None:
    global _WORKER_MODEL
    _WORKER_MODEL = model


def _frequencies(result, n_modes: int) -> np.ndarray:
    """Frequencies from a Prediction, a mapping with ``frequencies_hz`` or an array."""
    if isinstance(result, Prediction):
        f = result.frequencies_hz
    elif isinstance(result, Mapping):
        f = result["frequencies_hz"]
    else:
        f = result
    f = np.asarray(f, dtype=float).reshape(-1)
    if f.size < n_modes:
        raise ValueError(f"model returned {f.size} frequencies, {n_modes} wanted")
    return f[:n_modes]


def _evaluate_chunk(args) -> np.ndarray:
    rows, names, n_modes = args
    out = np.full((rows.shape[0], n_modes), np.nan)
    for i, row in enumerate(rows):
        try:
            f = _frequencies(
                _WORKER_MODEL.predict(dict(zip(names, row, strict=True)), n_modes), n_modes
            )
        except Exception:  # noqa: BLE001 - a failing point is a NaN row (-inf log-probability)
            continue
        if np.all(np.isfinite(f)):
            out[i] = f
    return out


class PoolEvaluator:
    """Evaluate a ``ParametricModel`` on batches of points in ``n_workers`` processes.

    Use as a context manager (or call ``close``).  Protocol attributes are forwarded to the model.
    """

    def __init__(self, model, n_workers: int | None = None):
        self.model = model
        self.parameter_names = tuple(model.parameter_names)
        self.n_workers = int(n_workers or os.cpu_count() or 1)
        saved = {k: os.environ.get(k) for k in BLAS_THREAD_VARIABLES}
        # spawned workers inherit the environment at start, before they import numpy
        os.environ.update({k: "1" for k in BLAS_THREAD_VARIABLES})
        try:
            ctx = mp.get_context("spawn")
            self._pool = ctx.Pool(self.n_workers, initializer=_init_worker, initargs=(model,))
        finally:
            for k, v in saved.items():
                if v is None:
                    os.environ.pop(k, None)
                else:
                    os.environ[k] = v

    def default_parameters(self) -> dict[str, float]:
        return self.model.default_parameters()

    def default_bounds(self) -> dict[str, tuple[float, float]]:
        return self.model.default_bounds()

    def predict(self, params, n_modes: int = 12):
        return self.model.predict(params, n_modes)

    def predict_frequencies_batch(
        self, theta: np.ndarray, names: tuple[str, ...], n_modes: int = 12
    ) -> np.ndarray:
        """(B, n_modes) frequencies [Hz] for theta (B, len(names)); NaN rows for failed points."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        chunks = np.array_split(theta, min(self.n_workers, max(theta.shape[0], 1)))
        parts = self._pool.map(_evaluate_chunk, [(c, tuple(names), n_modes) for c in chunks])
        return np.concatenate(parts, axis=0)

    def close(self) -> None:
        self._pool.close()
        self._pool.join()

    def __enter__(self) -> "PoolEvaluator":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
