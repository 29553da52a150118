"""Optional posterior of the re-calibrated model: emcee over the design
variables and the named effect's parameters, walkers started from the Laplace Gaussian.

The likelihood is the calibration layer's (``inference.LogPosterior``: the frequency block of
``inference.likelihood_blocks`` with ``SampledNoise``) with the noise model discovery used: the
data's frequency sd (sigma ~ 0, the sd added in quadrature), a fixed sigma, or an inferred sigma
with a half-normal prior (scale 5 %) integrated out by the sampler.  It is a likelihood of the
frequencies only: test shapes (``shape_evidence``) shape the evidence and the optimum, not this
posterior.
Costs ``walkers x steps`` model solves for the kept run (e.g. 16 x 500 = 8,000 solves, minutes on
the exhaust), plus, with the default "mixture" moves, ``walkers x 2 x adapt_steps`` adaptation
solves and 1000 for the coverage check (``inference.sampling``), hence off by default.
"""

import numpy as np

from bayesupdate.inference.likelihood import LikelihoodSpec, LogPosterior
from bayesupdate.inference.priors import prior_from_mapping
from bayesupdate.inference.sampling import SamplerSettings, sample_posterior

#: largest relative noise level a sampled sigma may take
SIGMA_MAX = 0.5


def likelihood_for(noise, pairing_method: str) -> LikelihoodSpec:
    """LikelihoodSpec matching discovery's noise model (module docstring)."""
    pairing = "order" if pairing_method == "order" else "problem"
    if noise.source == "fixed":
        return LikelihoodSpec(sigma=noise.sigma, pairing=pairing)
    if noise.source == "data sd":
        return LikelihoodSpec(sigma=1e-9, pairing=pairing)
    prior = prior_from_mapping({"kind": "halfnormal", "scale": 0.05}, (0.0, SIGMA_MAX), "sigma")
    return LikelihoodSpec(sigma=None, sigma_prior=prior, pairing=pairing)


def sample_final(
    result, steps: int = 500, walkers: int | None = None, seed: int = 1, moves: str = "mixture"
):
    """(PosteriorResult, LogPosterior) of ``result.final`` (module docstring).

    moves : ``SamplerSettings.moves``: "mixture" (default) or "de" (no adaptation stages: the
    cheaper choice for a short look, with DE's narrower tails: docs/validation/posterior.md)."""
    fit = result.final
    space = fit.space
    problem = space.problem
    spec = likelihood_for(result.noise, problem.pairing.method)
    log_post = LogPosterior(problem, spec)
    d = log_post.ndim
    walkers = int(walkers or max(2 * d + 2, 16))
    rng = np.random.default_rng(seed)
    cov = np.linalg.inv(fit.best.hessian)
    z = rng.multivariate_normal(fit.best.z, 0.5 * (cov + cov.T), size=walkers, method="cholesky")
    z = np.clip(z, space.z_low, space.z_high)
    theta = np.array([space.theta_from_z(row) for row in z])
    if spec.infer_sigma:
        m = int(np.sum(result.noise.used))
        rss = float(np.sum(fit.best.r[: space.n_frequency] ** 2))  # the frequency block
        sigma = np.sqrt(max(rss / m, 1e-8)) * np.exp(rng.normal(0, np.sqrt(0.5 / m), walkers))
        theta = np.column_stack([theta, sigma])
    settings = SamplerSettings(
        walkers=walkers, steps=steps, seed=seed, check_every=max(steps // 4, 1), moves=moves
    )
    posterior = sample_posterior(log_post, settings=settings, initial=theta)
    return posterior, log_post
