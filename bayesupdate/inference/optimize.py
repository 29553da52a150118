"""Point optimum: bounded least squares on the weighted residuals, multi-start, optional global.

The fit objective is seed eq. 19, Expr = sum_i w_i ((f_si - f_Ti) / f_Ti)^2, plus the optional mass
and MAC terms of ``ObjectiveSpec``; it is minimized as a sum of squared residuals with
``scipy.optimize.least_squares`` (trust-region reflective, bounded) in normalized coordinates
u = (theta - low) / (high - low) in [0, 1]^d (``parameter_space``'s unit box, every axis linear),
so thicknesses (1e-3 m) and densities (1e4 kg/m^3) are equally scaled.  Starts come from a
scrambled Sobol design (seeded).  The seed reports that different starts reach the same optimum;
``converged_starts`` counts starts whose objective is within 1 % of the best.

With shape-tracked pairing the objective has kinks: where two modes veer (the exhaust's modes 6
and 7) the tracked assignment flips, and the optima lie on that flip.  A gradient method stops
wherever it first meets the kink (on the exhaust, 1 of 9 starts within 1 % of the best), so each
end point is polished by a bounded Nelder-Mead simplex (Lagarias et al., SIAM J. Optim. 9 (1998);
adaptive parameters of Gao & Han, Comput. Optim. Appl. 51 (2012)), which needs no gradient and
walks along the kink (8 of 9 starts within 1 %, ``studies/paper_optimum.py``).  Every end on a
kink is polished, not only those near the best: on the exhaust (seed 0) a least-squares end 16
times above the best polished to within 0.15 % of it, and the optimum was another start's end than
the best before the polish on every beam case measured, so no margin on a polish's gain can skip
an end.  An end at a smooth minimum (first-order optimality ~0, ``STATIONARY_GRADIENT``) is not
polished: there the simplex, started 5 % wide, spends ~300 evaluations to move the objective in
its ninth digit (14 of the shell exhaust's 17 ends), while an end on a kink shows a gradient of
7e3..2e5 (the forward difference straddles the flip).  The polishes of a model with batched shapes
run in lockstep, each round's points one batched solve (``inference.nelder_mead``: scipy's steps
bit for bit).  On a certified reduced basis the least squares take the analytic Jacobian of the
reduced pencil (``inference.reduced_jacobian``: one eigen-solve instead of d + 1), and the test
for a smooth end still uses a forward difference at the end (``_end_optimality``).

A cheap surrogate (the certified reduced basis) may do the search, with the exact problem given as
``refine``: every end point is then evaluated on the exact model, and polished there unless it is
at the best (within 1 %) and that value agrees with the surrogate's to 1 %.  There the least
squares and the polish stop at the surrogate's resolution (``SURROGATE_LEAST_SQUARES``,
``SURROGATE_POLISH``: ~1e-6 in a frequency, inside a certified basis's 1e-4), not at 1e-12.
An optimum on a kink is where a surrogate's small shape error matters most: at the exhaust's
surrogate optimum the full model's tracked pairing of modes 6 and 7 flips (Expr 0.067 -> 0.078);
60 d exact Nelder-Mead evaluations from each end bring it back to the surrogate's value within
1 %.  Where the two agree
(the mAEWing1 deck: 15 ends on one optimum) the polish would cost 60 d full solves per end for a
move of the size of the surrogate's error.

The starts are independent: each (least squares and polish), and each end's polish on
``refine``, is one task on an executor (``compute``: serial, local processes or Dask),
a pure function of the problem and its start, so the result is the same bits on any executor.
"""

import numbers
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import partial

import numpy as np

from bayesupdate.compute.executors import executor_or_serial
from bayesupdate.compute.progress import phase
from bayesupdate.compute.stop import StopRequest
from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.likelihood import mass_function
from bayesupdate.inference.nelder_mead import SimplexSettings, minimize_together
from bayesupdate.inference.pairing import ResidualTable, pair_batch
from bayesupdate.inference.parameter_space import (
    FAILED_RELATIVE_ERROR,
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
        if not (isinstance(self.seed, numbers.Integral) and self.seed >= 0):
            raise BayesUpdateError(f"optimizer.seed: must be an integer >= 0, got {self.seed}")
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
    # imported here, not at the top: scipy.stats costs over a second, and a study file's
    # [optimizer] table is checked (CalibrationSettings) by every command that reads one
    from scipy import stats

    if design == "sobol":
        sampler = stats.qmc.Sobol(d=n_dim, scramble=True, seed=np.random.default_rng(seed))
        # Sobol balance needs a power of two; draw the next one and keep the first n_starts
        m = int(np.ceil(np.log2(max(n_starts, 1))))
        return sampler.random_base2(m)[:n_starts]
    if design == "lhs":
        return stats.qmc.LatinHypercube(d=n_dim, seed=np.random.default_rng(seed)).random(n_starts)
    raise BayesUpdateError(f"optimizer.design: {design!r}; use 'sobol' or 'lhs'")


def unit_box(problem: CalibrationProblem) -> ParameterSpace:
    """The optimizer's coordinates: u linear in theta on every axis (module docstring)."""
    return ParameterSpace(problem.parameters).linear()


def _residual_count(problem: CalibrationProblem) -> int:
    """Size of the residual vector (eq. 19 terms plus extra terms) of ``problem``."""
    return problem.residual_vector(problem.evaluate(problem.start)).size


#: ``_residual_function``'s default: build the batched path itself
_BUILD = object()


def _residual_function(
    problem: CalibrationProblem, count: EvaluationCount, n_res: int, batch=_BUILD
):
    """r(u): the weighted residuals (n_res,) of ``problem`` over its unit box (eq. 19 plus extra
    terms).  They are relative errors (unit 1): a failed model gets a 1000 % error in each
    (``parameter_space.FAILED_RELATIVE_ERROR``), counted in ``count``.  A model with batched
    shapes is evaluated on its batched path (``_batch_residuals``, as a batch of one), so r and
    its Jacobian (``_forward_jacobian``) come from the same solver.  ``batch``: that path as
    ``_unit_box_batch`` gave it (None: there is none), when the caller already has it."""
    if batch is _BUILD:
        batch = _unit_box_batch(problem, count, n_res)
    if batch is not None:
        return lambda u: batch(np.asarray(u, dtype=float)[None, :])[0]

    def residuals_at(theta: np.ndarray) -> np.ndarray | None:
        evaluation = problem.evaluate(theta)
        return problem.residual_vector(evaluation) if evaluation.ok else None

    return unit_box_residuals(unit_box(problem), residuals_at, np.ones(n_res), count)


def _batch_residuals(problem: CalibrationProblem, mass_fit=None, last=None):
    """theta (B, d) -> the weighted residuals (B, n_res) of ``problem.residual_vector``, NaN rows
    where the model failed, from one batched solve (``predict_batch_with_shapes``) and the
    batched MAC pairing (``pairing.pair_batch``: the assignment ``pair_modes`` makes per point);
    None unless the model gives batched sensor shapes and the problem pairs by shape (then
    ``problem.evaluate`` point by point).  Batched reduced solves agree with one-point ones to
    1e-12..2e-11 relative; a point costs ~0.6 ms batched against ~1.9 ms alone (the exhaust's
    reduced model).  ``mass_fit``: the masses of points inside its box from this verified
    polynomial (``_exact_mass_fit``) instead of one model call each.  ``last``: the model's
    predictions through this ``reduced_jacobian.LastSolve`` (the same bits), which keeps a
    one-point solve for the Jacobian there (None: the model's own)."""
    model, pairing, spec = problem.model, problem.pairing, problem.objective
    labels = {label: i for i, label in enumerate(getattr(model, "sensor_labels", ()))}
    if (
        pairing.method not in ("tracked", "mac")
        or not hasattr(model, "predict_batch_with_shapes")
        or not pairing.dof_labels
        or not set(pairing.dof_labels) <= set(labels)
    ):
        return None
    with_mass = spec.mass_weight > 0 and spec.mass_target_kg is not None
    mass_of = mass_function(model) if with_mass else None
    if with_mass and mass_of is None:
        return None
    rows = np.array([labels[label] for label in pairing.dof_labels], dtype=int)
    reference = pairing.test_shapes if pairing.method == "mac" else pairing.reference_shapes
    fixed = tuple(k for k in problem.fixed if k in model.parameter_names)
    names, fixed_values = problem.names + fixed, [problem.fixed[k] for k in fixed]
    f_test, sqrt_w = problem.data.frequencies_hz, np.sqrt(problem.weights)
    solve = model.predict_batch_with_shapes if last is None else last.predict_batch_with_shapes

    def residuals(theta: np.ndarray) -> np.ndarray:
        full = np.hstack([theta, np.tile(fixed_values, (theta.shape[0], 1))])
        freqs, shapes = solve(full, names, pairing.n_model)
        window = None if pairing.window is None else (pairing.test_hz, freqs, pairing.window)
        index, mac = pair_batch(reference, shapes[:, rows, :], window)
        parts = [sqrt_w * (np.take_along_axis(freqs, index, axis=1) - f_test) / f_test]
        if with_mass:
            mass = _masses(mass_of, mass_fit, names, theta, full)
            target = spec.mass_target_kg
            parts.append((np.sqrt(spec.mass_weight) * (mass - target) / target)[:, None])
        if spec.mass_properties is not None:  # measured CG / inertia: as ``residual_vector``
            props = np.array([_properties_or_nan(problem, names, row) for row in full])
            parts.append(spec.mass_properties.residuals(props))
        if spec.mac_weight > 0:
            parts.append(np.sqrt(spec.mac_weight * np.clip(1.0 - mac, 0, 1)))
        return np.hstack(parts)

    return residuals


def _masses(mass_of, mass_fit, names, theta: np.ndarray, full: np.ndarray) -> np.ndarray:
    """(B,) masses [kg] at the points theta (B, d) (``full``: with the fixed values, in
    ``names`` order): from the verified polynomial ``mass_fit`` inside its box, else (or without
    one) the model's, NaN where it rejects the values."""
    if mass_fit is not None and np.all((theta >= mass_fit.low) & (theta <= mass_fit.high)):
        return mass_fit(theta)
    return np.array([_mass_or_nan(mass_of, names, row) for row in full])


def _exact_mass_fit(problem: CalibrationProblem, seed: int = 0):
    """The verified polynomial of the problem's total mass over its bounds
    (``inference.mass_fit``; fixed values held) when its mass term is on, the model has batched
    shapes and the fit reproduces the model to ``likelihood.EXACT_MASS_REL_TOL`` (1e-10) at its
    check points; else None.  Why: on the shell exhaust's basis a model mass is 0.74 ms of a
    batched point's ~2.7 ms (one Python call into the 28,386-DOF model's property arrays), the
    fit 442 of them once per calibration (``LogPosterior.use_fitted_mass`` takes the same fit
    for the same reason; the exhaust's matches to ~1e-12)."""
    from bayesupdate.inference.likelihood import EXACT_MASS_REL_TOL
    from bayesupdate.inference.mass_fit import fit_problem_masses

    spec, model = problem.objective, problem.model
    if not (spec.mass_weight > 0 and spec.mass_target_kg is not None):
        return None
    mass_of = mass_function(model)
    if mass_of is None or not hasattr(model, "predict_batch_with_shapes"):
        return None
    fixed = tuple(k for k in problem.fixed if k in model.parameter_names)
    values = [problem.fixed[k] for k in fixed]
    fit = fit_problem_masses(
        mass_of, problem.names + fixed, values, problem.lower, problem.upper, seed
    )
    return fit if fit is not None and fit.max_rel_error <= EXACT_MASS_REL_TOL else None


def _properties_or_nan(problem: CalibrationProblem, names, row: np.ndarray) -> np.ndarray:
    """(k,) the measured CG / inertia components' model values at one point, NaN where the
    model rejects the values."""
    try:
        return problem.mass_property_values(dict(zip(names, map(float, row), strict=True)))
    except BayesUpdateError:
        return np.full(len(problem.objective.mass_properties.names), np.nan)


def _mass_or_nan(mass_of, names: tuple[str, ...], row: np.ndarray) -> float:
    """The model's mass [kg] at one point, NaN where it rejects the values."""
    try:
        return float(mass_of(dict(zip(names, map(float, row), strict=True))))
    except BayesUpdateError:
        return np.nan


def _unit_box_batch(
    problem: CalibrationProblem, count: EvaluationCount, n_res: int, mass_fit=None, last=None
):
    """u (B, d) in the unit box -> residuals (B, n_res) on the batched path (``_batch_residuals``;
    None without one), each failed point given ``unit_box_residuals``' failure value and counted
    in ``count`` (``mass_fit``, ``last``: as ``_batch_residuals``)."""
    batch = _batch_residuals(problem, mass_fit, last)
    if batch is None:
        return None
    box = unit_box(problem)
    failed = np.full(n_res, FAILED_RELATIVE_ERROR)

    def residuals(u: np.ndarray) -> np.ndarray:
        try:
            r = batch(box.theta_from_u(u))
        except Exception:  # a user's model may fail anywhere: every point of the batch fails
            r = np.full((u.shape[0], n_res), np.nan)
        bad = ~np.all(np.isfinite(r), axis=1)
        count.evaluations += u.shape[0]
        count.failed += int(bad.sum())
        r[bad] = failed
        return r

    return residuals


def _analytic_jacobian(
    problem: CalibrationProblem, count: EvaluationCount, mass_fit=None, last=None
):
    """u (d,) -> the Jacobian (n_res, d) of the batched residuals (``_batch_residuals``) in the
    unit box from the reduced basis's design derivatives (``inference.reduced_jacobian``: one
    eigen-solve), None at a point the basis does not cover; or None when ``problem`` has no
    such path.  The mass row: a forward difference of the masses with ``_forward_jacobian``'s
    steps.  ``last``: the ``reduced_jacobian.LastSolve`` of the residuals, whose eigen-solve at
    the same point is used instead of solving again (None: always solved here)."""
    from bayesupdate.inference.reduced_jacobian import (
        contraction_paths,
        eigen_derivatives,
        reduced_basis_of,
    )

    found = reduced_basis_of(problem)
    if found is None or _batch_residuals(problem) is None:
        return None
    model, basis = found
    pairing, spec = problem.pairing, problem.objective
    labels = {label: i for i, label in enumerate(model.sensor_labels)}
    rows = np.array([labels[label] for label in pairing.dof_labels], dtype=int)
    reference = pairing.test_shapes if pairing.method == "mac" else pairing.reference_shapes
    fixed = tuple(k for k in problem.fixed if k in model.parameter_names)
    names, fixed_values = problem.names + fixed, [problem.fixed[k] for k in fixed]
    columns = [model.parameter_names.index(n) for n in problem.names]
    weight = np.sqrt(problem.weights) / problem.data.frequencies_hz
    with_mass = spec.mass_weight > 0 and spec.mass_target_kg is not None
    mass_of = mass_function(model) if with_mass else None
    box, span = unit_box(problem), problem.upper - problem.lower
    paths = contraction_paths(basis, pairing.n_model, len(columns))

    def at(u: np.ndarray) -> np.ndarray:
        return np.hstack([box.theta_from_u(u), np.tile(fixed_values, (u.shape[0], 1))])

    def jacobian(u0: np.ndarray) -> np.ndarray | None:
        full = model._theta_full(at(u0[None, :]), names)
        if not (np.all(np.isfinite(full)) and model._inside(full)[0]):
            return None
        solved = None if last is None else last.solved(full, pairing.n_model)
        lam, y, dlam = eigen_derivatives(basis, full, columns, pairing.n_model, solved, paths)
        count.evaluations += 1
        f = np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)
        window = None if pairing.window is None else (pairing.test_hz, f[None, :], pairing.window)
        index = pair_batch(reference, (basis.V_sensor @ y)[None, rows, :], window)[0][0]
        df = dlam / (8 * np.pi**2 * f[:, None])  # d f / d theta [Hz per SI unit]
        parts = [weight[:, None] * df[index] * span[None, :]]
        if with_mass:
            h = np.full(u0.size, np.sqrt(np.finfo(float).eps))
            h = np.where(u0 + h > 1.0, -h, h)
            u = np.vstack([u0, u0 + np.diag(h)])
            m = _masses(mass_of, mass_fit, names, box.theta_from_u(u), at(u))
            scale = np.sqrt(spec.mass_weight) / spec.mass_target_kg
            parts.append(scale * ((m[1:] - m[0]) / ((u0 + h) - u0))[None, :])
        out = np.vstack(parts)
        return out if np.all(np.isfinite(out)) else None

    return jacobian


def _jacobian(problem: CalibrationProblem, count: EvaluationCount, batch, mass_fit=None, last=None):
    """scipy's ``jac`` for the least squares: the analytic Jacobian on a reduced basis
    (``_analytic_jacobian``, with ``last``), a batched forward difference where it has none
    (``batch``), or scipy's "2-point" without a batched path."""
    if batch is None:
        return "2-point"
    analytic = _analytic_jacobian(problem, count, mass_fit, last)
    if analytic is None:
        return partial(_forward_jacobian, batch)

    def jacobian(u0: np.ndarray) -> np.ndarray:
        out = analytic(u0)
        return _forward_jacobian(batch, u0) if out is None else out

    return jacobian


def _forward_jacobian(batch, u0: np.ndarray) -> np.ndarray:
    """Forward-difference Jacobian (n_res, d) of the residuals at u0 (d,) in [0, 1]^d, its d + 1
    points as one batch (``batch``: u (B, d) -> (B, n_res)).  The steps are scipy's "2-point"
    ones in the unit box (``_numdiff``: h = sqrt(eps) max(1, |u|) = sqrt(eps), turned back where
    u0 + h leaves the box), and r(u0) comes from the same batch, so a difference never mixes two
    solvers' rounding (batched and one-point solves differ by up to 2e-11, against h ~ 1.5e-8)."""
    h = np.full(u0.size, np.sqrt(np.finfo(float).eps))
    h = np.where(u0 + h > 1.0, -h, h)
    r = batch(np.vstack([u0, u0 + np.diag(h)]))
    step = (u0 + h) - u0
    return ((r[1:] - r[0]) / step[:, None]).T


def _nelder_mead_polish(residuals, u0: np.ndarray, value0: float, settings: SimplexSettings):
    """Bounded adaptive Nelder-Mead on sum(residuals(u)^2) in [0, 1]^d from a least-squares end
    point u0 (d,) with objective value0 (``nelder_mead``: scipy's algorithm, its stopping rules
    ``settings``); returns the better of the two (end, objective)."""
    ends, values, _ = minimize_together(
        lambda u: np.array([np.sum(residuals(row) ** 2) for row in u]), u0[None, :], settings
    )
    return _better(ends[0], float(values[0]), u0, value0)


def _better(end: np.ndarray, value: float, u0: np.ndarray, value0: float):
    """(end, value) of a polish when it improved on (u0, value0), else (u0, value0)."""
    if np.isfinite(value) and value < value0:
        return np.clip(end, 0.0, 1.0), value
    return u0, value0


def _polish_together(
    job: "_Fits", ends: list, values: list, which: list, counter: EvaluationCount
) -> tuple[list, list]:
    """The least-squares ends (u (d,) each, objectives each) at the indices ``which``
    Nelder-Mead polished (``job.simplex``), the polishes in lockstep and each round's points one
    batched solve (``nelder_mead.minimize_together``: the same steps as one polish at a time, at
    about half the cost per point on the shell exhaust's basis); (ends, objectives), each the
    better of the end and its polish."""
    ends, values = list(ends), list(values)
    if not which:
        return ends, values
    count = EvaluationCount()
    batch = _unit_box_batch(job.problem, count, job.n_res, job.mass_fit)

    def objective(u: np.ndarray) -> np.ndarray:
        job.stop.check()
        return np.sum(batch(u) ** 2, axis=1)

    with phase("calibration: polish of the ends", len(which), "ends") as running:
        polished, best, _ = minimize_together(
            objective,
            np.array([ends[i] for i in which]),
            job.simplex(len(ends[0])),
            lambda _i: running.advance(),
        )
    counter.evaluations += count.evaluations
    counter.failed += count.failed
    for i, end, value in zip(which, polished, best, strict=True):
        ends[i], values[i] = _better(end, float(value), ends[i], values[i])
    return ends, values


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
        from scipy import optimize  # here, not at the top: see space_filling_starts

        de = optimize.differential_evolution(
            lambda u: float(np.sum(residuals(u) ** 2)),
            bounds=[(0.0, 1.0)] * d,
            seed=np.random.default_rng(seed),
            polish=False,
            tol=1e-10,
        )
        u_starts = np.vstack([de.x, u_starts])
    return u_starts


@dataclass(frozen=True)
class _Fits:
    """The shared payload of the start tasks (sent to each worker once): the problem, its
    residual count, the least-squares budget (``max_nfev``; ``least_squares=False``: none, the
    ends are only re-evaluated), the Nelder-Mead budget per parameter (0: no polish), the
    run's stop request (only the serial executor shares the object itself), the polish's
    (xatol, fatol), the verified mass polynomial of the batched residuals (``_exact_mass_fit``;
    None: the model's masses) and the least squares' (xtol, ftol) (``SURROGATE_LEAST_SQUARES``
    on a surrogate whose ends are checked on the exact model)."""

    problem: CalibrationProblem
    n_res: int
    max_nfev: int | None
    polish_per_dim: int
    least_squares: bool = True
    stop: StopRequest = field(default_factory=StopRequest)
    tolerance: tuple[float, float] = (1e-7, 1e-10)
    mass_fit: object = None
    least_squares_tolerance: tuple[float, float] = (1e-12, 1e-12)

    def simplex(self, d: int) -> SimplexSettings:
        """The polish's stopping rules in d dimensions: ``tolerance`` (xatol, fatol) and the
        budget ``polish_per_dim`` d."""
        return SimplexSettings(*self.tolerance, max_evaluations=self.polish_per_dim * d)


def _fit_start(job: _Fits, item: tuple[np.ndarray, bool]) -> tuple:
    """One start (an executor task; item: start u (d,), whether to polish): bounded
    trust-region least squares, then the bounded Nelder-Mead polish unless the least-squares end
    is a smooth minimum (``_stationary``); (end u (d,), objective, evaluations, failures,
    whether the end is a smooth minimum).  A pure function of ``job`` and ``item``: the same bits
    wherever it runs."""
    u0, polish = item
    job.stop.check()  # a stop request a compiled extension swallowed (bayesupdate.compute.stop)
    count = EvaluationCount()
    last = _last_solve(job.problem) if job.least_squares else None
    batch = _unit_box_batch(job.problem, count, job.n_res, job.mass_fit, last)
    residuals = _residual_function(job.problem, count, job.n_res, batch)
    d = u0.size
    if job.least_squares:
        from scipy import optimize  # here, not at the top: see space_filling_starts

        fit = optimize.least_squares(
            residuals,
            np.clip(u0, 0.0, 1.0),
            jac=_jacobian(job.problem, count, batch, job.mass_fit, last),
            bounds=(np.zeros(d), np.ones(d)),
            method="trf",
            x_scale=1.0,
            xtol=job.least_squares_tolerance[0],
            ftol=job.least_squares_tolerance[1],
            gtol=1e-12,
            max_nfev=job.max_nfev,
        )
        end, value = np.clip(fit.x, 0.0, 1.0), float(np.sum(fit.fun**2))
        stationary = _stationary(fit, _end_optimality(fit, batch))
    else:
        end, value = u0, float(np.sum(residuals(u0) ** 2))
        stationary = False
    if polish and job.polish_per_dim and not stationary:
        end, value = _nelder_mead_polish(residuals, end, value, job.simplex(d))
    return end, value, count.evaluations, count.failed, stationary


def _last_solve(problem: CalibrationProblem):
    """A ``reduced_jacobian.LastSolve`` of ``problem``'s model when the least squares take the
    analytic Jacobian on its reduced basis (``reduced_basis_of``), else None."""
    from bayesupdate.inference.reduced_jacobian import LastSolve, reduced_basis_of

    found = reduced_basis_of(problem)
    return None if found is None else LastSolve(*found)


#: first-order optimality (scipy's ``least_squares`` ``optimality``: the uniform norm of the
#: gradient J^T r of 0.5 |r|^2 in the unit box, scaled to zero at an active bound) below which a
#: least-squares end is a smooth minimum and is not polished.  At the shell exhaust's 17 ends
#: (seed 1) the smooth minima had 2e-6..9e-6 and their polish lowered the objective by <= 9e-9
#: (relative); the three ends on a pairing kink had 7e3..1.2e4 (the forward difference straddles
#: the flip of the assignment).  The beam exhaust (tracked pairing, mass kept, seed 0, full
#: solves, first 5 starts): 4 ends on the mode 6/7 kink at 1.6e5..2.6e5, polished 4.9..5.8 %
#: lower; one smooth end at 2.8e-4, whose polish gained 1e-6 (relative).  The threshold sits
#: 36 times above the largest smooth value seen and 7e5 times below the smallest kink value
STATIONARY_GRADIENT = 1e-2


def _stationary(fit, optimality: float | None = None) -> bool:
    """Whether a least-squares result ``fit`` ended at a smooth minimum (first-order optimality
    ``optimality``, default scipy's, <= ``STATIONARY_GRADIENT``) rather than on a kink of the
    tracked pairing, where the polish is needed (module docstring)."""
    value = fit.optimality if optimality is None else optimality
    return bool(fit.status > 0 and value <= STATIONARY_GRADIENT)


def _end_optimality(fit, batch) -> float | None:
    """scipy's first-order optimality at the end of ``fit`` (|v g|_inf, g = J^T r, v the
    Coleman-Li scaling of the unit box: the distance to the bound g points to) from the batched
    forward difference (``_forward_jacobian``), None without a batched path (scipy's own is then
    a forward difference already).  Why a difference: the analytic Jacobian holds the pairing
    at the point, so at an end on a kink it gives one branch's gradient, which can be small; the
    difference straddles the flip there (the evidence of ``STATIONARY_GRADIENT``).  On the
    beam exhaust's basis, ends on the mode 6/7 kink passed the analytic gradient's test and were
    left 5 % above the best (``tests/test_calibration_exhaust.py``)."""
    if batch is None:
        return None
    u = np.clip(fit.x, 0.0, 1.0)
    g = _forward_jacobian(batch, u).T @ fit.fun
    v = np.where(g < 0, 1.0 - u, np.where(g > 0, u, 1.0))
    return float(np.max(np.abs(g * v)))


def _run_fits(
    job: _Fits, items: list, counter: EvaluationCount, executor, what: str = "calibration: starts"
) -> tuple[list, list]:
    """``_fit_start`` of every item on ``executor`` (results in item order), shown as the
    progress phase ``what``: (ends, objectives, whether each is a smooth minimum); the tasks'
    evaluations and failures are added to ``counter``."""
    stop = job.stop
    if getattr(executor, "kind", "serial") != "serial":
        job = replace(job, stop=StopRequest())  # a signal reaches this process, not the workers
    with phase(what, len(items), "fits") as running:
        out = executor_or_serial(executor).map(_fit_start, items, job, running.progress_callback())
    stop.check()
    counter.evaluations += sum(o[2] for o in out)
    counter.failed += sum(o[3] for o in out)
    return [o[0] for o in out], [o[1] for o in out], [o[4] for o in out]


def _local_fits(
    job: _Fits, u_starts: np.ndarray, counter: EvaluationCount, executor=None
) -> tuple[list, list]:
    """Bounded trust-region least squares from each start (n, d), each end Nelder-Mead polished
    (``job.polish_per_dim`` d evaluations); one task per start on ``executor``
    (``compute.executors``; None: here): (end points u (d,) each, objectives each).  Ends at a
    smooth minimum are not polished (``_stationary``).  On a model with batched shapes the
    polishes run after the least squares, together in this process (``_polish_together``)."""
    if not job.polish_per_dim or _batch_residuals(job.problem) is None:
        return _run_fits(job, [(u0, True) for u0 in u_starts], counter, executor)[:2]
    ends, values, smooth = _run_fits(job, [(u0, False) for u0 in u_starts], counter, executor)
    which = [i for i, done in enumerate(smooth) if not done]
    return _polish_together(job, ends, values, which, counter)


def _refined(
    refine: CalibrationProblem,
    problem: CalibrationProblem,
    counter: EvaluationCount,
    ends: list,
    objectives: list,
    executor=None,
) -> tuple[list, list]:
    """Re-evaluate every end point (u, (d,)) of a surrogate ``problem`` on the exact ``refine``
    and polish those within 5 % of the best there (60 d evaluations), except those within
    ``SURROGATE_AGREES`` of the best whose exact objective agrees with the surrogate's to
    ``SURROGATE_AGREES``; one task per end on
    ``executor``: (ends, objectives) on ``refine``; ``counter`` counts both models."""
    if refine.names != problem.names or not (
        np.array_equal(refine.lower, problem.lower) and np.array_equal(refine.upper, problem.upper)
    ):
        raise ValueError("calibrate: refine must have the parameters and bounds of problem")
    job = _Fits(refine, _residual_count(refine), None, 60, least_squares=False)
    # starts that end at one point (a corner of the box, one basin) are checked once: the
    # check is deterministic, and each costs up to 60 d full solves
    first, owner = _coinciding([(end, True) for end in ends])
    exact = _run_fits(job, [(ends[i], False) for i in first], counter, executor,
                      "calibration: exact values of the ends")[1]  # fmt: skip
    # ends more than 5 % above the best on the surrogate lie in other basins: not polished
    # (the surrogate's error is ~1e-4 in frequency); nor are ends at the best (within 1 %)
    # where the exact objective agrees with the surrogate's: their polish moves them by that
    # error only
    best = min(objectives)
    polish = []
    for k, i in enumerate(first):
        agrees = exact[k] <= (1 + SURROGATE_AGREES) * objectives[i] + 1e-15
        at_best = objectives[i] <= (1 + SURROGATE_AGREES) * best + 1e-15
        if objectives[i] <= 1.05 * best and not (agrees and at_best):
            polish.append(k)
    unique_ends, unique_objectives = [ends[i] for i in first], list(exact)
    if polish:
        done = _run_fits(job, [(ends[first[k]], True) for k in polish], counter, executor,
                         "calibration: exact check of the ends")[:2]  # fmt: skip
        for k, end, value in zip(polish, *done, strict=True):
            unique_ends[k], unique_objectives[k] = end, value
    return [unique_ends[k] for k in owner], [unique_objectives[k] for k in owner]


#: (xatol, fatol) of the polish on a surrogate whose ends are checked on the exact model: a move
#: of 1e-5 in the unit box changes a frequency by ~1e-6 (relative), far inside a certified
#: basis's 1e-4.  At the shell exhaust's ends it took 169-558 evaluations against 314-2,000 at
#: (1e-7, 1e-10), for objectives within 2e-5 of those (relative).  No test on the values
#: (fatol = inf): on a smooth stretch a simplex 1e-5 wide spans values far below the
#: surrogate's error anyway, and where its best vertex sits on a flip of the tracked pairing
#: (a jump in the objective) the spread never falls below the jump until the simplex has
#: collapsed onto that vertex in floating point: one shell exhaust end (seed 51) spent 162 of
#: its 438 evaluations there after the simplex was 1e-5 wide; at the three others the values
#: met 1e-8 before the points met 1e-5, so they end where they did (``docs/guide/
#: exhaust-shell.md``)
SURROGATE_POLISH = (1e-5, float("inf"))

#: (xtol, ftol) of the least squares on a surrogate whose ends are checked on the exact model
#: (scipy's step and cost-reduction tests; gtol stays 1e-12).  At (1e-12, 1e-12) the shell
#: exhaust's starts (seed 51) came within 1e-5 of their ends after 16-26 evaluations and spent
#: 26-71 there, creeping along the flat direction of ``rho_intermediate_muffler``; at these the
#: 13 smooth ends lie within 3.3e-6 of those (unit box; the polish's xatol is 1e-5), objectives
#: within 8e-11 (relative), the 4 ends on a kink (polished next) within 1.2e-8 and 4e-8, the
#: same ends smooth, in 939 evaluations against 1,204 (``docs/guide/exhaust-shell.md``)
SURROGATE_LEAST_SQUARES = (1e-8, 1e-10)

#: relative excess of an end's exact objective over the surrogate's below which the end is
#: not polished on the exact model: the tolerance of ``converged_starts`` (1 %).  The kink
#: the polish is for (module docstring) costs the exhaust's surrogate optimum +16 %
SURROGATE_AGREES = 0.01


def _coinciding(items: list, tol: float = 1e-9) -> tuple[list, list]:
    """Items (u (d,), polish) grouped where their polish flags agree and their u lie within
    ``tol`` of each other in the unit box: (first, the index of each group's first item;
    owner, per item the position of its group in ``first``)."""
    first: list[int] = []
    owner: list[int] = []
    for i, (u, polish) in enumerate(items):
        match = next(
            (k for k, j in enumerate(first)
             if items[j][1] == polish and np.max(np.abs(np.asarray(u) - items[j][0])) <= tol),
            None,
        )  # fmt: skip
        if match is None:
            first.append(i)
            match = len(first) - 1
        owner.append(match)
    return first, owner


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


def _with_refine(refine, problem, box, counter, ends, objectives, executor):
    """(the exact problem, its ends, their objectives) after ``_refined``; ``refine`` as in
    ``calibrate`` (a function of the ends is called once here)."""
    if callable(refine):
        refine = refine(box.theta_from_u(np.array(ends)), np.array(objectives))
    ends, objectives = _refined(refine, problem, counter, ends, objectives, executor)
    return refine, ends, objectives


def _fits_job(
    problem: CalibrationProblem, n_res: int, settings: CalibrationSettings, stop, surrogate: bool
) -> "_Fits":
    """The starts' task record: ``settings``' budget, a Nelder-Mead polish of 400 evaluations
    per parameter when ``settings.polish_ends``, and on a ``surrogate`` whose ends are checked
    on the exact model the tolerances of its resolution (``SURROGATE_POLISH``,
    ``SURROGATE_LEAST_SQUARES``)."""
    polish = 400 if settings.polish_ends else 0
    job = _Fits(problem, n_res, settings.max_nfev, polish, stop=stop or StopRequest(),
                mass_fit=_exact_mass_fit(problem))  # fmt: skip
    if surrogate:
        job = replace(job, tolerance=SURROGATE_POLISH,
                      least_squares_tolerance=SURROGATE_LEAST_SQUARES)  # fmt: skip
    return job


def calibrate(
    problem: CalibrationProblem,
    settings: CalibrationSettings = CalibrationSettings(),
    refine: CalibrationProblem | Callable[..., CalibrationProblem] | None = None,
    stop: StopRequest | None = None,
    executor=None,
) -> CalibrationResult:
    """Point optimum of the fit objective over the parameter bounds (module docstring).

    settings : CalibrationSettings (starts, seed, method, design, window, budget, polish).
    refine : the exact problem when ``problem`` is a surrogate of it (same parameters, bounds,
    data and pairing): every end is re-evaluated on it, those within 5 % of the best are
    polished on it (Nelder-Mead, 60 d evaluations) unless within 1 % of the best with an exact
    objective that agrees with the surrogate's to 1 %, and the result (objectives, table) is
    that of ``refine``; ``evaluations`` counts both models' evaluations.  Or a function
    (ends theta (n, d) SI, their objectives (n,)) -> that problem, called once when the starts
    have ended (a surrogate made exact where they ended: ``pipelines.calibrate``).
    stop : the run's ``compute.stop.StopRequest``, checked before each start (None: none).
    executor : where the starts (and the refine polishes) run, one task each
    (``compute.executors``; None: in this process); the result is the same bits on any.
    Returns CalibrationResult.  Model failures are counted in ``failed_evaluations``.
    """
    t0 = time.perf_counter()
    box = unit_box(problem)
    counter = EvaluationCount()
    n_res = _residual_count(problem)
    u_starts = _start_points(problem, box, _residual_function(problem, counter, n_res), settings)
    job = _fits_job(problem, n_res, settings, stop, surrogate=refine is not None)
    ends, objectives = _local_fits(job, u_starts, counter, executor)
    if refine is not None:
        problem, ends, objectives = _with_refine(refine, problem, box, counter, ends, objectives,
                                                 executor)  # fmt: skip
    ends, objectives = np.array(ends), np.array(objectives)
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

    For each weight W the fit minimizes Expr + W ((m - m_T)/m_T)^2.  Returns one dict per weight:
    {"mass_weight", "expr", "mass_kg", "mass_error_pct", "parameters", "swapped"}.
    """
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
