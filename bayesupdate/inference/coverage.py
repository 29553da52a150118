"""Frequentist check of the credible intervals: synthetic data with known truth and noise.

For each replicate r: frequencies f_T = f(theta_true) * (1 + noise_rel * z), z ~ N(0, 1) (the
likelihood's own model, so the intervals should cover at their nominal rate), then optimum,
posterior and the ``prob`` HDI of every parameter; coverage = share of replicates whose interval
holds the truth.  With R replicates its binomial sd is sqrt(p (1 - p) / R) (0.067 for p = 0.9,
R = 20).
"""

from collections.abc import Mapping

import numpy as np

from bayesupdate.inference.diagnostics import summarize
from bayesupdate.inference.likelihood import LikelihoodSpec, LogPosterior
from bayesupdate.inference.optimize import CalibrationSettings, calibrate
from bayesupdate.inference.problem import build_problem
from bayesupdate.inference.sampling import SamplerSettings, sample_posterior
from bayesupdate.modal_data import ModalData


def synthetic_data(
    model, truth: Mapping[str, float], n_modes: int, noise_rel: float, rng: np.random.Generator
) -> ModalData:
    """Model frequencies at ``truth`` (n_modes,) with relative Gaussian noise [Hz]."""
    f = np.asarray(model.predict(dict(truth), n_modes=n_modes).frequencies_hz, dtype=float)
    return ModalData(
        frequencies_hz=f * (1.0 + noise_rel * rng.standard_normal(f.size)), source="synthetic"
    )


def interval_coverage(
    model,
    truth: Mapping[str, float],
    n_modes: int,
    noise_rel: float,
    parameters: Mapping | None = None,
    replicates: int = 20,
    seed: int = 0,
    prob: float = 0.9,
    walkers: int = 16,
    steps: int = 2000,
    starts: int = 8,
    pairing: str = "order",
    transform: str = "none",
    max_nfev: int | None = None,
) -> dict:
    """Coverage of the ``prob`` HDI over ``replicates`` synthetic data sets (sigma = noise_rel).

    Returns {"coverage": {name: share}, "replicates", "prob", "intervals": {name: (R, 2)},
    "binomial_sd"}.  transform : the sampler's (``sample_posterior``); max_nfev : per start.
    """
    rng = np.random.default_rng(seed)
    hits: dict[str, list[bool]] = {}
    intervals: dict[str, list] = {}
    for r in range(replicates):
        data = synthetic_data(model, truth, n_modes, noise_rel, rng)
        problem = build_problem(model, data, parameters, pairing=pairing)
        problem = build_problem(
            model,
            data,
            parameters,
            pairing=pairing,
            fixed={k: v for k, v in truth.items() if k not in problem.names},
        )
        fit = CalibrationSettings(starts=starts, seed=seed + r, max_nfev=max_nfev)
        optimum = calibrate(problem, fit)
        log_post = LogPosterior(problem, LikelihoodSpec(sigma=noise_rel))
        settings = SamplerSettings(walkers=walkers, steps=steps, seed=seed + r, transform=transform)
        posterior = sample_posterior(log_post, optimum, settings)
        summary = summarize(posterior, hdi_prob=prob)
        for name in problem.names:
            low, high = summary[name]["hdi_low"], summary[name]["hdi_high"]
            hits.setdefault(name, []).append(bool(low <= truth[name] <= high))
            intervals.setdefault(name, []).append((low, high))
    return {
        "coverage": {name: float(np.mean(h)) for name, h in hits.items()},
        "replicates": replicates,
        "prob": prob,
        "intervals": {name: np.array(v) for name, v in intervals.items()},
        "binomial_sd": float(np.sqrt(prob * (1 - prob) / replicates)),
    }
