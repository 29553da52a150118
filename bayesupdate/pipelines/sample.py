"""The sample pipeline: a prepared study -> optimum, emcee posterior, diagnostics, predictions.

The result file is written atomically when an output path is given, with a checkpoint after
every block while sampling, so an interrupted run (Ctrl-C, SIGTERM) leaves a valid partial file
that ``resume`` continues.  Seeded: the same study gives the same chain, interrupted or not.
"""

import multiprocessing
import warnings
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from bayesupdate.compute.executors import PartnerProcess
from bayesupdate.compute.settings import SERIAL, ComputeSettings, a_core_is_free, open_executor
from bayesupdate.compute.stop import StopRequest
from bayesupdate.config import SamplerConfig
from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.checks import sampling_warnings
from bayesupdate.inference.diagnostics import (
    convergence_report,
    posterior_predictive,
    summarize,
)
from bayesupdate.inference.evaluators import split_pays
from bayesupdate.inference.likelihood import LogPosterior
from bayesupdate.inference.mass_properties import mass_property_report
from bayesupdate.inference.optimize import CalibrationResult, CalibrationSettings, calibrate
from bayesupdate.inference.reference_check import accuracy_against
from bayesupdate.inference.results import ResultWriter, read_config, read_sampler_state
from bayesupdate.inference.sampling import (
    PosteriorResult,
    SamplerSettings,
    SamplerState,
    sample_posterior,
)
from bayesupdate.pipelines.study import PreparedStudy
from bayesupdate.pipelines.surrogates import (
    basis_error_allowed,
    certify_rom,
    sampling_problem,
    screen_mismatch,
    screening_posterior,
)

#: least-squares evaluations per start of the optimum that places the walkers.  On ``sample
#: --model exhaust --data paper:ema`` (17 starts on the certified basis, 2026-11-29): unbudgeted
#: (about 90 a start) 5.4 s CPU, 40: 3.6 s with the same optimum (3e-8 relative in theta, Expr
#: 0.0689867 both) and the same distinct optima the walkers start around; 20: 2.2 s, the optimum
#: 1e-4 away.  The walkers then adapt for 750 steps before anything is kept.
START_NFEV = 40


@dataclass(frozen=True)
class SamplingOptions:
    """Where and how a sampling run goes.

    out : result file (HDF5), checkpointed while sampling; None: nothing is written.
    resume : continue the partial result in ``out`` (written by the same study).
    progress : show a progress bar.
    stop : the run's ``compute.stop.StopRequest`` (the command's signal handler sets it); None:
    the run cannot be stopped but by an exception.
    compute : where the independent work runs (``compute.executors``; ``run_sampling``).
    split : "auto": on a serial ``compute``, the walkers' batches are split with a worker process
    of the sampler's own when that pays (``split_executor``); None: never (``--workers 1``).
    Local ``compute`` workers split them always; the chain is the serial one either way.
    reference : a stored reference of this posterior (``inference.reference_check``: "mean",
    "sd", "names", "check_points", "check_log_p"); given, the draws are judged by it when the
    posterior is the one it was made for (diagnostics "reference").
    """

    out: str | Path | None = None
    resume: bool = False
    progress: bool = False
    stop: StopRequest | None = None
    compute: ComputeSettings = SERIAL
    reference: dict | None = field(default=None, repr=False)
    split: str | None = "auto"


@dataclass(frozen=True)
class SamplingRun:
    """What a sampling run produced.

    calibration : the optimum the walkers started from.  posterior : the chain and its
    diagnostics (``posterior.interrupted`` after a stop request).  summary : per-parameter
    diagnostics (``inference.diagnostics.summarize``), {} when interrupted.  predictions : the
    posterior predictive (``posterior_predictive``), {} when interrupted.  compute : where the
    independent work ran (the executor's ``describe()``: {"kind", "workers"[, "scheduler"]}).
    warnings : one-line warnings (``inference.checks.sampling_warnings``: a paired MAC below the
    threshold at the optimum, the posterior piled at a bound).  mass_properties : the measured
    mass, CG and inertia against the model at the posterior mean (``mass_properties_at``), ()
    when interrupted or nothing is measured.
    """

    calibration: CalibrationResult
    posterior: PosteriorResult
    summary: dict
    predictions: dict
    compute: dict | None = None
    warnings: tuple[str, ...] = ()
    mass_properties: tuple[dict, ...] = ()


def run_sampling(
    prepared: PreparedStudy,
    options: SamplingOptions = SamplingOptions(),
    calibration: CalibrationResult | None = None,
    surrogate: tuple | None = None,
) -> SamplingRun:
    """Optimum (unless ``calibration`` is given), then the posterior (module docstring), with
    the independent work (the reduced basis's solves, the optimum's starts, the walkers of a
    model that cannot batch) on the executor of ``options.compute``.  ``surrogate``: the
    (problem, rom) that ``surrogates.sampling_problem(prepared.problem, None, reduced,
    reduced_tol)`` already gave for this study (the demo builds it for its optimum), so the
    basis is not built twice; None: built here."""
    with open_executor(options.compute) as executor:
        run = _run_sampling(prepared, options, calibration, executor, surrogate)
        return replace(run, compute=executor.describe())


def _run_sampling(prepared, options, calibration, executor, surrogate=None) -> SamplingRun:
    study = prepared.study
    config = study.to_dict()
    state = _resume_state(options, config)
    cfg = study.sampler
    # the reduced model first: the multi-start optimum is then cheap too (checked in full at
    # the optimum below; a miss there falls back to full solves)
    if surrogate is None:
        problem, rom, full_reason = _reduced_or_why(prepared, cfg, executor)
    else:
        (problem, rom), full_reason = surrogate, None
    if calibration is None:
        calibration = calibrate(
            problem, walker_start_settings(study.optimizer), stop=options.stop, executor=executor
        )
    basis_note = {}
    if rom is not None:
        problem, rom, basis_note = _basis_at_optimum(problem, rom, prepared.likelihood, calibration)
        if rom is None:
            problem = prepared.problem
            full_reason = "the reduced basis missed its tolerance at the optimum"
    log_post = LogPosterior(problem, prepared.likelihood, executor=executor)
    screen, unscreened = _screen(problem, rom, prepared.likelihood, cfg, calibration)
    writer = ResultWriter(options.out, prepared.problem, calibration, config, "sample")
    with split_executor(options, executor, log_post, calibration) as splitting:
        posterior = _sample(
            log_post, calibration, cfg, screen, options, writer.checkpoint, state, splitting
        )
    if posterior.interrupted:
        writer.write(state=posterior.state)
        return SamplingRun(calibration, posterior, {}, {})
    posterior, summary = _diagnosed(posterior, log_post, rom, screen, cfg, basis_note)
    notes = {"full_solves_reason": full_reason, "screen_skipped": unscreened}
    if options.reference is not None:
        samples = posterior.samples()
        notes["reference"] = accuracy_against(options.reference, log_post, samples, log_post.names)
    notes = {k: v for k, v in notes.items() if v}
    if notes:
        posterior = replace(posterior, diagnostics={**posterior.diagnostics, **notes})
    predictions = posterior_predictive(log_post, posterior, cfg.predictive_draws, seed=cfg.seed)
    found = tuple(sampling_warnings(prepared.problem, calibration, posterior.samples()))
    writer.write(posterior=posterior, diagnostics=summary, predictions=predictions, warnings=found)
    means = {name: summary[name]["mean"] for name in posterior.names if name != "sigma"}
    masses = mass_properties_at(prepared, means)
    return SamplingRun(
        calibration, posterior, summary, predictions, warnings=found, mass_properties=masses
    )


@contextmanager
def split_executor(options: SamplingOptions, executor, log_post, calibration):
    """The executor the walkers' batches are split with (``sample_posterior``'s ``executor``):
    the run's own when it has local worker processes; else, with ``options.split`` "auto", one
    worker process of the sampler's own (closed on exit) when a core is free for it
    (``compute.settings.a_core_is_free``), this is not itself a worker process, and a batch of
    the posterior costs enough to repay the hand-off (``evaluators.split_pays``, at the
    optimum); else None (every batch here)."""
    if executor.kind == "processes":
        yield executor
        return
    # a worker process (the demo's parts run in two) never starts one of its own: its
    # siblings hold the other cores, and the load average lags a minute behind them
    in_worker = multiprocessing.parent_process() is not None
    if executor.kind != "serial" or options.split != "auto" or in_worker or not a_core_is_free():
        yield None
        return
    theta = calibration.theta
    if log_post.spec.infer_sigma:
        theta = np.append(theta, np.mean(log_post.spec.sigma_prior.bounds))
    if not split_pays(log_post, theta):
        yield None
        return
    with PartnerProcess() as own:
        yield own


def walker_start_settings(opt) -> CalibrationSettings:
    """The optimum's settings when it only places the walkers (the study's ``[optimizer]``
    ``opt``: starts, seed, method, design): no Nelder-Mead polish (calibrate's is ~5x the cost
    of the trust-region starts and moves the point along a kink by < 3 % in Expr) and
    ``START_NFEV`` evaluations per start."""
    return CalibrationSettings(
        starts=opt.starts, seed=opt.seed, method=opt.method, design=opt.design, polish=False,
        max_nfev=START_NFEV,
    )  # fmt: skip


def mass_properties_at(prepared: PreparedStudy, means: dict) -> tuple[dict, ...]:
    """The study's measured mass, CG and inertia against the model's at the parameter values
    ``means`` ({name: value}; the problem's fixed values fill the rest), model units
    (``inference.mass_properties.mass_property_report``); () when nothing is measured."""
    problem = prepared.problem
    return tuple(mass_property_report(problem, {**problem.fixed, **means}))


def _basis_at_optimum(problem, rom, likelihood, calibration) -> tuple:
    """(problem on the checked basis, the basis or None when it missed its tolerance, what was
    done: {"enrich_above", "size_before_optimum", "error_at_optimum"}).  The basis is enriched
    at the optimum when its error there could bias the posterior (``basis_error_allowed``)."""
    allowed = basis_error_allowed(problem, likelihood, calibration)
    theta = calibration.theta[None, :]
    checked, summary = certify_rom(rom, theta, problem.names, "the optimum", allowed)
    note = {
        "enrich_above": allowed,
        "size_before_optimum": int(rom.size),
        "error_at_optimum": summary["error_at"],
    }
    if not checked.certified:
        return problem, None, note
    return replace(problem, model=checked), checked, note


def _reduced_or_why(prepared, cfg: SamplerConfig, executor):
    """``sampling_problem``'s (problem, rom) and, when a built-in or deck FE model gets full
    solves although the study asks for the reduced basis, why (its warnings, re-issued)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        problem, rom = sampling_problem(
            prepared.problem, None, cfg.reduced, cfg.reduced_tol, executor=executor
        )
    for w in caught:
        warnings.warn(str(w.message), RuntimeWarning, stacklevel=2)
    why = "; ".join(str(w.message) for w in caught) if rom is None and cfg.reduced else ""
    return problem, rom, why or None


def _resume_state(options: SamplingOptions, config: dict) -> SamplerState | None:
    """The sampler state to continue from (``options.resume``), checked against the study."""
    out = options.out
    if not options.resume:
        return None
    if out is None or not Path(out).exists():
        raise BayesUpdateError(f"--resume: no result file {out} to resume; run without --resume")
    saved, status = read_config(out)
    if saved != _jsonable(config):
        raise BayesUpdateError(f"{out}: written by a different study/settings; cannot resume")
    state = read_sampler_state(out)
    if status == "complete":
        raise BayesUpdateError(f"{out}: the run is already complete; nothing to resume")
    return state


def _screen(problem, rom, likelihood, cfg: SamplerConfig, calibration) -> tuple:
    """(the screening posterior or None, why a configured screen was dropped or "")."""
    if not cfg.screen:
        return None, ""
    screen = screening_posterior(problem, rom, likelihood, cfg.reduced_tol)
    why = "" if screen is None else screen_mismatch(screen, calibration)
    return (None, why) if why else (screen, "")


def sampler_settings(cfg: SamplerConfig, progress: bool = False, ndim: int = 0) -> SamplerSettings:
    """The ``SamplerSettings`` a study's ``[sampler]`` table gives (``SamplerConfig()``: the
    defaults a user gets) for ``ndim`` sampled dimensions (the walkers where the table gives
    none: ``SamplerConfig.walkers_for``; a prepared study's are resolved already);
    ``target_ess = 0`` turns the ESS target off."""
    adapt = {} if cfg.adapt_steps is None else {"adapt_steps": cfg.adapt_steps}
    return SamplerSettings(
        **adapt,
        walkers=cfg.walkers_for(ndim),
        steps=cfg.steps,
        seed=cfg.seed,
        min_autocorr_times=cfg.min_autocorr_times,
        check_every=cfg.check_every,
        transform=cfg.transform,
        target_rhat=cfg.target_rhat,
        target_ess=cfg.target_ess or None,
        progress=progress,
        moves=cfg.moves,
    )


def _sample(
    log_post, calibration, cfg: SamplerConfig, screen, options, checkpoint, state, executor
):
    """emcee with the study's sampler settings; ``checkpoint`` (``ResultWriter.checkpoint``)
    after every block; the walkers' larger batches split with a local worker of ``executor``
    (``sample_posterior``)."""
    return sample_posterior(
        log_post,
        calibration,
        sampler_settings(cfg, options.progress),
        screen=screen,
        checkpoint=checkpoint,
        resume=state,
        stop_request=options.stop,
        executor=executor,
    )


def _diagnosed(posterior, log_post, rom, screen, cfg: SamplerConfig, basis_note=None):
    """(posterior with its convergence verdict and diagnostics, summary table); ``basis_note``
    (``_basis_at_optimum``) joins the diagnostics' "rom"."""
    summary = summarize(posterior, hdi_prob=cfg.hdi_prob)
    report = convergence_report(
        posterior, summary, cfg.target_rhat, cfg.target_ess, cfg.min_autocorr_times
    )
    posterior = replace(posterior, converged=report["converged"])
    extra = {
        "pairing_mode": log_post.mode,
        "pair_differs_fraction": log_post.pair_differs_fraction,
        "convergence": report,
    }
    names = log_post.problem.names
    if rom is not None:
        mean = posterior.samples()[:, : len(names)].mean(axis=0)
        at_mean = certify_rom(rom, mean[None, :], names, "the posterior mean")[1]
        extra["rom"] = {**at_mean, **(basis_note or {})}
    if screen is not None:
        extra["screen"] = {
            "size": int(screen.problem.model.size),
            "max_rel_error": float(screen.problem.model.max_rel_error),
            "evaluations": int(posterior.screen_evaluations),
        }
    posterior = replace(posterior, diagnostics={**posterior.diagnostics, **extra})
    return posterior, summary


def _jsonable(obj):
    import json

    return json.loads(
        json.dumps(
            obj, default=lambda o: o.tolist() if hasattr(o, "tolist") else str(o), sort_keys=True
        )
    )
