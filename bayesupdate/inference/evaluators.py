"""Point evaluators: batch evaluation on an executor for models without batch support (e.g. a
user's own model).

``PoolEvaluator(model, n_workers)`` runs on ``n_workers`` spawned local processes
(``compute.executors.ProcessExecutor``: BLAS pinned to one thread in every worker, set before the
worker imports numpy, since with n_workers processes on n cores threaded BLAS would only
oversubscribe); ``PoolEvaluator(model, executor=...)`` on any executor (Dask included).  The
model is shared once (``executor.share``), not sent per call.  ``predict_frequencies_batch`` maps
the rows of a parameter batch to the workers in contiguous chunks (results in chunk order) and
returns (B, n_modes) frequencies, NaN rows for points where the model raised or returned
non-finite values, so the evaluator is itself a ``BatchParametricModel`` (emcee
``vectorize=True``).

``PointEvaluator(problem, executor)`` is what the posterior of a model that cannot batch uses
(``LogPosterior(..., executor=...)``): ``problem.evaluate`` (predict and pair) at every walker of
a step on the executor, the problem shared once for the whole run, the evaluations returned in
walker order, so the chain is the serial chain bit for bit.
"""

import os
from collections.abc import Mapping

import numpy as np

from bayesupdate.compute.executors import ProcessExecutor
from bayesupdate.model_protocol import Prediction


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


def _evaluate_chunk(model, args) -> np.ndarray:
    rows, names, n_modes = args
    out = np.full((rows.shape[0], n_modes), np.nan)
    for i, row in enumerate(rows):
        try:
            f = _frequencies(model.predict(dict(zip(names, row, strict=True)), n_modes), n_modes)
        except Exception:  # noqa: BLE001 - a failing point is a NaN row (-inf log-probability)
            continue
        if np.all(np.isfinite(f)):
            out[i] = f
    return out


class PoolEvaluator:
    """Evaluate a ``ParametricModel`` on batches of points in ``n_workers`` processes, or on
    ``executor`` (then not closed here; ``n_workers`` defaults to its worker count).

    Use as a context manager (or call ``close``).  Protocol attributes are forwarded to the model.
    """

    def __init__(self, model, n_workers: int | None = None, executor=None):
        self.model = model
        self.parameter_names = tuple(model.parameter_names)
        if executor is None:
            self.n_workers = int(n_workers or os.cpu_count() or 1)
            self._executor, self._owned = ProcessExecutor(self.n_workers), True
        else:
            self.n_workers = int(n_workers or executor.workers)
            self._executor, self._owned = executor, False
        self._model = self._executor.share(model)

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
        tasks = [(c, tuple(names), n_modes) for c in chunks]
        parts = self._executor.map(_evaluate_chunk, tasks, self._model)
        return np.concatenate(parts, axis=0)

    def close(self) -> None:
        if self._owned:
            self._executor.close()

    def __enter__(self) -> "PoolEvaluator":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _evaluate_points(problem, rows: np.ndarray) -> list:
    """``problem.evaluate`` at each row of ``rows`` (n, d) (an executor task)."""
    return [problem.evaluate(theta) for theta in rows]


class PointEvaluator:
    """``problem.evaluate`` at a batch of points theta (n, d) on ``executor`` -> n Evaluations
    in point order (module docstring): contiguous chunks, one per worker; the problem is shared
    once here, not sent per call."""

    def __init__(self, problem, executor):
        self._executor = executor
        self._workers = max(int(executor.workers), 1)
        self._problem = executor.share(problem)

    def __call__(self, theta: np.ndarray) -> list:
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        if theta.shape[0] == 0:
            return []
        chunks = np.array_split(theta, min(self._workers, theta.shape[0]))
        parts = self._executor.map(_evaluate_points, chunks, self._problem)
        return [evaluation for part in parts for evaluation in part]
