"""The discover pipeline: a study (model + test data) -> what physics the model is missing.

The study's FE model, extended by the effects already known (``[effects]``, ``--effect``), runs
``discovery.workflow.discover`` against the study's data, with the measured mass properties
(``[data] mass / mass_sd / cg / inertia``) as data, read by the reader ``calibrate`` uses
(``pipelines.study.study_mass_terms``); optionally the final model's posterior is sampled too
(``discovery.posterior.sample_final``).
"""

from collections.abc import Callable
from dataclasses import dataclass, field, replace

from bayesupdate.compute.settings import SERIAL, ComputeSettings, open_executor
from bayesupdate.config import StudyConfig
from bayesupdate.discovery.results_io import extend_with_specs
from bayesupdate.discovery.settings import DiscoverySettings
from bayesupdate.discovery.workflow import DiscoveryPairing, DiscoveryResult, discover
from bayesupdate.errors import BayesUpdateError
from bayesupdate.pipelines.model_source import problem_parameters, study_model
from bayesupdate.pipelines.study import study_data, study_mass_terms


@dataclass(frozen=True)
class DiscoveryRequest:
    """settings : the discovery knobs.  effects : checked effect specs the model is extended by
    first (``pipelines.study.study_effects``).  posterior_steps : > 0 also samples the final
    model's posterior for that many steps (seed ``settings.seed + 1``; 0: not sampled).
    compute : where the scan and refits run (``compute.executors``; the result is the same)."""

    settings: DiscoverySettings = field(default_factory=DiscoverySettings)
    effects: tuple[str, ...] = ()
    posterior_steps: int = 0
    compute: ComputeSettings = SERIAL


@dataclass(frozen=True)
class DiscoveryRun:
    """model : the (extended) FE model discovery ran on.  effects : the specs it was extended
    by.  result : what discovery found.  posterior : (PosteriorResult, summary dict) of the final
    model, or None.  compute : where the work ran ({"kind", "workers", ...}).  pairing : the
    MAC pairing's record (``discovery.workflow.discovery_problem``: method, rules, refused test
    modes; {} without test shapes)."""

    model: object
    effects: tuple[str, ...]
    result: DiscoveryResult
    posterior: tuple | None = None
    compute: dict = field(default_factory=lambda: {"kind": "serial", "workers": 1})
    pairing: dict = field(default_factory=dict)


def study_pairing(study: StudyConfig, numbers: tuple[int, ...]) -> DiscoveryPairing:
    """The study's ``[pairing]`` (method, rules, extra modes) with the source numbers of its
    selected test modes (``inference.data.select_modes``): the pairing ``calibrate`` builds
    (``pipelines.study.prepare``), so discover pairs the modes that calibrate and correlate
    pair on the same study file."""
    cfg = study.pairing
    return DiscoveryPairing(cfg.method, cfg.rules(), cfg.extra_modes, tuple(numbers))


def study_mass_properties(study: StudyConfig, data, model) -> tuple:
    """(data, ``ObjectiveSpec``): the study's measured mass properties as ``calibrate`` takes
    them (``pipelines.study.study_mass_terms``: ``[data] mass / mass_sd`` in the model's units,
    the ``[objective]`` mass term, ``[data] cg / inertia``), and ``[likelihood] mass_sd`` (a
    relative sd) applied to the data's mass sd, which discovery's mass term reads
    (``discovery.mass_block``), as calibrate's likelihood reads it from there.  The CG and
    inertia terms are scaled at ``model``, the model before the known effects are added
    (``prepare`` scales them at the extended model; the same without effects)."""
    data, objective = study_mass_terms(study, data, model)
    sd_rel = study.likelihood.mass_sd
    if sd_rel is not None and data.mass_kg is not None:
        data = replace(data, mass_sd_kg=float(sd_rel) * data.mass_kg)
    return data, objective


def discover_study(
    study: StudyConfig,
    request: DiscoveryRequest = DiscoveryRequest(),
    progress: Callable[[str], None] | None = None,
) -> DiscoveryRun:
    """Run discovery on ``study`` (module docstring); ``progress`` receives progress lines."""
    data, numbers = study_data(study)
    model = study_model(study, data.dof_labels if data.shapes is not None else ())
    if not hasattr(model, "structure"):
        raise BayesUpdateError(
            f"model {study.model.source!r}: discovery extends an FE model's structure; "
            "use a built-in FE model such as 'exhaust'"
        )
    data, objective = study_mass_properties(study, data, model)
    model = extend_with_specs(model, request.effects)
    with open_executor(request.compute) as executor:
        compute = executor.describe()
        result = discover(
            model,
            data,
            request.settings,
            parameters=problem_parameters(study.parameters) or None,
            pairing=study_pairing(study, numbers),
            progress=progress,
            executor=executor,
            objective=objective,
        )
    posterior = None
    if request.posterior_steps > 0:
        from bayesupdate.discovery.posterior import sample_final
        from bayesupdate.inference.diagnostics import summarize

        seed = request.settings.seed + 1
        chain, _ = sample_final(result, steps=request.posterior_steps, seed=seed)
        posterior = (chain, summarize(chain))
    return DiscoveryRun(model, tuple(request.effects), result, posterior, compute, result.pairing)
