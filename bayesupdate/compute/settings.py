"""Which executor a run uses (``ComputeSettings``: serial, local processes or a Dask
scheduler) and the executor itself (``open_executor``).

How a command fills the settings in (``--workers``, ``--scheduler``, the study file's
``[compute]`` table, ``BAYESUPDATE_SCHEDULER``): ``config.compute_settings``.
"""

from dataclasses import dataclass

from bayesupdate.compute.dask import DaskExecutor
from bayesupdate.compute.executors import ProcessExecutor, SerialExecutor
from bayesupdate.errors import BayesUpdateError


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


def open_executor(settings: ComputeSettings = SERIAL):
    """The executor of ``settings`` (a context manager; ``close`` it when done).  Dask: connects
    to the scheduler and checks the workers' bayesupdate version (``compute.dask``)."""
    if settings.kind == "dask":
        return DaskExecutor(settings.scheduler, settings.retries)
    if settings.kind == "processes":
        return ProcessExecutor(settings.workers, settings.retries)
    return SerialExecutor()
