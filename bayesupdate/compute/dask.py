"""The Dask executor: tasks on the workers of an existing Dask scheduler (``dask[distributed]``,
the optional extra ``bayesupdate[dask]``).

Same contract as ``compute.executors.SerialExecutor.map``: results in submission order
(``Client.gather`` of the futures list), so arrival order cannot change a bit.  The shared
payload is replicated to every worker once per ``map`` (``Client.scatter(broadcast=True)``) and
passed to the tasks as a future, so it is not re-sent per task.  A worker lost mid-run (killed,
pre-empted) has its tasks rescheduled on the others by the scheduler; a task that raised is run
again up to ``retries`` times.  At connection the workers' bayesupdate version must equal the
client's: a different version could compute different numbers, so nothing runs.
"""

import logging
from concurrent.futures import CancelledError

import bayesupdate
from bayesupdate.compute.executors import SerialExecutor
from bayesupdate.errors import BayesUpdateError

CONNECT_TIMEOUT_S = 10
WORKER_TIMEOUT_S = 60
INSTALL = "install it with: pip install 'bayesupdate[dask]'"


def _worker_version() -> str:
    """The bayesupdate version of the process this runs in (on a worker: ``Client.run``)."""
    return bayesupdate.__version__


def client_version() -> str:
    return _worker_version()


def check_versions(client: str, workers: dict) -> None:
    """One-line error when any worker's bayesupdate version (``{address: version}``) is not the
    client's ``client``."""
    for address, version in sorted(workers.items()):
        if version != client:
            raise BayesUpdateError(
                f"Dask worker {address} runs bayesupdate {version}, this client {client}: "
                "install the same bayesupdate version on every worker"
            )


def _call(fn, shared, item):
    return fn(shared, item)


class DaskExecutor(SerialExecutor):
    """Tasks on the workers of the Dask scheduler at ``address`` (module docstring)."""

    kind = "dask"

    def __init__(self, address: str, retries: int = 2):
        try:
            from distributed import Client
        except ImportError:
            raise BayesUpdateError(f"--scheduler needs Dask (distributed); {INSTALL}") from None
        self.address, self.retries = address, int(retries)
        # a lost scheduler is said in one line (``map``): not the client's reconnection
        # attempts (errors with tracebacks) nor the closed comm's notice ("distributed.batched",
        # INFO on distributed's own handler); every level is restored at ``close``
        self._logs = [logging.getLogger(n) for n in ("distributed", "distributed.client")]
        self._log_levels = [log.level for log in self._logs]
        try:
            self.client = Client(address, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise BayesUpdateError(
                f"--scheduler {address}: cannot reach the Dask scheduler "
                f"({type(exc).__name__}); start one with 'dask scheduler' or check the address"
            ) from None
        for log in self._logs:
            log.setLevel(logging.CRITICAL)
        try:
            self._check_workers()
        except BaseException:
            self.close()
            raise

    def _check_workers(self) -> None:
        """At least one worker, every worker importing bayesupdate at the client's version."""
        try:
            self.client.wait_for_workers(1, timeout=WORKER_TIMEOUT_S)
        except (OSError, TimeoutError):
            raise BayesUpdateError(
                f"--scheduler {self.address}: no worker joined within {WORKER_TIMEOUT_S} s; "
                f"start workers with 'dask worker {self.address}'"
            ) from None
        try:
            versions = self.client.run(_worker_version)
        except Exception as exc:  # noqa: BLE001 - any failure on the worker side says the same
            raise BayesUpdateError(
                f"--scheduler {self.address}: the workers cannot import bayesupdate "
                f"({type(exc).__name__}); install bayesupdate {client_version()} on every worker"
            ) from None
        check_versions(client_version(), versions)

    @property
    def workers(self) -> int:
        return len(self.client.scheduler_info(n_workers=-1)["workers"])

    def share(self, obj):
        from distributed import Future

        if obj is None or isinstance(obj, Future):
            return obj
        return self.client.scatter(obj, broadcast=True, hash=False)

    def map(self, fn, items, shared=None, progress=None) -> list:
        items = list(items)
        if not items:
            return []
        handle = self.share(shared)
        try:
            futures = self.client.map(
                _call,
                [fn] * len(items),
                [handle] * len(items),
                items,
                pure=False,
                retries=self.retries,
            )
            return self._gather(futures, progress)
        except (OSError, TimeoutError, CancelledError) as exc:
            # our futures are cancelled by the client when its scheduler connection is lost
            # (``FutureCancelledError``, reason "scheduler-connection-lost"); nobody else
            # cancels them
            raise BayesUpdateError(
                f"--scheduler {self.address}: lost the Dask scheduler mid-run "
                f"({type(exc).__name__}); restart it and run again (sample --out: add --resume)"
            ) from None

    def _gather(self, futures: list, progress) -> list:
        """The futures' results in submission order; ``progress(index, result)`` as each
        finishes.  A task that raised: the first such task's error in submission order."""
        if progress is None:
            return self.client.gather(futures)
        from distributed import as_completed

        index = {future.key: i for i, future in enumerate(futures)}
        results = {}
        # this client is not the default one (``set_as_default=False``): give its loop
        for future in as_completed(futures, loop=self.client.loop):
            if future.status == "finished":
                i = index[future.key]
                results[i] = future.result()
                progress(i, results[i])
        if len(results) < len(futures):
            self.client.gather(futures)  # raises the error of the first failed task
        return [results[i] for i in range(len(futures))]

    def describe(self) -> dict:
        return {"kind": self.kind, "workers": self.workers, "scheduler": self.address}

    def close(self) -> None:
        try:
            self.client.close()
        finally:
            for log, level in zip(self._logs, self._log_levels, strict=True):
                log.setLevel(level)
