"""``bayesupdate sample``: posterior of the parameters (and sigma) with emcee."""

import contextlib
import json
import signal
import sys

import numpy as np

from bayesupdate.commands._shared import (
    add_compute_arguments,
    add_full_argument,
    add_study_arguments,
    add_write_bdf_argument,
    check_outputs,
    compute_from_args,
    report_refused,
    report_warnings,
    study_from_args,
    write_bdf,
)
from bayesupdate.compute import progress
from bayesupdate.compute.stop import StopRequest
from bayesupdate.errors import BayesUpdateError

NAME = "sample"
HELP = "posterior of the parameters with emcee (mixture or DE moves), diagnostics, predictive bands"
DESCRIPTION = """Sample the posterior: Gaussian likelihood on relative frequency errors
(sigma_i = sigma / sqrt(w_i)), priors per parameter, emcee, walkers started at the multi-start
optimum, run until 50 autocorrelation times and R-hat <= 1.01, bulk ESS >= 400
(sampler.target_rhat / target_ess) or --steps.  Moves (--moves, sampler.moves): "mixture"
(default) fits a Gaussian mixture + prior independence proposal in two adaptation stages, freezes
it and keeps only the run after that (0.8 mixture, 0.2 differential evolution); "de" uses
differential-evolution moves alone.  A mixture that cannot be fitted falls back to DE ("moves":
{"kind": "de", "fallback": why} in --json).

  bayesupdate sample study.toml --out post.h5
  bayesupdate sample --model shear_building --data freqs.csv --out post.h5 --json

FE models (built-in ones and Nastran decks) are sampled on a certified reduced basis (checked in
full at the optimum and the posterior mean; a warning suggests --full when it misses its
tolerance); --full forces full solves.  Proposals are first screened on a coarser basis
(delayed acceptance; exact, only the survivors are solved; with --full the certified basis
screens the full solves; sampler.screen).
With frequency-only data, model modes are tracked by shape against the reference
design for every walker (no silent mode swaps).

Ctrl-C (or SIGTERM) keeps a valid partial result in --out; --resume continues it and, with the
same seed, ends with the same chain as an uninterrupted run.  --json prints {"parameters": {NAME:
{"mean", "sd", "hdi_low", "hdi_high", "r_hat", "ess_bulk"}}, "sigma", "evaluations", "wall_s",
"autocorr_time", "rom": {"size", "max_rel_error", "error_at_posterior_mean", "error_at_optimum",
"size_before_optimum", "enrich_above"} | null (the basis is enriched at the optimum when its
error there exceeds enrich_above, a tenth of the likelihood's smallest relative sd),
"full_solves_reason": why an FE model got full solves instead of its reduced basis | null,
"screen": {"size", "max_rel_error", "evaluations"} | null, "screen_skipped": why a configured
screen was not used (its error above the likelihood's smallest sd) | null,
"pairing", "pair_differs_fraction", "moves": {"kind", "requested", "fallback", "components",
"adapt_steps", "coverage", "stuck", "coordinates": per fit, "sampler" or "unit box"},
"stop": {"checks", "steps", "held_before" (what held the run at the check before the stop:
"tau", "r_hat" or "ess"), "ess_at_stop", "ess_over_target"},
"split": {"batches", "stopped"} | null (the walkers' batches evaluated in two parts at once, half
on a worker process: with --workers N >= 2, or by default when a core is free and a batch costs
enough, so that, like wall_s, it depends on the machine's load at the start; --workers 1 keeps
one process; the chain is the same bits either way),
"compute": {"kind", "workers"}, "test_modes" (each test mode's number in its source),
"pairing_rules" ({"method", "mac_threshold", "frequency_window", "refused"}: test modes refused
at the reference design, as calibrate), "warnings" (the posterior piled at a bound, a paired MAC
below the threshold at the optimum; also on stderr and in --out), "mass_properties": [{name,
measured, predicted, unit, sd}] of the measured mass, CG and inertia at the posterior mean
(model units), ...}."""


def add_arguments(parser) -> None:
    add_study_arguments(parser, sampling=True)
    add_compute_arguments(parser)
    add_full_argument(parser)
    add_write_bdf_argument(parser)
    parser.add_argument(
        "--moves",
        metavar="KIND",
        help="sampler moves: mixture (default; frozen mixture proposal + DE) or de",
    )
    parser.add_argument(
        "--sampler",
        choices=("emcee", "tmcmc"),
        default="emcee",
        help="emcee (default) or tmcmc: tempered SMC from the prior, with the log evidence",
    )
    parser.add_argument(
        "--particles", type=int, default=1000, help="tmcmc: number of particles (default 1000)"
    )


def run(args) -> int:
    if args.resume and not args.out:
        raise BayesUpdateError("--resume needs --out FILE (the partial result to continue)")
    check_outputs(args, resume=args.resume)  # before the imports below
    from bayesupdate.pipelines.study import prepare

    study = study_from_args(args)
    compute = compute_from_args(args, study)
    prepared = prepare(study, effects=tuple(args.effect))
    report_refused(prepared.problem)
    if args.sampler == "tmcmc":
        return _run_tmcmc(prepared, args)
    run = _sample_with_stop_handlers(prepared, args, compute)
    posterior = run.posterior
    if posterior.interrupted:
        where = f"; partial result in {args.out}, continue with --resume" if args.out else ""
        print(f"sample: stopped after {posterior.chain.shape[0]} steps{where}", file=sys.stderr)
        raise KeyboardInterrupt
    out = sample_json(posterior, run.summary, prepared.likelihood, run.predictions)
    out["compute"] = run.compute
    out["test_modes"] = [int(n) for n in prepared.problem.mode_numbers]
    out["pairing_rules"] = prepared.problem.pairing.to_dict()
    out["warnings"] = list(run.warnings)
    report_warnings(run.warnings)
    out["timings"] = progress.timings()
    out["mass_properties"] = list(run.mass_properties)
    means = {k: v["mean"] for k, v in out["parameters"].items()}
    write_bdf(args.write_bdf, prepared.problem.model, means)
    if not out["converged"]:  # said on every path, never implied by a number in a table
        reason = (out["convergence"] or {}).get("reason", "")
        print(f"warning: the posterior did not converge: {reason}", file=sys.stderr)
    if args.json:
        print(json.dumps(out))
    else:
        _print_summary(out, run.summary, study.sampler)
    return 0


def _asked_one_process(args, study) -> bool:
    """Whether the user asked for this process alone (--workers 1, [compute] workers = 1)."""
    table = study.extensions.get("compute")
    return args.workers == 1 or (table is not None and table.workers == 1 and not table.scheduler)


def _sample_with_stop_handlers(prepared, args, compute):
    """``pipelines.sample.run_sampling`` with SIGTERM/SIGINT turned into a checkpointed stop."""
    from bayesupdate.pipelines.sample import SamplingOptions, run_sampling

    stop = StopRequest()
    options = SamplingOptions(
        out=args.out,
        resume=args.resume,
        progress=not (args.json or args.no_progress),
        stop=stop,
        compute=compute,
        # --workers 1 or [compute] workers = 1: this process alone, no worker of the sampler's
        split=None if _asked_one_process(args, prepared.study) else "auto",
    )
    previous_hook, sys.unraisablehook = sys.unraisablehook, stop.quiet_unraisable
    previous_excepthook, sys.excepthook = sys.excepthook, stop.quiet_excepthook
    previous = signal.signal(signal.SIGTERM, stop.handler)
    # a process started in the background by a non-interactive shell inherits SIGINT ignored,
    # and Python then never raises KeyboardInterrupt: make Ctrl-C/SIGINT always checkpoint
    previous_int = signal.signal(signal.SIGINT, stop.handler)
    try:
        with progress.silenced() if args.no_progress else contextlib.nullcontext():
            return run_sampling(prepared, options)
    finally:
        signal.signal(signal.SIGTERM, previous)
        signal.signal(signal.SIGINT, previous_int)
        sys.unraisablehook = previous_hook
        sys.excepthook = previous_excepthook


def _print_summary(out: dict, summary: dict, sampler) -> None:
    """The terminal table of a sampling run (without --json)."""
    print(
        f"{out['steps']} steps x {out['walkers']} walkers, {out['evaluations']} evaluations "
        f"({out['failed_evaluations']} failed), {out['wall_s']:.1f} s, "
        f"converged ({_criteria(sampler)}): {out['converged']}"
    )
    rom = out["rom"]
    print(
        "full FE solves"
        if rom is None
        else f"reduced basis: size {rom['size']}, max relative frequency error "
        f"{rom['max_rel_error']:.1e}"
    )
    if out["screen_skipped"]:
        print(f"screen: {out['screen_skipped']}")
    if out["pair_differs_fraction"] is not None:
        print(
            f"pairing by shape: {out['pair_differs_fraction']:.0%} of evaluations pair "
            "differently from the mode order"
        )
    print("name                      mean         sd     hdi_low    hdi_high  r_hat  ess_bulk")
    for name, row in summary.items():
        print(
            f"{name:20s} {row['mean']:10.5g} {row['sd']:10.4g} {row['hdi_low']:10.5g} "
            f"{row['hdi_high']:10.5g} {row['r_hat']:6.3f} {row['ess_bulk']:8.0f}"
        )


def _criteria(sampler) -> str:
    """The stopping rule in words, e.g. ">= 50 tau, R-hat <= 1.01, ESS >= 1000"."""
    parts = [f">= {sampler.min_autocorr_times:g} tau"]
    if sampler.target_rhat is not None:
        parts.append(f"R-hat <= {sampler.target_rhat:g}")
    if sampler.target_ess:
        parts.append(f"ESS >= {sampler.target_ess:g}")
    return ", ".join(parts)


def sample_json(posterior, summary: dict, likelihood, predictions: dict | None = None) -> dict:
    """The ``sample --json`` object of a ``PosteriorResult``, its summary, the
    ``LikelihoodSpec`` and the posterior predictive, plus failed_evaluations, steps, walkers,
    converged, convergence ({"converged", "reason" (null when converged), "max_r_hat",
    "min_ess_bulk", "target_rhat", "target_ess", "steps"}), swap_fraction (share of checked
    draws whose modes are swapped against their order; None if the model gives no shapes), "rom"
    ({"size", "max_rel_error", "error_at"} of the reduced basis used, null with --full),
    "screen" ({"size", "max_rel_error" against the reduced basis, "evaluations"} of the delayed-
    acceptance surrogate, null without), "pairing" (likelihood mode) and "pair_differs_fraction"
    (share of likelihood evaluations paired differently from the order pairing; null unless the
    likelihood paired by shape)."""
    keys = ("mean", "sd", "hdi_low", "hdi_high", "r_hat", "ess_bulk")
    params = {
        name: {k: summary[name][k] for k in keys} for name in posterior.names if name != "sigma"
    }
    if likelihood.infer_sigma:
        sigma = {k: summary["sigma"][k] for k in keys}
    else:
        sigma = {"fixed": float(likelihood.sigma)}
    return {
        "parameters": params,
        "sigma": sigma,
        "evaluations": int(posterior.evaluations),
        "failed_evaluations": int(posterior.failed_evaluations),
        "wall_s": float(posterior.wall_s),
        "autocorr_time": [float(t) for t in posterior.autocorr_time],
        "steps": int(posterior.chain.shape[0]),
        "walkers": int(posterior.chain.shape[1]),
        "converged": bool(posterior.converged),
        "convergence": posterior.diagnostics.get("convergence"),
        "rom": _rom_json(posterior.diagnostics.get("rom")),
        "full_solves_reason": posterior.diagnostics.get("full_solves_reason"),
        "screen": posterior.diagnostics.get("screen"),
        "screen_skipped": posterior.diagnostics.get("screen_skipped"),
        "pairing": posterior.diagnostics.get("pairing_mode"),
        "pair_differs_fraction": _finite_or_none(
            posterior.diagnostics.get("pair_differs_fraction")
        ),
        "moves": posterior.diagnostics.get("moves"),
        "stop": posterior.diagnostics.get("stop"),
        "split": posterior.diagnostics.get("split"),
        "swap_fraction": None
        if not predictions or not np.isfinite(predictions["swap_fraction"])
        else float(predictions["swap_fraction"]),
    }


def _rom_json(rom: dict | None) -> dict | None:
    if not rom:
        return None
    return {
        "size": int(rom["size"]),
        "max_rel_error": float(rom["max_rel_error"]),
        "error_at_posterior_mean": _finite_or_none(rom.get("error_at")),
        "error_at_optimum": _finite_or_none(rom.get("error_at_optimum")),
        "size_before_optimum": rom.get("size_before_optimum"),
        "enrich_above": _finite_or_none(rom.get("enrich_above")),
    }


def _finite_or_none(value) -> float | None:
    return None if value is None or not np.isfinite(value) else float(value)


def _run_tmcmc(prepared, args) -> int:
    """``--sampler tmcmc``: ``pipelines.sample_tmcmc``; the JSON or a short table."""
    from bayesupdate.inference.tmcmc import TMCMCSettings
    from bayesupdate.pipelines.sample_tmcmc import sample_tmcmc, tmcmc_json

    if args.out or args.resume or args.write_bdf:
        raise BayesUpdateError("--sampler tmcmc: --out, --resume and --write-bdf need emcee")
    cfg = prepared.study.sampler
    settings = TMCMCSettings(particles=args.particles, seed=cfg.seed)
    out = tmcmc_json(sample_tmcmc(prepared, settings), cfg.hdi_prob)
    out["timings"] = progress.timings()
    if args.json:
        print(json.dumps(out))
        return 0
    for name, p in out["parameters"].items():
        interval = f"[{p['q_low']:.6g}, {p['q_high']:.6g}]"
        print(f"{name:28s} {p['mean']:12.6g} sd {p['sd']:10.4g}  {interval}")
    print(
        f"log evidence {out['log_evidence']:.3f} nats; {out['stages']} stages, "
        f"{out['evaluations']} evaluations"
    )
    return 0
