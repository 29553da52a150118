"""Calibration with uncertainty: data in, pairing, seed eq. 19, point optimum, emcee posterior.

Typical use (a thin script)::

    from bayesupdate.inference import (build_problem, calibrate, CalibrationSettings,
                                       LikelihoodSpec, LogPosterior,
                                       SamplerSettings, sample_posterior, summarise,
                                       load_modal_data)
    problem = build_problem(model, load_modal_data("paper:ema"))
    optimum = calibrate(problem, CalibrationSettings(starts=16, seed=0))
    log_post = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    settings = SamplerSettings(walkers=32, steps=5000, seed=1)
    posterior = sample_posterior(log_post, optimum, settings)
    table = summarise(posterior)
"""

from bayesupdate.inference.checks import calibration_warnings, sampling_warnings
from bayesupdate.inference.data import (
    ModeSelection,
    load_modal_data,
    register_loader,
    select_modes,
)
from bayesupdate.inference.diagnostics import posterior_predictive, summarise
from bayesupdate.inference.likelihood import LikelihoodSpec, LogPosterior
from bayesupdate.inference.optimize import (
    CalibrationResult,
    CalibrationSettings,
    calibrate,
    pareto_front_mass,
)
from bayesupdate.inference.pairing import (
    ModePairing,
    PairingRules,
    RefusedMode,
    ResidualTable,
    pair_modes,
)
from bayesupdate.inference.priors import Prior, prior_from_mapping
from bayesupdate.inference.problem import (
    CalibrationProblem,
    ObjectiveSpec,
    ParameterSpec,
    build_parameter_specs,
    build_problem,
    objective_expr,
)
from bayesupdate.inference.results import (
    export_netcdf,
    read_result,
    read_sampler_state,
    to_datatree,
    write_result,
)
from bayesupdate.inference.sampling import (
    PosteriorResult,
    SamplerSettings,
    SamplerState,
    default_moves,
    sample_posterior,
)
from bayesupdate.inference.tmcmc import TMCMCResult, TMCMCSettings, tmcmc
from bayesupdate.inference.user_model import FunctionModel, load_user_model

__all__ = [
    "CalibrationProblem",
    "CalibrationResult",
    "CalibrationSettings",
    "FunctionModel",
    "LikelihoodSpec",
    "LogPosterior",
    "ModePairing",
    "ModeSelection",
    "ObjectiveSpec",
    "PairingRules",
    "ParameterSpec",
    "PosteriorResult",
    "Prior",
    "RefusedMode",
    "ResidualTable",
    "SamplerSettings",
    "SamplerState",
    "TMCMCResult",
    "TMCMCSettings",
    "build_parameter_specs",
    "build_problem",
    "calibrate",
    "calibration_warnings",
    "default_moves",
    "export_netcdf",
    "load_modal_data",
    "load_user_model",
    "objective_expr",
    "pair_modes",
    "pareto_front_mass",
    "posterior_predictive",
    "prior_from_mapping",
    "read_result",
    "read_sampler_state",
    "register_loader",
    "sample_posterior",
    "sampling_warnings",
    "select_modes",
    "summarise",
    "tmcmc",
    "to_datatree",
    "write_result",
]
