"""Which executor a run uses (``ComputeSettings``: serial, local processes or a Dask
scheduler) and the executor itself (``open_executor``).

How a command fills the settings in (``--workers``, ``--scheduler``, the study file's
``[compute]`` table, ``BAYESUPDATE_SCHEDULER``): ``config.compute_settings``.
"""

import os
from dataclasses import dataclass

from bayesupdate.compute.dask import DaskExecutor
from bayesupdate.compute.executors import ProcessExecutor, SerialExecutor
from bayesupdate.errors import BayesUpdateError

#: most local worker processes a run may ask for (a typo beyond it: the OS caps processes far
#: lower, and a pool of more fails inside the standard library)
MAX_WORKERS = 1024


@dataclass(frozen=True)
class ComputeSettings:
    """workers : local worker processes (1: serial, in this process).  scheduler : address of a
    Dask scheduler (then ``workers`` is ignored: the cluster has its own).  retries : times a
    task lost with its worker (or, on Dask, a task that raised) is run again."""

    workers: int = 1
    scheduler: str | None = None
    retries: int = 2

    def __post_init__(self):
        if not 1 <= int(self.workers) <= MAX_WORKERS:
            raise BayesUpdateError(
                f"--workers / compute.workers: must be in 1..{MAX_WORKERS}, got {self.workers}"
            )
        if int(self.retries) < 0:
            raise BayesUpdateError(f"compute.retries: must be >= 0, got {self.retries}")

    @property
    def kind(self) -> str:
        """ "serial", "processes" or "dask"."""
        if self.scheduler is not None:
            return "dask"
        return "processes" if self.workers > 1 else "serial"


SERIAL = ComputeSettings()


def open_executor(settings: ComputeSettings = SERIAL):
    """The executor of ``settings`` (a context manager; ``close`` it when done).  Dask: connects
    to the scheduler and checks the workers' bayesupdate version (``compute.dask``)."""
    if settings.kind == "dask":
        return DaskExecutor(settings.scheduler, settings.retries)
    if settings.kind == "processes":
        return ProcessExecutor(settings.workers, settings.retries)
    return SerialExecutor()


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity where the platform has one)."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0)) or 1
    return os.cpu_count() or 1


def a_core_is_free(cores: int | None = None, load: float | None = None) -> bool:
    """Whether a second process would find a core of its own: 2 usable cores or more and the
    last minute's load average (``os.getloadavg``; the platform's, all processes) below
    cores - 0.5.  cores, load: given, instead of this machine's (tests)."""
    cores = usable_cores() if cores is None else int(cores)
    if load is None:
        load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float(cores)
    return cores >= 2 and load < cores - 0.5
