"""One HDF5 file per run (written atomically) and its export to an ArviZ DataTree / netCDF.

Schema ``bayesupdate-result/1`` (all arrays SI; frequencies in Hz):

/                      attrs: schema, kind ("calibration" | "posterior"), status ("complete" |
                       "partial" - a checkpoint that ``sample --resume`` continues), created_utc,
                       config_json (the study as JSON; resume checks it), command,
                       warnings_json (list of one-line warnings, ``inference.checks``),
                       timings_json ({phase: wall time [s]} of the command's phases,
                       ``compute.progress``; like wall_s, not reproducible)
/versions              attrs: python, bayesupdate, numpy, scipy, emcee, arviz, h5py
/inputs                frequencies_hz (m,), weights (m,), [sd_hz (m,)], attrs: source,
                       [measured_mass_kg, measured_mass_sd_kg],
                       parameter_names, bounds (d, 2) dataset, priors_json, pairing_method,
                       fixed_json, model, test_modes (m,) each mode's 1-based number in
                       the data source, pairing_json (method, mac_threshold,
                       frequency_window, refused: the test modes left out at the
                       reference design, ``ModePairing.to_dict``),
                       [test_pairing_json: the study's [test] geometry
                       paired with the model: transform, per point its model node, element,
                       xyz and distance (``testgeom.TestPairing.to_dict``)]
/optimum               theta (d,), attrs: parameter_names, objective, expr, mass_kg, swapped,
                       starts, converged_starts, failed_evaluations, evaluations, method, wall_s,
                       [mass_properties_json: [{name, measured, predicted, unit, sd}] of the
                       measured mass, CG and inertia at the optimum, in the model's units];
                       frequencies_hz (m,), start_points (n, d), end_points (n, d),
                       end_objectives (n,), distinct_optima (k,)
/optimum/residuals     test_hz, model_hz, error_pct, mac (NaN = no shapes), model_mode (1-based)
/posterior             chain (steps, walkers, d), log_prob (steps, walkers), autocorr_time (d,),
                       acceptance (walkers,), attrs: names, burn, evaluations, failed_evaluations,
                       wall_s, converged (the run met its R-hat / ESS / tau targets),
                       convergence_reason ("" when converged), interrupted, seed
/posterior/state       coords (walkers, d), last_log_prob (walkers,), accepted (walkers,),
                       rng_keys (624,) uint32, attrs: rng_pos, rng_has_gauss, rng_cached_gaussian,
                       moves_json (the move scheme and frozen proposal, ``SamplerState.moves``)
/posterior/diagnostics attrs: summary_json (see diagnostics.summarize), sampling_json
                       ({"pairing_mode", "pair_differs_fraction", "rom": {size,
                       max_rel_error, certified, tol, n_modes, error_at (posterior mean)},
                       "convergence": diagnostics.convergence_report}), timings_json
                       (the run's wall-time parts [s]; like wall_s, not reproducible)
/posterior/predictions draw_index (n,), frequencies_hz (n, m), predictive_hz (n, m),
                       attrs: swap_fraction
"""

import json
import platform
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING

import h5py
import numpy as np

from bayesupdate.atomic import atomic_path
from bayesupdate.compute import progress
from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.mass_properties import mass_property_report
from bayesupdate.inference.optimize import CalibrationResult
from bayesupdate.inference.problem import CalibrationProblem

if TYPE_CHECKING:  # the sampler and emcee load where a posterior is read, not for an optimum
    from bayesupdate.inference.sampling import PosteriorResult, SamplerState

SCHEMA = "bayesupdate-result/1"


@dataclass(frozen=True)
class ResultWriter:
    """The result file of one run, rewritten whole (``write_result``) each time a part is new.

    path : the HDF5 file (None: nothing is written).  problem, calibration, config, command:
    as ``write_result``.  ``write(**parts)`` writes the file with ``parts`` (posterior, state,
    diagnostics, predictions, warnings) and the run's phase timings so far; ``checkpoint`` is the
    sampler's callback (``sampling.sample_posterior``): the chain so far after each unfinished
    block (status "partial", which ``sample --resume`` continues)."""

    path: str | Path | None
    problem: CalibrationProblem
    calibration: CalibrationResult
    config: dict
    command: str = ""

    def write(self, **parts) -> None:
        if self.path is not None:
            write_result(
                self.path, self.problem, self.calibration, self.config, command=self.command,
                timings=progress.timings(), **parts,
            )  # fmt: skip

    def checkpoint(self, state: "SamplerState") -> None:
        if not state.finished:
            self.write(state=state)


def package_versions() -> dict[str, str]:
    import importlib.metadata as md

    out = {"python": platform.python_version()}
    for name in ("bayesupdate", "numpy", "scipy", "emcee", "arviz", "h5py"):
        try:
            out[name] = md.version(name)
        except md.PackageNotFoundError:
            out[name] = "unknown"
    return out


def _json_default(obj):
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    return str(obj)


def _write_state(group: h5py.Group, state: "SamplerState") -> None:
    kind, keys, pos, has_gauss, cached = state.random_state
    group["coords"] = state.coords
    group["last_log_prob"] = state.last_log_prob
    group["accepted"] = state.accepted
    group["rng_keys"] = np.asarray(keys, dtype=np.uint32)
    group.attrs.update(
        rng_kind=str(kind),
        rng_pos=int(pos),
        rng_has_gauss=int(has_gauss),
        rng_cached_gaussian=float(cached),
        evaluations=int(state.evaluations),
        failed=int(state.failed),
        wall_s=float(state.wall_s),
        finished=bool(state.finished),
    )
    if state.moves is not None:  # the frozen proposal a resume continues with
        group.attrs["moves_json"] = json.dumps(state.moves)


def test_pairing_record(model) -> dict | None:
    """The ``[test]`` pairing a model's structure carries (``metadata["test_pairing"]``; a
    reduced model's through its FE model), or None."""
    for holder in (model, getattr(model, "fe", None)):
        metadata = getattr(getattr(holder, "structure", None), "metadata", None)
        if isinstance(metadata, dict) and "test_pairing" in metadata:
            return metadata["test_pairing"]
    return None


def write_result(
    path: str | Path,
    problem: CalibrationProblem,
    calibration: CalibrationResult,
    config: dict | None = None,
    posterior: "PosteriorResult | None" = None,
    state: "SamplerState | None" = None,
    diagnostics: dict | None = None,
    predictions: dict | None = None,
    command: str = "",
    warnings: tuple[str, ...] | list[str] = (),
    timings: dict | None = None,
) -> Path:
    """Write the run to ``path`` atomically (temporary file + rename).

    Give ``posterior`` for a finished sampling run, or only ``state`` for a checkpoint
    (status "partial").  ``warnings``: one-line warnings of the run (``inference.checks``).
    timings : {phase name: wall time [s]} of the run's phases (``compute.progress.timings``),
    kept as the JSON attribute ``timings_json``.
    Returns the path.
    """
    kind = "posterior" if (posterior is not None or state is not None) else "calibration"
    partial = posterior is None and state is not None
    if posterior is not None and posterior.interrupted:
        partial = True
    with atomic_path(path) as tmp, h5py.File(tmp, "w") as h5:
        h5.attrs.update(
            schema=SCHEMA,
            kind=kind,
            status="partial" if partial else "complete",
            created_utc=datetime.now(UTC).isoformat(timespec="seconds"),
            config_json=json.dumps(config or {}, default=_json_default, sort_keys=True),
            command=command,
            warnings_json=json.dumps(list(warnings)),
            timings_json=json.dumps(timings or {}),
        )
        h5.create_group("versions").attrs.update(package_versions())
        _write_inputs(h5.create_group("inputs"), problem)
        _write_optimum(h5.create_group("optimum"), calibration)
        report = mass_property_report(problem, problem.as_mapping(calibration.theta))
        if report:
            h5["optimum"].attrs["mass_properties_json"] = json.dumps(report)
        if kind == "posterior":
            _write_posterior_group(h5, posterior, state, diagnostics, predictions)
    return Path(path)


def _write_posterior_group(h5, posterior, state, diagnostics, predictions) -> None:
    """The /posterior group of ``write_result``: chain or checkpoint state, diagnostics and the
    posterior predictions."""
    post = h5.create_group("posterior")
    _write_posterior(post, posterior, state)
    if diagnostics is not None:
        group = post.create_group("diagnostics")
        group.attrs["summary_json"] = json.dumps(diagnostics)
        # the run's clock (wall-time parts) apart, as wall_s: the rest is the seeded
        # run's and the same bits on every rerun
        extra = posterior.diagnostics
        clock = extra.get("timings")
        extra = {k: v for k, v in extra.items() if k not in ("summary", "timings")}
        if extra:
            group.attrs["sampling_json"] = json.dumps(extra, default=float)
        if clock:
            group.attrs["timings_json"] = json.dumps(clock)
    if predictions is not None:
        pred = post.create_group("predictions")
        for name in ("draw_index", "frequencies_hz", "predictive_hz"):
            pred[name] = predictions[name]
        pred.attrs["swap_fraction"] = predictions["swap_fraction"]


def _write_inputs(inputs: h5py.Group, problem: CalibrationProblem) -> None:
    """The data and the problem: test frequencies, weights, sd, bounds, priors, measured mass,
    and the test geometry's pairing where the model's sensors came from one."""
    pairing = test_pairing_record(problem.model)
    if pairing is not None:
        inputs.attrs["test_pairing_json"] = json.dumps(pairing)
    data = problem.data
    inputs["frequencies_hz"] = data.frequencies_hz
    inputs["test_modes"] = problem.mode_numbers
    inputs["weights"] = problem.weights
    if data.frequency_sd_hz is not None:
        inputs["sd_hz"] = data.frequency_sd_hz
    inputs["bounds"] = np.column_stack([problem.lower, problem.upper])
    inputs.attrs.update(
        source=data.source,
        parameter_names=list(problem.names),
        priors_json=json.dumps({p.name: p.prior.to_dict() for p in problem.parameters}),
        pairing_method=problem.pairing.method,
        pairing_json=json.dumps(problem.pairing.to_dict()),
        fixed_json=json.dumps(problem.fixed, default=_json_default),
        model=type(problem.model).__name__,
    )
    for name in ("mass_kg", "mass_sd_kg"):
        if getattr(data, name) is not None:
            inputs.attrs[f"measured_{name}"] = float(getattr(data, name))


def _write_optimum(opt: h5py.Group, calibration: CalibrationResult) -> None:
    """The point optimum, its multi-start record and its residual table."""
    opt["theta"] = calibration.theta
    opt["frequencies_hz"] = calibration.frequencies_hz
    opt["start_points"] = calibration.start_points
    opt["end_points"] = calibration.end_points
    opt["end_objectives"] = calibration.end_objectives
    opt["distinct_optima"] = np.asarray(calibration.distinct_optima, dtype=int)
    opt.attrs.update(
        parameter_names=list(calibration.names),
        objective=calibration.objective,
        expr=calibration.expr,
        mass_kg=np.nan if calibration.mass_kg is None else calibration.mass_kg,
        swapped=calibration.swapped,
        starts=calibration.starts,
        converged_starts=calibration.converged_starts,
        failed_evaluations=calibration.failed_evaluations,
        evaluations=calibration.evaluations,
        method=calibration.method,
        wall_s=calibration.wall_s,
    )
    table = opt.create_group("residuals")
    for name in ("test_hz", "model_hz", "error_pct", "mac", "model_mode"):
        table[name] = getattr(calibration.table, name)


def _write_posterior(
    post: h5py.Group, posterior: "PosteriorResult | None", state: "SamplerState | None"
) -> None:
    """The chain, the sampler state to resume from, and (finished runs) its summary attributes."""
    source = posterior.state if posterior is not None else state
    post["chain"] = source.chain
    post["log_prob"] = source.log_prob
    _write_state(post.create_group("state"), source)
    if posterior is None:
        return
    post["autocorr_time"] = posterior.autocorr_time
    post["acceptance"] = posterior.acceptance
    convergence = posterior.diagnostics.get("convergence") or {}
    post.attrs.update(
        names=list(posterior.names),
        burn=posterior.burn,
        evaluations=posterior.evaluations,
        failed_evaluations=posterior.failed_evaluations,
        wall_s=posterior.wall_s,
        converged=posterior.converged,
        convergence_reason=convergence.get("reason") or "",
        interrupted=posterior.interrupted,
        seed=posterior.seed,
    )


def _open(path: str | Path) -> h5py.File:
    try:
        h5 = h5py.File(path, "r")
    except OSError as exc:
        raise BayesUpdateError(f"{path}: not a readable result file ({exc})") from exc
    if h5.attrs.get("schema") != SCHEMA:
        h5.close()
        raise BayesUpdateError(f"{path}: not a bayesupdate result (schema {SCHEMA} expected)")
    return h5


def read_config(path: str | Path) -> tuple[dict, str]:
    """(config dict, status) of a result file."""
    with _open(path) as h5:
        return json.loads(h5.attrs["config_json"]), str(h5.attrs["status"])


def read_sampler_state(path: str | Path) -> "SamplerState":
    """The sampler state of a (partial) posterior result, for ``sample_posterior(resume=...)``."""
    from bayesupdate.inference.sampling import SamplerState

    with _open(path) as h5:
        if "posterior" not in h5:
            raise BayesUpdateError(
                f"{path}: has no posterior to resume; run sample without --resume"
            )
        post = h5["posterior"]
        g = post["state"]
        a = g.attrs
        random_state = (
            str(a["rng_kind"]),
            np.asarray(g["rng_keys"][()], dtype=np.uint32),
            int(a["rng_pos"]),
            int(a["rng_has_gauss"]),
            float(a["rng_cached_gaussian"]),
        )
        return SamplerState(
            chain=post["chain"][()],
            log_prob=post["log_prob"][()],
            coords=g["coords"][()],
            last_log_prob=g["last_log_prob"][()],
            random_state=random_state,
            accepted=g["accepted"][()],
            evaluations=int(a["evaluations"]),
            failed=int(a["failed"]),
            wall_s=float(a["wall_s"]),
            finished=bool(a["finished"]),
            moves=json.loads(a["moves_json"]) if "moves_json" in a else None,
        )


def read_result(path: str | Path) -> dict:
    """The whole file as nested dicts of numpy arrays and attributes (for plots and studies)."""

    def walk(group):
        out = {
            "attrs": {
                k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in group.attrs.items()
            }
        }
        for key, item in group.items():
            out[key] = walk(item) if isinstance(item, h5py.Group) else item[()]
        return out

    with _open(path) as h5:
        return walk(h5)


def to_datatree(path: str | Path):
    """ArviZ DataTree of a posterior result: posterior (walkers as chains, post-burn draws),
    sample_stats.lp, posterior_predictive.frequencies_hz, observed_data.frequencies_hz.

    Save it with ``.to_netcdf(file)``.
    """
    import arviz_base

    res = read_result(path)
    if "posterior" not in res or "autocorr_time" not in res["posterior"]:
        raise BayesUpdateError(f"{path}: no finished posterior to export")
    post = res["posterior"]
    burn = int(post["attrs"]["burn"])
    chain = np.moveaxis(post["chain"][burn:], 1, 0)  # (walkers, draws, d)
    names = list(post["attrs"]["names"])
    groups = {
        "posterior": {name: chain[..., j] for j, name in enumerate(names)},
        "sample_stats": {"lp": np.moveaxis(post["log_prob"][burn:], 1, 0)},
        "observed_data": {"frequencies_hz": res["inputs"]["frequencies_hz"]},
    }
    if "predictions" in post:
        groups["posterior_predictive"] = {
            "frequencies_hz": post["predictions"]["predictive_hz"][None, ...]
        }
    return arviz_base.from_dict(
        groups,
        dims={"frequencies_hz": ["mode"]},
        attrs={"posterior": {"source": "bayesupdate", "schema": SCHEMA}},
    )


def export_netcdf(path: str | Path, netcdf_path: str | Path) -> Path:
    """Write ``to_datatree(path)`` to ``netcdf_path`` atomically (needs h5netcdf or netCDF4)."""
    tree = to_datatree(path)
    engine = None
    for module, name in (("h5netcdf", "h5netcdf"), ("netCDF4", "netcdf4")):
        try:
            __import__(module)
            engine = name
            break
        except ImportError:
            continue
    if engine is None:
        raise BayesUpdateError(
            f"{netcdf_path}: writing netCDF needs the h5netcdf package; pip install h5netcdf"
        )
    with atomic_path(netcdf_path, suffix=".nc") as tmp:
        tree.to_netcdf(tmp, engine=engine)
    return Path(netcdf_path)
