"""TMCMC evidence against discovery's Laplace evidence on the exhaust.

One hidden-effect case of ``hidden_effect_study`` (default ``added_mass@8:m=0.5``, fast path:
12 frequencies with 0.3 % noise and 40-DOF shapes with 3 % noise, seed 0, as that study's
first case) goes through ``discover``.  For the baseline and the two best candidates, TMCMC
(``inference.tmcmc``) computes log Z with the same likelihood (each fit's ``FitSpace``: the
frequency block and the shape block at the levels discovery fixed, MAC pairing to the test
shapes) and the same prior, in the same axis coordinates z.  The model is the certified reduced
basis of each (extended) FE model over its prior box, predicted in batches; the evidence ratio
full / reduced is E_post[L_full / L_reduced], estimated on ``--check`` posterior particles with
full solves and added (``full_correction``).

    .venv/bin/python studies/tmcmc_evidence.py --seed 0 --json-out s0.json   # one seed
    .venv/bin/python studies/tmcmc_evidence.py --combine s0.json s1.json     # the table

Prints, per model: Laplace log Z, TMCMC log Z, their difference [nats], the stages, the
evaluations, and what explains a gap (posterior sd and skew against the Laplace Gaussian,
the truncation term, the number of distinct optima).
"""

import argparse
import json
import os
import sys
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).parent))

import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402
from scipy.special import logsumexp  # noqa: E402

from bayesupdate.inference.tmcmc import TMCMCSettings, tmcmc  # noqa: E402


def batched_log_likelihood(space, model):
    """theta (n, d) -> (n,) discovery's log L (``FitSpace.likelihood``) with ``model`` solving
    a batch at once; pairing per point as ``CalibrationProblem.evaluate`` does."""
    from bayesupdate.inference.likelihood_blocks import relative_errors
    from bayesupdate.inference.pairing import pair_modes
    from bayesupdate.model_protocol import Prediction

    problem = space.problem
    fixed = tuple(k for k in problem.fixed if k in model.parameter_names)
    names = problem.names + fixed
    fixed_values = np.array([problem.fixed[k] for k in fixed], dtype=float)
    labels = tuple(model.sensor_labels)
    likelihood = space.likelihood

    def log_like(theta: np.ndarray) -> np.ndarray:
        full = np.hstack([theta, np.tile(fixed_values, (theta.shape[0], 1))])
        freqs, shapes = model.predict_batch_with_shapes(full, names, problem.pairing.n_model)
        out = np.full(theta.shape[0], -np.inf)
        for i in range(theta.shape[0]):  # pairing per point: cheap against the batched solve
            if not np.all(np.isfinite(freqs[i])):
                continue
            paired = pair_modes(Prediction(freqs[i], shapes[i], labels), problem.pairing)
            e = relative_errors(freqs[i][paired.model_index], problem.data.frequencies_hz)
            value = likelihood.log_likelihood(space.residual_vector(e, paired.shapes))
            out[i] = value if np.isfinite(value) else -np.inf
        return out

    return log_like


def full_log_likelihood(space, theta: np.ndarray) -> np.ndarray:
    """(n,) log L with full solves (the path discovery's fits take), per point."""
    out = np.empty(theta.shape[0])
    for i, point in enumerate(theta):
        e, evaluation = space.relative_errors(point)
        shapes = None if evaluation.paired is None else evaluation.paired.shapes
        out[i] = space.likelihood.log_likelihood(space.residual_vector(e, shapes))
    return out


def tmcmc_of_fit(fit, settings: TMCMCSettings, check: int) -> dict:
    """TMCMC log Z of one discovery fit (module docstring) and what explains a gap."""
    from bayesupdate.fe.reduced.model import reduced_model_for

    space = fit.space
    pspace = space.parameter_space
    bounds = {a.name: a.bounds for a in space.axes}
    t0 = time.perf_counter()
    model = reduced_model_for(space.problem.model, bounds, n_modes=space.problem.pairing.n_model)
    build_s = time.perf_counter() - t0
    log_like_theta = batched_log_likelihood(space, model)

    def prior_sample(rng, n):
        theta = np.column_stack([a.prior.sample(rng, n) for a in space.axes])
        return pspace.z_from_theta(theta)

    t0 = time.perf_counter()
    result = tmcmc(
        prior_sample,
        pspace.log_prior_z,
        lambda z: log_like_theta(pspace.theta_from_z(z)),
        settings,
        progress=lambda stage, beta: print(
            f"  {fit.label} stage {stage} beta {beta:.3g} {time.perf_counter() - t0:.0f} s",
            flush=True,
        ),
    )
    wall = time.perf_counter() - t0
    rng = np.random.default_rng(settings.seed + 1000)
    pick = rng.choice(result.samples.shape[0], size=check, replace=False)
    theta_check = pspace.theta_from_z(result.samples[pick])
    delta = full_log_likelihood(space, theta_check) - result.log_likelihood[pick]
    correction = float(logsumexp(delta) - np.log(check))
    best = fit.best
    laplace_sd = np.sqrt(np.diag(np.linalg.inv(best.hessian)))
    z = result.samples
    return {
        "label": fit.label,
        "names": list(fit.names),
        "laplace_log_evidence": float(fit.log_evidence),
        "laplace_optima": len(fit.optima),
        "laplace_log_like": float(best.log_like),
        "tmcmc_log_evidence_reduced": result.log_evidence,
        "full_correction": correction,
        "full_correction_sd": float(np.std(delta)),
        "tmcmc_log_evidence": result.log_evidence + correction,
        "stages": result.stages,
        "betas": result.betas.tolist(),
        "ess": result.ess.tolist(),
        "acceptance": result.acceptance.tolist(),
        "evaluations": result.evaluations,
        "wall_s": wall,
        "reduced_build_s": build_s,
        "reduced_model": str(model),
        "max_log_like_particles": float(np.max(result.log_likelihood)),
        "post_mean_minus_laplace_over_sd": ((z.mean(0) - best.z) / laplace_sd).tolist(),
        "post_sd_over_laplace_sd": (z.std(0) / laplace_sd).tolist(),
        "post_skew": stats.skew(z, axis=0).tolist(),
        "laplace_at_bound": (
            (np.abs(best.z - space.z_low) < 2 * laplace_sd)
            | (np.abs(space.z_high - best.z) < 2 * laplace_sd)
        ).tolist(),
    }


def run(args) -> int:
    from hidden_effect_study import case_data

    from bayesupdate.discovery.workflow import discover

    t0 = time.perf_counter()
    data, _, base = case_data(args.case, "fast", args.noise, args.data_seed, args.shape_noise)
    result = discover(base, data)
    print(f"discover: {result.verdict}, {time.perf_counter() - t0:.0f} s", flush=True)
    settings = TMCMCSettings(particles=args.particles, mcmc_steps=args.mcmc_steps, seed=args.seed)
    rows = []
    for fit in [result.baseline, *result.fits[:2]]:
        row = tmcmc_of_fit(fit, settings, args.check)
        rows.append(row)
        print(
            f"{row['label']:24s} Laplace {row['laplace_log_evidence']:10.2f}  TMCMC "
            f"{row['tmcmc_log_evidence']:10.2f} (reduced {row['tmcmc_log_evidence_reduced']:.2f})"
            f"  diff {row['tmcmc_log_evidence'] - row['laplace_log_evidence']:+.2f}  "
            f"stages {row['stages']}  evals {row['evaluations']}  {row['wall_s']:.0f} s",
            flush=True,
        )
    out = {"case": args.case, "seed": args.seed, "settings": vars(args), "models": rows}
    if args.json_out:
        Path(args.json_out).write_text(json.dumps(out, indent=1))
    return 0


def combine(paths: list[str]) -> int:
    """The table over seeds: mean TMCMC log Z, its MC error (sd over seeds), differences."""
    runs = [json.loads(Path(p).read_text()) for p in paths]
    print(f"case {runs[0]['case']}, seeds {[r['seed'] for r in runs]}")
    print(f"{'model':24s} {'Laplace':>10s} {'TMCMC':>10s} {'MC sd':>6s} {'diff':>7s}  per seed")
    for k, row in enumerate(runs[0]["models"]):
        values = np.array([r["models"][k]["tmcmc_log_evidence"] for r in runs])
        sd = float(np.std(values, ddof=1)) if values.size > 1 else float("nan")
        diff = values.mean() - row["laplace_log_evidence"]
        print(
            f"{row['label']:24s} {row['laplace_log_evidence']:10.2f} {values.mean():10.2f} "
            f"{sd:6.2f} {diff:+7.2f}  {np.round(values, 2).tolist()}"
        )
    for k, row in enumerate(runs[0]["models"][1:], start=1):
        bf_t = [r["models"][k]["tmcmc_log_evidence"] - r["models"][0]["tmcmc_log_evidence"]
                for r in runs]  # fmt: skip
        bf_l = row["laplace_log_evidence"] - runs[0]["models"][0]["laplace_log_evidence"]
        print(f"ln BF {row['label']} vs baseline: Laplace {bf_l:.2f}, TMCMC {np.mean(bf_t):.2f}")
    print("\nTMCMC posterior against the Laplace Gaussian (z coordinates), per seed")
    for r in runs:
        for m in r["models"]:
            print(
                f"seed {r['seed']} {m['label']}: max log L of the particles "
                f"{m['max_log_like_particles']:.2f} (Laplace optimum {m['laplace_log_like']:.2f})"
            )
            for j, name in enumerate(m["names"]):
                print(
                    f"    {name:32s} (mean - z*)/sd {m['post_mean_minus_laplace_over_sd'][j]:+6.2f}"
                    f"  sd ratio {m['post_sd_over_laplace_sd'][j]:5.2f}"
                    f"  skew {m['post_skew'][j]:+5.2f}"
                    f"  near bound {m['laplace_at_bound'][j]}"
                )
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--case", default="added_mass@8:m=0.5")
    parser.add_argument("--noise", type=float, default=0.003)
    parser.add_argument("--shape-noise", type=float, default=0.03)
    parser.add_argument("--data-seed", type=int, default=0)
    parser.add_argument("--seed", type=int, default=0, help="TMCMC seed")
    parser.add_argument("--particles", type=int, default=1000)
    parser.add_argument("--mcmc-steps", type=int, default=3)
    parser.add_argument("--check", type=int, default=60, help="full-solve check particles")
    parser.add_argument("--json-out")
    parser.add_argument("--combine", nargs="+", metavar="JSON")
    args = parser.parse_args(argv)
    return combine(args.combine) if args.combine else run(args)


if __name__ == "__main__":
    sys.exit(main())
