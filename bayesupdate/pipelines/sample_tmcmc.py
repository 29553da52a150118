"""``bayesupdate sample --sampler tmcmc``: a prepared study -> TMCMC posterior and log evidence.

The same posterior as ``pipelines.sample`` (``inference.LogPosterior``: the study's likelihood,
priors and, when inferred, sigma with its prior) on the same certified reduced model
(``surrogates.sampling_problem``, checked in full at the posterior mean), sampled by
``inference.tmcmc`` in the parameters' own units (theta).  Needs no optimum: the particles start
from the prior.  The model evidence log Z comes with it (Ching & Chen 2007, eq. 18).
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.inference.likelihood import LogPosterior
from bayesupdate.inference.tmcmc import TMCMCResult, TMCMCSettings, tmcmc
from bayesupdate.pipelines.sample import mass_properties_at
from bayesupdate.pipelines.study import PreparedStudy
from bayesupdate.pipelines.surrogates import certify_rom, sampling_problem


@dataclass(frozen=True)
class TMCMCRun:
    """names : parameter names (+ "sigma" when inferred), columns of ``result.samples``.
    result : the TMCMC result.  rom : reduced-model summary at the posterior mean (None on
    full solves).  evaluations / failed : model evaluations, and those that failed.
    mass_properties : the measured mass, CG and inertia against the model at the posterior
    mean (``pipelines.sample.mass_properties_at``)."""

    names: tuple[str, ...]
    result: TMCMCResult
    rom: dict | None
    evaluations: int
    failed: int
    mass_properties: tuple[dict, ...] = ()


def _prior_functions(log_post: LogPosterior):
    """(prior_sample(rng, n) -> (n, D), log_prior (n, D) -> (n,)) of the model parameters and,
    when inferred, sigma (last column)."""
    priors = log_post.priors
    sigma_prior = log_post.spec.sigma_prior if log_post.spec.infer_sigma else None
    d = len(priors)

    def prior_sample(rng, n):
        columns = [p.sample(rng, n) for p in priors]
        if sigma_prior is not None:
            columns.append(sigma_prior.sample(rng, n))
        return np.column_stack(columns)

    def log_prior(x):
        lp = log_post.log_prior(x[:, :d])
        return lp if sigma_prior is None else lp + sigma_prior.logpdf(x[:, d])

    return prior_sample, log_prior


def sample_tmcmc(prepared: PreparedStudy, settings: TMCMCSettings, progress=None) -> TMCMCRun:
    """TMCMC posterior of a prepared study (module docstring).  progress(stage, beta) is passed
    to ``tmcmc``.  A stall raises ``BayesUpdateError`` (one line)."""
    cfg = prepared.study.sampler
    problem, rom = sampling_problem(prepared.problem, None, cfg.reduced, cfg.reduced_tol)
    log_post = LogPosterior(problem, prepared.likelihood)
    prior_sample, log_prior = _prior_functions(log_post)

    def log_likelihood(x):
        # the posterior minus the prior: the callers evaluate only where the prior is positive
        return log_post(x) - log_prior(x)

    result = tmcmc(prior_sample, log_prior, log_likelihood, settings, progress=progress)
    summary = None
    if rom is not None:
        names = problem.names
        mean = result.samples[:, : len(names)].mean(axis=0)
        summary = certify_rom(rom, mean[None, :], names, "the posterior mean")[1]
    means = {
        name: float(result.samples[:, j].mean())
        for j, name in enumerate(log_post.names)
        if name != "sigma"
    }
    masses = mass_properties_at(prepared, means)
    return TMCMCRun(log_post.names, result, summary, log_post.evaluations, log_post.failed, masses)


def tmcmc_json(run: TMCMCRun, hdi_prob: float = 0.9) -> dict:
    """JSON-ready: {"sampler": "tmcmc", "parameters": {NAME: {"mean", "sd", "q_low",
    "q_high"}}, "log_evidence", "stages", "betas", "ess", "acceptance", "particles",
    "evaluations", "failed", "rom", "mass_properties"}; q_low / q_high the central
    ``hdi_prob`` interval."""
    samples = run.result.samples
    tail = 50.0 * (1.0 - hdi_prob)
    low, high = np.percentile(samples, [tail, 100.0 - tail], axis=0)
    parameters = {
        name: {
            "mean": float(samples[:, j].mean()),
            "sd": float(samples[:, j].std(ddof=1)),
            "q_low": float(low[j]),
            "q_high": float(high[j]),
        }
        for j, name in enumerate(run.names)
    }
    r = run.result
    return {
        "sampler": "tmcmc",
        "parameters": parameters,
        "log_evidence": r.log_evidence,
        "stages": r.stages,
        "betas": r.betas.tolist(),
        "ess": r.ess.tolist(),
        "acceptance": r.acceptance.tolist(),
        "particles": int(samples.shape[0]),
        "evaluations": int(run.evaluations),
        "failed": int(run.failed),
        "rom": run.rom,
        "mass_properties": list(run.mass_properties),
    }
