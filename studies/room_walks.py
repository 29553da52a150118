"""Walks: how often a ``discover`` and a ``sample`` run cross from one room of the package into
another, and how often such a crossing climbs back up the layers.

A room is a top-level directory of ``bayesupdate/`` (``fe``, ``inference``, ``compute``, ...) or a
top-level module (``config``, ``cli``, the core's ``errors``, ``correlation``, ...).  The rooms'
layers, bottom to top, are pyproject.toml's (``[tool.importlinter]``): core, compute, fe/ema/
testgeom, models/nastran/inference, discovery, config, pipelines, edge (commands, cli, report).

The tracer is ``sys.setprofile``: on every Python function call the callee's room is that of its
source file; the caller's room is that of the innermost calling frame in ``bayesupdate/``
(frames of numpy, scipy or emcee in between are skipped: emcee calling our log-density is a
call from the sampler's room).  Calls of compiled functions are not seen.  A call from one room
into another is a crossing; the crossing *enters* the callee's room, and *climbs back up* when
the callee's layer is above the caller's (a lower room calling a higher one: a callback, e.g.
an executor running a task function).  A module body run at its import (``<module>``), and
what it calls, is not a crossing: where a module is first imported says nothing of the walk.
Each crossing is counted twice: as events (every call; a loop of 500 sampler steps calling the
model is 500 events) and as call sites (distinct pairs of calling function and called function:
the same loop is one site).  The walk's shape is the call sites; the events say how hot each
site is.

A climb is either *named* (the lower room's code names the higher function: it imports it,
perhaps late, which is a cycle the layer contracts would refuse at the top of a module) or a
*callback* (the function object was handed down: the caller's frame holds it in a local or
closure variable, e.g. the ``fn`` an executor's ``map`` was given, or the residual function a
fit was given).  A callback keeps the lower room ignorant of the higher one (dependency
inversion); the table gives both, and the site list marks each climb ``UP`` (named) or ``cb``.

Runs, through the CLI in this process (the user's path):
- ``discover`` of the exhaust against the paper's test frequencies (``paper:ema``), added masses
  only, one baseline start, three quick refits, one full refit (``tests/test_parallel_executor``'s
  small discovery);
- ``sample`` of the exhaust against the same data, 16 walkers, 60 steps, DE moves, 2 starts.

Issue 38 asks that a run "enter each room at most twice and climb back up at most twice" and
leaves the counting open.  Three readings are measured:

- **the path reading** (``path_walk``): a walk is the stack from the command down to a call, its
  rooms in order (consecutive frames of one room merged).  Per path, the times a room occurs and
  the steps up a layer; the most over every path of the run.  A loop makes one path, however
  often it runs;
- **the per-pair reading** (``doors``, below): per run, each pair of rooms is crossed at no more
  than two call sites;
- **the sequence reading** (``sequence_walk``): every function of the package in the order of its
  first call, consecutive ones of a room merged into stays; per room its stays, and the stays in
  a higher layer than the one before as climbs.  It counts every return to a caller's room that
  then calls a function it had not called before, so a function that calls a lower room and
  then a helper of its own climbs once: layered code of any shape climbs often.

The per-pair reading is:  per run, each pair of rooms (caller room ->
callee room) is crossed at no more than two call sites.  Per pair, not per room: the bottom
rooms (``compute``, the core's ``modal_data``) are entered from every room above them by design,
so a per-room total counts clients, while a caller that walks into one room many times to do
one thing shows in its pair.  Sites, not events: a loop of 500 sampler steps is one site.  A
site whose callee is a property getter (``ModalData.n_modes``, ``CalibrationProblem.names``) is
a read of a record handed down, marked ``rd`` and counted apart: "work sites" leave it out.

A climbing site whose callee is a protocol method its caller's line does not name (``pickle``
running an object's ``__reduce__`` inside an executor's ``share``) is a callback too: the object
was handed down.

Measured (this script): discover enters 11 rooms and climbs at 2 sites (26 events), both
executor callbacks (``discovery.workflow:discovery_task``, ``inference.optimize:_fit_start``);
sample enters 10 rooms and climbs at 3 sites (7 events), all callbacks: ``_fit_start``,
``fe.reduced.basis:_solve_point`` and ``fe.assembly:ElementProperties.__reduce__`` (the split
worker's share of the model; it had 2 sites before the split worker, and 4 while the pairing's
reference memo lived in ``pipelines``: ``inference.problem`` called it back up, and it is
``fe.reference_memo`` now, an FE solve's memo beside the FE model).  Before discovery had one
task entry and built its refits' residual function itself, discover climbed at 5 sites (388
events): three discovery task functions, ``_fit_start`` and inference's
``unit_box_residuals`` calling discovery's ``residuals_at``.

Pairs crossed at more than two sites, before -> after the commands were thinned (the study's
overrides in one ``config.with_overrides``, the move scheme checked in ``pipelines.study.prepare``,
the mass properties at the posterior mean computed by the pipeline) and the mass keys got one
reader (``pipelines.study.study_mass_terms``):
- discover: 27 pairs crossed, 13 at more than two sites (12 at more than two work sites), 151
  sites, 126 work sites; unchanged.  Worst: discovery -> inference 46 sites (31 work), models
  -> fe 31, discovery -> compute 10, inference -> compute 7, inference -> fe 6; of the
  pipelines' and commands' own pairs: pipelines -> compute 4 (open_executor and the executor's
  ``with`` and ``describe``), pipelines -> inference 4, pipelines -> config 4 (3 work),
  pipelines -> discovery 3, commands -> config 3.
- sample: 24 pairs, 12 at more than two sites, 11 -> 10 at more than two work sites; 156 -> 154
  sites, 123 -> 121 work sites (181 sites, 140 work sites with the split worker and the
  reference memo, 2026-11-29).  commands -> config 5 -> 3 sites (``load_study``,
  ``with_overrides``, ``compute_settings``), commands -> inference 5 -> 3 sites (3 -> 1 work:
  ``ModePairing.to_dict``; the other two are property reads), pipelines -> inference 30 -> 32
  sites (22 -> 24 work: the move check and the mass report moved there from the command).
  Worst: models -> fe 31 (the exhaust's ``StructureBuilder`` calls), pipelines -> inference
  32, inference -> fe 15, inference -> compute 14, pipelines -> fe 12 (4 work), fe -> compute 8.

The three readings, before the rooms of issue 38 (6a78c33, ``--legacy-rooms``: its parallel,
parallel_executor, parallel_dask and interrupts modules in the compute layer) and now
(2026-11-30); the package also grew between them (a discover run first-calls 377 functions
then, 496 now):
- path: discover, a room at most 3 times on one path (``discovery > parallel_executor >
  discovery > inference > discovery``) and 2 climbs -> 2 and 1; sample 2 and 1 -> 2 and 1.
  ``tests/test_room_walks.py`` holds both runs to at most 2 and 2, with every climb a callback;
- climbing sites over the run: discover 5 -> 2; sample 3 -> 3 (a callback each; one is pickle
  running ``ElementProperties.__reduce__`` as the split worker's share is written);
- per pair: discover 10 -> 13 pairs over two sites, sample 10 -> 12;
- sequence: discover 90 stays in 14 rooms and 40 climbs -> 102 in 12 and 46; sample 100 in 13
  and 47 -> 135 in 11 and 63.

Run: .venv/bin/python studies/room_walks.py [--sites] [--legacy-rooms]
(--sites: list every crossing site; for 6a78c33, check it out and put it first on PYTHONPATH)
"""

import argparse
import contextlib
import functools
import inspect
import io
import linecache
import sys
import tempfile
from collections import Counter
from itertools import pairwise
from pathlib import Path

import bayesupdate
from bayesupdate.cli import main as cli

PACKAGE = Path(bayesupdate.__file__).resolve().parent
CORE = (
    "errors",
    "units",
    "atomic",
    "modal_data",
    "model_protocol",
    "correlation",
    "uff_read",
    "paper",
)
#: layer of each room, bottom (0) to top (pyproject.toml's [tool.importlinter] comment)
LAYERS = {
    **dict.fromkeys(("bayesupdate", *CORE), 0),
    "compute": 1,
    **dict.fromkeys(("fe", "ema", "testgeom"), 2),
    **dict.fromkeys(("models", "nastran", "inference"), 3),
    "discovery": 4,
    "config": 5,
    "pipelines": 6,
    **dict.fromkeys(("commands", "cli", "report", "plotting", "__main__"), 7),
}

#: the top-level modules that held the compute room's work before it had one (6a78c33)
LEGACY_COMPUTE = ("parallel", "parallel_executor", "parallel_dask", "interrupts")

DISCOVERY_STUDY = """
[model]
source = "exhaust"
[data]
source = "paper:ema"
[discovery]
kinds = ["added_mass"]
baseline_starts = 1
quick_refits = 3
per_kind = 1
max_refits = 1
max_nfev = 8
loo_top = 1
loo_draws = 100
"""

SAMPLE_STUDY = """
[model]
source = "exhaust"
[data]
source = "paper:ema"
[optimizer]
starts = 2
[sampler]
walkers = 16
steps = 60
check_every = 30
min_autocorr_times = 1e9
moves = "de"
predictive_draws = 20
"""


def room_of(filename: str) -> str | None:
    """The room of a source file, None outside the package."""
    try:
        parts = Path(filename).resolve().relative_to(PACKAGE).parts
    except ValueError:
        return None
    if len(parts) == 1:
        return "bayesupdate" if parts[0] == "__init__.py" else parts[0].removesuffix(".py")
    return parts[0]


class WalkTracer:
    """A ``sys.setprofile`` function that records every crossing between rooms (module
    docstring): ``events[(from, to)]`` and ``sites[(from, to)]`` = {(caller, callee)}."""

    def __init__(self):
        self._rooms: dict = {}
        self.events: Counter = Counter()
        self.sites: dict[tuple[str, str], set] = {}
        #: climbing sites whose callee the caller was handed (module docstring)
        self.callbacks: set = set()
        #: sites whose callee is a property getter: a record's field read, not work
        self.reads: set = set()
        #: the path reading: rooms on the stack from the command down to each call
        #: (consecutive frames of one room merged), with how often each path was called
        self.paths: Counter = Counter()
        #: the sequence reading: each function's room, in the order of its first call
        self.first: list[str] = []
        self._seen: set = set()
        #: per running Python frame, its path (None inside an import), kept by call and return
        self._stack: list[tuple[str, ...] | None] = []

    def _room(self, code) -> str | None:
        room = self._rooms.get(code, False)
        if room is False:
            room = self._rooms[code] = room_of(code.co_filename)
        return room

    def __call__(self, frame, event, _arg) -> None:
        if event == "return":
            if self._stack:  # a frame entered before the tracer was set has no entry
                self._stack.pop()
            return
        if event != "call":
            return
        room = self._room(frame.f_code)
        path = self._push(room, frame.f_code.co_name == "<module>")
        if room is None or path is None:
            return
        caller = frame.f_back
        while caller is not None and self._room(caller.f_code) is None:
            caller = caller.f_back
        if caller is None or caller.f_code.co_name == "<module>":
            return  # called from outside the package (this script), or at an import
        self.paths[path] += 1
        if frame.f_code not in self._seen:
            self._seen.add(frame.f_code)
            self.first.append(room)
        source = self._room(caller.f_code)
        if source != room:
            key = (source, room)
            self.events[key] += 1
            site = (_name(caller.f_code), _name(frame.f_code))
            self.sites.setdefault(key, set()).add(site)
            if climbs(key) and (_handed(caller, frame.f_code) or _implicit(caller, frame.f_code)):
                self.callbacks.add(site)
            if _is_property(frame):
                self.reads.add(site)

    def _push(self, room: str | None, module: bool) -> tuple[str, ...] | None:
        """The path of a frame being called (its caller's path, with its room appended where
        that differs from the last), kept until it returns; None inside an import (a module
        body of the package and everything it calls)."""
        top = self._stack[-1] if self._stack else ()
        if top is None or (module and room is not None):
            path = None
        elif room is None or (top and top[-1] == room):
            path = top
        else:
            path = (*top, room)
        self._stack.append(path)
        return path


def _handed(caller, code) -> bool:
    """Whether ``caller``'s frame holds, in a local or closure variable, the function whose code
    is ``code`` (a plain function, a bound method or a ``functools.partial`` of one)."""
    for value in caller.f_locals.values():
        func = getattr(value, "func", value)  # functools.partial
        func = getattr(func, "__func__", func)  # bound method
        if getattr(func, "__code__", None) is code:
            return True
    return False


def _implicit(caller, code) -> bool:
    """Whether the callee is a protocol method (``__reduce__``, ``__eq__``, ...) that the
    caller's line does not name: the interpreter or the standard library calls it on an object
    the caller was handed (``pickle.dumps(obj)`` in an executor runs ``obj``'s ``__reduce__``),
    a callback in effect."""
    name = code.co_name
    dunder = name.startswith("__") and name.endswith("__")
    return dunder and name not in linecache.getline(caller.f_code.co_filename, caller.f_lineno)


def _is_property(frame) -> bool:
    """Whether the called frame runs a property getter of its ``self`` (``property`` or
    ``functools.cached_property``): reading a field of a record handed down the walk."""
    owner = frame.f_locals.get("self")
    if owner is None:
        return False
    try:
        attr = inspect.getattr_static(type(owner), frame.f_code.co_name)
    except AttributeError:
        return False
    return isinstance(attr, property | functools.cached_property)


def _name(code) -> str:
    module = Path(code.co_filename).resolve().relative_to(PACKAGE).with_suffix("")
    return f"{'.'.join(module.parts)}:{code.co_qualname}"


def traced(argv: list[str]) -> WalkTracer:
    """Run ``bayesupdate ARGV`` in this process under a ``WalkTracer``."""
    tracer = WalkTracer()
    out = io.StringIO()
    sys.setprofile(tracer)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
            code = cli(argv)
    finally:
        sys.setprofile(None)
    if code != 0:
        raise SystemExit(f"bayesupdate {' '.join(argv)} failed ({code})")
    return tracer


def climbs(key: tuple[str, str]) -> bool:
    """Whether a crossing from key[0] into key[1] goes up the layers."""
    return LAYERS.get(key[1], 8) > LAYERS.get(key[0], 8)


def table(tracer: WalkTracer) -> list[tuple[str, int, int, int, int, int]]:
    """Per room entered: (room, entering sites, entering events, climbing sites, climbing
    events, named climbing sites: those not callbacks), rooms by layer."""
    rooms = sorted({to for _, to in tracer.events}, key=lambda r: (LAYERS.get(r, 8), r))
    rows = []
    for room in rooms:
        keys = [k for k in tracer.events if k[1] == room]
        up = [k for k in keys if climbs(k)]
        rows.append((
            room,
            sum(len(tracer.sites[k]) for k in keys),
            sum(tracer.events[k] for k in keys),
            sum(len(tracer.sites[k]) for k in up),
            sum(tracer.events[k] for k in up),
            sum(len(tracer.sites[k] - tracer.callbacks) for k in up),
        ))  # fmt: skip
    return rows


def doors(tracer: WalkTracer) -> list[tuple[str, str, int, int]]:
    """Per crossed pair of rooms (caller room -> callee room): (from, to, call sites, work
    sites: those that are not a property read), most work sites first."""
    rows = [(*key, len(found), len(found - tracer.reads)) for key, found in tracer.sites.items()]
    return sorted(rows, key=lambda r: (-r[3], -r[2], r[0], r[1]))


def report_doors(tracer: WalkTracer) -> None:
    """The pairs of rooms crossed at more than two call sites (the reading of "enter each room
    at most twice" in the module docstring)."""
    rows = doors(tracer)
    over = [r for r in rows if r[2] > 2]
    over_work = [r for r in rows if r[3] > 2]
    print(
        f"room pairs crossed {len(rows)}; at more than 2 sites {len(over)} "
        f"(more than 2 work sites: {len(over_work)}); sites {sum(r[2] for r in rows)}, "
        f"work sites {sum(r[3] for r in rows)}"
    )
    for source, room, found, work in over:
        print(f"  {source:>10} -> {room:<12} sites {found:3d}  work sites {work:3d}")


def path_walk(tracer: WalkTracer) -> tuple[dict[str, tuple[int, tuple]], tuple[int, tuple]]:
    """The path reading: per room, the most times one path enters it, with such a path; and the
    most climbs (steps to a higher layer) on one path, with such a path."""
    entries: dict[str, tuple[int, tuple]] = {}
    climbs_most: tuple[int, tuple] = (0, ())
    for path in tracer.paths:
        for room, times in Counter(path).items():
            if times > entries.get(room, (0, ()))[0]:
                entries[room] = (times, path)
        up = sum(climbs(step) for step in pairwise(path))
        if up > climbs_most[0]:
            climbs_most = (up, path)
    return entries, climbs_most


def sequence_walk(tracer: WalkTracer) -> tuple[Counter, int]:
    """The sequence reading: the rooms of the functions in the order of their first call,
    consecutive ones merged into stays; per room its stays, and the number of stays in a higher
    layer than the stay before."""
    stays = [room for i, room in enumerate(tracer.first) if i == 0 or tracer.first[i - 1] != room]
    return Counter(stays), sum(climbs(step) for step in pairwise(stays))


def report_readings(tracer: WalkTracer) -> None:
    """The path and the sequence readings (module docstring), a line each, rooms over two."""
    entries, (up, path) = path_walk(tracer)
    most = max(times for times, _ in entries.values())
    print(f"path reading: {len(tracer.paths)} paths; most entries of a room on one path {most}; "
          f"most climbs on one path {up} ({' > '.join(path)})")  # fmt: skip
    for room, (times, example) in sorted(entries.items()):
        if times > 2:
            print(f"  {room} entered {times} times on {' > '.join(example)}")
    stays, up = sequence_walk(tracer)
    over = {room: n for room, n in stays.most_common() if n > 2}
    print(f"sequence reading: {len(tracer.first)} functions, {sum(stays.values())} stays in "
          f"{len(stays)} rooms, {up} climbs; rooms with more than 2 stays: {over}")  # fmt: skip


def report(name: str, tracer: WalkTracer, sites: bool) -> None:
    rows = table(tracer)
    print(f"\n{name}: rooms entered {len(rows)}")
    print(f"{'room':<12} {'enter sites':>11} {'enter events':>13} {'climb sites':>11} "
          f"{'climb events':>13} {'named climbs':>12}")  # fmt: skip
    for room, *counts in [*rows, ("all", *(sum(r[i] for r in rows) for i in range(1, 6)))]:
        a, b, c, d, e = counts
        print(f"{room:<12} {a:>11} {b:>13} {c:>11} {d:>13} {e:>12}")
    report_doors(tracer)
    report_readings(tracer)
    listed = sorted(k for k in tracer.sites if sites or climbs(k))
    print("crossing sites" if sites else "climbing sites (a lower room calls a higher one)")
    for key in listed:
        for caller, callee in sorted(tracer.sites[key]):
            arrow = (
                ("rd" if (caller, callee) in tracer.reads else "  ")
                if not climbs(key)
                else "cb"
                if (caller, callee) in tracer.callbacks
                else "UP"
            )
            print(f"  {arrow} {key[0]} -> {key[1]}: {caller} -> {callee}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sites", action="store_true", help="list every crossing site")
    parser.add_argument(
        "--legacy-rooms",
        action="store_true",
        help="the package as of 6a78c33 (before issue 38's rooms): its parallel, "
        "parallel_executor, parallel_dask and interrupts modules in the compute layer",
    )
    args = parser.parse_args()
    if args.legacy_rooms:
        LAYERS.update(dict.fromkeys(LEGACY_COMPUTE, LAYERS["compute"]))
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "discover.toml").write_text(DISCOVERY_STUDY)
        (folder / "sample.toml").write_text(SAMPLE_STUDY)
        runs = {
            "discover": ["discover", str(folder / "discover.toml"), "--json", "--quiet"],
            "sample": ["sample", str(folder / "sample.toml"), "--json", "--quiet"],
        }
        for name, argv in runs.items():
            report(name, traced(argv), args.sites)
    return 0


if __name__ == "__main__":
    sys.exit(main())
