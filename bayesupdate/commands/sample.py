"""``bayesupdate sample``: posterior of the parameters (and sigma) with emcee."""

import json
import signal
import sys

from bayesupdate import interrupts
from bayesupdate.commands.calibrate import (
    add_full_argument,
    add_study_arguments,
    model_extension,
    study_from_args,
)
from bayesupdate.errors import BayesUpdateError

NAME = "sample"
HELP = "posterior of the parameters with emcee (DE moves), diagnostics, predictive bands"
DESCRIPTION = """Sample the posterior: Gaussian likelihood on relative frequency errors
(sigma_i = sigma / sqrt(w_i)), priors per parameter, emcee with differential-evolution moves,
walkers started at the multi-start optimum, run until 50 autocorrelation times and R-hat <= 1.01,
bulk ESS >= 400 (sampler.target_rhat / target_ess) or --steps.

  bayesupdate sample study.toml --out post.h5
  bayesupdate sample --model shear_building --data freqs.csv --out post.h5 --json

Built-in FE models are sampled on a certified reduced basis (checked in full at the optimum and
the posterior mean; a warning suggests --full when it misses its tolerance); --full forces full
solves.  Proposals are first screened on a coarser basis (delayed acceptance; exact, only the
survivors are solved; with --full the certified basis screens the full solves; sampler.screen).
With frequency-only data, model modes are tracked by shape against the reference
design for every walker (no silent mode swaps).

Ctrl-C (or SIGTERM) keeps a valid partial result in --out; --resume continues it and, with the
same seed, ends with the same chain as an uninterrupted run.  --json prints {"parameters": {NAME:
{"mean", "sd", "hdi_low", "hdi_high", "r_hat", "ess_bulk"}}, "sigma", "evaluations", "wall_s",
"autocorr_time", "rom": {"size", "max_rel_error", "error_at_posterior_mean"} | null,
"screen": {"size", "max_rel_error", "evaluations"} | null,
"pairing", "pair_differs_fraction", ...}."""


def add_arguments(parser) -> None:
    add_study_arguments(parser, sampling=True)
    add_full_argument(parser)


def run(args) -> int:
    from bayesupdate.atomic import check_output_path
    from bayesupdate.inference.runner import prepare, run_sampling, sample_json

    study = study_from_args(args)
    if args.resume and not args.out:
        raise BayesUpdateError("--resume needs --out FILE (the partial result to continue)")
    if args.out:
        check_output_path(args.out, force=args.force or args.resume)
    prepared = prepare(study, extend=model_extension(args, study))
    interrupts.clear()
    previous_hook, sys.unraisablehook = sys.unraisablehook, interrupts.quiet_unraisable
    previous_excepthook, sys.excepthook = sys.excepthook, interrupts.quiet_excepthook
    previous = signal.signal(signal.SIGTERM, interrupts.stop_handler)
    # a process started in the background by a non-interactive shell inherits SIGINT ignored,
    # and Python then never raises KeyboardInterrupt: make Ctrl-C/SIGINT always checkpoint
    previous_int = signal.signal(signal.SIGINT, interrupts.stop_handler)
    try:
        _, posterior, summary, predictions = run_sampling(
            prepared, args.out, resume=args.resume, progress=not (args.json or args.no_progress)
        )
    finally:
        signal.signal(signal.SIGTERM, previous)
        signal.signal(signal.SIGINT, previous_int)
        sys.unraisablehook = previous_hook
        sys.excepthook = previous_excepthook
        interrupts.clear()
    if posterior.interrupted:
        where = f"; partial result in {args.out}, continue with --resume" if args.out else ""
        print(f"sample: stopped after {posterior.chain.shape[0]} steps{where}", file=sys.stderr)
        raise KeyboardInterrupt
    out = sample_json(posterior, summary, prepared.likelihood, predictions)
    if not out["converged"]:  # said on every path, never implied by a number in a table
        reason = (out["convergence"] or {}).get("reason", "")
        print(f"warning: the posterior did not converge: {reason}", file=sys.stderr)
    if args.json:
        print(json.dumps(out))
    else:
        print(
            f"{out['steps']} steps x {out['walkers']} walkers, {out['evaluations']} evaluations "
            f"({out['failed_evaluations']} failed), {out['wall_s']:.1f} s, "
            f"converged ({_criteria(study.sampler)}): {out['converged']}"
        )
        rom = out["rom"]
        print(
            "full FE solves"
            if rom is None
            else f"reduced basis: size {rom['size']}, max relative frequency error "
            f"{rom['max_rel_error']:.1e}"
        )
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
    return 0


def _criteria(sampler) -> str:
    """The stopping rule in words, e.g. ">= 50 tau, R-hat <= 1.01, ESS >= 1000"."""
    parts = [f">= {sampler.min_autocorr_times:g} tau"]
    if sampler.target_rhat is not None:
        parts.append(f"R-hat <= {sampler.target_rhat:g}")
    if sampler.target_ess:
        parts.append(f"ESS >= {sampler.target_ess:g}")
    return ", ".join(parts)
