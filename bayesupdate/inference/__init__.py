"""Calibration with uncertainty: data in, pairing, seed eq. 19, point optimum, emcee posterior.

Typical use (a thin script)::

    from bayesupdate.inference import (build_problem, calibrate, CalibrationSettings,
                                       LikelihoodSpec, LogPosterior,
                                       SamplerSettings, sample_posterior, summarize,
                                       load_modal_data)
    problem = build_problem(model, load_modal_data("paper:ema"))
    optimum = calibrate(problem, CalibrationSettings(starts=16, seed=0))
    log_post = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    settings = SamplerSettings(walkers=32, steps=5000, seed=1)
    posterior = sample_posterior(log_post, optimum, settings)
    table = summarize(posterior)

The names are loaded on first use (PEP 562 ``__getattr__``), each from its own module: this
package's ``__init__`` runs for every ``bayesupdate.inference.*`` import, and loading all of them
there (the optimizer with ``scipy.optimize`` and ``scipy.stats``, the sampler with emcee, h5py)
cost a command that needs one data loader a second or more.  ``tmcmc`` is bound at import: it
is also a submodule's name, and a submodule imported first would otherwise take the name.
"""

import importlib
from typing import TYPE_CHECKING

from bayesupdate.inference.tmcmc import TMCMCResult, TMCMCSettings, tmcmc

if TYPE_CHECKING:  # the lazy names' modules, for type checkers and the import-graph checks
    from bayesupdate.inference.checks import calibration_warnings, sampling_warnings
    from bayesupdate.inference.data import (
        ModeSelection,
        load_modal_data,
        register_loader,
        select_modes,
    )
    from bayesupdate.inference.diagnostics import posterior_predictive, summarize
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
    from bayesupdate.inference.user_model import FunctionModel, load_user_model

#: submodule -> the names it lends this package (the TYPE_CHECKING block, as data)
_SOURCES = {
    "checks": ("calibration_warnings", "sampling_warnings"),
    "data": ("ModeSelection", "load_modal_data", "register_loader", "select_modes"),
    "diagnostics": ("posterior_predictive", "summarize"),
    "likelihood": ("LikelihoodSpec", "LogPosterior"),
    "optimize": ("CalibrationResult", "CalibrationSettings", "calibrate", "pareto_front_mass"),
    "pairing": ("ModePairing", "PairingRules", "RefusedMode", "ResidualTable", "pair_modes"),
    "priors": ("Prior", "prior_from_mapping"),
    "problem": (
        "CalibrationProblem",
        "ObjectiveSpec",
        "ParameterSpec",
        "build_parameter_specs",
        "build_problem",
        "objective_expr",
    ),
    "results": (
        "export_netcdf",
        "read_result",
        "read_sampler_state",
        "to_datatree",
        "write_result",
    ),
    "sampling": (
        "PosteriorResult",
        "SamplerSettings",
        "SamplerState",
        "default_moves",
        "sample_posterior",
    ),
    "user_model": ("FunctionModel", "load_user_model"),
}
_SOURCE_OF = {name: module for module, names in _SOURCES.items() for name in names}


#: names spelt with -ise before release 0.2.0 -> their -ize names (a DeprecationWarning)
_DEPRECATED = {"summarise": "summarize"}


def __getattr__(name: str):
    if name in _DEPRECATED:
        import warnings

        new = _DEPRECATED[name]
        warnings.warn(f"bayesupdate.inference.{name} is deprecated; use {new}",
                      DeprecationWarning, stacklevel=2)  # fmt: skip
        name = new
    module = _SOURCE_OF.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{module}"), name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


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
    "summarize",
    "tmcmc",
    "to_datatree",
    "write_result",
]
