"""Where a pipeline's model comes from: a built-in name, a Nastran deck, a user's
``package.module:function``, or the final model of a discovery result file.

This is the one place that knows every kind of model source, so inference (which sees only the
``model_protocol``) and discovery (which extends FE models) need not import ``models``.
"""

from collections.abc import Mapping

from bayesupdate.errors import BayesUpdateError


def resolve_model(source: str, parameters: Mapping | None = None, sensors=(), options=None):
    """A built-in model name (``bayesupdate.models.get_model``), a Nastran deck path, or a
    ``module:function`` spec (``inference.user_model.load_user_model``: its parameters and
    bounds come from ``parameters``, the study's ``{name: {bounds, start}}`` tables; ``sensors``
    labels its shape rows).  ``options`` are the built-in model factory's keyword arguments."""
    from bayesupdate.inference.user_model import load_user_model
    from bayesupdate.models import BUILTIN_MODELS, get_model
    from bayesupdate.nastran import is_nastran_path

    if is_nastran_path(source):
        return get_model(str(source), **(options or {}))
    if ":" in str(source):
        return load_user_model(source, parameters or {}, tuple(sensors))
    if source not in BUILTIN_MODELS:
        raise BayesUpdateError(
            f"model.source {source!r}: unknown; built-in models are {sorted(BUILTIN_MODELS)} "
            "or give 'package.module:function'"
        )
    try:
        return get_model(source, **(options or {}))
    except ImportError as exc:
        raise BayesUpdateError(
            f"model {source!r}: not available in this installation ({exc})"
        ) from exc
    except TypeError as exc:
        raise BayesUpdateError(f"model.options: not accepted by {source!r} ({exc})") from exc


def study_model(study):
    """The model of a ``config.StudyConfig`` (its ``[model]`` table and parameter tables)."""
    return resolve_model(
        study.model.source, study.parameters, study.model.sensors, study.model.options
    )


def extended_model_from_result(path):
    """(model, parameters): the final model of a discovery result file as a model source.

    The base model is rebuilt by name (built-in models), extended by the stored effect specs
    (their fitted values become the effect parameters' defaults); ``parameters`` holds the
    re-fitted design variables and effect parameters (SI)."""
    from bayesupdate.discovery.results_io import extend_with_specs, read_discovery_summary
    from bayesupdate.models import get_model

    summary = read_discovery_summary(path)
    model = extend_with_specs(get_model(summary["model"]), summary["effects"])
    return model, summary["final_parameters"]
