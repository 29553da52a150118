"""Exhaust posterior (five design variables + sigma, data = seed Table 2) from a cold start to
R-hat <= 1.01 and bulk ESS >= 1000: move schemes side by side, certified reduced basis vs full FE.

BLAS is pinned to one thread (set below, before numpy is imported).

Run:
  .venv/bin/python benchmarks/posterior_speed.py --seeds 5      # DE vs mixture, 5 seeds each
  .venv/bin/python benchmarks/posterior_speed.py --seed-list 31 47 --moves mixture   # chosen seeds
  .venv/bin/python benchmarks/posterior_speed.py --save rom.npz   # reduced basis (default)
  .venv/bin/python benchmarks/posterior_speed.py --full --steps 1000 --starts 1 --save full.npz
  .venv/bin/python benchmarks/posterior_speed.py --compare rom.npz full.npz   # no sampling

Pipeline (the CLI's, ``pipelines.sample.run_sampling``): the exhaust model, tracked pairing at the
reference design -> [reduced: ``surrogates.sampling_problem``: certified reduced basis over the
prior box, 14 modes] -> multi-start optimum (``--starts``, ``--max-nfev`` per start) -> [reduced:
``certify_at`` the optimum] -> emcee with DE moves, ``--walkers`` walkers started around the
optimum, in logit coordinates (``--transform``), checked every ``--check-every`` steps and run
until R-hat <= 1.01 and bulk ESS >= 1000 for every parameter (the sampler's own
``target_rhat`` / ``target_ess`` stopping rule; or ``--steps``); likelihood on
relative errors with sigma inferred (half-normal prior, scale 0.1), uniform priors on the
model bounds, modes paired by shape for every walker (batched on the reduced model, per point
in full).  Wall and CPU time count everything from building the model; the reduced run is
checked in full at the posterior mean too.

The user's command (``--user N``): ``bayesupdate sample --model exhaust --data paper:ema
--json`` exactly as a user types it (the study's defaults: 32 walkers, R-hat <= 1.01, bulk ESS >=
400, the weighed mass in the likelihood, sigma fixed), N cold runs in fresh processes, imports
included, wall and CPU (the child's user + system time), steps, and the stop: which criterion
held the run at the check before the stop (``diagnostics["stop"]``: "r_hat" means the ESS at
the stop is what R-hat needed, not an overshoot of the checks) and the least bulk ESS at the
stop over the ESS target.  ``--code DIR [DIR ...]``: one source tree per variant (PYTHONPATH),
runs interleaved so that every variant sees the same machine load; e.g. before and after:
  .venv/bin/python benchmarks/posterior_speed.py --user 3 --code /path/to/main .
then the paired CPU ratios against the first tree, of the whole run and per kept step.  A
variant may add arguments to the command after a colon, comma-separated: ``--code . .:--workers=1``
runs the tree once as the user does (the walkers' batches split with a worker of the sampler's
own when a core is free) and once in one process alone.  Each row has ``split``: the batches
evaluated in two parts at once (0 in one process).
``--user-seeds S [S ...]``: each round runs these sampler seeds (``--seed``) too: a change that
reorders the random draws changes where the R-hat stop lands, so one seed compares two chain
lengths as much as two codes.  ``--overshoot`` (not for timing): each run also writes its result
file, and the row says at which step (every 10th) the stop rule first held on the stored chain
(``first_hold``) and the stop's steps over that (the checks' overshoot; the ESS's over its
target is ``ess_over_target``).

``--split-batches``: the exhaust's exact and screen batches of 16, 24 and 32 points whole and
split with one local worker process (``inference.evaluators.SplitDensity``, what ``sample`` does
when a core is free): wall and this process's CPU per batch.

Timed runs (``--seeds`` / ``--seed-list``) print each set-up phase (model + reduced basis,
optimum, screening basis; wall and CPU), then one JSON row per run: cold-start wall and CPU,
steps, exact and screened evaluations, tau, acceptance, the sampler's own wall-time split
(``diagnostics["timings"]``: adaptation stages, exact and screening calls, convergence checks)
and the accuracy against the importance-sampling reference; then medians and ranges.
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from dataclasses import replace  # noqa: E402

import numpy as np  # noqa: E402

from bayesupdate.inference.diagnostics import summarize  # noqa: E402
from bayesupdate.inference.likelihood import LikelihoodSpec, LogPosterior  # noqa: E402
from bayesupdate.inference.optimize import CalibrationSettings, calibrate  # noqa: E402
from bayesupdate.inference.priors import prior_from_mapping  # noqa: E402
from bayesupdate.inference.problem import build_problem  # noqa: E402
from bayesupdate.inference.sampling import TIMED, SamplerSettings, sample_posterior  # noqa: E402
from bayesupdate.models import get_model  # noqa: E402
from bayesupdate.models.exhaust_paper import paper_ema  # noqa: E402
from bayesupdate.pipelines.surrogates import sampling_problem, screening_posterior  # noqa: E402


def likelihood() -> LikelihoodSpec:
    sigma_prior = prior_from_mapping({"kind": "halfnormal", "scale": 0.1}, (0.0, 1.0), "sigma")
    # pairing "auto": tracked by shape (batched with the reduced model, per point in full)
    return LikelihoodSpec(sigma=None, sigma_prior=sigma_prior)


def run(args, reduced: bool) -> dict:
    t0, c0 = time.perf_counter(), time.process_time()
    fe = get_model("exhaust")
    data = paper_ema()
    # the CLI's pipeline (pipelines.sample.run_sampling): tracked pairing at the reference
    # design, the certified reduced model over the parameter box (14 modes = 12 test + 2 extra),
    # optimum
    problem = build_problem(fe, data)
    problem, rom = sampling_problem(problem, reduced=reduced)
    t_model = time.perf_counter() - t0
    fit = CalibrationSettings(starts=args.starts, seed=0, max_nfev=args.max_nfev)
    calibration = calibrate(problem, fit)
    info = {}
    if rom is not None:
        rom, info["error_at_optimum"] = rom.certify_at(calibration.theta[None, :], problem.names)
        problem = replace(problem, model=rom)
    t_opt = time.perf_counter() - t0
    spec = likelihood()
    log_post = LogPosterior(problem, spec)
    screen = None if args.no_screen else screening_posterior(problem, rom, spec)
    t_screen = time.perf_counter() - t0
    settings = SamplerSettings(
        walkers=args.walkers,
        steps=args.steps,
        seed=args.seed,
        min_autocorr_times=50.0,
        check_every=args.check_every,
        transform=args.transform,
        target_rhat=1.01,
        target_ess=1000,
    )
    post = sample_posterior(log_post, calibration, settings, screen=screen)
    summary = summarize(post)
    wall = time.perf_counter() - t0
    cpu = time.process_time() - c0
    flat = post.chain[post.burn :].reshape(-1, post.chain.shape[-1])
    if rom is not None:
        info["error_at_mean"] = rom.certify_at(flat[:, :-1].mean(axis=0)[None, :], problem.names)[1]
    return dict(
        label="reduced" if reduced else "full",
        wall_s=wall,
        cpu_s=cpu,
        model_s=t_model,
        optimum_s=t_opt - t_model,
        screen_s=t_screen - t_opt,
        sampling_s=wall - t_screen,
        screen_evaluations=post.screen_evaluations,
        screen_size=None if screen is None else screen.problem.model.size,
        steps=post.chain.shape[0],
        burn=post.burn,
        evaluations=post.evaluations,
        converged=post.converged,
        names=post.names,
        summary=summary,
        mean=flat.mean(axis=0),
        sd=flat.std(axis=0, ddof=1),
        rom=rom.summary() if rom is not None else None,
        pair_differs=log_post.pair_differs_fraction,
        **info,
    )


def report(r: dict) -> None:
    print(
        f"\n[{r['label']}] wall {r['wall_s']:.1f} s, CPU {r['cpu_s']:.1f} s "
        f"(model {r['model_s']:.1f}, optimum "
        f"{r['optimum_s']:.1f}, screen basis {r['screen_s']:.1f}, sampling {r['sampling_s']:.1f}); "
        f"{r['steps']} steps (burn {r['burn']}), {r['evaluations']} exact evaluations, "
        f"{r['screen_evaluations']} screening evaluations (basis size {r['screen_size']}), "
        f"converged={r['converged']}"
    )
    if r.get("rom"):
        print(
            f"  rom: {r['rom']}  error at optimum {r.get('error_at_optimum', float('nan')):.1e}, "
            f"at the posterior mean {r.get('error_at_mean', float('nan')):.1e}"
        )
    print(f"  share of evaluations paired differently from the order: {r['pair_differs']:.3f}")
    ok = True
    print(f"  {'name':<26}{'mean':>12}{'sd':>12}{'r_hat':>8}{'ess_bulk':>10}")
    for name in r["names"]:
        s = r["summary"][name]
        ok &= s["r_hat"] <= 1.01 and s["ess_bulk"] >= 1000
        print(
            f"  {name:<26}{s['mean']:>12.5g}{s['sd']:>12.3g}"
            f"{s['r_hat']:>8.4f}{s['ess_bulk']:>10.0f}"
        )
    print(f"  R-hat <= 1.01 and ESS >= 1000 for every parameter: {ok}")


def _reference_study():
    """studies/posterior_reference.py as a module (its problem builder and reference file)."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "studies" / "posterior_reference.py"
    spec = importlib.util.spec_from_file_location("posterior_reference", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module, path.parents[1] / "tests" / "data" / "posterior_reference_exhaust.json"


def setup(args) -> tuple:
    """The reference study's problem (``exhaust_posterior``: the same calls, in order), each
    set-up phase timed: (log_post, calibration, screen, phases {name: (wall, CPU) [s]})."""
    study, _ = _reference_study()
    phases, clock = {}, [time.perf_counter(), time.process_time()]

    def lap(name: str) -> None:
        now = [time.perf_counter(), time.process_time()]
        phases[name] = (now[0] - clock[0], now[1] - clock[1])
        clock[:] = now

    problem = build_problem(get_model("exhaust"), paper_ema())
    problem, rom = sampling_problem(problem, reduced=True)
    lap("model + reduced basis")
    fit = CalibrationSettings(starts=args.starts, seed=0, max_nfev=args.max_nfev)
    calibration = calibrate(problem, fit)
    rom = rom.certify_at(calibration.theta[None, :], problem.names)[0]
    problem = replace(problem, model=rom)
    lap("optimum")
    spec = study.likelihood()
    screen = screening_posterior(problem, rom, spec)
    lap("screening basis")
    return LogPosterior(problem, spec), calibration, screen, phases


def split_batches(args, repeats: int = 40) -> None:
    """The exhaust's exact and screen batches (16, 24, 32 points near the optimum) evaluated
    whole and split with one local worker (``inference.evaluators.SplitDensity``): wall and this
    process's CPU per batch [ms], means over ``repeats`` calls, interleaved; the split values
    checked equal to the whole batch's.  On a loaded machine the wall times say little (the
    worker waits for a core); this process's CPU is what the split leaves on its core."""
    from bayesupdate.compute.executors import PartnerProcess, ProcessExecutor
    from bayesupdate.inference.evaluators import split_densities

    log_post, calibration, screen, _ = setup(args)
    rng = np.random.default_rng(0)
    p = log_post.problem
    theta = calibration.theta + 0.02 * (p.upper - p.lower) * rng.standard_normal((32, 5))
    theta = np.hstack([np.clip(theta, p.lower, p.upper), np.full((32, 1), 0.05)])
    for make in (PartnerProcess, lambda: ProcessExecutor(1)):
        with make() as executor:
            _split_rows(executor, split_densities((log_post, screen), executor), theta, repeats)


def _split_rows(executor, split: tuple, theta: np.ndarray, repeats: int) -> None:
    """``split_batches``' rows for one executor (a pipe partner or a one-process pool)."""
    whole_densities = tuple(s.density for s in split)
    for s in split:
        s.wait_started()
    for name, whole, parted in zip(("exact", "screen"), whole_densities, split, strict=True):
        for n in (16, 24, 32):
            x = theta[:n]
            assert np.array_equal(whole(x), parted(x))
            row = {"density": name, "points": n, "load": round(os.getloadavg()[0], 1),
                   "hand_off": executor.kind}  # fmt: skip
            for label, f in (("whole", whole), ("split", parted)):
                t0, c0 = time.perf_counter(), time.process_time()
                for _ in range(repeats):
                    f(x)
                row[f"{label}_wall_ms"] = round((time.perf_counter() - t0) / repeats * 1e3, 2)
                row[f"{label}_cpu_ms"] = round((time.process_time() - c0) / repeats * 1e3, 2)
            print(row, flush=True)


def _timed_run(args, moves: str, seed: int, setup_parts: tuple, reference) -> dict:
    """One sampling run from the built problem, with the set-up's time added ("cold start")."""
    log_post, calibration, screen, phases = setup_parts
    settings = SamplerSettings(
        walkers=args.walkers, steps=args.steps, seed=seed, check_every=args.check_every,
        transform=args.transform, target_rhat=1.01, target_ess=1000, moves=moves,
        adapt_steps=args.adapt_steps,
    )  # fmt: skip
    fresh = LogPosterior(log_post.problem, log_post.spec)
    t1, c1 = time.perf_counter(), time.process_time()
    post = sample_posterior(fresh, calibration, settings, screen=screen)
    wall, cpu = time.perf_counter() - t1, time.process_time() - c1
    summary = summarize(post)
    acceptance = post.acceptance
    moves_info = post.diagnostics.get("moves") or {}
    row = dict(
        moves=moves, seed=seed,
        wall_s=sum(w for w, _ in phases.values()) + wall,
        cpu_s=sum(c for _, c in phases.values()) + cpu,
        sampling_s=wall, sampling_cpu_s=cpu, steps=post.chain.shape[0],
        evaluations=post.evaluations, screen_evaluations=post.screen_evaluations,
        tau=float(np.max(post.autocorr_time)), tau_each=np.round(post.autocorr_time, 1).tolist(),
        acceptance=float(np.mean(acceptance)), converged=post.converged,
        r_hat=max(v["r_hat"] for v in summary.values()),
        ess=min(v["ess_bulk"] for v in summary.values()),
        kind=moves_info.get("kind"), coverage=moves_info.get("coverage"),
        stuck=moves_info.get("stuck"), fallback=moves_info.get("fallback"),
        repairs=moves_info.get("repairs", 0), first_check=moves_info.get("first_check"),
        coordinates=moves_info.get("coordinates"),
        load=round(os.getloadavg()[0], 1),
        **post.diagnostics.get("timings", {}),
    )  # fmt: skip
    if reference is not None:
        row.update(_reference_study()[0].compare(reference, post.samples()))
    return row


def timed_runs(args) -> list[dict]:
    """Each move scheme of ``--moves`` on each seed (``--seed-list``, or ``--seeds`` from
    ``--first-seed``; interleaved, so both see the same machine load), on one problem built once
    (its set-up time, per phase, is added to each run: "cold start" = set-up + sampling)."""
    import json

    _, ref_path = _reference_study()
    reference = json.loads(ref_path.read_text()) if ref_path.exists() else None
    parts = setup(args)
    for name, (wall, cpu) in parts[3].items():
        print(f"set-up: {name}: wall {wall:.1f} s, CPU {cpu:.1f} s", flush=True)
    seeds = args.seed_list or list(range(args.first_seed, args.first_seed + args.seeds))
    rows = []
    for seed in seeds:
        for moves in args.moves:
            rows.append(_timed_run(args, moves, seed, parts, reference))
            print(json.dumps(rows[-1]), flush=True)
    return rows


def table(rows: list[dict]) -> None:
    """Median and range per move scheme, and the accuracy against the reference."""
    for moves in dict.fromkeys(r["moves"] for r in rows):
        mine = [r for r in rows if r["moves"] == moves]
        print(f"\n[{moves}] {len(mine)} seeds, all converged: {all(r['converged'] for r in mine)}")
        keys = ("wall_s", "cpu_s", "sampling_s", "sampling_cpu_s", "steps", "evaluations",
                "screen_evaluations", "tau", "acceptance", "load", *TIMED)  # fmt: skip
        for key in keys:
            v = np.array([r.get(key, np.nan) for r in mine], dtype=float)
            print(f"  {key:<20} median {np.median(v):>10.2f}   min {v.min():>10.2f}   "
                  f"max {v.max():>10.2f}")  # fmt: skip
        if "mean_error_in_sd" in mine[0]:
            worst_mean = max(max(r["mean_error_in_sd"]) for r in mine)
            worst_sd = max(max(map(abs, r["sd_error_relative"])) for r in mine)
            print(f"  against the reference: worst |mean error| {worst_mean:.3f} sd, worst "
                  f"|sd error| {100 * worst_sd:.1f} %")  # fmt: skip
    for moves in dict.fromkeys(r["moves"] for r in rows):
        mine = [r for r in rows if r["moves"] == moves]
        wall, cpu = (np.median([r[k] for r in mine]) for k in ("wall_s", "cpu_s"))
        print(f"[{moves}] median cold-start wall {wall:.1f} s, CPU {cpu:.1f} s (wall / CPU "
              f"{wall / cpu:.2f}) over {len(mine)} seeds")  # fmt: skip
    schemes = {r["moves"] for r in rows}
    if {"de", "mixture"} <= schemes:
        for key in ("wall_s", "cpu_s"):
            med = {m: np.median([r[key] for r in rows if r["moves"] == m]) for m in schemes}
            print(f"\nmedian {key}: de / mixture = {med['de'] / med['mixture']:.2f}")


def first_hold(path: str, stride: int = 10) -> int | None:
    """The first step count (a multiple of ``stride``) at which the stop rule of an empty
    ``[sampler]`` table (``pipelines.sample.sampler_settings(SamplerConfig())``) holds for the
    chain stored in the result file ``path``, None when it never does: a prefix of the chain is
    what the run had at that step, so the stop's overshoot is its step count over this one."""
    from bayesupdate.config import SamplerConfig
    from bayesupdate.inference.results import read_result
    from bayesupdate.inference.sampling import _stop_rule
    from bayesupdate.pipelines.sample import sampler_settings

    chain = np.asarray(read_result(path)["posterior"]["chain"])
    settings = sampler_settings(SamplerConfig())
    for n in range(stride, chain.shape[0] + 1, stride):
        if _stop_rule(chain[:n], n, settings)[1]:
            return n
    return None


def user_run(code: str, seed: int | None = None, overshoot: bool = False) -> dict:
    """One ``bayesupdate sample --model exhaust --data paper:ema --json`` in a fresh process
    on the source tree ``code`` (``--seed seed`` added when given): wall and CPU [s] of the
    whole process, and its JSON's numbers.  ``overshoot``: the run writes its result file
    (``--out``, in a temporary folder: not the user's command, so not for timing) and the row
    gets ``first_hold`` (``first_hold``) and ``overshoot`` = steps / first_hold."""
    import json
    import resource
    import subprocess
    import sys
    import tempfile

    code, _, extra = code.partition(":")
    env = {**os.environ, "PYTHONPATH": os.path.abspath(code)}
    command = [sys.executable, "-m", "bayesupdate", "sample", "--model", "exhaust", "--data",
               "paper:ema", "--json", *[a for a in extra.split(",") if a]]  # fmt: skip
    if seed is not None:
        command += ["--seed", str(seed)]
    if overshoot:
        folder = tempfile.mkdtemp(prefix="posterior_speed_")
        command += ["--out", os.path.join(folder, "run.h5")]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    # run in the tree itself: ``python -m`` puts the working folder first on sys.path
    done = subprocess.run(
        command, env=env, capture_output=True, text=True, check=True, cwd=os.path.abspath(code)
    )
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = json.loads(done.stdout)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    least_ess = min(p["ess_bulk"] for p in out["parameters"].values())
    stop = out.get("stop") or {}
    held = None
    if overshoot:
        held = first_hold(command[-1])
        os.remove(command[-1])
        os.rmdir(os.path.dirname(command[-1]))
    return dict(
        code=code + (f":{extra}" if extra else ""), seed=seed, wall_s=round(wall, 2),
        cpu_s=round(cpu, 2), steps=out["steps"],
        walkers=out["walkers"], evaluations=out["evaluations"], converged=out["converged"],
        min_ess=round(least_ess), ess_over_target=round(least_ess / 400.0, 2),
        held_before=stop.get("held_before"), checks=stop.get("checks"),
        screen_evaluations=(out.get("screen") or {}).get("evaluations"),
        max_r_hat=round(max(p["r_hat"] for p in out["parameters"].values()), 4),
        means={k: p["mean"] for k, p in out["parameters"].items()},
        phases={k: round(v, 2) for k, v in (out.get("timings") or {}).items()},
        load=round(os.getloadavg()[0], 1), split=(out.get("split") or {}).get("batches", 0),
        first_hold=held, overshoot=None if not held else round(out["steps"] / held, 3),
    )  # fmt: skip


def user_runs(n: int, codes: list[str], seeds: list | None = None, overshoot: bool = False) -> None:
    """``n`` rounds of ``user_run`` over the variants ``codes`` (interleaved; each round runs
    every seed of ``seeds``, default the study's own), one JSON row per run, then the medians
    per variant and, against the first variant, the paired CPU ratios (same round and seed):
    of the whole run, and of its kept steps' share (CPU / kept steps; the kept chain's length
    follows its random stream, which a change of the draws' order changes)."""
    import json

    rows = []
    for _ in range(n):
        for seed in seeds or [None]:
            for code in codes:
                rows.append(user_run(code, seed, overshoot))
                print(json.dumps(rows[-1]), flush=True)
    for code in codes:
        mine = [r for r in rows if r["code"] == code]
        keys = ("wall_s", "cpu_s", "steps", "evaluations", "min_ess", "ess_over_target", "load")
        med = {k: float(np.median([r[k] for r in mine])) for k in keys}
        print(f"[{code}] {len(mine)} runs: median wall {med['wall_s']:.1f} s, CPU "
              f"{med['cpu_s']:.1f} s, steps {med['steps']:.0f}, exact evaluations "
              f"{med['evaluations']:.0f}, least ESS {med['min_ess']:.0f} "
              f"({med['ess_over_target']:.1f} x the target 400), load average "
              f"{med['load']:.1f}; held before the stop: "
              f"{[r['held_before'] for r in mine]}")  # fmt: skip
    first = [r for r in rows if r["code"] == codes[0]]
    for code in codes[1:]:
        mine = [r for r in rows if r["code"] == code]
        cpu = [b["cpu_s"] / a["cpu_s"] for a, b in zip(first, mine, strict=True)]
        step = [(b["cpu_s"] / b["steps"]) / (a["cpu_s"] / a["steps"])
                for a, b in zip(first, mine, strict=True)]  # fmt: skip
        print(f"[{code}] / [{codes[0]}] paired CPU ratios {np.round(cpu, 3).tolist()} (median "
              f"{np.median(cpu):.3f}); CPU per kept step {np.round(step, 3).tolist()} (median "
              f"{np.median(step):.3f})")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--full", action="store_true", help="full FE solves instead of the ROM")
    ap.add_argument("--steps", type=int, default=20000, help="step budget of the main run")
    # R-hat <= 1.01 needs ~100 tau steps per walker whatever the walker count, and ESS ~ walkers x
    # steps / tau: 16 walkers reach ESS >= 1000 when R-hat does, with half the evaluations of 32
    ap.add_argument("--walkers", type=int, default=16)
    ap.add_argument("--transform", default="logit", choices=("logit", "none"))
    ap.add_argument("--check-every", type=int, default=250, help="steps between checks")
    ap.add_argument(
        "--adapt-steps", type=int, default=SamplerSettings.adapt_steps,
        help="steps of each adaptation stage of the mixture moves",
    )  # fmt: skip
    ap.add_argument("--starts", type=int, default=4, help="optimizer starts")
    ap.add_argument("--max-nfev", type=int, default=300, help="evaluations per start")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--seeds", type=int, default=0, help="timed runs: N seeds per move scheme")
    ap.add_argument("--first-seed", type=int, default=1, help="with --seeds: the first seed")
    ap.add_argument("--seed-list", type=int, nargs="+", help="timed runs on these seeds")
    ap.add_argument("--moves", nargs="+", default=["de", "mixture"], help="with --seeds")
    ap.add_argument(
        "--no-screen", action="store_true", help="no delayed acceptance (every proposal exact)"
    )
    ap.add_argument("--user", type=int, default=0, help="N cold runs of the user's command")
    ap.add_argument("--code", nargs="+", default=["."], help="with --user: source trees")
    ap.add_argument(
        "--user-seeds", type=int, nargs="+", help="with --user: sampler seeds (--seed) per round"
    )
    ap.add_argument(
        "--overshoot", action="store_true",
        help="with --user: write each run's result file and find where the stop rule first held"
        " (not for timing: the user's command writes no file)",
    )  # fmt: skip
    ap.add_argument(
        "--split-batches", action="store_true",
        help="exact and screen batches whole and split with one worker process (ms per batch)",
    )  # fmt: skip
    ap.add_argument("--save", help="save means/sd/wall to this .npz")
    ap.add_argument("--compare", nargs=2, metavar=("ROM_NPZ", "FULL_NPZ"), help="compare runs")
    args = ap.parse_args()
    if args.compare:
        compare(*args.compare)
        return
    if args.user:
        user_runs(args.user, args.code, args.user_seeds, args.overshoot)
        return
    if args.split_batches:
        split_batches(args)
        return
    warnings.simplefilter("default")
    if args.seeds or args.seed_list:
        table(timed_runs(args))
        return
    r = run(args, reduced=not args.full)
    report(r)
    if args.save:
        keys = ("mean", "sd", "wall_s", "cpu_s", "steps", "evaluations")
        np.savez(args.save, names=np.array(r["names"]), **{k: r[k] for k in keys})


def compare(rom_file: str, full_file: str) -> None:
    """Means of the two saved runs in units of the full run's posterior sd, and the wall ratio
    per sampler step (the full run is usually shorter: its wall time to convergence would be
    steps_rom / steps_full times longer)."""
    r, f = np.load(rom_file), np.load(full_file)
    diff = np.abs(r["mean"] - f["mean"]) / f["sd"]
    per_step = (float(f["wall_s"]) / int(f["steps"])) / (float(r["wall_s"]) / int(r["steps"]))
    per_step_cpu = (float(f["cpu_s"]) / int(f["steps"])) / (float(r["cpu_s"]) / int(r["steps"]))
    print(f"reduced: {int(r['steps'])} steps, wall {float(r['wall_s']):.0f} s, CPU "
          f"{float(r['cpu_s']):.0f} s; full: {int(f['steps'])} steps, wall "
          f"{float(f['wall_s']):.0f} s, CPU {float(f['cpu_s']):.0f} s")  # fmt: skip
    print(
        f"full / reduced time per step (incl. set-up): wall {per_step:.1f}, CPU {per_step_cpu:.1f}"
    )
    print(f"full run extrapolated to the reduced run's steps: wall "
          f"{per_step * float(r['wall_s']):.0f} s")  # fmt: skip
    for name, d in zip(r["names"], diff, strict=True):
        print(f"  {str(name):<26} |mean_rom - mean_full| / sd_full = {d:.3f}")
    print(f"  means within 0.1 sd: {bool(np.all(diff <= 0.1))}")


if __name__ == "__main__":
    main()
