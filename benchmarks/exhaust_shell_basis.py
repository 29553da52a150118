"""The certified reduced basis of the shell exhaust at its default mesh (density 32, 28,386 DOFs),
and the posterior on it against the beam exhaust in the same run.

BLAS is pinned to one thread (set below, before numpy is imported).

Run (slow: the basis's full solves, then two posteriors; about an hour on the shared machine):
  .venv/bin/python benchmarks/exhaust_shell_basis.py
  .venv/bin/python benchmarks/exhaust_shell_basis.py --mesh-density 16 --steps 500  # a quick look

Path (the CLI's, ``pipelines.sample.run_sampling`` / ``benchmarks/posterior_speed.py``): the model
(``get_model``), the calibration problem against seed Table 2 (tracked pairing at the reference
design, 12 test modes + 2 extra, the measured mass kept as in the demo), the certified reduced
basis over the whole bounds box (``pipelines.surrogates.sampling_problem``:
``fe.reduced.reduced_model_for``, tol 1e-4, default settings), then:
  (a) the basis: size, its largest relative frequency error on the validation points (the error
      bound it is certified to), build time (wall and CPU);
  (b) speed: the median time of one full sparse solve (``FEModel.solve``, the modes the pairing
      needs) against one reduced solve (``ReducedFEModel.predict``) and per point of a batch of
      ``--batch`` points (``predict_frequencies_batch``), at fresh random points of the box,
      with the largest relative frequency difference there;
  (c) the posterior, for the shell and the beam exhaust one after the other in this process (same
      load): the optimum (``--starts`` starts on the basis), the basis certified at it, delayed
      acceptance on a coarser basis, emcee (mixture moves, logit coordinates) for a fixed budget
      of ``--steps`` x ``--walkers`` (stopping earlier only if R-hat <= 1.01 and ESS >= 1000 are
      met); wall and CPU time of each stage, exact and screening evaluations, R-hat and ESS.

Build comparison (``--compare-build``; no posterior): the same basis (the bounds box and model
modes of (a), cache off) built in one process with the strategies of ``fe.reduced`` side by side:
"plain" (32 snapshots, no sensitivities, no greedy: the build before design sensitivities),
"default" (the settings a large model gets: 8 snapshots with sensitivities, the residual
greedy), and "default, 2 workers" (the same on the executor seam, ``--workers 2``).  Printed per
build: full solves (snapshots, greedy, validation), wall and CPU time, size, certified error and
the ratios to "plain".
  .venv/bin/python benchmarks/exhaust_shell_basis.py --compare-build
  .venv/bin/python benchmarks/exhaust_shell_basis.py --compare-build --mesh-density 16

Calibration runs (``--calibrate-runs N``; no posterior): the user's command
``bayesupdate calibrate --model exhaust_shell --data paper:ema --json``, each run a fresh process,
its CPU (user + system, the process and its children: the machine is shared, so CPU is the
number to compare) and wall time, in a cache folder of its own (``BAYESUPDATE_CACHE_DIR``):
  "first"        the folder empty: the basis is built, the calibration kept (``--first-runs``
                 times, the folder emptied before each; default 1: a build costs minutes);
  "cached"       the same command again: the optimum recalled and checked by one full solve,
                 no basis loaded (N times);
  "basis cached" ``--seed 1`` (other starts, the same basis): the basis loaded and checked by
                 one full solve at a fresh point, the search and the refine step run (one full
                 solve at the best end, which gives the optimum's numbers when the optimum is
                 that point) (N times, each with a new seed so that no optimum is kept;
                 ``--first-seed`` S: seeds S, S + 1, ...: in a kept folder, seeds not run
                 there yet, or their optima are recalled).
Medians per kind, the objectives and the largest difference of the optimum's frequencies
between the runs.
  .venv/bin/python benchmarks/exhaust_shell_basis.py --calibrate-runs 3
  .venv/bin/python benchmarks/exhaust_shell_basis.py --calibrate-runs 3 --first-runs 0 \
      --cache-dir ~/.cache/bayesupdate   # a folder a first run filled: cached runs only
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from dataclasses import replace  # noqa: E402

import numpy as np  # noqa: E402

from bayesupdate.inference.diagnostics import summarize  # noqa: E402
from bayesupdate.inference.likelihood import LikelihoodSpec, LogPosterior  # noqa: E402
from bayesupdate.inference.optimize import CalibrationSettings, calibrate  # noqa: E402
from bayesupdate.inference.priors import prior_from_mapping  # noqa: E402
from bayesupdate.inference.problem import ObjectiveSpec, build_problem  # noqa: E402
from bayesupdate.inference.sampling import SamplerSettings, sample_posterior  # noqa: E402
from bayesupdate.models import get_model  # noqa: E402
from bayesupdate.models.exhaust_paper import MEASURED_MASS_KG, paper_ema  # noqa: E402
from bayesupdate.pipelines.surrogates import sampling_problem, screening_posterior  # noqa: E402


class Clock:
    """Wall and CPU time since the last ``lap``."""

    def __init__(self):
        self.wall, self.cpu = time.perf_counter(), time.process_time()

    def lap(self) -> tuple[float, float]:
        w, c = time.perf_counter(), time.process_time()
        out = (w - self.wall, c - self.cpu)
        self.wall, self.cpu = w, c
        return out


def model_and_basis(name: str, options: dict) -> dict:
    """(a): the model, the problem against Table 2 and its certified basis, each timed."""
    clock = Clock()
    fe = get_model(name, **options)
    t_model = clock.lap()
    # the demo's objective: the measured 12.29 kg kept (weight 10)
    objective = ObjectiveSpec(mass_target_kg=MEASURED_MASS_KG, mass_weight=10.0)
    problem = build_problem(fe, paper_ema(), objective=objective)
    t_problem = clock.lap()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        problem_r, rom = sampling_problem(problem)
    t_basis = clock.lap()
    return dict(
        fe=fe, problem=problem, problem_r=problem_r, rom=rom, n_dof=fe.structure.n_dof,
        model_s=t_model, problem_s=t_problem, basis_s=t_basis,
        warnings=[str(w.message) for w in caught],
        summary=None if rom is None else rom.summary(),
    )  # fmt: skip


def speed(fe, rom, names, n_modes: int, repeats: int, batch: int) -> dict:
    """(b): median full and reduced solve times [s] at fresh random points of the box and the
    largest relative frequency difference between them."""
    rng = np.random.default_rng(12345)
    low, high = rom.low, rom.high
    theta = low + rng.random((max(repeats, batch), len(low))) * (high - low)
    t_full, t_red, err = [], [], []
    for row in theta[:repeats]:
        p = dict(zip(names, map(float, row), strict=True))
        t0 = time.perf_counter()
        f_full = fe.solve(p, n_modes=n_modes).frequencies_hz
        t_full.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        f_red = rom.predict(p, n_modes=n_modes).frequencies_hz
        t_red.append(time.perf_counter() - t0)
        err.append(np.max(np.abs(f_red / f_full - 1)))
    t0 = time.perf_counter()
    rom.predict_frequencies_batch(theta[:batch], names, n_modes)
    t_batch = (time.perf_counter() - t0) / batch
    full, red = float(np.median(t_full)), float(np.median(t_red))
    return dict(
        full_solve_s=full, reduced_solve_s=red, reduced_batch_per_point_s=t_batch,
        speedup=full / red, speedup_batch=full / t_batch, max_rel_diff=float(max(err)),
        points=repeats,
    )  # fmt: skip


def posterior(problem, rom, args) -> dict:
    """(c): optimum, certification at it, screening basis and a fixed-budget posterior."""
    clock = Clock()
    fit = CalibrationSettings(starts=args.starts, seed=0, max_nfev=args.max_nfev)
    calibration = calibrate(problem, fit)
    t_opt = clock.lap()
    error_at_optimum = None
    if rom is not None:
        rom, error_at_optimum = rom.certify_at(calibration.theta[None, :], problem.names)
        problem = replace(problem, model=rom)
    t_cert = clock.lap()
    sigma_prior = prior_from_mapping({"kind": "halfnormal", "scale": 0.1}, (0.0, 1.0), "sigma")
    spec = LikelihoodSpec(sigma=None, sigma_prior=sigma_prior)
    log_post = LogPosterior(problem, spec)
    screen = screening_posterior(problem, rom, spec)
    t_screen = clock.lap()
    settings = SamplerSettings(
        walkers=args.walkers, steps=args.steps, seed=1, check_every=args.check_every,
        transform="logit", target_rhat=1.01, target_ess=1000,
    )  # fmt: skip
    post = sample_posterior(log_post, calibration, settings, screen=screen)
    t_sample = clock.lap()
    summary = summarize(post)
    return dict(
        expr=float(calibration.expr), theta=[float(v) for v in calibration.theta],
        error_at_optimum=None if error_at_optimum is None else float(error_at_optimum),
        optimum=t_opt, certify=t_cert, screen_basis=t_screen, sampling=t_sample,
        steps=int(post.chain.shape[0]), walkers=int(post.chain.shape[1]),
        evaluations=int(post.evaluations), screen_evaluations=post.screen_evaluations,
        converged=bool(post.converged),
        max_r_hat=max(v["r_hat"] for v in summary.values()),
        min_ess=min(v["ess_bulk"] for v in summary.values()),
        means={k: v["mean"] for k, v in summary.items()},
    )  # fmt: skip


def one_model(name: str, options: dict, args) -> dict:
    built = model_and_basis(name, options)
    rom, problem = built["rom"], built["problem"]
    print(
        f"[{name}] {built['n_dof']} DOFs; model {built['model_s'][0]:.1f} s, problem "
        f"{built['problem_s'][0]:.1f} s, basis wall {built['basis_s'][0]:.1f} s CPU "
        f"{built['basis_s'][1]:.1f} s: {built['summary']}; warnings {built['warnings']}",
        flush=True,
    )
    out = {k: v for k, v in built.items() if k not in ("fe", "problem", "problem_r", "rom")}
    if rom is not None:
        n_modes = problem.pairing.n_model
        out["speed"] = speed(built["fe"], rom, problem.names, n_modes, args.repeats, args.batch)
        print(f"[{name}] speed {json.dumps(out['speed'])}", flush=True)
    if args.steps > 0:
        out["posterior"] = posterior(built["problem_r"], rom, args)
        print(f"[{name}] posterior {json.dumps(out['posterior'])}", flush=True)
    return out


def compare_builds(args) -> dict:
    """The build comparison of the module docstring: {label: numbers}."""
    from bayesupdate.compute.executors import ProcessExecutor
    from bayesupdate.fe.reduced import certification, reduced_model_for

    os.environ["BAYESUPDATE_NO_CACHE"] = "1"
    fe = get_model("exhaust_shell", mesh_density=args.mesh_density)
    objective = ObjectiveSpec(mass_target_kg=MEASURED_MASS_KG, mass_weight=10.0)
    problem = build_problem(fe, paper_ema(), objective=objective)
    bounds = {p.name: p.bounds for p in problem.parameters}
    counted = {"solves": 0}
    solves = certification.full_solves

    def counting(fe_, names, theta, *a, **k):
        counted["solves"] += theta.shape[0]
        return solves(fe_, names, theta, *a, **k)

    certification.full_solves = counting
    builds = {
        "plain": ({"n_snapshots": 32, "sensitivities": False, "greedy_train": 0}, 0),
        "default": ({}, 0),
        f"default, {args.workers} workers": ({}, args.workers),
    }
    rows = {}
    try:
        for label, (options, workers) in builds.items():
            if label.endswith("workers") and not workers:
                continue  # --workers 0: serial builds only
            counted["solves"] = 0
            executor = ProcessExecutor(workers) if workers else None
            clock = Clock()
            rom = reduced_model_for(fe, bounds, n_modes=problem.pairing.n_model,
                                    executor=executor, **options)  # fmt: skip
            wall, cpu = clock.lap()
            if executor is not None:
                executor.close()
            rows[label] = dict(
                solves=counted["solves"], wall_s=wall, cpu_s=cpu, size=rom.size,
                max_rel_error=rom.max_rel_error, certified=rom.certified,
                history=[(h.size, h.max_rel_error) for h in rom.certification.history],
            )  # fmt: skip
            print(f"[build {label}] {json.dumps(rows[label])}", flush=True)
    finally:
        certification.full_solves = solves
    base = rows["plain"]
    for label, row in rows.items():
        print(
            f"[build {label}] solves {row['solves']} ({row['solves'] / base['solves']:.2f} of "
            f"plain), wall {row['wall_s']:.1f} s ({row['wall_s'] / base['wall_s']:.2f}), CPU "
            f"{row['cpu_s']:.1f} s, size {row['size']}, certified {row['max_rel_error']:.2e}",
            flush=True,
        )
    return rows


def _timed_run(extra: list[str], env: dict) -> dict:
    """One ``bayesupdate calibrate`` process: CPU [s] (user + system of the child), wall [s],
    its --json output."""
    import resource
    import subprocess
    import sys

    command = [sys.executable, "-m", "bayesupdate", "calibrate", "--model", "exhaust_shell",
               "--data", "paper:ema", "--json", *extra]  # fmt: skip
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True, check=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return dict(cpu_s=cpu, wall_s=wall, json=json.loads(done.stdout.strip().splitlines()[-1]))


def calibrate_runs(args) -> dict:
    """The calibration runs of the module docstring: {kind: {"runs": [...], medians}}."""
    import shutil
    import tempfile

    folder = args.cache_dir or tempfile.mkdtemp(prefix="bayesupdate-bench-cache-")
    env = {**os.environ, "BAYESUPDATE_CACHE_DIR": folder, "BAYESUPDATE_NO_CACHE": "0"}
    kinds = {"first": [], "cached": [], "basis cached": []}
    try:
        for _ in range(args.first_runs):
            shutil.rmtree(folder, ignore_errors=True)
            kinds["first"].append(_timed_run([], env))
            print(f"[first] {_row(kinds['first'][-1])}", flush=True)
        for i in range(args.calibrate_runs):
            kinds["cached"].append(_timed_run([], env))
            print(f"[cached] {_row(kinds['cached'][-1])}", flush=True)
            seed = str(args.first_seed + i)
            kinds["basis cached"].append(_timed_run(["--seed", seed], env))
            print(f"[basis cached] {_row(kinds['basis cached'][-1])}", flush=True)
    finally:
        if not args.cache_dir:
            shutil.rmtree(folder, ignore_errors=True)
    first = next(runs[0] for runs in kinds.values() if runs)
    reference = np.array(first["json"]["frequencies_hz"])
    out = {}
    for kind, runs in kinds.items():
        if not runs:
            continue
        diff = max(np.max(np.abs(np.array(r["json"]["frequencies_hz"]) / reference - 1))
                   for r in runs)  # fmt: skip
        out[kind] = dict(
            runs=[{k: v for k, v in r.items() if k != "json"} | {"objective": r["json"][
                "objective"], "timings": r["json"].get("timings")} for r in runs],
            median_cpu_s=float(np.median([r["cpu_s"] for r in runs])),
            median_wall_s=float(np.median([r["wall_s"] for r in runs])),
            max_rel_frequency_diff_to_first=float(diff),
        )  # fmt: skip
        print(
            f"[{kind}] {len(runs)} runs: median CPU {out[kind]['median_cpu_s']:.1f} s, wall "
            f"{out[kind]['median_wall_s']:.1f} s; optimum's frequencies within "
            f"{diff:.1e} of the first run's (or, with no first run, the first cached one's)",
            flush=True,
        )
    return out


def _row(run: dict) -> str:
    return (f"CPU {run['cpu_s']:.1f} s, wall {run['wall_s']:.1f} s, objective "
            f"{run['json']['objective']:.6g}, timings {run['json'].get('timings')}")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh-density", type=int, default=32, help="shell mesh density (32)")
    ap.add_argument("--repeats", type=int, default=3, help="full solves timed (3)")
    ap.add_argument("--batch", type=int, default=200, help="points of the reduced batch (200)")
    ap.add_argument("--steps", type=int, default=2000, help="posterior budget (0: none)")
    ap.add_argument("--walkers", type=int, default=16)
    ap.add_argument("--check-every", type=int, default=250)
    ap.add_argument("--starts", type=int, default=2, help="optimizer starts")
    ap.add_argument("--max-nfev", type=int, default=150, help="evaluations per start")
    ap.add_argument("--save", help="write the numbers to this JSON file")
    ap.add_argument("--compare-build", action="store_true", help="the build comparison only")
    ap.add_argument("--workers", type=int, default=2, help="local workers of the comparison")
    ap.add_argument(
        "--calibrate-runs",
        type=int,
        default=0,
        help="the calibration runs only: cached runs of each kind (0: none)",
    )
    ap.add_argument("--first-runs", type=int, default=1, help="first runs (empty cache)")
    ap.add_argument(
        "--first-seed",
        type=int,
        default=1,
        help="seed of the first 'basis cached' run, the next ones +1 each (1); in a kept "
        "--cache-dir, seeds not run there before, or their optima are recalled",
    )
    ap.add_argument(
        "--cache-dir",
        help="the calibration runs' cache folder, kept (default: a new "
        "temporary one, removed); with --first-runs 0, one a first run filled",
    )
    args = ap.parse_args()
    warnings.simplefilter("default")
    print(f"load average at start: {os.getloadavg()}", flush=True)
    if args.calibrate_runs:
        rows = calibrate_runs(args)
        print(f"load average at end: {os.getloadavg()}", flush=True)
        if args.save:
            with open(args.save, "w") as fh:
                json.dump(rows, fh, indent=1, default=float)
        return
    if args.compare_build:
        rows = compare_builds(args)
        print(f"load average at end: {os.getloadavg()}", flush=True)
        if args.save:
            with open(args.save, "w") as fh:
                json.dump(rows, fh, indent=1, default=float)
        return
    rows = {
        "exhaust_shell": one_model("exhaust_shell", {"mesh_density": args.mesh_density}, args),
        "exhaust": one_model("exhaust", {}, args),
    }
    print(f"load average at end: {os.getloadavg()}", flush=True)
    if args.save:
        with open(args.save, "w") as fh:
            json.dump(rows, fh, indent=1, default=float)


if __name__ == "__main__":
    main()
