"""Posterior of the exhaust's five design variables and sigma given seed Table 2, and how far it
moves under model-form uncertainty (joint stiffnesses as nuisance parameters; runner-up
geometries of the FE fit).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python studies/uncertainty_study.py \
        [--steps 6000] [--runner-ups 2] [--out studies/out/uncertainty] [--workers 2]
    OPENBLAS_NUM_THREADS=1 .venv/bin/python studies/uncertainty_study.py --coverage 20 \
        --steps 1500        # synthetic exhaust, coverage of the 90 % intervals only

Cases: ``best`` (the stored best geometry, five design variables + sigma), ``best+joints`` (the
same with the six joint spring factors k_A__B sampled as nuisance parameters, lognormal prior
mu = 0, sigma = ``--joint-sigma`` of the log, truncated to [0.1, 10]: the connection stiffness a
shell model resolves and this beam model lumps), and ``geometry N`` (runner-up geometries, five
design variables).  Each case: certified reduced model over the prior box
(``pipelines.surrogates.sampling_problem``), multi-start optimum on it, emcee (DE moves) from the
optimum, checked in full at the optimum and the posterior mean.  Priors uniform on the bounds;
sigma inferred (half-normal, scale 0.1); shape-tracked pairing in the likelihood.

Prints the design variables' marginal posterior (mean, sd, 90 % HDI) per case side by side,
the thickness-density correlations of the best case and the least-determined combinations, and
writes one HDF5 result per case, figures of the best case and ``summary.json``.
"""

import argparse
import json
from pathlib import Path

import numpy as np

from bayesupdate.inference import (
    CalibrationSettings,
    LikelihoodSpec,
    LogPosterior,
    SamplerSettings,
    build_problem,
    calibrate,
    load_modal_data,
    posterior_predictive,
    prior_from_mapping,
    read_result,
    sample_posterior,
    summarize,
    write_result,
)
from bayesupdate.inference.coverage import interval_coverage
from bayesupdate.inference.plots import DesignReference, save_all
from bayesupdate.models import get_model
from bayesupdate.models.exhaust_paper import (
    DESIGN_VARIABLES,
    TABLE3_INITIAL_SI,
    TABLE3_OPTIMUM_SI,
)
from bayesupdate.pipelines.surrogates import certify_rom, sampling_problem


def run_case(label, geometry, joints, args, out: Path) -> dict:
    model = get_model("exhaust", geometry=geometry, joint_nuisance=joints)
    table = {name: {} for name in DESIGN_VARIABLES}
    if joints:
        for name in model.parameter_names:
            if name.startswith("k_"):
                table[name] = {"prior": {"kind": "lognormal", "mu": 0.0, "sigma": args.joint_sigma}}
    problem = build_problem(model, load_modal_data("paper:ema"), table, pairing="tracked")
    problem, rom = sampling_problem(problem)
    optimum = calibrate(problem, CalibrationSettings(starts=args.starts, seed=0, max_nfev=400))
    spec = LikelihoodSpec(
        sigma=None,
        sigma_prior=prior_from_mapping({"kind": "halfnormal", "scale": 0.1}, (0.0, 1.0), "sigma"),
    )
    log_post = LogPosterior(problem, spec)
    settings = SamplerSettings(
        walkers=max(args.walkers, 2 * log_post.ndim + 2),
        steps=args.steps,
        seed=args.seed,
        min_autocorr_times=50.0,
        check_every=1000,
        transform="logit",
    )
    posterior = sample_posterior(log_post, optimum, settings)
    summary = summarize(posterior)
    rom_info = None
    if rom is not None:
        mean = posterior.samples()[:, : len(problem.names)].mean(axis=0)
        rom_info = certify_rom(rom, mean[None, :], problem.names, f"{label} posterior mean")[1]
    predictions = posterior_predictive(log_post, posterior, seed=args.seed)
    path = write_result(
        out / f"posterior_{label.replace(' ', '_').replace('+', '_')}.h5",
        problem,
        optimum,
        {**vars(args), "case": label},
        posterior=posterior,
        diagnostics=summary,
        predictions=predictions,
        command="uncertainty_study",
    )
    draws = posterior.samples()
    return {
        "label": label,
        "path": str(path),
        "optimum": optimum.parameters,
        "optimum_expr": optimum.expr,
        "summary": summary,
        "names": list(posterior.names),
        "draws": draws,
        "steps": int(posterior.chain.shape[0]),
        "wall_s": posterior.wall_s,
        "r_hat_max": max(row["r_hat"] for row in summary.values()),
        "ess_min": min(row["ess_bulk"] for row in summary.values()),
        "pair_differs_fraction": log_post.pair_differs_fraction,
        "rom": rom_info,
    }


def print_table(cases: list[dict]) -> None:
    print("\nmarginal posterior of the design variables: mean (sd) [90 % HDI]; Table 3 optimum")
    for name in DESIGN_VARIABLES:
        scale = 1e3 if name.startswith("t_") else 1.0
        unit = "mm" if name.startswith("t_") else "kg/m3"
        print(f"{name} [{unit}]  (paper optimum {TABLE3_OPTIMUM_SI[name] * scale:.4g})")
        for c in cases:
            row = c["summary"][name]
            print(
                f"   {c['label']:<14} {row['mean'] * scale:9.4g} ({row['sd'] * scale:8.3g}) "
                f"[{row['hdi_low'] * scale:9.4g}, {row['hdi_high'] * scale:9.4g}]"
            )
    print(
        "\nper case: steps, wall s, R-hat max, ESS min, sigma mean, optimum Expr, pairing differs"
    )
    for c in cases:
        print(
            f"   {c['label']:<14} {c['steps']:6d} {c['wall_s']:7.0f} {c['r_hat_max']:7.3f} "
            f"{c['ess_min']:7.0f} {c['summary']['sigma']['mean']:.3f} {c['optimum_expr']:.4f} "
            f"{c['pair_differs_fraction']:.2f}"
        )


def coverage_study(replicates: int, steps: int, noise: float = 0.02) -> dict:
    """Synthetic exhaust: data = the reduced model at seed Table 3's optimum (the known truth)
    with ``noise`` relative Gaussian noise on the 12 frequencies, sigma fixed at ``noise``;
    coverage of the 90 % HDI of each design variable over ``replicates`` seeds."""
    from bayesupdate.fe.reduced import reduced_model_for

    rom = reduced_model_for(get_model("exhaust"), tol=1e-4, seed=0, n_modes=12)
    truth = {name: TABLE3_OPTIMUM_SI[name] for name in DESIGN_VARIABLES}
    result = interval_coverage(
        rom,
        truth,
        12,
        noise,
        {name: {} for name in DESIGN_VARIABLES},
        replicates=replicates,
        walkers=16,
        steps=steps,
        starts=2,
        transform="logit",
        max_nfev=300,
    )
    print(
        f"\ncoverage of the 90 % HDI over {replicates} synthetic data sets (noise {noise:.0%}, "
        f"binomial sd {result['binomial_sd']:.3f}):"
    )
    for name, share in result["coverage"].items():
        print(f"  {name:<26} {share:.2f}")
    print(f"  all parameters pooled      {np.mean(list(result['coverage'].values())):.2f}")
    return result


def _case_task(shared: tuple, item: tuple) -> dict:
    """One case on the executor (shared: the parsed arguments and the output folder)."""
    args, out = shared
    return run_case(*item, args, out)


def _run_cases(plan: list, args, out: Path) -> list[dict]:
    """The cases of ``plan`` on the executor of ``--workers``/``--scheduler`` (independent,
    each seeded by ``--seed``: the same results serial or parallel), in plan order."""
    from bayesupdate.compute.settings import open_executor
    from bayesupdate.config import compute_settings

    def progress(i, case):
        print(f"{case['label']}: {case['steps']} steps, {case['wall_s']:.0f} s, "
              f"R-hat max {case['r_hat_max']:.3f}", flush=True)  # fmt: skip

    with open_executor(compute_settings(args.workers, args.scheduler)) as executor:
        return executor.map(_case_task, plan, (args, out), progress=progress)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=6000)
    parser.add_argument("--walkers", type=int, default=32)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--starts", type=int, default=4)
    parser.add_argument("--runner-ups", type=int, default=2, help="runner-up geometries 1..N")
    parser.add_argument("--joint-sigma", type=float, default=0.7, help="sd of log joint factor")
    parser.add_argument("--out", default="studies/out/uncertainty")
    parser.add_argument("--workers", type=int, help="cases in N local processes (default: serial)")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="cases on a Dask scheduler")
    parser.add_argument(
        "--coverage", type=int, default=0, help="only the synthetic coverage check, N seeds"
    )
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.coverage:
        result = coverage_study(args.coverage, steps=args.steps)
        (out / "coverage.json").write_text(
            json.dumps({k: v for k, v in result.items() if k != "intervals"}, indent=1)
        )
        return

    plan = [("best", "best", False), ("best+joints", "best", True)]
    plan += [(f"geometry {g}", g, False) for g in range(1, args.runner_ups + 1)]
    cases = _run_cases(plan, args, out)
    table3 = DesignReference(TABLE3_INITIAL_SI, TABLE3_OPTIMUM_SI, "seed Table 3 optimum")
    save_all(read_result(cases[0]["path"]), out, table3)
    print_table(cases)

    best = cases[0]
    names = best["names"]
    corr = np.corrcoef(best["draws"].T)
    print("\ncorrelations thickness - density (best geometry):")
    for a in names:
        for b in names:
            if a.startswith("t_") and b.startswith("rho_"):
                print(f"  {a} / {b}: {corr[names.index(a), names.index(b)]:+.2f}")
    eigval, eigvec = np.linalg.eigh(corr)
    print("least-determined combinations (largest eigenvalues of the posterior correlation):")
    for k in np.argsort(eigval)[::-1][:2]:
        terms = " ".join(
            f"{eigvec[j, k]:+.2f}*{names[j]}" for j in np.argsort(-abs(eigvec[:, k]))[:3]
        )
        print(f"  eigenvalue {eigval[k]:.2f}: {terms}")
    (out / "summary.json").write_text(
        json.dumps(
            {
                "cases": [{k: v for k, v in c.items() if k != "draws"} for c in cases],
                "correlation_best": corr.tolist(),
                "names_best": names,
            },
            indent=1,
            default=float,
        )
    )


if __name__ == "__main__":
    main()
