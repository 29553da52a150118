"""Point optimum: bounded least squares on the weighted residuals, multi-start, optional global.

The fit objective is seed eq. 19, Expr = sum_i w_i ((f_si - f_Ti) / f_Ti)^2, plus the optional mass
and MAC terms of ``ObjectiveSpec``; it is minimised as a sum of squared residuals with
``scipy.optimize.least_squares`` (trust-region reflective, bounded) in normalised coordinates
u = (theta - low) / (high - low) in [0, 1]^d (``parameter_space``'s unit box, every axis linear),
so thicknesses (1e-3 m) and densities (1e4 kg/m^3) are equally scaled.  Starts come from a
scrambled Sobol design (seeded).  The seed reports that different starts reach the same optimum;
``converged_starts`` counts starts whose objective is within 1 % of the best.

With shape-tracked pairing the objective has kinks: where two modes veer (the exhaust's modes 6
and 7) the tracked assignment flips, and the optima lie on that flip.  A gradient method stops
wherever it first meets the kink (on the exhaust, 1 of 9 starts within 1 % of the best), so each
end point is polished by a bounded Nelder-Mead simplex (Lagarias et al., SIAM J. Optim. 9 (1998);
adaptive parameters of Gao & Han, Comput. Optim. Appl. 51 (2012)), which needs no gradient and
walks along the kink (8 of 9 starts within 1 %, ``studies/paper_optimum.py``).

A cheap surrogate (the certified reduced basis) may do the search, with the exact problem given as
``refine``: every end point is then polished again on the exact model.  An optimum on a kink is
where a surrogate's small shape error matters most: at the exhaust's surrogate optimum the full
model's tracked pairing of modes 6 and 7 flips (Expr 0.067 -> 0.078); 60 d exact Nelder-Mead
evaluations from each end bring it back to the surrogate's value within 1 %.
"""

import time
from dataclasses import dataclass

import numpy as np
from scipy import optimize, stats

from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.pairing import ResidualTable
from bayesupdate.inference.parameter_space import (
    EvaluationCount,
    ParameterSpace,
    unit_box_residuals,
)
from bayesupdate.inference.problem import CalibrationProblem
from bayesupdate.interrupts import StopRequest


@dataclass(frozen=True)
class CalibrationResult:
    """The point optimum and how the starts behaved.

    theta : (d,) best parameters (SI), in ``names`` order.  objective : fit objective at theta
    (eq. 19 plus extra terms).  expr : eq. 19 alone with the data's weights.  start_points,
    end_points : (n_starts, d); end_objectives : (n_starts,).  distinct_optima : indices of starts
    whose end points differ (> 2 % of the bounds box) and whose objectives are within
    ``objective_window`` of the best, best first; used to start walkers in every mode.
    """

    names: tuple[str, ...]
    theta: np.ndarray
    objective: float
    expr: float
    mass_kg: float | None
    frequencies_hz: np.ndarray
    table: ResidualTable
    starts: int
    converged_starts: int
    start_points: np.ndarray
    end_points: np.ndarray
    end_objectives: np.ndarray
    distinct_optima: tuple[int, ...]
    failed_evaluations: int
    evaluations: int
    method: str
    wall_s: float

    @property
    def parameters(self) -> dict[str, float]:
        return dict(zip(self.names, map(float, self.theta), strict=True))

    @property
    def swapped(self) -> bool:
        return self.table.swapped


@dataclass(frozen=True)
class CalibrationSettings:
    """How ``calibrate`` searches, validated once when made.

    starts : number of space-filling starts (plus the reference start if ``include_start``).
    seed : seeds the design (and differential evolution).  design : "sobol" or "lhs".
    method : "least_squares" (multi-start TRF) or "global" (``differential_evolution`` seeded,
    polished by least squares; its starts are then the DE population's best plus the design).
    objective_window : end points with objective <= best * (1 + window) (and apart from each
    other by > 2 % of the bounds box) are ``distinct_optima``; walkers start around each.
    max_nfev : evaluation budget of each least-squares start (None: scipy's default).
    polish : Nelder-Mead polish of every end point (module docstring); None = on unless a budget
    ``max_nfev`` is given (a budgeted fit is a quick one).  Its budget is 400 d evaluations.
    """

    starts: int = 16
    seed: int = 0
    method: str = "least_squares"
    design: str = "sobol"
    include_start: bool = True
    objective_window: float = 0.5
    max_nfev: int | None = None
    polish: bool | None = None

    def __post_init__(self) -> None:
        if self.method not in ("least_squares", "global"):
            raise BayesUpdateError(
                f"optimizer.method: {self.method!r}; use 'least_squares' or 'global'"
            )
        if self.starts < 1:
            raise BayesUpdateError(f"optimizer.starts: must be >= 1, got {self.starts}")
        if self.design not in ("sobol", "lhs"):
            raise BayesUpdateError(f"optimizer.design: {self.design!r}; use 'sobol' or 'lhs'")
        if not self.objective_window >= 0:
            raise BayesUpdateError(
                f"optimizer.objective_window: must be >= 0, got {self.objective_window}"
            )
        if self.max_nfev is not None and self.max_nfev < 1:
            raise BayesUpdateError(f"optimizer.max_nfev: must be >= 1, got {self.max_nfev}")

    @property
    def polish_ends(self) -> bool:
        """Whether every end point is polished (``polish``, or by default when unbudgeted)."""
        return self.max_nfev is None if self.polish is None else bool(self.polish)


def space_filling_starts(n_starts: int, n_dim: int, seed: int, design: str = "sobol") -> np.ndarray:
    """Seeded space-filling points in [0, 1]^d, (n_starts, n_dim) (scrambled Sobol or LHS)."""
    if n_starts < 1:
        raise BayesUpdateError(f"optimizer.starts: must be >= 1, got {n_starts}")
    if design == "sobol":
        sampler = stats.qmc.Sobol(d=n_dim, scramble=True, seed=np.random.default_rng(seed))
        # Sobol balance needs a power of two; draw the next one and keep the first n_starts
        m = int(np.ceil(np.log2(max(n_starts, 1))))
        return sampler.random_base2(m)[:n_starts]
    if design == "lhs":
        return stats.qmc.LatinHypercube(d=n_dim, seed=np.random.default_rng(seed)).random(n_starts)
    raise BayesUpdateError(f"optimizer.design: {design!r}; use 'sobol' or 'lhs'")


def unit_box(problem: CalibrationProblem) -> ParameterSpace:
    """The optimiser's coordinates: u linear in theta on every axis (module docstring)."""
    return ParameterSpace(problem.parameters).linear()


def _residual_function(problem: CalibrationProblem, count: EvaluationCount):
    """r(u): the weighted residuals of ``problem`` over its unit box (eq. 19 plus extra terms).
    They are relative errors (unit 1): a failed model gets a 1000 % error in each
    (``parameter_space.FAILED_RELATIVE_ERROR``), counted in ``count``."""
    n_res = problem.residual_vector(problem.evaluate(problem.start)).size

    def residuals_at(theta: np.ndarray) -> np.ndarray | None:
        evaluation = problem.evaluate(theta)
        return problem.residual_vector(evaluation) if evaluation.ok else None

    return unit_box_residuals(unit_box(problem), residuals_at, np.ones(n_res), count)


def _nelder_mead_polish(residuals, u0: np.ndarray, value0: float, max_evaluations: int):
    """Bounded adaptive Nelder-Mead on sum(residuals(u)^2) in [0, 1]^d from a least-squares end
    point u0 (d,) with objective value0; returns the better of the two (end, objective)."""
    fit = optimize.minimize(
        lambda u: float(np.sum(residuals(u) ** 2)),
        u0,
        method="Nelder-Mead",
        bounds=[(0.0, 1.0)] * u0.size,
        options={"xatol": 1e-7, "fatol": 1e-10, "maxfev": max_evaluations, "adaptive": True},
    )
    if np.isfinite(fit.fun) and fit.fun < value0:
        return np.clip(fit.x, 0.0, 1.0), float(fit.fun)
    return u0, value0


def _start_points(
    problem: CalibrationProblem, box: ParameterSpace, residuals, settings: CalibrationSettings
) -> np.ndarray:
    """Starts in the unit box ``box``, (n, d): the reference start (``include_start``), the
    seeded space-filling design and, for ``method="global"``, differential evolution's best
    first (it evaluates ``residuals``)."""
    d, seed = len(problem.parameters), settings.seed
    u_starts = space_filling_starts(settings.starts, d, seed, settings.design)
    if settings.include_start:
        u_starts = np.vstack([box.u_from_theta(problem.start), u_starts])
    if settings.method == "global":
        de = optimize.differential_evolution(
            lambda u: float(np.sum(residuals(u) ** 2)),
            bounds=[(0.0, 1.0)] * d,
            seed=np.random.default_rng(seed),
            polish=False,
            tol=1e-10,
        )
        u_starts = np.vstack([de.x, u_starts])
    return u_starts


def _local_fits(
    residuals, u_starts: np.ndarray, max_nfev: int | None, polish: bool, stop: StopRequest
) -> tuple[list, list]:
    """Bounded trust-region least squares from each start (n, d), each end Nelder-Mead polished
    (400 d evaluations) when ``polish``: (end points u (d,) each, objectives each)."""
    d = u_starts.shape[1]
    ends, objectives = [], []
    for u0 in u_starts:
        stop.check()  # a stop request a compiled extension swallowed (bayesupdate.interrupts)
        fit = optimize.least_squares(
            residuals,
            np.clip(u0, 0.0, 1.0),
            bounds=(np.zeros(d), np.ones(d)),
            method="trf",
            x_scale=1.0,
            xtol=1e-12,
            ftol=1e-12,
            gtol=1e-12,
            max_nfev=max_nfev,
        )
        end, value = np.clip(fit.x, 0.0, 1.0), float(np.sum(fit.fun**2))
        if polish:
            end, value = _nelder_mead_polish(residuals, end, value, max_evaluations=400 * d)
        ends.append(end)
        objectives.append(value)
    return ends, objectives


def _refined(
    refine: CalibrationProblem,
    problem: CalibrationProblem,
    counter: EvaluationCount,
    ends: list,
    objectives: list,
) -> None:
    """Re-evaluate every end point (u, (d,)) of a surrogate ``problem`` on the exact ``refine``
    and polish those within 5 % of the best there (60 d evaluations); ``ends`` and
    ``objectives`` are updated in place, ``counter`` counts both models."""
    if refine.names != problem.names or not (
        np.array_equal(refine.lower, problem.lower) and np.array_equal(refine.upper, problem.upper)
    ):
        raise ValueError("calibrate: refine must have the parameters and bounds of problem")
    d = len(problem.parameters)
    # one count over both models: a failure of either is reported
    residuals = _residual_function(refine, counter)
    # ends more than 5 % above the best on the surrogate lie in other basins: re-evaluated
    # exactly, not polished (the surrogate's error is ~1e-4 in frequency)
    near_best = np.asarray(objectives) <= 1.05 * min(objectives)
    for k, end in enumerate(ends):
        value = float(np.sum(residuals(end) ** 2))
        if near_best[k]:
            end, value = _nelder_mead_polish(residuals, end, value, max_evaluations=60 * d)
        ends[k], objectives[k] = end, value


def _best_evaluation(
    problem: CalibrationProblem,
    box: ParameterSpace,
    ends: np.ndarray,
    order: np.ndarray,
    counter: EvaluationCount,
):
    """(index, theta (d,), Evaluation) of the best end point (u in ``box``, (n, d)) whose model
    evaluates; a failure there (a one-off eigen-solve failure) falls back to the next best in
    ``order`` (indices of ``ends``, best first)."""
    for best in map(int, order):
        theta = box.theta_from_u(ends[best])
        evaluation = problem.evaluate(theta)
        counter.evaluations += 1
        if evaluation.ok:
            return best, theta, evaluation
        counter.failed += 1
    raise BayesUpdateError(f"calibration: the model failed at every start ({evaluation.error})")


def _distinct_optima(
    ends: np.ndarray, objectives: np.ndarray, order: np.ndarray, best_obj: float, window: float
) -> tuple[int, ...]:
    """Indices (best first) of end points u (n, d) with objective <= best * (1 + window), each
    more than 2 % of the unit box from every earlier one."""
    distinct: list[int] = []
    limit = best_obj + window * max(best_obj, 1e-12) + 1e-12
    for i in order:
        if objectives[i] > limit:
            break
        if all(np.max(np.abs(ends[i] - ends[j])) > 0.02 for j in distinct):
            distinct.append(int(i))
    return tuple(distinct)


def calibrate(
    problem: CalibrationProblem,
    settings: CalibrationSettings = CalibrationSettings(),
    refine: CalibrationProblem | None = None,
    stop: StopRequest | None = None,
) -> CalibrationResult:
    """Point optimum of the fit objective over the parameter bounds (module docstring).

    settings : CalibrationSettings (starts, seed, method, design, window, budget, polish).
    refine : the exact problem when ``problem`` is a surrogate of it (same parameters, bounds,
    data and pairing): each end point within 5 % of the best is polished on it (Nelder-Mead,
    60 d evaluations), every end is re-evaluated on it, and the result (objectives, table) is that
    of ``refine``; ``evaluations`` counts both models' evaluations.
    stop : the run's ``interrupts.StopRequest``, checked before each start (None: none).
    Returns CalibrationResult.  Model failures are counted in ``failed_evaluations``.
    """
    t0 = time.perf_counter()
    box = unit_box(problem)
    counter = EvaluationCount()
    residuals = _residual_function(problem, counter)
    u_starts = _start_points(problem, box, residuals, settings)
    ends, objectives = _local_fits(
        residuals, u_starts, settings.max_nfev, settings.polish_ends, stop or StopRequest()
    )
    if refine is not None:
        _refined(refine, problem, counter, ends, objectives)
        problem = refine
    ends = np.array(ends)
    objectives = np.array(objectives)
    order = np.argsort(objectives, kind="stable")
    best, theta, evaluation = _best_evaluation(problem, box, ends, order, counter)
    best_obj = objectives[best]
    tol = 0.01 * max(best_obj, 1e-12)
    window = settings.objective_window
    return CalibrationResult(
        names=problem.names,
        theta=theta,
        objective=float(np.sum(problem.residual_vector(evaluation) ** 2)),
        expr=float(problem.expr(evaluation.frequencies_hz)),
        mass_kg=evaluation.mass_kg,
        frequencies_hz=evaluation.frequencies_hz,
        table=problem.table(evaluation),
        starts=int(u_starts.shape[0]),
        converged_starts=int(np.sum(objectives <= best_obj + tol)),
        start_points=box.theta_from_u(u_starts),
        end_points=box.theta_from_u(ends),
        end_objectives=objectives,
        distinct_optima=_distinct_optima(ends, objectives, order, best_obj, window),
        failed_evaluations=counter.failed,
        evaluations=counter.evaluations,
        method=settings.method,
        wall_s=time.perf_counter() - t0,
    )


def pareto_front_mass(
    problem: CalibrationProblem,
    mass_target_kg: float,
    mass_weights: np.ndarray | None = None,
    starts: int = 8,
    seed: int = 0,
    polish: bool | None = None,
) -> list[dict]:
    """Front of eq. 19 against the mass error, by sweeping the weight of the mass term.

    starts, seed, polish: as ``CalibrationSettings`` (polish=False: ~10x cheaper, each point may
    stay on a pairing kink a few % above its polished value).

    For each weight W the fit minimises Expr + W ((m - m_T)/m_T)^2.  Returns one dict per weight:
    {"mass_weight", "expr", "mass_kg", "mass_error_pct", "parameters", "swapped"}.
    """
    from dataclasses import replace

    from bayesupdate.inference.problem import ObjectiveSpec

    weights = np.geomspace(1e-3, 1e3, 13) if mass_weights is None else np.asarray(mass_weights)
    settings = CalibrationSettings(starts=starts, seed=seed, polish=polish)
    front = []
    for w in weights:
        spec = replace(
            problem.objective, mass_target_kg=float(mass_target_kg), mass_weight=float(w)
        )
        sub = replace(problem, objective=spec if w > 0 else ObjectiveSpec())
        result = calibrate(sub, settings)
        mass = result.mass_kg
        front.append(
            {
                "mass_weight": float(w),
                "expr": result.expr,
                "mass_kg": mass,
                "mass_error_pct": None
                if mass is None
                else 100.0 * (mass - mass_target_kg) / mass_target_kg,
                "parameters": result.parameters,
                "swapped": result.swapped,
            }
        )
    return front
