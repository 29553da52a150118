"""``bayesupdate demo``: the main job - the seed's whole story with a report."""

import sys
from pathlib import Path

NAME = "demo"
HELP = "run the seed's whole story (model, test, calibration, uncertainty, discovery) + report"
DESCRIPTION = """Run the embedded default end to end and write a report:
  (a) the seed's case: the built-in exhaust vs seed Table 1, calibrated against Table 2
      (optimum and posterior), and discovery of the missing physics;
  (b) a virtual test campaign: a hidden-truth exhaust -> simulated impact-test FRFs (UFF 58) ->
      automatic identification -> calibration -> posterior -> discovery.
Writes into --out: report.html (self-contained), report.md, figures/, HDF5 results, the UFF file.

  bayesupdate demo --out demo_out            # the whole run (a few minutes)
  bayesupdate demo --out demo_out --quick    # a first look (about a minute)"""


def add_arguments(parser):
    parser.add_argument("--out", default="demo_out", help="output folder (default demo_out)")
    parser.add_argument("--quick", action="store_true", help="smaller run for a first look")
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    parser.add_argument("--force", action="store_true", help="write into a non-empty --out")


def run(args) -> int:
    from bayesupdate.demo import DemoSettings, check_out_folder, run_demo

    out = check_out_folder(Path(args.out), args.force)
    record = run_demo(
        DemoSettings(out=out, quick=args.quick, seed=args.seed),
        say=lambda line: print(line, file=sys.stderr, flush=True),
    )
    width = max(len(k) for k, _ in record.rows)
    print("\nsummary")
    for key, value in record.rows:
        print(f"  {key:<{width}}  {value}")
    print(f"\nreport: {record.files[0]}\n        {record.files[1]}")
    return 0
