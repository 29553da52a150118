"""CPU seconds of each figure a posterior's result file gets (``inference.plots``: trace, pair,
predictive, residuals), drawn and written as PNG; the median over ``--repeats`` rounds.

The figures are drawn in the process that writes a report (``sample``'s figures, the demo's
main process beside its two workers), so their CPU is wall time a user waits.  Give a result
file of ``bayesupdate sample --out FILE`` (or a demo's ``seed_case.h5``); to compare two
checkouts, run this script from each with ``PYTHONPATH=<checkout>``, alternating.

    bayesupdate sample --model exhaust --data paper:ema --out /tmp/post.h5 --quiet
    python benchmarks/figure_speed.py /tmp/post.h5 --repeats 5
"""

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from bayesupdate import plotting
from bayesupdate.inference import plots
from bayesupdate.inference.results import read_result

FIGURES = ("trace", "pair", "predictive", "residuals")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("result", type=Path, help="a result file with a finished posterior")
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    result = read_result(args.result)
    names = result["posterior"]["attrs"]["names"]
    print(f"{args.result}: {len(names)} parameters; CPU seconds per figure, median of "
          f"{args.repeats}")  # fmt: skip
    with tempfile.TemporaryDirectory() as folder:
        for name in FIGURES:
            maker = getattr(plots, f"plot_{name}")
            spent = []
            for k in range(args.repeats):
                t0 = time.process_time()
                plotting.save(maker(result), Path(folder) / f"{name}_{k}.png")
                spent.append(time.process_time() - t0)
            print(f"  {name:10s} {np.median(spent):6.3f} s  ({min(spent):.3f}-{max(spent):.3f})")


if __name__ == "__main__":
    main()
