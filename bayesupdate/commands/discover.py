"""``bayesupdate discover``: find where model and test disagree, name the missing effect."""

import json
import sys

from bayesupdate.commands._shared import (
    add_compute_arguments,
    add_study_arguments,
    check_outputs,
    compute_from_args,
    plot_folder,
    study_file,
)
from bayesupdate.errors import BayesUpdateError

NAME = "discover"
HELP = "find where model and test disagree, name the missing effect, add it, show the gap shrink"
DESCRIPTION = """Discovery on top of the calibration: the baseline calibration of the design
variables, modes flagged against the noise, a score test of every effect of the library at
every admissible location, refits of the promising ones with the design variables, comparison
by Laplace evidence (Bayes factors vs the baseline) and PSIS-LOO, and a verdict: "explained"
(one effect wins: ln BF > 3 vs baseline and >= 2 vs the runner-up, and fits within noise),
"no discrepancy" or "unexplained".

  bayesupdate discover --model exhaust --data test.h5 --out discovery.h5 --json
  bayesupdate discover study.toml --out discovery.h5 --plots figs/
  bayesupdate discover --model exhaust --data paper:ema --effect bend_flexibility@elbow:factor=2

--json prints {"verdict", "flagged_modes", "named_effect": {"kind", "location", "parameters"},
"candidates": [{"kind", "location", "log_evidence", "loo", ...}], "gap_before", "gap_after",
...} (gaps: seed eq. 19 Expr; flagged_modes: test modes by their number in the data source,
a study's [data] modes selection included; an effect's parameters in the model's units: a
Nastran deck's own, e.g. lbf s^2/in for a mass, while --effect specs are SI).  Noise: the
data's frequency sd when given, else --sigma, else inferred from the frequency-only baseline's
residuals (robust), and held fixed.  When the data
have mode shapes (an identified test, paired by MAC), each mode's shape residual is evidence too,
at a level fixed the same way: its stated sd (identification estimates one; floored at 1 %),
raised to its misfit at the baseline where that misfit rejects it, so no single mode can drag the
design away from what the frequencies say (bayesupdate.discovery.shape_evidence); the JSON's
"noise" says which modes were raised.  A study's measured mass properties ([data] mass,
mass_sd, cg, inertia) are data as in calibrate: an effect that adds mass pays for the weight it
adds (each candidate's "mass_z": model minus measured, in sds).  On a Nastran deck the library
also scales the modulus of one line property's elements ("stiffness_change@PBEAM 1003")."""


def add_arguments(parser) -> None:
    # study, --model, --data, --out, --force, --json, --seed, --starts, --effect: as calibrate
    add_study_arguments(parser)
    parser.add_argument("--kinds", help="comma-separated effect kinds to consider (default all)")
    parser.add_argument("--sigma", type=float, help="fixed relative frequency noise level")
    parser.add_argument(
        "--threshold",
        type=float,
        help="posterior log odds (ln BF + prior log odds) a candidate must beat (default 3)",
    )
    parser.add_argument(
        "--effect-prior",
        type=float,
        help="prior probability that one library effect is present, spread equally over the "
        "candidates scanned (default 0.5)",
    )
    parser.add_argument("--max-refits", type=int, help="candidates fitted to convergence")
    parser.add_argument("--plots", metavar="DIR", help="write residuals/localization/ranking PNG")
    add_compute_arguments(parser)
    parser.add_argument(
        "--posterior-steps",
        type=int,
        default=0,
        help="also sample the re-calibrated model's posterior with emcee (steps; default off)",
    )


def _settings(study, args):
    from bayesupdate.discovery.settings import DiscoverySettings

    settings = study.extensions.get("discovery") or DiscoverySettings()
    changes = {
        "seed": args.seed,
        "baseline_starts": args.starts,
        "sigma": args.sigma,
        "threshold_log_odds": args.threshold,
        "effect_prior": args.effect_prior,
        "max_refits": args.max_refits,
        "kinds": tuple(k.strip() for k in args.kinds.split(",")) if args.kinds else None,
    }
    return settings.replaced(**{k: v for k, v in changes.items() if v is not None})


def run(args) -> int:
    check_outputs(args)  # before the imports below
    from bayesupdate.compute.progress import timings as phase_timings
    from bayesupdate.discovery.results_io import discovery_summary, write_discovery
    from bayesupdate.pipelines.discover import DiscoveryRequest, discover_study
    from bayesupdate.pipelines.study import study_effects

    study = study_file(args)  # --no-mass leaves the measured mass properties out, as calibrate
    plot_folder(args.plots)
    if args.posterior_steps < 0:
        raise BayesUpdateError(f"--posterior-steps must be >= 0, got {args.posterior_steps}")
    specs = study_effects(study, tuple(args.effect))
    compute = compute_from_args(args, study)
    request = DiscoveryRequest(_settings(study, args), specs, args.posterior_steps, compute)
    progress = None if args.json else (lambda message: print(message, file=sys.stderr))
    found = discover_study(study, request, progress)
    result, posterior = found.result, found.posterior
    for refused in found.pairing.get("refused", []):
        print(f"pairing: {refused['message']}", file=sys.stderr)
    timings = phase_timings()
    if args.out:
        write_discovery(
            args.out, result, list(specs), study.to_dict(), command=NAME, posterior=posterior,
            timings=timings,
        )  # fmt: skip
    if args.plots:
        from bayesupdate.discovery.plots import save_plots

        save_plots(result, args.plots, getattr(found.model, "structure", None))
    summary = discovery_summary(result)
    summary["compute"] = found.compute
    if found.pairing:
        summary["pairing"] = found.pairing
    summary["timings"] = timings
    if posterior is not None:
        summary["posterior"] = posterior[1]
    if args.json:
        print(json.dumps(summary))
        return 0
    _print_summary(result, summary, list(specs))
    return 0


def _print_summary(result, summary: dict, specs: list) -> None:
    """The terminal report of a discovery run (without --json)."""
    print(f"verdict: {result.verdict} - {result.reason}")
    print(f"noise: {result.noise.source}, sigma = {100 * result.noise.sigma:.3g} %")
    print(f"flagged modes: {summary['flagged_modes']}")
    print(
        f"prior log odds of each of {summary['scanned']} candidates vs the baseline: "
        f"{summary['prior_log_odds']:.2f}; baseline posterior probability "
        f"{summary['baseline']['posterior_probability']:.3g}"
    )
    print(
        "candidate                                  ln BF  log odds  P(post)  LOO elpd  Expr  stage"
    )
    for c in summary["candidates"][:10]:
        loo = "      -" if c["loo"] is None else f"{c['loo']:9.2f}"
        label = f"{c['kind']}@{c['location']}"
        print(
            f"  {label:38s} {c['log_bayes_factor']:8.2f} {c['log_posterior_odds']:8.2f} "
            f"{c['posterior_probability']:8.3g} {loo} {c['expr']:9.4g}  {c['stage']}"
        )
    print(
        f"gap (Expr, seed eq. 19): before {summary['gap_before']:.4g}, "
        f"after {summary['gap_after']:.4g}"
    )
    if result.effects:
        print("extended model: " + " ".join(f"--effect {s}" for s in specs + result.effects))
