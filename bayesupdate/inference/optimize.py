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

from bayesupdate import interrupts
from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.pairing import ResidualTable
from bayesupdate.inference.parameter_space import (
    EvaluationCount,
    ParameterSpace,
    unit_box_residuals,
)
from bayesupdate.inference.problem import CalibrationProblem


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

    def to_json(self) -> dict:
        """The ``calibrate --json`` object (issue 4 item 10)."""
        return {
            "parameters": self.parameters,
            "objective": float(self.expr),
            "mass_kg": None if self.mass_kg is None else float(self.mass_kg),
            "frequencies_hz": [float(f) for f in self.frequencies_hz],
            "targets_hz": [float(f) for f in self.table.test_hz],
            "starts": int(self.starts),
            "converged_starts": int(self.converged_starts),
        }


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


def calibrate(
    problem: CalibrationProblem,
    starts: int = 16,
    seed: int = 0,
    method: str = "least_squares",
    design: str = "sobol",
    include_start: bool = True,
    objective_window: float = 0.5,
    max_nfev: int | None = None,
    polish: bool | None = None,
    refine: CalibrationProblem | None = None,
) -> CalibrationResult:
    """Point optimum of the fit objective over the parameter bounds.

    starts : number of space-filling starts (plus the reference start if ``include_start``).
    method : "least_squares" (multi-start TRF) or "global" (``differential_evolution`` seeded,
    polished by least squares; its starts are then the DE population's best plus the design).
    objective_window : end points with objective <= best * (1 + window) (and apart from each
    other by > 2 % of the bounds box) are ``distinct_optima``; walkers start around each.
    max_nfev : evaluation budget of each least-squares start (None: scipy's default).
    polish : Nelder-Mead polish of every end point (module docstring); None = on unless a budget
    ``max_nfev`` is given (a budgeted fit is a quick one).  Its budget is 400 d evaluations.
    refine : the exact problem when ``problem`` is a surrogate of it (same parameters, bounds,
    data and pairing): each end point within 5 % of the best is polished on it (Nelder-Mead,
    60 d evaluations), every end is re-evaluated on it, and the result (objectives, table) is that
    of ``refine``; ``evaluations`` counts both models' evaluations.
    Returns CalibrationResult.  Model failures are counted in ``failed_evaluations``.
    """
    if method not in ("least_squares", "global"):
        raise BayesUpdateError(f"optimizer.method: {method!r}; use 'least_squares' or 'global'")
    t0 = time.perf_counter()
    polish = max_nfev is None if polish is None else bool(polish)
    d = len(problem.parameters)
    box = unit_box(problem)
    counter = EvaluationCount()
    residuals = _residual_function(problem, counter)
    u_starts = space_filling_starts(starts, d, seed, design)
    if include_start:
        u_starts = np.vstack([box.u_from_theta(problem.start), u_starts])
    if method == "global":
        de = optimize.differential_evolution(
            lambda u: float(np.sum(residuals(u) ** 2)),
            bounds=[(0.0, 1.0)] * d,
            seed=np.random.default_rng(seed),
            polish=False,
            tol=1e-10,
        )
        u_starts = np.vstack([de.x, u_starts])
    ends, objectives = [], []
    for u0 in u_starts:
        interrupts.check()  # a stop request a compiled extension swallowed (bayesupdate.interrupts)
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
    if refine is not None:
        if refine.names != problem.names or not (
            np.array_equal(refine.lower, problem.lower)
            and np.array_equal(refine.upper, problem.upper)
        ):
            raise ValueError("calibrate: refine must have the parameters and bounds of problem")
        # one count over both models: a failure of either is reported
        problem = refine
        residuals = _residual_function(problem, counter)
        # ends more than 5 % above the best on the surrogate lie in other basins: re-evaluated
        # exactly, not polished (the surrogate's error is ~1e-4 in frequency)
        near_best = np.asarray(objectives) <= 1.05 * min(objectives)
        for k, end in enumerate(ends):
            value = float(np.sum(residuals(end) ** 2))
            if near_best[k]:
                end, value = _nelder_mead_polish(residuals, end, value, max_evaluations=60 * d)
            ends[k], objectives[k] = end, value
    ends = np.array(ends)
    objectives = np.array(objectives)
    order = np.argsort(objectives, kind="stable")
    # re-evaluate the best end point; a failure there (a one-off eigen-solve failure) falls back
    # to the next best end point instead of ending the run
    for best in map(int, order):
        theta = box.theta_from_u(ends[best])
        evaluation = problem.evaluate(theta)
        counter.evaluations += 1
        if evaluation.ok:
            break
        counter.failed += 1
    else:
        raise BayesUpdateError(f"calibration: the model failed at every start ({evaluation.error})")
    best_obj = objectives[best]
    tol = 0.01 * max(best_obj, 1e-12)
    converged = int(np.sum(objectives <= best_obj + tol))
    distinct: list[int] = []
    window = best_obj + objective_window * max(best_obj, 1e-12) + 1e-12
    for i in order:
        if objectives[i] > window:
            break
        if all(np.max(np.abs(ends[i] - ends[j])) > 0.02 for j in distinct):
            distinct.append(int(i))
    return CalibrationResult(
        names=problem.names,
        theta=theta,
        objective=float(np.sum(problem.residual_vector(evaluation) ** 2)),
        expr=float(problem.expr(evaluation.frequencies_hz)),
        mass_kg=evaluation.mass_kg,
        frequencies_hz=evaluation.frequencies_hz,
        table=problem.table(evaluation),
        starts=int(u_starts.shape[0]),
        converged_starts=converged,
        start_points=box.theta_from_u(u_starts),
        end_points=box.theta_from_u(ends),
        end_objectives=objectives,
        distinct_optima=tuple(distinct),
        failed_evaluations=counter.failed,
        evaluations=counter.evaluations,
        method=method,
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

    starts, seed, polish: as ``calibrate`` (polish=False: ~10x cheaper, each point may stay on
    a pairing kink a few % above its polished value).

    For each weight W the fit minimises Expr + W ((m - m_T)/m_T)^2.  Returns one dict per weight:
    {"mass_weight", "expr", "mass_kg", "mass_error_pct", "parameters", "swapped"}.
    """
    from dataclasses import replace

    from bayesupdate.inference.problem import ObjectiveSpec

    weights = np.geomspace(1e-3, 1e3, 13) if mass_weights is None else np.asarray(mass_weights)
    front = []
    for w in weights:
        spec = replace(
            problem.objective, mass_target_kg=float(mass_target_kg), mass_weight=float(w)
        )
        sub = replace(problem, objective=spec if w > 0 else ObjectiveSpec())
        result = calibrate(sub, starts=starts, seed=seed, polish=polish)
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
