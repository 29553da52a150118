"""A large model's calibration kept on disk: the same command on the same model, data and
settings recalls its optimum instead of searching again, and checks it by one full solve.

The optimum of ``pipelines.calibrate`` is a pure function of the certified basis (its vectors),
the problem (data, parameters and their bounds and starts, pairing, objective, fixed values, the
reference prediction) and the optimizer's settings; the entry's key is the SHA-256 of all of them
and the package version (``compute.cache.content_key``), in the same store as the bases
(``compute.cache.ArrayStore``: ``BAYESUPDATE_CACHE_DIR``, ``--no-cache``, atomic writes,
checksums, least recently used out).  A recalled optimum is evaluated by one full solve, as a
fresh one is (``calibrate.evaluated_in_full``; with as many modes as the solve that gave the
stored numbers, ``solve_modes``, so that the same computation gives the same bits), and used
only when that full objective reproduces the stored one to ``RECALL_AGREES``; otherwise the
calibration runs again (with a note).
Only the large-model path uses it: there a search costs tens of seconds, a beam model's one less
than the full solve that checks a recalled optimum would.
"""

import time
import warnings
from dataclasses import dataclass, replace

import numpy as np

from bayesupdate import __version__
from bayesupdate.compute.cache import ArrayStore, content_key
from bayesupdate.compute.progress import phase
from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.optimize import CalibrationResult, CalibrationSettings
from bayesupdate.inference.problem import CalibrationProblem
from bayesupdate.model_protocol import Prediction

#: format of a kept calibration; bump when the stored arrays change meaning
MEMO_FORMAT = "calibration-1"
#: relative agreement of a recalled optimum's full objective with the stored one: the same
#: full solve on the same machine gives the same bits; another BLAS build differs by ~1e-13
RECALL_AGREES = 1e-9


def memo_key(problem: CalibrationProblem, tol: float, settings: CalibrationSettings) -> str:
    """The content key of the calibration of ``problem`` (the exact one, on an ``FEModel``) on
    its certified basis of tolerance ``tol`` with ``settings`` (module docstring), computed
    without building or loading the basis: the basis enters by its own key
    (``ReducedFEModel.content_key``).  Parameters enter by name, bounds and start (their priors
    do not move the optimum).  "" (nothing is kept) for a model without a reduced form: its
    calibration runs on full solves, with the warning ``sampling_problem`` gives."""
    parameters = tuple((p.name, p.bounds, p.start) for p in problem.parameters)
    try:
        basis = basis_of(problem, tol).content_key()
    except BayesUpdateError:
        return ""
    return content_key(
        MEMO_FORMAT, __version__, basis, problem.names, parameters, problem.data,
        problem.pairing, problem.objective, problem.fixed, problem.reference, problem.test_modes,
        settings,
    )  # fmt: skip


def basis_of(problem: CalibrationProblem, tol: float):
    """The (unbuilt) ``ReducedFEModel`` that ``pipelines.surrogates.sampling_problem`` builds
    for ``problem`` with tolerance ``tol``: the calibrated parameters' bounds, fixed ones in a
    +-0.1 % box around their value, the modes the pairing needs, seed 0
    (``tests/test_calibration_memo.py`` holds the two to the same key)."""
    from bayesupdate.fe.reduced import ReducedFEModel, ReducedSettings

    model = problem.model
    bounds = {p.name: p.bounds for p in problem.parameters}
    for name, value in problem.fixed.items():
        if name in model.parameter_names and value > 0:
            bounds[name] = (value * (1 - 1e-3), value * (1 + 1e-3))
    settings = ReducedSettings(n_modes=problem.pairing.n_model, tol=tol, seed=0)
    return ReducedFEModel(model, bounds, settings)


def memo_arrays(
    result: CalibrationResult, basis_error: float, solve_modes: int = 0
) -> dict[str, np.ndarray]:
    """What is kept of ``result`` (the full model's optimum) and the basis's relative frequency
    error there: the optimum, the starts and ends, the counts, the full objective and the modes
    of the full solve that gave it (``solve_modes``; 0: the pairing's)."""
    return {
        "solve_modes": np.array(solve_modes, dtype=int),
        "theta": result.theta,
        "objective": np.array(result.objective),
        "basis_error": np.array(basis_error),
        "start_points": result.start_points,
        "end_points": result.end_points,
        "end_objectives": result.end_objectives,
        "distinct_optima": np.array(result.distinct_optima, dtype=int),
        "counts": np.array(
            [result.starts, result.converged_starts, result.failed_evaluations, result.evaluations]
        ),
        "method": np.array(result.method),
    }


def recalled(
    problem: CalibrationProblem, arrays: dict[str, np.ndarray] | None, tol: float
) -> CalibrationResult | None:
    """The kept calibration ``arrays`` (``memo_arrays``) as a result of ``problem``, its
    objective, frequencies, mass and table from one full solve at the optimum; None when there
    is nothing kept, or (with a note) when the entry is unreadable or that full objective does
    not reproduce the stored one.  The basis's error at the optimum is warned about again
    when it exceeds ``tol``, as in the run that stored it."""
    if arrays is None:
        return None
    t0 = time.perf_counter()
    kept = _kept_fields(arrays)
    if kept is None:
        return None
    theta, stored, basis_error, (starts, converged, failed, evaluations), ends = kept[:5]
    distinct, method, modes = kept[5:]
    with phase("calibration: kept optimum, full solve", 1, "solves"):
        evaluation = _evaluated(problem, theta, modes)
    objective = np.nan if evaluation is None or not evaluation.ok else (
        float(np.sum(problem.residual_vector(evaluation) ** 2)))  # fmt: skip
    if not abs(objective - stored) <= RECALL_AGREES * abs(stored):
        warnings.warn(
            f"kept calibration not reproduced by a full solve at its optimum (objective "
            f"{objective:.6g} against {stored:.6g}); calibrating again",
            RuntimeWarning,
            stacklevel=2,
        )
        return None
    if not basis_error <= tol:
        warnings.warn(
            f"reduced basis off by {basis_error:.2e} at the optimum (tol {tol:g}): the ends "
            "were polished on it; rerun with --full for a polish on full solves",
            RuntimeWarning,
            stacklevel=2,
        )
    return CalibrationResult(
        names=problem.names,
        theta=theta,
        objective=objective,
        expr=float(problem.expr(evaluation.frequencies_hz)),
        mass_kg=evaluation.mass_kg,
        frequencies_hz=evaluation.frequencies_hz,
        table=problem.table(evaluation),
        starts=starts,
        converged_starts=converged,
        start_points=ends[0],
        end_points=ends[1],
        end_objectives=ends[2],
        distinct_optima=distinct,
        failed_evaluations=failed,
        evaluations=evaluations,
        method=method,
        wall_s=time.perf_counter() - t0,
    )


def _kept_fields(arrays: dict[str, np.ndarray]):
    """The fields of a kept calibration (``memo_arrays``): (theta (d,), objective, basis error,
    (starts, converged, failed, evaluations), (start points, end points, end objectives),
    distinct optima, method, the solve's modes); None, with a note, when unreadable."""
    try:
        starts, converged, failed, evaluations = map(int, arrays["counts"])
        return (
            np.asarray(arrays["theta"], dtype=float),
            float(arrays["objective"]),
            float(arrays["basis_error"]),
            (starts, converged, failed, evaluations),
            (arrays["start_points"], arrays["end_points"], arrays["end_objectives"]),
            tuple(int(i) for i in arrays["distinct_optima"]),
            str(arrays["method"]),
            int(arrays.get("solve_modes", 0)),
        )
    except (KeyError, ValueError, TypeError) as exc:
        warnings.warn(f"kept calibration unreadable ({exc}); calibrating again", RuntimeWarning,
                      stacklevel=3)  # fmt: skip
        return None


@dataclass(frozen=True, eq=False)
class SolvedPoint:
    """``fe`` (an ``FEModel``) whose prediction at ``parameters`` (all of them, SI) is the full
    solve ``solution`` made there (an ``FEResult``, its lowest modes); every other point and
    property is ``fe``'s own.  The model of the problem that evaluates an optimum solved
    already (``evaluated_in_full``)."""

    fe: object
    parameters: dict
    solution: object

    def __getattr__(self, name):
        if name in ("fe", "parameters", "solution"):  # not set yet (a copy, an unpickling)
            raise AttributeError(name)
        return getattr(self.fe, name)

    def predict(self, params=None, n_modes: int = 12):
        p = self.fe.full_parameters(params)
        s = self.solution
        if p != self.parameters or n_modes > s.frequencies_hz.size:
            return self.fe.predict(params, n_modes)
        shapes = s.sensor_shapes[:, :n_modes]
        return Prediction(s.frequencies_hz[:n_modes], shapes, s.sensor_labels, s.mass_kg)


def _evaluated(problem: CalibrationProblem, theta: np.ndarray, modes: int):
    """``problem``'s evaluation at ``theta`` (d,) from one full solve of ``modes`` modes (the
    pairing's when 0 or fewer), as the run that kept it made it, so that the same computation
    gives the same bits; None when theta does not fit the problem or that solve fails."""
    if theta.shape != (len(problem.names),):
        return None
    if modes <= problem.pairing.n_model:
        return problem.evaluate(theta)
    try:
        solution = problem.model.solve(problem.as_mapping(theta), modes)
    except (BayesUpdateError, np.linalg.LinAlgError):
        return None
    model = SolvedPoint(problem.model, solution.parameters, solution)
    return replace(problem, model=model).evaluate(theta)


def keep(
    store: ArrayStore, key: str, result: CalibrationResult, basis_error: float,
    solve_modes: int = 0,
) -> None:  # fmt: skip
    """``result`` with its basis error and the modes of the full solve that gave its numbers
    (``solve_modes``; 0: the pairing's) stored under ``key`` in ``store`` (a no-op when the
    store is disabled or the key empty; a folder that cannot be written gives one warning)."""
    if key and np.isfinite(result.objective):
        store.save(key, memo_arrays(result, basis_error, solve_modes))
