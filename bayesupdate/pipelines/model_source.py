"""Where a pipeline's model comes from: a built-in name, a Nastran deck, a user's
``package.module:function``, or the final model of a discovery result file.

This is the one place that knows every kind of model source, so inference (which sees only the
``model_protocol``) and discovery (which extends FE models) need not import ``models``, and
``models`` (built-in structures by name) need not import ``nastran``: every command and pipeline
resolves its model here.
"""

from collections.abc import Mapping

from bayesupdate.errors import BayesUpdateError


def is_deck(source) -> bool:
    """Whether the model source ``source`` is a Nastran deck path (.bdf, .dat, .nas, .blk)."""
    from bayesupdate.nastran import is_nastran_path

    return is_nastran_path(source)


def resolve_model(
    source: str, parameters: Mapping | None = None, sensors=(), options=None, deck=None,
    units=None, needs_parameters: bool = True,
):  # fmt: skip
    """A built-in model name (``bayesupdate.models.get_model``), a Nastran deck path, or a
    ``module:function`` spec (``inference.user_model.load_user_model``: its parameters and
    bounds come from ``parameters``, the study's ``{name: {bounds, start}}`` tables; ``sensors``
    labels its shape rows).  ``options`` are the built-in model factory's keyword arguments.

    A Nastran deck (``nastran.load_nastran_model``) takes its parameters from the tables'
    ``binds`` and reads shapes at ``deck = (test DOF labels, {test node: GRID id})``, in its
    own ``units`` (a name, ``nastran.units``; None: recognized from the deck).  A deck without
    bound parameters is refused unless ``needs_parameters`` is False (``modes``, ``correlate``:
    a model at its own values; a DESVAR whose relation cannot be bound is then left out with a
    note, not refused: ``load_nastran_model(strict=)``)."""
    from bayesupdate.inference.user_model import load_user_model
    from bayesupdate.models import BUILTIN_MODELS, get_model
    from bayesupdate.nastran import is_nastran_path, load_nastran_model

    if is_nastran_path(source):
        if options:
            raise BayesUpdateError(f"model.options: a Nastran deck takes none ({source})")
        labels, points = deck if deck is not None else ((), None)
        model = load_nastran_model(
            str(source), parameters, labels, points, units=units, strict=needs_parameters
        )
        if needs_parameters and not model.parameter_names:
            raise BayesUpdateError(
                f"model {source}: a Nastran deck's parameters are deck fields; give them in a "
                'study file, e.g. [parameters.t] binds = "PSHELL 3 T" (or DESVAR/DVPREL1 cards)'
            )
        return model
    if _points_given(deck):
        raise BayesUpdateError("model.test_points: only a Nastran deck (model.source) maps them")
    if units is not None:
        raise BayesUpdateError("model.units: only a Nastran deck has its own units (SI here)")
    bound = [name for name, entry in (parameters or {}).items() if "binds" in entry]
    if bound:
        raise BayesUpdateError(
            f"parameters.{bound[0]}.binds: only a Nastran deck's parameters bind deck fields "
            f"(model.source {source!r})"
        )
    if ":" in str(source):
        return load_user_model(source, parameters or {}, tuple(sensors))
    if source not in BUILTIN_MODELS:
        raise BayesUpdateError(
            f"model.source {source!r}: unknown model; built-in models are "
            f"{sorted(BUILTIN_MODELS)}, or give 'package.module:function' or a Nastran deck "
            "(.bdf, .dat, .nas, .blk)"
        )
    try:
        return get_model(source, **(options or {}))
    except ImportError as exc:
        raise BayesUpdateError(
            f"model {source!r}: not available in this installation ({exc})"
        ) from exc
    except TypeError as exc:
        raise BayesUpdateError(f"model.options: not accepted by {source!r} ({exc})") from exc


def deck_test_model(source, parameters: Mapping | None, table: Mapping | None):
    """The Nastran deck at ``source`` measured in V (z) and H (y) at every point of the
    test-point ``table`` (``nastran.test_points``; labels ``<point>V``, ``<point>H``): the
    model ``simulate`` tests.  parameters : ``{name: {binds, ...}}`` tables."""
    from bayesupdate.nastran import load_nastran_model
    from bayesupdate.nastran.test_points import HOW, table_points, with_test_points

    if not table:
        raise BayesUpdateError(f"model {source}: a Nastran deck has no sensor layout; {HOW}")
    model = load_nastran_model(str(source), parameters)
    points = table_points(model.structure, table)
    labels = [f"{k}{d}" for k in points for d in "VH"]
    return model.with_structure(with_test_points(model.structure, labels, table, model.name))


def _points_given(deck) -> bool:
    return deck is not None and bool(deck[1])


def study_model(study, test_labels=(), needs_parameters: bool = True):
    """The model of a ``config.StudyConfig`` (its ``[model]`` table and parameter tables);
    a Nastran deck reads shapes at ``test_labels`` (the test data's DOF labels), mapped by
    ``[model.test_points]``, or by position through the study's ``[test]`` geometry
    (``paired_study_model``), which any FE model takes.  ``needs_parameters``: as
    ``resolve_model``."""
    if study.test is not None:
        return paired_study_model(study, test_labels, needs_parameters)[0]
    return resolve_model(
        study.model.source,
        study.parameters,
        study.model.sensors,
        study.model.options,
        deck=(tuple(test_labels), dict(study.model.test_points)),
        units=study.model.units,
        needs_parameters=needs_parameters,
    )


def paired_study_model(study, test_labels=(), needs_parameters: bool = True):
    """(model, ``testgeom.TestPairing`` or None): the study's FE model whose sensors are the
    test DOFs ``test_labels``, paired with it by the ``[test]`` table (read the geometry, align
    it, pair each point with the nearest node or element point: ``testgeom``).  Without labels
    (frequencies only) the geometry is read and checked, and the model keeps its sensors.
    ``needs_parameters``: as ``resolve_model``."""
    from bayesupdate.testgeom import pair_structure, read_geometry, with_pairing

    cfg = study.test
    model = resolve_model(
        study.model.source, study.parameters, study.model.sensors, study.model.options,
        units=study.model.units, needs_parameters=needs_parameters,
    )  # fmt: skip
    geometry = read_geometry(cfg.geometry, cfg.length_unit)
    if not test_labels:
        return model, None
    if not (hasattr(model, "structure") and hasattr(model, "with_structure")):
        raise BayesUpdateError(
            f"[test] geometry: model {study.model.source!r} has no FE structure to pair the test "
            "with; use a built-in model or a Nastran deck"
        )
    pairing = pair_structure(
        model.structure, geometry, test_labels, cfg.settings(), cfg.model_length_unit
    )
    if pairing.shared:  # allowed (two sensors on one spot), never silent
        import warnings

        groups = "; ".join(", ".join(map(str, g)) for g in pairing.shared)
        warnings.warn(
            f"[test] {cfg.geometry}: test points {groups} sit on one model point", stacklevel=2
        )
    return model.with_structure(with_pairing(model.structure, pairing)), pairing


def problem_parameters(parameters: Mapping) -> dict:
    """The study's parameter tables without ``binds`` (which the model has consumed)."""
    return {k: {f: v for f, v in e.items() if f != "binds"} for k, e in parameters.items()}


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
