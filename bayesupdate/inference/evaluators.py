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

``split_densities((exact, screen), executor)`` is what a sampler on a batched model uses with a
local worker (``sampling.sample_posterior(..., executor=...)``): each batch of
``SPLIT_MIN_POINTS`` walkers or more is cut in two halves, the first evaluated in this process
while a worker evaluates the rest, the values back in row order and the worker's evaluations
counted here, so the chain is the serial chain bit for bit: the reduced solve's products over
the batch give each point the same bits in any batch (``compute.batch_rows``), and the first
split batch of a run is checked against the whole batch.  ``split_pays``: whether a density's
batches cost enough to repay the hand-off.
"""

import os
import pickle
import time
from collections.abc import Mapping
from concurrent.futures.process import BrokenProcessPool

import numpy as np

from bayesupdate.compute.batch_rows import MIN_ROWS
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


#: the counters of a ``LogPosterior`` that a worker's share of a batch adds to (``_remote_part``)
SPLIT_COUNTERS = ("evaluations", "failed", "pair_checked", "pair_differs")
#: the fewest points a batch is split at.  Until 2026-11-29 the cut had to fall at a multiple
#: of 8 rows (where the earlier machine's OpenBLAS rounded a row as in the whole batch), so only
#: batches of 16 or more were split; the SkylakeX kernels round rows in blocks of 12, which
#: stopped every split of ``sample --model exhaust --data paper:ema`` at its first check.  With
#: the products made independent of the batch (``compute.batch_rows``, for batches of
#: ``MIN_ROWS`` = 5 rows or more: each part of a split batch has that many) any cut gives the
#: whole batch's bits, and the delayed-acceptance batches that survive the screen (6-16 points
#: of the exhaust's exact posterior, 0.46 ms each) are split too: with the least at 8 that
#: command took 14.7-15.0 s against 15.3-15.5 s with the least at 16 (3 runs each,
#: alternated, the same chain)
SPLIT_MIN_POINTS = 2 * MIN_ROWS
#: points of the batch ``split_pays`` times
SPLIT_PROBE_POINTS = 16


#: the CPU a batch of ``SPLIT_PROBE_POINTS`` must cost before a sampler splits its batches with
#: a worker of its own (``split_pays``): the hand-off costs this process about 1-2 ms a batch on
#: the loaded 2-core machine (the exhaust's screened batch of 16 on a partner process: 4.7 ms
#: split against 7.0 ms whole, ``benchmarks/posterior_speed.py --split-batches``), so a batch
#: must cost several times that for its other half to repay it
SPLIT_PAYS_S = 5e-3


def split_pays(density, theta: np.ndarray) -> bool:
    """Whether a batch of ``SPLIT_PROBE_POINTS`` copies of the point theta (d,) costs ``density``
    at least ``SPLIT_PAYS_S`` of this process's CPU (the density's counters are left as they
    were).  The exhaust's reduced posterior: about 15 ms; an analytic test model: microseconds.
    """
    batch = np.tile(np.asarray(theta, dtype=float), (SPLIT_PROBE_POINTS, 1))
    c0 = time.process_time()
    _uncounted(density, batch)
    return time.process_time() - c0 >= SPLIT_PAYS_S


def _counters(density) -> dict:
    """{counter: value} of ``density``'s ``SPLIT_COUNTERS`` (those it has)."""
    return {k: getattr(density, k) for k in SPLIT_COUNTERS if hasattr(density, k)}


def _uncounted(density, theta: np.ndarray) -> np.ndarray:
    """``density(theta)`` with its counters left as they were (a check, not a sampler's call)."""
    saved = _counters(density)
    values = np.asarray(density(theta), dtype=float)
    for name, value in saved.items():
        setattr(density, name, value)
    return values


def split_point(n: int) -> int:
    """Where a batch of n points is cut (its first part stays in this process): half, the
    larger half here when n is odd (this process also hands the other part over and back);
    0 (not split) below ``SPLIT_MIN_POINTS``."""
    return 0 if n < SPLIT_MIN_POINTS else (n + 1) // 2


def _loaded(densities, _item) -> int:
    """Nothing but loading the shared densities (a worker's warm-up task)."""
    return len(densities)


def _remote_part(densities, item) -> tuple:
    """(values (n,), counter increments, last error) of ``densities[which]`` at theta (n, d)
    (an executor task; item: (which, theta))."""
    which, theta = item
    density = densities[which]
    before = _counters(density)
    values = density(theta)
    counts = {k: getattr(density, k) - v for k, v in before.items()}
    return values, counts, getattr(density, "last_error", "")


class SplitDensity:
    """A vectorized log-density (n, d) -> (n,) whose larger batches are evaluated in two parts
    at once: the first ``split_point(n)`` rows in this process, the rest on a local worker
    process, values returned in row order.  The counters of the density (``SPLIT_COUNTERS``)
    count the worker's points too.  Made by ``split_densities``; a worker that died (killed,
    out of memory) ends the splitting: from then on every batch runs here, with the same
    values."""

    def __init__(self, density, which: int, executor, handle, ready=None):
        self.density = density
        self._which, self._executor, self._handle = which, executor, handle
        # the worker's warm-up task (start, imports, the payload): until it is done every
        # batch runs here, so the run never waits on a worker that is still starting
        self._ready = ready
        self.splits = 0
        self.checked = False
        self.stopped = ""

    def __getattr__(self, name):
        # everything else (names, ndim, problem, counters) is the density's own
        return getattr(self.density, name)

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        h = split_point(theta.shape[0]) if self._executor is not None else 0
        if h == 0 or not self._started() or self._executor is None:  # (a dead worker)
            return self.density(theta)
        try:
            future = self._executor.submit(_remote_part, (self._which, theta[h:]), self._handle)
        except BrokenProcessPool:
            self._executor = None
            return self.density(theta)
        head = np.asarray(self.density(theta[:h]), dtype=float)
        try:
            tail, counts, error = future.result()
        except BrokenProcessPool:
            self._executor = None
            return np.concatenate([head, self.density(theta[h:])])
        for name, increment in counts.items():
            setattr(self.density, name, getattr(self.density, name) + increment)
        if error and hasattr(self.density, "last_error"):
            self.density.last_error = error
        values = np.concatenate([head, tail])
        if not self.checked:
            values = self._check(theta, values)
        self.splits += 1
        return values

    def wait_started(self) -> None:
        """Wait for the worker's warm-up (a caller that wants the next batch split)."""
        if self._ready is not None:
            self._ready.result()

    def _started(self) -> bool:
        """Whether the worker has finished its warm-up (False while it is still starting); its
        reply is read here, before any batch is sent."""
        if self._ready is None:
            return True
        if not self._ready.done():
            return False
        try:
            self._ready.result()
        except BrokenProcessPool:
            self._executor = None
        self._ready = None
        return True

    def _check(self, theta: np.ndarray, values: np.ndarray) -> np.ndarray:
        """The first split batch evaluated whole here too, uncounted: the same bits, or this
        density rounds a row by its place in the batch (a user's model with its own products
        over the batch; ``compute.batch_rows``) and splitting stops (``stopped`` says why);
        the whole batch's values either way."""
        whole = _uncounted(self.density, theta)
        self.checked = True
        if not np.array_equal(whole, values, equal_nan=True):
            self._executor = None
            self.stopped = "a split batch differs from the whole batch in the last bits"
        return whole


def split_densities(densities: tuple, executor) -> tuple:
    """Each of ``densities`` (vectorized log-densities, e.g. a run's exact posterior and its
    delayed-acceptance screen; None entries stay None) as a ``SplitDensity`` on ``executor``,
    all shared with the workers in one payload (a worker keeps one payload at a time).  The
    densities as they are when the executor has no local worker processes, one of them sends
    its points to the executor already (``LogPosterior.on_executor``), or they cannot be
    pickled.  Share them in their
    final form: a worker evaluates the copy it was sent."""
    if executor is None or getattr(executor, "kind", "serial") not in ("processes", "partner"):
        return densities
    if any(getattr(d, "on_executor", False) for d in densities):
        return densities  # its points are spread over the workers already
    try:
        handle = executor.share(tuple(densities))
    except (pickle.PicklingError, TypeError, AttributeError):
        return densities  # e.g. a user's model holding a lock or an open file: not sent
    try:
        ready = executor.submit(_loaded, None, handle)  # it starts while this one works on
    except BrokenProcessPool:
        return densities  # the worker is gone already
    return tuple(
        None if d is None else SplitDensity(d, i, executor, handle, ready)
        for i, d in enumerate(densities)
    )
