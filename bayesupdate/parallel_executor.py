"""Where independent tasks run: this process, local worker processes, or a Dask cluster.

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
True)``, ``parallel_dask``).

Which executor (``ComputeSettings``, ``compute_settings``): ``--workers N`` (N local processes,
N = 1 serial), ``--scheduler ADDRESS`` (an existing Dask scheduler), else the study file's
``[compute]`` table (``workers`` or ``scheduler``), else the ``BAYESUPDATE_SCHEDULER`` environment
variable, else serial.

Local workers are spawned (not forked: the parent may hold BLAS and solver threads) with BLAS
pinned to one thread (``parallel.BLAS_THREAD_VARIABLES``): n processes on n cores with threaded
BLAS would only oversubscribe.  A worker process that dies (killed, out of memory) breaks the
pool; the pool is restarted and the unfinished tasks are run again, up to ``retries`` times.
"""

import os
import pickle
import re
import tempfile
import uuid
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path

from bayesupdate.errors import BayesUpdateError
from bayesupdate.parallel import BLAS_THREAD_VARIABLES

SCHEDULER_VARIABLE = "BAYESUPDATE_SCHEDULER"
# tcp://host:port, tls://host:port, or host:port (Dask's default protocol is tcp)
_ADDRESS = re.compile(r"^(?:(tcp|tls|ucx|ws|wss)://)?(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._-]+):(\d+)$")


def check_address(address: str, where: str = "--scheduler") -> str:
    """The Dask scheduler ``address`` if well formed (``[tcp://]host:port``), else a one-line
    error naming ``where`` it came from."""
    text = str(address).strip()
    match = _ADDRESS.match(text)
    if match is None or not 0 < int(match.group(3)) < 65536:
        raise BayesUpdateError(
            f"{where}: {address!r} is not a Dask scheduler address; give tcp://HOST:PORT "
            "(e.g. tcp://head:8786)"
        )
    return text if match.group(1) else f"tcp://{text}"


@dataclass(frozen=True)
class ComputeSettings:
    """workers : local worker processes (1: serial, in this process).  scheduler : address of a
    Dask scheduler (then ``workers`` is ignored: the cluster has its own).  retries : times a
    task lost with its worker (or, on Dask, a task that raised) is run again."""

    workers: int = 1
    scheduler: str | None = None
    retries: int = 2

    def __post_init__(self):
        if int(self.workers) < 1:
            raise BayesUpdateError(f"--workers / compute.workers: must be >= 1, got {self.workers}")
        if int(self.retries) < 0:
            raise BayesUpdateError(f"compute.retries: must be >= 0, got {self.retries}")

    @property
    def kind(self) -> str:
        """ "serial", "processes" or "dask"."""
        if self.scheduler is not None:
            return "dask"
        return "processes" if self.workers > 1 else "serial"


SERIAL = ComputeSettings()


def parse_compute_table(table, where: str) -> ComputeSettings:
    """The study file's ``[compute]`` table: ``workers = N`` or ``scheduler = "tcp://..."``
    (not both), optional ``retries``."""
    unknown = sorted(set(table) - {"workers", "scheduler", "retries"})
    if unknown:
        raise BayesUpdateError(
            f"{where}.{unknown[0]}: unknown key; valid keys are ['retries', 'scheduler', 'workers']"
        )
    for key in ("workers", "retries"):
        if key in table and (isinstance(table[key], bool) or not isinstance(table[key], int)):
            raise BayesUpdateError(f"{where}.{key}: must be an integer, got {table[key]!r}")
    if "workers" in table and "scheduler" in table:
        raise BayesUpdateError(f"{where}: give workers or scheduler, not both")
    scheduler = table.get("scheduler")
    if scheduler is not None:
        scheduler = check_address(scheduler, f"{where}.scheduler")
    return ComputeSettings(table.get("workers", 1), scheduler, table.get("retries", 2))


def compute_settings(
    workers: int | None = None,
    scheduler: str | None = None,
    study: ComputeSettings | None = None,
    environ=None,
) -> ComputeSettings:
    """The executor settings of a command: ``--workers``/``--scheduler`` (not both), else the
    study file's ``[compute]``, else ``BAYESUPDATE_SCHEDULER``, else serial."""
    if workers is not None and scheduler is not None:
        raise BayesUpdateError("give --workers (local processes) or --scheduler (Dask), not both")
    retries = (study or SERIAL).retries
    if workers is not None:
        if workers < 1:
            raise BayesUpdateError(f"--workers: must be >= 1, got {workers}")
        return ComputeSettings(workers, None, retries)
    if scheduler is not None:
        return ComputeSettings(1, check_address(scheduler), retries)
    if study is not None and study != SERIAL:
        return study
    env = (os.environ if environ is None else environ).get(SCHEDULER_VARIABLE, "").strip()
    if env:
        return ComputeSettings(1, check_address(env, SCHEDULER_VARIABLE), retries)
    return SERIAL


class SerialExecutor:
    """Every task in this process, in order."""

    kind = "serial"
    workers = 1

    def share(self, obj):
        return obj

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
        import multiprocessing as mp

        self.workers, self.retries = int(workers), int(retries)
        self._context = mp.get_context("spawn")
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
        for k, v in self._saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def open_executor(settings: ComputeSettings = SERIAL):
    """The executor of ``settings`` (a context manager; ``close`` it when done).  Dask: connects
    to the scheduler and checks the workers' bayesupdate version (``parallel_dask``)."""
    if settings.kind == "dask":
        from bayesupdate.parallel_dask import DaskExecutor

        return DaskExecutor(settings.scheduler, settings.retries)
    if settings.kind == "processes":
        return ProcessExecutor(settings.workers, settings.retries)
    return SerialExecutor()


def executor_or_serial(executor):
    """``executor``, or a serial one when None (library calls without an executor)."""
    return SerialExecutor() if executor is None else executor
