"""Where independent tasks run: this process or local worker processes (a Dask cluster:
``compute.dask``, same contract).

One seam for every embarrassingly parallel loop (discovery's scan and refits, reduced-basis
snapshots): ``executor.map(fn, items, shared)`` returns ``[fn(shared, item) for item in items]``
in submission order, whatever order the workers finish in, so a seeded run gives the same bits on
every executor (each task is a pure function of ``shared`` and its item; nothing is reduced in
arrival order).  ``fn`` must be a module-level function (it is pickled by reference).
``progress(index, result)``, when given, is called in this process as each task finishes (in
arrival order: for progress lines only, never for the result).

``shared`` (e.g. the FE model and the calibration problem) is sent to each worker once per
``map``, not once per task: local processes read it from one pickle file and keep it in a
per-process cache keyed by a token; Dask replicates it to every worker (``scatter(broadcast=
True)``, ``compute.dask``).

Which executor a run uses: ``compute.settings`` (``ComputeSettings``, ``open_executor``); how a
command chooses it from its options, study file and environment: ``config.compute_settings``.

Local workers are spawned (not forked: the parent may hold BLAS and solver threads) with BLAS
pinned to one thread (``compute.blas.BLAS_THREAD_VARIABLES``): n processes on n cores with
threaded BLAS would only oversubscribe.  A worker process that dies (killed, out of memory)
breaks the pool; the pool is restarted and the unfinished tasks are run again, up to ``retries``
times.
"""

import multiprocessing
import os
import pickle
import signal
import tempfile
import uuid
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path

from bayesupdate.compute.blas import BLAS_THREAD_VARIABLES
from bayesupdate.errors import BayesUpdateError


class SerialExecutor:
    """Every task in this process, in order."""

    kind = "serial"
    workers = 1

    def share(self, obj):
        return obj

    def submit(self, fn, item, shared=None) -> "Finished":
        """``fn(shared, item)``, run now; its ``result()`` (the form of ``ProcessExecutor.
        submit``, so a caller overlaps its own work with a task where there is a worker)."""
        return Finished(fn(shared, item))

    def map(self, fn, items, shared=None, progress=None) -> list:
        results = []
        for i, item in enumerate(items):
            results.append(fn(shared, item))
            if progress is not None:
                progress(i, results[-1])
        return results

    def describe(self) -> dict:
        """The result file's ``"compute"`` record."""
        return {"kind": self.kind, "workers": self.workers}

    def close(self) -> None:
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


@dataclass(frozen=True)
class Finished:
    """A task already run: ``result()`` returns its value (``SerialExecutor.submit``)."""

    value: object

    def result(self):
        return self.value


@dataclass(frozen=True)
class _SharedFile:
    """A shared payload pickled once to ``path``; workers cache it under ``token``."""

    token: str
    path: str


_WORKER_SHARED: dict[str, object] = {}


def _load_shared(handle):
    if not isinstance(handle, _SharedFile):
        return handle
    if handle.token not in _WORKER_SHARED:
        _WORKER_SHARED.clear()  # one payload at a time: a map's model replaces the last one
        _WORKER_SHARED[handle.token] = pickle.loads(Path(handle.path).read_bytes())
    return _WORKER_SHARED[handle.token]


def _run_task(fn, handle, item):
    return fn(_load_shared(handle), item)


class ProcessExecutor(SerialExecutor):
    """``workers`` spawned local processes (module docstring)."""

    kind = "processes"

    def __init__(self, workers: int, retries: int = 2):
        self.workers, self.retries = int(workers), int(retries)
        self._context = multiprocessing.get_context("spawn")
        self._folder = tempfile.TemporaryDirectory(prefix="bayesupdate-shared-")
        self._saved = {k: os.environ.get(k) for k in BLAS_THREAD_VARIABLES}
        # spawned workers inherit the environment at start, before they import numpy; workers
        # are (re)started lazily, so the variables stay set while the executor lives
        os.environ.update({k: "1" for k in BLAS_THREAD_VARIABLES})
        self._pool = self._new_pool()

    def _new_pool(self) -> ProcessPoolExecutor:
        return ProcessPoolExecutor(self.workers, mp_context=self._context)

    def share(self, obj):
        if isinstance(obj, _SharedFile) or obj is None:
            return obj
        token = uuid.uuid4().hex
        path = Path(self._folder.name) / f"{token}.pickle"
        path.write_bytes(pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL))
        return _SharedFile(token, str(path))

    def map(self, fn, items, shared=None, progress=None) -> list:
        items = list(items)
        handle = self.share(shared)
        results: dict[int, object] = {}
        for attempt in range(self.retries + 1):
            if self._attempt(fn, handle, items, results, progress):
                break
            # a worker died: finished results are kept, the rest run again on a new pool
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = self._new_pool()
            if attempt == self.retries:
                raise BayesUpdateError(
                    f"local workers died {self.retries + 1} times (killed, or out of "
                    "memory?); run with fewer --workers"
                )
        return [results[i] for i in range(len(items))]

    def submit(self, fn, item, shared=None):
        """One task ``fn(shared, item)`` on a worker, not waited for: a
        ``concurrent.futures.Future`` (its ``result()`` raises ``BrokenProcessPool`` when the
        worker died; no retry here: the caller can run the task itself).  ``shared``: a handle
        from ``share`` (sent once) or a payload sent with this task."""
        return self._pool.submit(_run_task, fn, self.share(shared), item)

    def _attempt(self, fn, handle, items: list, results: dict, progress) -> bool:
        """Run the items not yet in ``results`` (filled in as they finish); False if the pool
        broke (a worker died).  A task that raised: the first such task's error in submission
        order is raised once every task has finished, whatever order they finished in."""
        todo = [i for i in range(len(items)) if i not in results]
        futures = {self._pool.submit(_run_task, fn, handle, items[i]): i for i in todo}
        broken, errors = False, {}
        for future in as_completed(futures):
            i = futures[future]
            try:
                results[i] = future.result()
            except BrokenProcessPool:
                broken = True
                continue
            except Exception as exc:  # noqa: BLE001 - re-raised below, in submission order
                errors[i] = exc
                continue
            if progress is not None:
                progress(i, results[i])
        if errors:
            raise errors[min(errors)]
        return not broken

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)
        self._folder.cleanup()
        _restore_environment(self._saved)


def _restore_environment(saved: dict) -> None:
    """The environment variables ``saved`` ({name: value, None where unset}) put back as they
    were before an executor set the workers' BLAS threads."""
    for k, v in saved.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v


def executor_or_serial(executor):
    """``executor``, or a serial one when None (library calls without an executor)."""
    return SerialExecutor() if executor is None else executor


def _partner_loop(conn) -> None:
    """A partner process's loop: (fn, shared handle, item) in, (True, result) or (False, error)
    out, until None or the pipe closes.  Ctrl-C is the caller's to handle (a terminal sends it
    to the whole process group): the caller stops, then closes this process."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    while True:
        try:
            message = conn.recv()
        except (EOFError, OSError):
            return
        if message is None:
            return
        fn, handle, item = message
        try:
            reply = (True, fn(_load_shared(handle), item))
        except Exception as exc:  # noqa: BLE001 - sent back, raised in the caller
            reply = (False, exc)
        try:
            conn.send(reply)
        except (pickle.PicklingError, TypeError, AttributeError):
            conn.send((False, RuntimeError(f"{type(reply[1]).__name__}: {reply[1]}")))


class _PipeTask:
    """A task sent to a ``PartnerProcess``: ``result()`` waits for its reply (read once, kept);
    ``done()`` whether the reply has come.  Replies come in the order the tasks were sent, so a
    caller reads each task's result before it sends the next (``PartnerProcess.submit``)."""

    def __init__(self, conn):
        self._conn, self._reply = conn, None

    def done(self) -> bool:
        return self._reply is not None or self._conn.poll()

    def result(self):
        if self._reply is None:
            try:
                self._reply = self._conn.recv()
            except (EOFError, OSError) as exc:
                raise BrokenProcessPool(f"the partner process died: {exc}") from None
        ok, value = self._reply
        if not ok:
            raise value
        return value


class PartnerProcess(ProcessExecutor):
    """One spawned local process that runs one task at a time, sent over a pipe: the hand-off
    for work split between this process and one other (a sampler's walker batches,
    ``inference.evaluators.SplitDensity``).  A pool's hand-off goes through its management
    thread, whose wake-ups cost this process 1-3 ms a task on a loaded machine; a pipe costs it
    the two pickles.  BLAS pinned to one thread as in ``ProcessExecutor``; ``share`` as there.
    ``map`` runs its tasks one after the other there."""

    kind = "partner"

    def __init__(self):
        self.workers, self.retries = 1, 0
        self._context = multiprocessing.get_context("spawn")
        self._folder = tempfile.TemporaryDirectory(prefix="bayesupdate-shared-")
        self._saved = {k: os.environ.get(k) for k in BLAS_THREAD_VARIABLES}
        os.environ.update({k: "1" for k in BLAS_THREAD_VARIABLES})
        self._conn, child = self._context.Pipe()
        self._process = self._context.Process(target=_partner_loop, args=(child,), daemon=True)
        self._process.start()
        child.close()

    def submit(self, fn, item, shared=None) -> _PipeTask:
        """Send ``fn(shared, item)`` to the partner; read the returned task's ``result()``
        before the next ``submit``.  Raises ``BrokenProcessPool`` when the partner is gone."""
        try:
            self._conn.send((fn, self.share(shared), item))
        except (OSError, ValueError) as exc:
            raise BrokenProcessPool(f"the partner process is gone: {exc}") from None
        return _PipeTask(self._conn)

    def map(self, fn, items, shared=None, progress=None) -> list:
        handle = self.share(shared)
        results = []
        for i, item in enumerate(items):
            results.append(self.submit(fn, item, handle).result())
            if progress is not None:
                progress(i, results[-1])
        return results

    def close(self) -> None:
        try:
            self._conn.send(None)
        except (OSError, ValueError):
            pass
        self._process.join(timeout=10)
        if self._process.is_alive():
            self._process.kill()
        self._conn.close()
        self._folder.cleanup()
        _restore_environment(self._saved)
