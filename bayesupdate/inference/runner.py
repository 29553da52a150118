"""From a ``StudyConfig`` to results: the steps shared by the CLI commands and the studies.

``prepare(study)`` validates everything (model, data, parameters, priors, pairing, likelihood)
before any heavy computation; ``run_calibration`` / ``run_sampling`` then do the work and write
the result file atomically (with checkpoints while sampling).
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bayesupdate.config import StudyConfig
from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.data import load_modal_data
from bayesupdate.inference.diagnostics import posterior_predictive, summarise
from bayesupdate.inference.likelihood import LikelihoodSpec, LogPosterior
from bayesupdate.inference.optimize import CalibrationResult, calibrate
from bayesupdate.inference.priors import prior_from_mapping
from bayesupdate.inference.problem import CalibrationProblem, ObjectiveSpec, build_problem
from bayesupdate.inference.results import read_config, read_sampler_state, write_result
from bayesupdate.inference.sampling import PosteriorResult, sample_posterior
from bayesupdate.inference.user_model import resolve_model


@dataclass(frozen=True)
class PreparedStudy:
    study: StudyConfig
    problem: CalibrationProblem
    likelihood: LikelihoodSpec


def likelihood_spec(study: StudyConfig) -> LikelihoodSpec:
    cfg = study.likelihood
    sigma_prior = None
    if cfg.sigma_prior is not None:
        table = dict(cfg.sigma_prior)
        bounds = table.pop("bounds", [0.0, np.inf])
        if table.get("kind") == "uniform" and not np.all(np.isfinite(bounds)):
            raise BayesUpdateError(
                "likelihood.sigma_prior: a uniform prior needs bounds = [lo, hi]"
            )
        sigma_prior = prior_from_mapping(table, tuple(bounds), "sigma")
    return LikelihoodSpec(
        sigma=cfg.sigma, sigma_prior=sigma_prior, mass_sd_rel=cfg.mass_sd, pairing=cfg.pairing
    )


def prepare(study: StudyConfig) -> PreparedStudy:
    """Build model, data and problem from a study; raises BayesUpdateError on any bad input."""
    model = resolve_model(
        study.model.source, study.parameters, study.model.sensors, study.model.options
    )
    data = load_modal_data(study.data.as_source())
    objective = ObjectiveSpec(
        mass_target_kg=study.objective.mass_kg,
        mass_weight=study.objective.mass_weight,
        mac_weight=study.objective.mac_weight,
    )
    problem = build_problem(
        model,
        data,
        study.parameters or None,
        study.pairing.method,
        study.pairing.extra_modes,
        objective,
    )
    likelihood = likelihood_spec(study)
    ndim = len(problem.parameters) + int(likelihood.infer_sigma)
    if study.sampler.walkers < max(2 * ndim, 4):
        raise BayesUpdateError(
            f"sampler.walkers: {study.sampler.walkers} is too few for {ndim} sampled parameters; "
            f"use at least {max(2 * ndim, 4)}"
        )
    for key in ("steps", "check_every", "predictive_draws"):
        if getattr(study.sampler, key) < 1:
            raise BayesUpdateError(f"sampler.{key}: must be >= 1")
    if not 0 < study.sampler.hdi_prob < 1:
        raise BayesUpdateError("sampler.hdi_prob: must be in (0, 1)")
    return PreparedStudy(study, problem, likelihood)


def run_calibration(prepared: PreparedStudy) -> CalibrationResult:
    opt = prepared.study.optimizer
    return calibrate(
        prepared.problem, starts=opt.starts, seed=opt.seed, method=opt.method, design=opt.design
    )


def run_sampling(
    prepared: PreparedStudy,
    out: str | Path | None = None,
    resume: bool = False,
    progress: bool = False,
    calibration: CalibrationResult | None = None,
) -> tuple[CalibrationResult, PosteriorResult, dict, dict]:
    """Optimum, then posterior; checkpoints to ``out`` after every block when ``out`` is given.

    resume : continue the partial result in ``out`` (its study must equal this one).
    Returns (calibration, posterior, diagnostics summary, predictions).
    """
    study = prepared.study
    config = study.to_dict()
    state = None
    if resume:
        if out is None or not Path(out).exists():
            raise BayesUpdateError(
                f"--resume: no result file {out} to resume; run without --resume"
            )
        saved, status = read_config(out)
        if saved != _jsonable(config):
            raise BayesUpdateError(f"{out}: written by a different study/settings; cannot resume")
        state = read_sampler_state(out)
        if status == "complete":
            raise BayesUpdateError(f"{out}: the run is already complete; nothing to resume")
    calibration = calibration or run_calibration(prepared)
    log_post = LogPosterior(prepared.problem, prepared.likelihood)
    cfg = study.sampler

    def checkpoint(sampler_state):
        if out is not None and not sampler_state.finished:
            write_result(
                out, prepared.problem, calibration, config, state=sampler_state, command="sample"
            )

    posterior = sample_posterior(
        log_post,
        calibration,
        walkers=cfg.walkers,
        steps=cfg.steps,
        seed=cfg.seed,
        min_autocorr_times=cfg.min_autocorr_times,
        check_every=cfg.check_every,
        progress=progress,
        checkpoint=checkpoint,
        resume=state,
    )
    if posterior.interrupted:
        if out is not None:
            write_result(
                out, prepared.problem, calibration, config, state=posterior.state, command="sample"
            )
        return calibration, posterior, {}, {}
    summary = summarise(posterior, hdi_prob=cfg.hdi_prob)
    predictions = posterior_predictive(log_post, posterior, cfg.predictive_draws, seed=cfg.seed)
    if out is not None:
        write_result(
            out,
            prepared.problem,
            calibration,
            config,
            posterior=posterior,
            diagnostics=summary,
            predictions=predictions,
            command="sample",
        )
    return calibration, posterior, summary, predictions


def _jsonable(obj):
    import json

    return json.loads(
        json.dumps(
            obj, default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o), sort_keys=True
        )
    )


def sample_json(
    posterior: PosteriorResult,
    summary: dict,
    likelihood: LikelihoodSpec,
    predictions: dict | None = None,
) -> dict:
    """The ``sample --json`` object (issue 4 item 10), plus failed_evaluations, steps, walkers,
    converged and swap_fraction (share of checked draws whose modes are swapped; None if the
    model gives no shapes)."""
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
        "swap_fraction": None
        if not predictions or not np.isfinite(predictions["swap_fraction"])
        else float(predictions["swap_fraction"]),
    }
