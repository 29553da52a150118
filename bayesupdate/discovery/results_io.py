"""A discovery result on disk (HDF5, written atomically) and the extended model as a source.

Schema ``bayesupdate-discovery/1`` (relative errors are (f_model - f_test) / f_test):

/                   attrs: schema, kind = "discovery", verdict, reason, created_utc, command,
                    model (base model name), base_effects_json (effects the model had before),
                    effects_json (spec list of the extended model: base effects + the named one),
                    summary_json (``discovery_summary``: also the ``discover --json`` object),
                    settings_json (``DiscoverySettings.flat``), config_json, timings_json
                    ({phase: wall time [s]}, ``compute.progress``; not reproducible)
/versions           attrs: package versions
/inputs             frequencies_hz (m,), [weights (m,)], [sd_hz (m,)], attrs: source,
                    [test_pairing_json: the study's [test] geometry's pairing]
/baseline           theta (d,), residual_rel (m,), frequencies_hz (m,), attrs: names,
                    log_evidence, expr, loo_json
/final              the re-calibrated model (baseline when nothing was named): same datasets,
                    attrs: names, label, expr, effects_json
/flags              z (m,), p_value (m,), flagged (m,) bool, mac (m,), [shape_p_value (m,)
                    with known shape noise], attrs: chi2, chi2_dof,
                    chi2_p, noise_source, noise_sigma
/localization       candidate (n,) str, delta_chi2 (n,), step_theta (n,); location (k,) str,
                    location_score (k,); part (p,) str, strain_excess (p,), kinetic_excess (p,);
                    comac_label (s,) str, comac (s,)
/final/posterior    (with --posterior-steps) chain (steps, walkers, d), log_prob, attrs: names,
                    burn, summary_json
/candidates/NNN     theta, residual_rel, frequencies_hz, attrs: label, kind, location, names,
                    log_evidence, log_bayes_factor, log_posterior_odds, expr, stage, optima,
                    loo_json

``pipelines.model_source.extended_model_from_result(path)`` rebuilds the final model from it.
"""

import json
from datetime import UTC, datetime
from pathlib import Path

import h5py
import numpy as np

from bayesupdate.atomic import atomic_path
from bayesupdate.discovery.shape_evidence import SHAPE_SD_FLOOR_REL
from bayesupdate.errors import BayesUpdateError

SCHEMA = "bayesupdate-discovery/1"


def _strings(values) -> np.ndarray:
    return np.array([str(v) for v in values], dtype=h5py.string_dtype())


def _write_fit(group, fit) -> None:
    group["theta"] = np.asarray(fit.theta, float)
    group["residual_rel"] = np.asarray(fit.residual_rel, float)
    group["frequencies_hz"] = np.asarray(fit.frequencies_hz, float)
    group.attrs.update(
        names=json.dumps(list(fit.names)),
        label=fit.label,
        log_evidence=float(fit.log_evidence),
        expr=float(fit.expr),
        stage=fit.stage,
        optima=len(fit.optima),
        loo_json=json.dumps(fit.loo),
    )


def _design(fit) -> dict[str, float]:
    """The design variables of a fit (its parameters less the effect's), model units."""
    effect = set(fit.effect_parameters)
    prefix = f"{fit.kind}@{fit.location}:"
    return {k: v for k, v in fit.parameters.items() if k.removeprefix(prefix) not in effect}


def mass_z(fit) -> dict[str, float] | None:
    """{component: (model - measured) / sd} of the measured mass properties at the fit
    (``mass_block``: the weight's relative error over its relative sd); None when the study
    measured none."""
    block = fit.space.mass
    if block is None:
        return None
    r = fit.best.r[fit.space.likelihood.inner.size :]
    return {name: float(v) for name, v in zip(block.names, r, strict=True)}


def _candidate_summary(result, fit, probability: float, score_delta_chi2: float) -> dict:
    """One fitted candidate of ``discovery_summary``."""
    return {
        "kind": fit.kind,
        "location": fit.location,
        "log_evidence": float(fit.log_evidence),
        "loo": None if fit.loo is None else fit.loo["elpd"],
        "log_bayes_factor": result.log_bayes_factor(fit),
        "log_posterior_odds": result.log_posterior_odds(fit),
        "posterior_probability": float(probability),
        "expr": float(fit.expr),
        "parameters": fit.effect_parameters,
        "design": _design(fit),
        "error_pct": [float(v) for v in 100 * fit.residual_rel],
        "mass_z": mass_z(fit),
        "score_delta_chi2": float(score_delta_chi2),
        "optima": len(fit.optima),
        "stage": fit.stage,
    } | ({} if fit.model_error is None else {"model_error": float(fit.model_error)})


def _shape_noise_summary(fit) -> dict | None:
    """How the shape block's levels were set (``shape_evidence``): the stated source ("data sd",
    or "floor" when the data give none: a stated fallback), the floor, each used mode's level as
    a fraction of the RMS amplitude, the modes raised to their baseline misfit and the modes whose
    misfit rejects their stated level in this fit (1-based)."""
    shapes = fit.space.shapes
    if shapes is None:
        return None
    rejects = shapes.stated_rejections(fit.space.shape_residuals(fit.best.r))
    return {
        "source": shapes.source,
        "floor_sd_rel": SHAPE_SD_FLOOR_REL,
        "sd_rel": [float(v) for v in shapes.scale * np.sqrt(shapes.n_dof)],
        "modes": [int(i) + 1 for i in shapes.modes],
        "raised_to_baseline_misfit": [int(i) + 1 for i in shapes.modes[shapes.raised]],
        "rejecting_stated_level": [int(i) + 1 for i in shapes.modes[rejects]],
    }


def discovery_summary(result) -> dict:
    """The summary of a ``workflow.DiscoveryResult``:
    stored as the result file's ``summary_json`` and printed by ``discover --json``
    (``flagged_modes``: the flagged test modes by their number in the data source)."""
    from bayesupdate.discovery.workflow import source_modes

    scores = {s.label: s.delta_chi2 for s in result.localization.scores}
    probability = np.exp(result.log_posterior_probabilities())
    named, final, baseline = result.named, result.final, result.baseline
    if named is not None:
        named = {
            "kind": named.kind,
            "location": named.location,
            "parameters": named.effect_parameters,
        } | ({} if named.model_error is None else {"model_error": float(named.model_error)})
    return {
        "verdict": result.verdict,
        "flagged_modes": source_modes(result.flags, result.baseline),
        "named_effect": named,
        "candidates": [
            _candidate_summary(result, f, probability[k + 1], scores.get(f.label, np.nan))
            for k, f in enumerate(result.fits)
        ],
        "prior_log_odds": result.prior_log_odds,
        "gap_before": float(baseline.expr),
        "gap_after": float(final.expr),
        "reason": result.reason,
        "ambiguous_with": [f.label for f in result.ambiguous_with],
        "baseline": {
            "log_evidence": float(baseline.log_evidence),
            "posterior_probability": float(probability[0]),
            "loo": None if baseline.loo is None else baseline.loo["elpd"],
            "parameters": baseline.parameters,
            "mass_z": mass_z(baseline),
        },
        "design_after": final.parameters,
        "error_pct_before": [float(v) for v in 100 * baseline.residual_rel],
        "error_pct_after": [float(v) for v in 100 * final.residual_rel],
        "noise": {
            "source": result.noise.source,
            "sigma_rel": float(result.noise.sigma),
            "shapes": _shape_noise_summary(baseline),
        },
        "effects": result.effects,
        "scanned": len(result.localization.scores),
        "wall_s": float(result.wall_s),
    } | ({} if result.reduced is None else {"reduced": result.reduced})


def write_discovery(
    path,
    result,
    base_effects=(),
    config: dict | None = None,
    command: str = "discover",
    posterior=None,
    timings: dict | None = None,
):
    """Write ``result`` (workflow.DiscoveryResult) to ``path`` atomically (schema above).
    posterior : optional (PosteriorResult, summary dict) of the final model.  timings :
    {phase name: wall time [s]} (``compute.progress.timings``), the JSON attribute
    ``timings_json``."""
    from bayesupdate.inference.results import package_versions, test_pairing_record

    summary = discovery_summary(result)
    problem = result.baseline.space.problem
    data = problem.data
    effects = list(base_effects) + result.effects
    with atomic_path(path) as tmp, h5py.File(tmp, "w") as h5:
        h5.attrs.update(
            schema=SCHEMA,
            kind="discovery",
            verdict=result.verdict,
            reason=result.reason,
            created_utc=datetime.now(UTC).isoformat(timespec="seconds"),
            command=command,
            model=str(result.model_name).split("+")[0],
            base_effects_json=json.dumps(list(base_effects)),
            effects_json=json.dumps(effects),
            summary_json=json.dumps(summary),
            settings_json=json.dumps(result.settings.flat(), default=str),
            config_json=json.dumps(config or {}, default=str),
        )
        h5.create_group("versions").attrs.update(package_versions())
        h5.attrs["timings_json"] = json.dumps(timings or {})
        _write_inputs(h5.create_group("inputs"), data)
        pairing = test_pairing_record(problem.model)
        if pairing is not None:  # the study's [test] geometry, as calibrate and sample keep it
            h5["inputs"].attrs["test_pairing_json"] = json.dumps(pairing)
        _write_fit(h5.create_group("baseline"), result.baseline)
        final = h5.create_group("final")
        _write_fit(final, result.final)
        final.attrs["effects_json"] = json.dumps(effects)
        if posterior is not None:
            _write_posterior(final.create_group("posterior"), *posterior)
        _write_flags(h5.create_group("flags"), result)
        _write_localization(h5.create_group("localization"), result.localization)
        _write_candidates(h5.create_group("candidates"), result)
    return Path(path)


def _write_inputs(g, data) -> None:
    g["frequencies_hz"] = data.frequencies_hz
    if data.weights is not None:
        g["weights"] = data.weights
    if data.frequency_sd_hz is not None:
        g["sd_hz"] = data.frequency_sd_hz
    g.attrs["source"] = data.source


def _write_posterior(g, chain, summary: dict) -> None:
    g["chain"], g["log_prob"] = chain.chain, chain.log_prob
    g.attrs.update(
        names=json.dumps(list(chain.names)),
        burn=int(chain.burn),
        summary_json=json.dumps(summary, default=float),
    )


def _write_flags(g, result) -> None:
    f = result.flags
    g["z"], g["p_value"], g["flagged"], g["mac"] = f.z, f.p_value, f.flagged, f.mac
    if f.shape_p_value is not None:
        g["shape_p_value"] = f.shape_p_value
    g.attrs.update(
        chi2=f.chi2,
        chi2_dof=f.chi2_dof,
        chi2_p=f.chi2_p,
        noise_source=result.noise.source,
        noise_sigma=result.noise.sigma,
    )


def _write_localization(g, loc) -> None:
    g["candidate"] = _strings(s.label for s in loc.scores)
    g["delta_chi2"] = np.array([s.delta_chi2 for s in loc.scores], float)
    g["step_theta"] = np.array([s.step_theta for s in loc.scores], float)
    g["location"] = _strings(item[0] for item in loc.locations)
    g["location_score"] = np.array([item[1] for item in loc.locations], float)
    g["part"] = _strings(item[0] for item in loc.part_energy)
    g["strain_excess"] = np.array([item[1] for item in loc.part_energy], float)
    g["kinetic_excess"] = np.array([item[2] for item in loc.part_energy], float)
    g["comac_label"] = _strings(loc.comac)
    g["comac"] = np.array(list(loc.comac.values()), float)


def _write_candidates(cands, result) -> None:
    for i, fit in enumerate(result.fits):
        c = cands.create_group(f"{i:03d}")
        _write_fit(c, fit)
        c.attrs.update(
            kind=fit.kind,
            location=fit.location,
            log_bayes_factor=result.log_bayes_factor(fit),
            log_posterior_odds=result.log_posterior_odds(fit),
        )


def read_discovery_summary(path) -> dict:
    """The JSON summary and the effect list of a discovery result file."""
    try:
        with h5py.File(path, "r") as h5:
            if h5.attrs.get("schema") != SCHEMA:
                raise BayesUpdateError(f"{path}: not a discovery result ({SCHEMA})")
            out = json.loads(h5.attrs["summary_json"])
            out["model"] = str(h5.attrs["model"])
            out["effects"] = json.loads(h5.attrs["effects_json"])
            final = h5["final"]
            names = json.loads(final.attrs["names"])
            out["final_parameters"] = dict(zip(names, map(float, final["theta"][()]), strict=True))
            return out
    except OSError as exc:
        raise BayesUpdateError(f"{path}: cannot read discovery result ({exc})") from exc


def extend_with_specs(model, specs) -> object:
    """``model`` extended by each effect spec (``KIND@LOCATION[:name=value]``) in turn."""
    from bayesupdate.discovery.effects import extend_model, parse_effect_spec

    if specs and not hasattr(model, "structure"):
        raise BayesUpdateError(
            "effects need an FE model (a built-in model such as 'exhaust'); "
            "a package.module:function model cannot be extended"
        )
    for spec in specs:
        model = extend_model(model, parse_effect_spec(spec))
    return model
