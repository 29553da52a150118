"""``bayesupdate demo``: the main job - the seed's whole story with a report."""

import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from bayesupdate.commands._shared import plot_folder, seed_value
from bayesupdate.errors import BayesUpdateError

NAME = "demo"
HELP = "run the seed's whole story (model, test, calibration, uncertainty, discovery) + report"
DESCRIPTION = """Run the embedded default end to end and write a report:
  (a) the seed's case on the shell exhaust (exhaust_shell, mesh density 16) vs seed Table 1,
      calibrated against Table 2 (optimum, front and posterior on its certified basis), beside
      the beam exhaust (its optimum and front), and discovery of what the beam one misses;
  (b) a virtual test campaign on the beam exhaust: a hidden-truth exhaust -> simulated
      impact-test FRFs (UFF 58) -> automatic identification -> calibration -> posterior ->
      discovery.
Writes into --out: report.html (self-contained), report.md, figures/, HDF5 results, the UFF file.

  bayesupdate demo --out demo_out            # the whole run (about 8.5 minutes of CPU)
  bayesupdate demo --out demo_out --quick    # a first look (about 2.5 minutes of CPU)

--quick: fewer starts, walkers and steps, no discovery on the seed case; its posteriors are not
expected to converge and say so.

On 2 cores or more the parts run side by side in 2 worker processes (--workers N; --workers 1:
one after the other in this process, with the sampler's progress bars); the numbers are the
same bits.  Each step is announced as it starts, with the seconds since the start, and each
part's figures are drawn as it finishes.

--case aircraft runs a real case instead: the mAEWing1 flying wing's own Nastran model (v3.3)
updated against its own ground vibration test, beside the authors' updated model (v4.2), on
the data packaged with bayesupdate (identify, correlate, sensitivity, calibrate, sample,
discover); writes updated.bdf, posterior_mean.bdf, report.md and aircraft.json into --out.
--json prints that object: "comparison" has one row per paired GVT mode with test_hz, v33_hz,
v42_hz, ours_hz, mac_v33, mac_v42, mac_ours, ours_mean_hz, ours_band_hz (5-95 %), held_out.

  bayesupdate demo --case aircraft --out air_out --json"""


QUICK_NOTE = (
    "quick run: {s.starts} starts, {s.walkers} walkers x {s.steps} steps (not expected to "
    "converge), no discovery on the seed case"
)


def add_arguments(parser):
    parser.add_argument("--out", default="demo_out", help="output folder (default demo_out)")
    parser.add_argument("--quick", action="store_true", help="smaller run for a first look")
    parser.add_argument("--seed", type=seed_value, default=0, help="random seed (default 0)")
    parser.add_argument("--force", action="store_true", help="write into a non-empty --out")
    parser.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="run the demo's parts in N local processes (default: 2 where this process may "
        "use 2 cores or more, else 1: serial); the results are the same bits",
    )
    parser.add_argument(
        "--case",
        choices=("exhaust", "aircraft"),
        default="exhaust",
        help="exhaust (default): the seed's story; aircraft: the mAEWing1 GVT",
    )
    parser.add_argument(
        "--json", action="store_true", help="print one JSON object (--case aircraft)"
    )


def run(args) -> int:
    if args.case == "aircraft":
        from bayesupdate.commands._demo_aircraft import run as run_aircraft

        return run_aircraft(args, check_out_folder(Path(args.out), args.force), say)
    if args.json:
        raise BayesUpdateError("demo --json: only with --case aircraft")
    from bayesupdate.compute.settings import ComputeSettings, open_executor
    from bayesupdate.pipelines.demo import DemoSettings, demo_steps, run_demo
    from bayesupdate.report.demo_report import part_figures

    compute = ComputeSettings(default_workers() if args.workers is None else args.workers)
    out = check_out_folder(Path(args.out), args.force)
    settings = DemoSettings(out=out, quick=args.quick, seed=args.seed, progress=sys.stderr.isatty())
    lines = StepLines(time.time(), (*demo_steps(settings), *_LAST_STEPS))
    if settings.quick:
        say(QUICK_NOTE.format(s=settings))
    if compute.workers > 1:
        say(f"{compute.workers} worker processes: the parts' steps are announced as they start")
    figures = {}
    with open_executor(compute) as executor:
        results = run_demo(
            settings,
            lines,
            executor,
            lambda task, part: figures.update(part_figures(task, part, out)),
        )
    _report(results, figures, lines)
    return 0


_LAST_STEPS = ("the two exhausts side by side", "report")


def _report(results, figures: dict, lines) -> None:
    """The side by side, the report (``figures``: drawn as the parts arrived) and the summary
    on stdout."""
    from bayesupdate.pipelines.demo import side_by_side
    from bayesupdate.pipelines.exhaust_comparison import better_exhaust
    from bayesupdate.report.demo_report import summary_rows, write_demo_report

    lines("report", _LAST_STEPS[0])
    comparison = side_by_side(results)
    lines("report", _LAST_STEPS[1])
    files = write_demo_report(results, comparison, figures)
    rows = summary_rows(results, time.time() - lines.t0)
    rows.insert(-1, ("beam or shell exhaust", better_exhaust(comparison)[1]))
    width = max(len(k) for k, _ in rows)
    print("\nsummary")
    for key, value in rows:
        print(f"  {key:<{width}}  {value}")
    print(f"\nreport: {files[0]}\n        {files[1]}")


def default_workers() -> int:
    """2 where this process may use 2 cores or more (the demo has two balanced halves), else 1."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return 2 if (cores or 1) >= 2 else 1


@dataclass(frozen=True)
class StepLines:
    """The demo's step announcements on stderr: ``[i/n] step  (t s)`` as a step starts, ``done:
    task`` as a task ends; t counts from ``t0`` (``time.time()``, the same clock in every
    process).  A module-level frozen class: it is pickled to the worker processes."""

    t0: float
    steps: tuple[str, ...]

    def __call__(self, task: str, name: str | None) -> None:
        elapsed = f"({time.time() - self.t0:.0f} s)"
        if name is None:
            say(f"      done: {task}  {elapsed}")
        else:
            say(f"[{self.steps.index(name) + 1}/{len(self.steps)}] {name}  {elapsed}")


def say(line: str) -> None:
    """Progress goes to stderr: stdout carries the summary only."""
    print(line, file=sys.stderr, flush=True)


def check_out_folder(out: Path, force: bool) -> Path:
    """The demo writes into ``out``; refuse a non-empty folder unless ``force``."""
    out = Path(out)
    if out.is_dir() and any(out.iterdir()) and not force:
        raise BayesUpdateError(f"--out {out}: folder is not empty; use --force to overwrite")
    return plot_folder(out, "--out")
