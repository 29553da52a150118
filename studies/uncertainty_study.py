"""Posterior of the exhaust's five design variables and sigma given seed Table 2.

    .venv/bin/python studies/uncertainty_study.py [--steps 5000] [--out studies/out/uncertainty]

Priors uniform on the model's bounds; sigma inferred (halfnormal, scale 0.1); joint stiffnesses,
when the model exposes them as parameters, sampled as nuisance parameters with lognormal priors
(sd of the log 1.0 around the model's value).  Prints the posterior table, the thickness-density
correlations and the parameter combinations the data cannot tell apart (the eigenvectors of the
posterior correlation matrix with the largest eigenvalues), and writes the result file, the
figures and ``summary.json``.
"""

import argparse
import json
from pathlib import Path

import numpy as np

from bayesupdate.inference import (
    LikelihoodSpec,
    LogPosterior,
    build_problem,
    calibrate,
    load_modal_data,
    posterior_predictive,
    prior_from_mapping,
    read_result,
    sample_posterior,
    summarise,
    write_result,
)
from bayesupdate.inference.plots import save_all
from bayesupdate.models import get_model
from bayesupdate.paper import DESIGN_VARIABLES


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--walkers", type=int, default=32)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--starts", type=int, default=16)
    parser.add_argument("--geometry", default="best")
    parser.add_argument("--out", default="studies/out/uncertainty")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    model = get_model("exhaust", geometry=args.geometry)
    bounds = model.default_bounds()
    defaults = model.default_parameters()
    table = {name: {} for name in bounds if name in DESIGN_VARIABLES}
    for name in bounds:
        if name not in DESIGN_VARIABLES:  # nuisance: joint stiffness etc.
            table[name] = {
                "prior": {"kind": "lognormal", "mu": float(np.log(defaults[name])), "sigma": 1.0}
            }
    problem = build_problem(model, load_modal_data("paper:ema"), table, pairing="tracked")
    optimum = calibrate(problem, starts=args.starts, seed=0)
    spec = LikelihoodSpec(
        sigma=None,
        sigma_prior=prior_from_mapping(
            {"kind": "halfnormal", "scale": 0.1}, (0.0, np.inf), "sigma"
        ),
    )
    log_post = LogPosterior(problem, spec)
    posterior = sample_posterior(
        log_post, optimum, walkers=args.walkers, steps=args.steps, seed=args.seed, progress=True
    )
    summary = summarise(posterior)
    predictions = posterior_predictive(log_post, posterior, seed=args.seed)
    path = write_result(
        out / "posterior.h5",
        problem,
        optimum,
        vars(args),
        posterior=posterior,
        diagnostics=summary,
        predictions=predictions,
        command="uncertainty_study",
    )
    save_all(read_result(path), out)

    print(
        f"{posterior.chain.shape[0]} steps, {posterior.evaluations} evaluations "
        f"({posterior.failed_evaluations} failed), {posterior.wall_s:.0f} s, "
        f"swap fraction of draws {predictions['swap_fraction']}"
    )
    for name, row in summary.items():
        print(
            f"{name:26s} mean {row['mean']:.4g} sd {row['sd']:.3g} "
            f"90% HDI [{row['hdi_low']:.4g}, {row['hdi_high']:.4g}] r_hat {row['r_hat']:.3f} "
            f"ess {row['ess_bulk']:.0f}"
        )
    draws = posterior.samples()
    corr = np.corrcoef(draws.T)
    names = list(posterior.names)
    print("\ncorrelations thickness - density:")
    for a in names:
        for b in names:
            if a.startswith("t_") and b.startswith("rho_"):
                print(f"  {a} / {b}: {corr[names.index(a), names.index(b)]:+.2f}")
    eigval, eigvec = np.linalg.eigh(corr)
    print("\nleast-determined combinations (largest eigenvalues of the posterior correlation):")
    for k in np.argsort(eigval)[::-1][:2]:
        terms = " ".join(
            f"{eigvec[j, k]:+.2f}*{names[j]}" for j in np.argsort(-abs(eigvec[:, k]))[:3]
        )
        print(f"  eigenvalue {eigval[k]:.2f}: {terms}")
    (out / "summary.json").write_text(
        json.dumps(
            {
                "posterior": summary,
                "correlation": corr.tolist(),
                "names": names,
                "swap_fraction": predictions["swap_fraction"],
                "wall_s": posterior.wall_s,
            },
            indent=1,
        )
    )


if __name__ == "__main__":
    main()
