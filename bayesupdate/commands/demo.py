"""``bayesupdate demo``: the main job - the seed's whole story with a report."""

import sys
import time
from pathlib import Path

from bayesupdate.atomic import make_writable_folder
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

  bayesupdate demo --out demo_out            # the whole run (about 7 minutes of CPU)
  bayesupdate demo --out demo_out --quick    # a first look (about 2.5 minutes of CPU)

--quick: fewer starts, walkers and steps, no discovery on the seed case; its posteriors are not
expected to converge and say so.

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
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--force", action="store_true", help="write into a non-empty --out")
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
    from bayesupdate.pipelines.demo import DemoSettings, demo_steps, run_demo, side_by_side
    from bayesupdate.pipelines.exhaust_comparison import better_exhaust
    from bayesupdate.report.demo_report import summary_rows, write_demo_report

    out = check_out_folder(Path(args.out), args.force)
    settings = DemoSettings(out=out, quick=args.quick, seed=args.seed, progress=sys.stderr.isatty())
    steps = (*demo_steps(settings), "the two exhausts side by side", "report")
    t0 = time.perf_counter()
    counter = iter(range(1, len(steps) + 1))
    if settings.quick:
        say(QUICK_NOTE.format(s=settings))

    def step(name):
        say(f"[{next(counter)}/{len(steps)}] {name}  ({time.perf_counter() - t0:.0f} s)")

    results = run_demo(settings, step)
    step("the two exhausts side by side")
    comparison = side_by_side(results)
    step("report")
    files = write_demo_report(results, comparison)
    rows = summary_rows(results, time.perf_counter() - t0)
    rows.insert(-1, ("beam or shell exhaust", better_exhaust(comparison)[1]))
    width = max(len(k) for k, _ in rows)
    print("\nsummary")
    for key, value in rows:
        print(f"  {key:<{width}}  {value}")
    print(f"\nreport: {files[0]}\n        {files[1]}")
    return 0


def say(line: str) -> None:
    """Progress goes to stderr: stdout carries the summary only."""
    print(line, file=sys.stderr, flush=True)


def check_out_folder(out: Path, force: bool) -> Path:
    """The demo writes into ``out``; refuse a non-empty folder unless ``force``."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise BayesUpdateError(f"--out {out}: is a file; give a folder")
    if out.exists() and any(out.iterdir()) and not force:
        raise BayesUpdateError(f"--out {out}: folder is not empty; use --force to overwrite")
    try:
        make_writable_folder(out)
    except OSError:
        raise BayesUpdateError(f"--out {out}: cannot write there; choose another folder") from None
    return out
