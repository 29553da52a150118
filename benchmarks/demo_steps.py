"""Where the CPU seconds of ``bayesupdate demo`` go: each step of ``pipelines.demo.run_demo``,
the side by side and the report, timed in one process (CPU and wall), then the import of the
package and the posteriors' own split (``diagnostics["timings"]``: adaptation stages, exact and
screening log-posterior calls, convergence checks), each optimum's evaluations and wall seconds
and discovery's own timings.

``--workers 2`` runs the demo's tasks as ``bayesupdate demo`` does on two cores
(``pipelines.demo.demo_tasks`` on local processes, the figures drawn in this process as each
part arrives): each step's CPU is then the CPU of the process it ran in, printed as it ends, and
the totals add the workers' CPU (``RUSAGE_CHILDREN``).

The reduced bases come from ``BAYESUPDATE_CACHE_DIR`` as in a user's run: give an empty folder
for a fresh clone's first run, the same folder again for a second run.  BLAS is pinned to one
thread (set below, before numpy is imported).  On a shared machine the CPU seconds are the
number to compare; the wall seconds say how loaded it was.

    python benchmarks/demo_steps.py --quick --out /tmp/demo_steps
    python benchmarks/demo_steps.py --quick --workers 2 --out /tmp/demo_steps
    python benchmarks/demo_steps.py --out /tmp/demo_steps          # the full demo
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import resource  # noqa: E402
import shutil  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402


def _clocks() -> tuple[float, float]:
    return time.time(), time.process_time()


class StepClock:
    """The demo's ``step(task, name)``: each step's CPU and wall seconds in the process it ran
    in, printed as it ends with that process's id and the seconds since ``t0`` at its end (the
    workers' critical path: which task ends last, and on which worker), and kept in ``rows``
    (read back in a serial run only: a worker's copy stays in the worker).  Module level:
    pickled to the workers."""

    def __init__(self, t0: float):
        self.t0, self.rows, self.open = t0, [], {}

    def __call__(self, task: str, name: str | None) -> None:
        now = _clocks()
        if task in self.open:
            (label, w0, c0), (w1, c1) = self.open.pop(task), now
            self.rows.append((label, c1 - c0, w1 - w0))
            where = f"pid {os.getpid()}, ends at {w1 - self.t0:6.1f} s"
            print(
                f"  {c1 - c0:7.1f} s CPU  {w1 - w0:7.1f} s wall  {label}  ({where})",
                file=sys.stderr,
            )
        if name is not None:
            self.open[task] = (name, *now)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="output folder (emptied first)")
    ap.add_argument("--quick", action="store_true", help="demo --quick")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=1, help="local processes (1: serial)")
    args = ap.parse_args()
    out = Path(args.out)
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)

    wall0, cpu0 = _clocks()
    from bayesupdate.compute.settings import ComputeSettings, open_executor
    from bayesupdate.pipelines.demo import DemoSettings, run_demo, side_by_side
    from bayesupdate.report.demo_report import part_figures, write_demo_report

    clock, figures, drawn = StepClock(wall0), {}, []
    wall, cpu = _clocks()
    clock.rows.append(("import", cpu - cpu0, wall - wall0))
    settings = DemoSettings(out=out, quick=args.quick, seed=args.seed)

    def on_part(task, record):
        w0, c0 = _clocks()
        figures.update(part_figures(task, record, out))
        drawn.append((task, time.process_time() - c0, time.time() - w0, time.time() - wall0))

    with open_executor(ComputeSettings(args.workers)) as executor:
        results = run_demo(settings, clock, executor, on_part)
    clock("report", "the two exhausts side by side")
    comparison = side_by_side(results)
    clock("report", "report (the figures drawn as the parts arrived: below)")
    write_demo_report(results, comparison, figures)
    clock("report", None)
    wall1, cpu1 = _clocks()
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    workers_cpu = children.ru_utime + children.ru_stime

    quick = " --quick" if args.quick else ""
    print(f"demo{quick}, {args.workers} worker(s): CPU and wall seconds per step")
    for label, cpu, wall in clock.rows:  # a serial run's steps; with workers: this process's
        print(f"  {cpu:7.1f} s CPU  {wall:7.1f} s wall  {label}")
    for task, cpu, wall, end in drawn:
        print(f"  {cpu:7.1f} s CPU  {wall:7.1f} s wall  figures of {task} (ends at {end:.1f} s)")
    print(
        f"  {cpu1 - cpu0:7.1f} s CPU here + {workers_cpu:.1f} s CPU in workers, "
        f"{wall1 - wall0:7.1f} s wall  in all; load average {os.getloadavg()}"
    )
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
    """The optimizers' and discovery's own records: where a step's seconds went inside it (each
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
