"""Progress of long phases: the layers below say what they are doing, the edge chooses how it is
shown.

Code anywhere in the package wraps a phase that can take more than a second or two (a reduced
basis's full solves, the calibration's starts, ...) in ``with phase(name, total, unit) as p:``
and calls ``p.advance()`` per step.  Nothing is shown and nothing is recorded unless the caller
at the edge opened a ``reporting(mode)`` context: the library stays silent for a user's own
scripts and tests, and the CLI shows

- ``"bar"``: a tqdm bar per phase on stderr (a terminal);
- ``"lines"``: one line per phase on stderr when it ends, with its count and wall time (a log,
  a pipe, CI), for phases of ``SHOWN_FROM_S`` seconds or more;
- ``"off"``: nothing (``--quiet``); the phases' wall times are recorded in every mode.

A command writes them (``timings()``: {phase: wall time [s]}) into its result file (the attribute
``timings_json``) and its ``--json`` output; ``silenced()`` hides the phases inside it from the
display but keeps their times (``sample --no-progress``).

Worker processes of an executor have no reporting context: their phases are silent, and the
parent's phase advances as their tasks finish (``executor.map(..., progress=...)``).
"""

import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field

MODES = ("bar", "lines", "off")
#: a phase shorter than this [s] is timed but not shown (short work needs no progress, and a
#: user error found before any long work stays the one line on stderr)
SHOWN_FROM_S = 2.0


@dataclass(frozen=True)
class PhaseTime:
    """One finished phase: its name, steps done, wall time [s]."""

    name: str
    count: int
    wall_s: float


@dataclass
class Recorder:
    """What a ``reporting`` context saw: its mode and the finished phases in order."""

    mode: str
    stream: object = None
    phases: list[PhaseTime] = field(default_factory=list)

    def timings(self) -> dict[str, float]:
        """{phase name: wall time [s]} (a repeated name sums), for result files and --json."""
        out: dict[str, float] = {}
        for p in self.phases:
            out[p.name] = round(out.get(p.name, 0.0) + p.wall_s, 3)
        return out


_ACTIVE: ContextVar[Recorder | None] = ContextVar("bayesupdate_progress", default=None)


def active() -> Recorder | None:
    """The ``Recorder`` of the ``reporting`` context this code runs in, or None (a library
    caller's script, a worker process)."""
    return _ACTIVE.get()


def timings() -> dict[str, float]:
    """{phase name: wall time [s]} of the phases finished so far in the active ``reporting``
    context (``Recorder.timings``), {} outside one: what a command writes into its result file
    and its --json output."""
    recorder = _ACTIVE.get()
    return {} if recorder is None else recorder.timings()


def mode_for(quiet: bool, stream=None) -> str:
    """The mode a command uses: "off" with ``--quiet``, "bar" on a terminal, else "lines"."""
    stream = sys.stderr if stream is None else stream
    if quiet:
        return "off"
    return "bar" if getattr(stream, "isatty", lambda: False)() else "lines"


@contextmanager
def reporting(mode: str, stream=None) -> Iterator[Recorder]:
    """Show the phases run inside (module docstring) on ``stream`` (default stderr); yields the
    ``Recorder`` with their wall times."""
    if mode not in MODES:
        raise ValueError(f"progress mode {mode!r}: one of {MODES}")
    recorder = Recorder(mode, sys.stderr if stream is None else stream)
    token = _ACTIVE.set(recorder)
    try:
        yield recorder
    finally:
        _ACTIVE.reset(token)


@contextmanager
def silenced() -> Iterator[None]:
    """Phases run inside are timed into the active ``reporting`` context but not shown (a
    command's ``--no-progress``); nothing changes outside one."""
    outer = _ACTIVE.get()
    if outer is None:
        yield
        return
    token = _ACTIVE.set(Recorder("off", outer.stream, outer.phases))  # the same list of phases
    try:
        yield
    finally:
        _ACTIVE.reset(token)


class Phase:
    """A running phase: ``advance(n)`` steps; ``count`` so far."""

    def __init__(self, name: str, total: int | None, unit: str, recorder: Recorder | None):
        self.name, self.total, self.unit = name, total, unit
        self.count = 0
        self._bar = None
        if recorder is not None and recorder.mode == "bar":
            from tqdm.auto import tqdm

            self._bar = tqdm(
                total=total, desc=name, unit=unit, file=recorder.stream, leave=False, delay=0.5
            )

    def advance(self, n: int = 1) -> None:
        self.count += n
        if self._bar is not None:
            self._bar.update(n)

    def progress_callback(self):
        """An executor's ``progress(index, result)``: one step per finished task."""
        return lambda _index, _result: self.advance()

    def _close(self) -> None:
        if self._bar is not None:
            self._bar.close()


@contextmanager
def phase(name: str, total: int | None = None, unit: str = "it") -> Iterator[Phase]:
    """A phase of work named ``name`` with ``total`` steps (None: unknown) of ``unit``; shown and
    timed only inside ``reporting`` (module docstring)."""
    recorder = _ACTIVE.get()
    running = Phase(name, total, unit, recorder)
    t0 = time.perf_counter()
    try:
        yield running
    finally:
        running._close()
        if recorder is not None:
            wall = time.perf_counter() - t0
            recorder.phases.append(PhaseTime(name, running.count, wall))
            if recorder.mode in ("bar", "lines") and wall >= SHOWN_FROM_S:
                done = f"{running.count} {unit}" if running.count else "done"
                print(f"{name}: {done} in {wall:.1f} s", file=recorder.stream, flush=True)
