"""From a ``StudyConfig`` to results: the steps shared by the CLI commands and the studies.

``prepare(study)`` validates everything (model, data, parameters, priors, pairing, likelihood)
before any heavy computation; ``run_calibration`` / ``run_sampling`` then do the work and write
the result file atomically (with checkpoints while sampling).
"""

import warnings
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from bayesupdate.config import StudyConfig
from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.data import load_modal_data
from bayesupdate.inference.diagnostics import (
    convergence_report,
    posterior_predictive,
    summarise,
)
from bayesupdate.inference.likelihood import LikelihoodSpec, LogPosterior
from bayesupdate.inference.optimize import CalibrationResult, calibrate
from bayesupdate.inference.priors import prior_from_mapping
from bayesupdate.inference.problem import CalibrationProblem, ObjectiveSpec, build_problem
from bayesupdate.inference.results import read_config, read_sampler_state, write_result
from bayesupdate.inference.sampling import PosteriorResult, sample_posterior
from bayesupdate.inference.user_model import resolve_model
from bayesupdate.modal_data import ModalData


@dataclass(frozen=True)
class PreparedStudy:
    study: StudyConfig
    problem: CalibrationProblem
    likelihood: LikelihoodSpec


#: weight of the mass term of the fit objective when the data carry a measured mass: on seed
#: Table 2 it keeps the exhaust's mass within 0.4 % of the weighed 12.29 kg (the seed keeps its
#: mass: 12.12 kg at its optimum) at an eq. 19 cost of 0.067 (tests/test_calibration_exhaust.py)
DEFAULT_MASS_WEIGHT = 10.0


def measured_mass(study: StudyConfig, data: ModalData) -> ModalData:
    """``data`` with the study's ``[data] mass_kg / mass_sd_kg`` applied, and without any
    measured mass when ``[objective] use_measured_mass = false`` (``--no-mass``)."""
    if not study.objective.use_measured_mass:
        return replace(data, mass_kg=None, mass_sd_kg=None)
    cfg = study.data
    if cfg.mass_kg is None and cfg.mass_sd_kg is None:
        return data
    mass = cfg.mass_kg if cfg.mass_kg is not None else data.mass_kg
    sd = cfg.mass_sd_kg if cfg.mass_sd_kg is not None else data.mass_sd_kg
    if cfg.mass_kg is not None and cfg.mass_sd_kg is None:
        sd = None  # a new mass does not inherit the sd of another
    return replace(data, mass_kg=mass, mass_sd_kg=sd)


def objective_spec(study: StudyConfig, data: ModalData) -> ObjectiveSpec:
    """The fit objective's extra terms: the mass term targets ``[objective] mass_kg``, else the
    data's measured mass, with ``mass_weight`` (default ``DEFAULT_MASS_WEIGHT`` when there is a
    target, else 0)."""
    cfg = study.objective
    target = cfg.mass_kg if cfg.mass_kg is not None else data.mass_kg
    weight = cfg.mass_weight
    if weight is None:
        weight = DEFAULT_MASS_WEIGHT if target is not None else 0.0
    return ObjectiveSpec(mass_target_kg=target, mass_weight=weight, mac_weight=cfg.mac_weight)


def likelihood_spec(study: StudyConfig, data: ModalData | None = None) -> LikelihoodSpec:
    """The likelihood of a study; the mass sd is ``[likelihood] mass_sd``, else the data's."""
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
    mass_sd = cfg.mass_sd
    if mass_sd is None and data is not None:
        mass_sd = data.mass_sd_rel
    return LikelihoodSpec(
        sigma=cfg.sigma, sigma_prior=sigma_prior, mass_sd_rel=mass_sd, pairing=cfg.pairing
    )


def prepare(study: StudyConfig, extend=None) -> PreparedStudy:
    """Build model, data and problem from a study; raises BayesUpdateError on any bad input.

    extend : optional callable model -> model applied after the model is resolved (the command
    layer passes the discovery effects of ``--effect`` / ``[effects]`` this way, so inference
    does not import discovery)."""
    model = resolve_model(
        study.model.source, study.parameters, study.model.sensors, study.model.options
    )
    if extend is not None:
        model = extend(model)
    data = measured_mass(study, load_modal_data(study.data.as_source()))
    objective = objective_spec(study, data)
    problem = build_problem(
        model,
        data,
        study.parameters or None,
        study.pairing.method,
        study.pairing.extra_modes,
        objective,
    )
    likelihood = likelihood_spec(study, data)
    if likelihood.mass_sd_rel is not None and objective.mass_target_kg is None:
        raise BayesUpdateError(
            "likelihood.mass_sd: no mass to compare with; "
            "give [data] mass_kg or [objective] mass_kg"
        )
    ndim = len(problem.parameters) + int(likelihood.infer_sigma)
    if study.sampler.walkers < max(2 * ndim, 4):
        raise BayesUpdateError(
            f"sampler.walkers: {study.sampler.walkers} is too few for {ndim} sampled parameters; "
            f"use at least {max(2 * ndim, 4)}"
        )
    for key in ("steps", "check_every", "predictive_draws"):
        if getattr(study.sampler, key) < 1:
            raise BayesUpdateError(f"sampler.{key}: must be >= 1")
    if study.sampler.transform not in ("none", "logit"):
        raise BayesUpdateError(
            f"sampler.transform: {study.sampler.transform!r}; use 'logit' or 'none'"
        )
    cfg = study.sampler
    if cfg.target_rhat is not None and not cfg.target_rhat >= 1.0:
        raise BayesUpdateError(f"sampler.target_rhat: must be >= 1, got {cfg.target_rhat}")
    if cfg.target_ess is not None and not cfg.target_ess >= 0:
        raise BayesUpdateError(f"sampler.target_ess: must be >= 0, got {cfg.target_ess}")
    if not 0 < study.sampler.hdi_prob < 1:
        raise BayesUpdateError("sampler.hdi_prob: must be in (0, 1)")
    return PreparedStudy(study, problem, likelihood)


def run_calibration(prepared: PreparedStudy) -> CalibrationResult:
    """Multi-start optimum.  Built-in FE models search on their certified reduced basis and
    polish every end point on the full model (``calibrate(..., refine=...)``), so the result is
    the full model's; ``sampler.reduced = false`` (``--full``) searches on full solves."""
    opt = prepared.study.optimizer
    cfg = prepared.study.sampler
    search, rom = sampling_problem(prepared.problem, None, cfg.reduced, cfg.reduced_tol)
    return calibrate(
        search,
        starts=opt.starts,
        seed=opt.seed,
        method=opt.method,
        design=opt.design,
        polish=opt.polish,
        refine=None if rom is None else prepared.problem,
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
    cfg = study.sampler
    # the reduced model first: the multi-start optimum is then cheap too (checked in full at
    # the optimum below; a miss there falls back to full solves)
    problem, rom = sampling_problem(prepared.problem, None, cfg.reduced, cfg.reduced_tol)
    if calibration is None:
        opt = study.optimizer
        # the optimum only places the walkers: no Nelder-Mead polish (calibrate's is ~5x the
        # cost of the trust-region starts and moves the point along a kink by < 3 % in Expr)
        calibration = calibrate(
            problem,
            starts=opt.starts,
            seed=opt.seed,
            method=opt.method,
            design=opt.design,
            polish=False,
        )
    if rom is not None:
        rom = certify_rom(rom, calibration.theta[None, :], problem.names, "the optimum")[0]
        problem = replace(problem, model=rom)
        if not rom.certified:
            problem, rom = prepared.problem, None
    log_post = LogPosterior(problem, prepared.likelihood)
    screen = (
        screening_posterior(problem, rom, prepared.likelihood, cfg.reduced_tol)
        if cfg.screen
        else None
    )

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
        transform=cfg.transform,
        target_rhat=cfg.target_rhat,
        target_ess=cfg.target_ess or None,
        screen=screen,
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
    report = convergence_report(
        posterior, summary, cfg.target_rhat, cfg.target_ess, cfg.min_autocorr_times
    )
    posterior = replace(posterior, converged=report["converged"])
    extra = {
        "pairing_mode": log_post.mode,
        "pair_differs_fraction": log_post.pair_differs_fraction,
        "convergence": report,
    }
    if rom is not None:
        mean = posterior.samples()[:, : len(problem.names)].mean(axis=0)
        extra["rom"] = certify_rom(rom, mean[None, :], problem.names, "the posterior mean")[1]
    if screen is not None:
        extra["screen"] = {
            "size": int(screen.problem.model.size),
            "max_rel_error": float(screen.problem.model.max_rel_error),
            "evaluations": int(posterior.screen_evaluations),
        }
    posterior = replace(posterior, diagnostics={**posterior.diagnostics, **extra})
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


def sampling_problem(
    problem: CalibrationProblem,
    calibration: CalibrationResult | None = None,
    reduced: bool = True,
    tol: float = 1e-4,
    seed: int = 0,
) -> tuple[CalibrationProblem, object | None]:
    """The problem the sampler uses: a built-in FE model gets a certified reduced basis
    (``fe.reduced.reduced_model_for``) over the calibrated parameters' bounds, with the model
    modes the pairing needs (test modes + extra modes), certified again at the optimum.
    Fixed parameters keep a narrow box (+-0.1 %) around their value.  Returns (problem, rom);
    rom is None with ``reduced=False``, for other models, or when no certified basis exists
    (then a RuntimeWarning says full solves are used)."""
    from bayesupdate.fe.model import FEModel
    from bayesupdate.fe.reduced import ReducedFEModel, reduced_model_for

    model = problem.model
    if not reduced or not isinstance(model, FEModel):
        return problem, None
    bounds = {p.name: p.bounds for p in problem.parameters}
    for name, value in problem.fixed.items():
        if name in model.parameter_names and value > 0:
            bounds[name] = (value * (1 - 1e-3), value * (1 + 1e-3))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rom = reduced_model_for(model, bounds, tol=tol, seed=seed, n_modes=problem.pairing.n_model)
    for w in caught:
        warnings.warn(str(w.message), RuntimeWarning, stacklevel=2)
    if not isinstance(rom, ReducedFEModel) or not rom.certified:
        return problem, None
    if calibration is not None:
        rom = certify_rom(rom, calibration.theta[None, :], problem.names, "the optimum")[0]
        if not rom.certified:
            return problem, None
    return replace(problem, model=rom), rom


def screening_posterior(
    problem: CalibrationProblem, rom, likelihood: LikelihoodSpec, tol: float = 1e-4
) -> LogPosterior | None:
    """The surrogate posterior for delayed-acceptance sampling (``inference.delayed_acceptance``).

    With a reduced model (``rom``): the same problem on a coarser basis inside it
    (``ReducedFEModel.coarsened``).  On full solves of a built-in FE model (``--full``): the
    certified reduced model itself, so the exact full-model posterior is sampled with full
    solves only for the proposals the reduced model lets through.  None for other models."""
    if rom is not None:
        return LogPosterior(replace(problem, model=rom.coarsened()), likelihood)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # no reduced model: plain sampling, nothing to warn about
        screen_problem, screen_rom = sampling_problem(problem, None, True, tol)
    if screen_rom is None:
        return None
    return LogPosterior(screen_problem, likelihood)


def certify_rom(rom, theta: np.ndarray, names: tuple[str, ...], where: str) -> tuple:
    """Full solve(s) at theta (k, len(names)); warn (suggesting --full) when the reduced model
    misses its tolerance there.  Returns (the checked ROM, its ``summary()`` plus ``error_at``)."""
    rom, err = rom.certify_at(theta, names)
    if not rom.certified or not err <= rom.tol:
        warnings.warn(
            f"reduced model not certified at {where} (relative frequency error {err:.2e}, tol "
            f"{rom.tol:g}); the posterior may carry reduced-basis error: rerun with --full",
            RuntimeWarning,
            stacklevel=2,
        )
    return rom, {**rom.summary(), "error_at": float(err)}


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
        "screen": posterior.diagnostics.get("screen"),
        "pairing": posterior.diagnostics.get("pairing_mode"),
        "pair_differs_fraction": _finite_or_none(
            posterior.diagnostics.get("pair_differs_fraction")
        ),
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
    }


def _finite_or_none(value) -> float | None:
    return None if value is None or not np.isfinite(value) else float(value)
