"""Where the CPU seconds of ``bayesupdate demo`` go: each step of ``pipelines.demo.run_demo``,
the side by side and the report, timed in one process (CPU and wall), then the import of the
package and the posteriors' own split (``diagnostics["timings"]``: adaptation stages, exact and
screening log-posterior calls, convergence checks), each optimum's evaluations and wall seconds
and discovery's own timings.

The reduced bases come from ``BAYESUPDATE_CACHE_DIR`` as in a user's run: give an empty folder
for a fresh clone's first run, the same folder again for a second run.  BLAS is pinned to one
thread (set below, before numpy is imported).  On a shared machine the CPU seconds are the
number to compare; the wall seconds say how loaded it was.

    python benchmarks/demo_steps.py --quick --out /tmp/demo_steps
    python benchmarks/demo_steps.py --out /tmp/demo_steps          # the full demo
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import shutil  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402


def _clocks() -> tuple[float, float]:
    return time.perf_counter(), time.process_time()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="output folder (emptied first)")
    ap.add_argument("--quick", action="store_true", help="demo --quick")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    out = Path(args.out)
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)

    wall0, cpu0 = _clocks()
    from bayesupdate.pipelines.demo import DemoSettings, run_demo, side_by_side
    from bayesupdate.report.demo_report import write_demo_report

    marks = [("import", wall0, cpu0)]

    def step(name: str) -> None:
        marks.append((name, *_clocks()))
        print(f"  [{time.process_time() - cpu0:7.1f} s CPU] {name}", file=sys.stderr, flush=True)

    settings = DemoSettings(out=out, quick=args.quick, seed=args.seed)
    results = run_demo(settings, step)
    step("the two exhausts side by side")
    comparison = side_by_side(results)
    step("report")
    write_demo_report(results, comparison)
    marks.append(("end", *_clocks()))

    print(f"demo{' --quick' if args.quick else ''}: CPU and wall seconds per step")
    for (name, w0, c0), (_, w1, c1) in zip(marks, marks[1:], strict=False):
        print(f"  {c1 - c0:7.1f} s CPU  {w1 - w0:7.1f} s wall  {name}")
    print(f"  {marks[-1][2] - cpu0:7.1f} s CPU  {marks[-1][1] - wall0:7.1f} s wall  in all")
    for label, part in (("seed case (shell)", results.seed), ("virtual test", results.virtual)):
        posterior = part.run.posterior
        moves = posterior.diagnostics.get("moves") or {}
        reference = posterior.diagnostics.get("reference") or {}
        judged = (
            f"{'met' if reference.get('accurate') else 'NOT met'} ({reference.get('worst')})"
            if reference.get("applies")
            else "does not apply"
        )
        print(
            f"{label} posterior: {posterior.chain.shape[0]} kept steps x "
            f"{posterior.chain.shape[1]} walkers after {moves.get('adapt_steps')} adaptation "
            f"steps; {posterior.evaluations} exact and {posterior.screen_evaluations} screening "
            f"evaluations; wall split {json.dumps(posterior.diagnostics.get('timings'))}; "
            f"reference {judged}"
        )
    _print_inner_splits(results)


def _print_inner_splits(results) -> None:
    """The optimisers' and discovery's own records: where a step's seconds went inside it (each
    optimum's evaluations and wall seconds, of which the Nelder-Mead polish of every start is
    most when polished; discovery's ``timings``)."""
    optima = (
        ("seed case (shell) optimum", results.seed_optimum.calibration),
        ("beam exhaust optimum", results.beam_optimum.calibration),
        ("virtual test optimum", results.virtual.run.calibration),
    )
    for label, c in optima:
        print(
            f"{label}: {c.evaluations} evaluations in {c.wall_s:.1f} s wall, "
            f"{c.converged_starts}/{c.starts} starts at the best, Expr {c.expr:.6f}"
        )
    for label, part in (("seed", results.seed_discovery), ("virtual", results.virtual_discovery)):
        if part is not None:
            timings = {k: round(v, 1) for k, v in part.run.result.timings.items()}
            print(f"{label} discovery wall split: {json.dumps(timings)}")


if __name__ == "__main__":
    main()
