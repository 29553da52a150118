"""The calibrate pipeline: a prepared study -> its multi-start point optimum (seed eq. 19).

Built-in FE models search on their certified reduced basis (``pipelines.surrogates``), and the
ends are checked on the exact model (``calibrate(..., refine=...)``).  Where a full solve is
cheap (beam models: milliseconds) the ends near the best are polished on full solves.  On a
large model (``fe.reduced.settings.LARGE_MODEL_DOFS`` DOFs or more: the shell exhaust's
28,386 DOFs cost ~1.5 s of CPU per solve) that polish, 60 d Nelder-Mead evaluations per end,
would be thousands of full solves; there the basis is instead made exact at the best end (its
full modes join the basis, ``ReducedFEModel.certify_at``, every checked point re-verified:
``basis_made_exact``), the ends are polished on that basis, and the optimum is evaluated by one
full solve, which gives the reported objective, frequencies and table, and the basis's error
there (a warning above its tolerance: ``evaluated_in_full``).  When the optimum is the best end
(to the polish's resolution, ``same_point``: the usual case, the ends of its basin differing in
the objective's ninth digit), the best end's full solve is that solve: the point solved is
reported, with the numbers of that solve (the basis's modes and its extra modes), and no second
solve of 28,386 DOFs is made.  A full solve that fails at the
best end or at the optimum gives a one-line warning naming the point.  The whole step
(``calibrate_on_exact_basis``) is pure functions and frozen records; its result is kept on disk
and recalled by the same command again (``pipelines.calibration_memo``).  This is the
trust-region idea of reduced-basis optimization: optimize on the surrogate, make it exact at the
iterate and check it there in full (Yue & Meerbergen, SIAM J. Optim. 23 (2013) 1344; Qian,
Grepl, Veroy & Willcox, SIAM J. Sci. Comput. 39 (2017) S434).
"""

import warnings
from dataclasses import dataclass, replace

import numpy as np

from bayesupdate.compute.cache import ArrayStore
from bayesupdate.compute.progress import phase
from bayesupdate.fe.reference_memo import large_fe_model
from bayesupdate.inference.optimize import (
    SURROGATE_POLISH,
    CalibrationResult,
    CalibrationSettings,
    calibrate,
)
from bayesupdate.inference.problem import CalibrationProblem
from bayesupdate.pipelines import calibration_memo as memo
from bayesupdate.pipelines.study import PreparedStudy
from bayesupdate.pipelines.surrogates import sampling_problem


def run_calibration(prepared: PreparedStudy, executor=None) -> CalibrationResult:
    """Multi-start optimum.  Built-in FE models search on their certified reduced basis and
    check the ends on the full model (module docstring), so the reported optimum is the full
    model's; ``sampler.reduced = false`` (``--full``) searches on full solves.  The reduced
    basis's full solves, the starts and the polishes run on ``executor``
    (``compute.executors``; None: here).  A large model's calibration is kept on disk and the
    same command again recalls it, checked by one full solve (``pipelines.calibration_memo``;
    off with the cache)."""
    opt = prepared.study.optimizer
    cfg = prepared.study.sampler
    problem = prepared.problem
    settings = CalibrationSettings(
        starts=opt.starts, seed=opt.seed, method=opt.method, design=opt.design, polish=opt.polish
    )
    kept = cfg.reduced and large_fe_model(problem.model)
    store = ArrayStore.from_environment() if kept else ArrayStore(None)
    key = memo.memo_key(problem, cfg.reduced_tol, settings) if store.enabled else ""
    recalled = memo.recalled(problem, store.load(key), cfg.reduced_tol) if key else None
    if recalled is not None:
        return recalled
    search, rom = sampling_problem(problem, None, cfg.reduced, cfg.reduced_tol, executor=executor)
    if rom is None:
        return calibrate(search, settings, executor=executor)
    if not large_model(rom):
        return calibrate(search, settings, refine=problem, executor=executor)
    run = calibrate_on_exact_basis(problem, search, rom, settings, executor)
    memo.keep(store, key, run.result, run.error_at_optimum, run.solve_modes)
    return run.result


def large_model(rom) -> bool:
    """Whether ``rom``'s FE model is large enough that a full solve takes seconds
    (``fe.reduced.settings.LARGE_MODEL_DOFS`` DOFs or more)."""
    from bayesupdate.fe.reduced.settings import LARGE_MODEL_DOFS

    return rom.fe.structure.n_dof >= LARGE_MODEL_DOFS


@dataclass(frozen=True)
class BasisMadeExact:
    """What making the basis exact at the best end gave (``basis_made_exact``).

    basis : the reduced model the ends are polished on (enriched at the best end, or the basis
    as built when the enlarged one misses its tolerance or size, or the full solve there fails).
    point : (d,) the best end (SI, in the problem's ``names`` order).  error : the relative
    frequency error of the basis as built at that point (NaN when its full solve failed).
    solution : the full solve there (``fe.model.FEResult``, the basis's modes and its
    ``extra_modes``), None when it failed; the optimum's numbers when the optimum is that point
    (``evaluated_in_full``).
    """

    basis: object
    point: np.ndarray
    error: float
    solution: object = None


@dataclass(frozen=True)
class ExactBasisCalibration:
    """A large model's calibration (``calibrate_on_exact_basis``): the result (the full model's
    numbers at the optimum), the basis the ends were polished on, that basis's relative
    frequency error at the optimum against the full solve there (NaN when that solve failed),
    and the modes that solve computed (the pairing's, or the best end's solve with the basis's
    ``extra_modes`` when the optimum is that point: ``evaluated_in_full``)."""

    result: CalibrationResult
    made_exact: BasisMadeExact
    error_at_optimum: float
    solve_modes: int = 0


def calibrate_on_exact_basis(
    problem: CalibrationProblem, search: CalibrationProblem, rom, settings, executor=None
) -> ExactBasisCalibration:
    """The multi-start optimum of ``search`` (``problem`` on the certified basis ``rom``;
    ``settings``: ``CalibrationSettings``), its ends polished on the basis made exact at the
    best end (``basis_made_exact``) and the optimum evaluated by one full solve
    (``evaluated_in_full``): the module docstring's refine step."""
    made: list[BasisMadeExact] = []  # the refine step's outcome; lives for this call only

    def refine(ends: np.ndarray, objectives: np.ndarray) -> CalibrationProblem:
        made.append(basis_made_exact(problem, rom, ends, objectives))
        return replace(problem, model=made[-1].basis)

    result = calibrate(search, settings, refine=refine, executor=executor)
    exact = made[-1]
    if exact.solution is not None and same_point(problem, result.theta, exact.point):
        # the optimum is the best end to the polish's resolution: report the point solved
        result = replace(result, theta=exact.point.copy())
    reused = exact.solution is not None and np.array_equal(result.theta, exact.point)
    modes = exact.solution.frequencies_hz.size if reused else problem.pairing.n_model
    result, error = evaluated_in_full(problem, exact.basis, result, (exact.point, exact.solution))
    return ExactBasisCalibration(result, exact, error, modes)


def same_point(problem: CalibrationProblem, theta: np.ndarray, other: np.ndarray) -> bool:
    """Whether ``theta`` and ``other`` (d,) (SI) lie within the polish's resolution of each
    other in the unit box of ``problem``'s bounds (``inference.optimize.SURROGATE_POLISH``'s
    xatol, 1e-5: ~1e-6 in a frequency, far inside a certified basis's 1e-4).  Ends of one
    basin polished on a basis made exact at one of them differ there by round-off in the
    objective's ninth digit, and which of them is the lowest is that round-off."""
    span = problem.upper - problem.lower
    return bool(np.max(np.abs((theta - other) / span)) <= SURROGATE_POLISH[0])


def basis_made_exact(
    problem: CalibrationProblem, rom, ends: np.ndarray, objectives: np.ndarray
) -> BasisMadeExact:
    """``rom`` made exact at the best of ``ends`` (n, d) (SI) by ``objectives`` (n,): its full
    modes join the basis and every point it was certified on is re-verified
    (``ReducedFEModel.certify_at``).  The basis as built when the enlarged one misses its
    tolerance or size, or when the full solve at that point fails (a one-line warning naming
    the point, either way)."""
    best = np.asarray(ends[int(np.argmin(objectives))], dtype=float)
    row, solution = solved_at(rom, *full_point(problem, rom, best))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        checked, error = _certified_at(rom, row, solution)
    where = _named(problem, best)
    if not np.isfinite(error):
        warnings.warn(
            f"full solve failed at the best end ({where}): the ends are polished on the basis "
            "as built",
            RuntimeWarning,
            stacklevel=2,
        )
        return BasisMadeExact(rom, best, float("nan"))
    if not checked.certified:
        for w in caught:
            warnings.warn(
                f"{w.message} at the best end ({where}); the ends are polished on the basis as "
                "built",
                RuntimeWarning,
                stacklevel=2,
            )
        return BasisMadeExact(rom, best, error, solution)
    return BasisMadeExact(checked, best, error, solution)


def solved_at(rom, point: np.ndarray, names: tuple[str, ...]):
    """((1, n_params) ``point`` (1, len(names)) with ``rom``'s defaults for its other
    parameters (SI), the full solve there with the modes ``certify_points`` needs to check and
    enrich the basis: an ``FEResult``, None when it fails or the point lies outside the basis's
    box, where ``certify_at`` checks nothing)."""
    from bayesupdate.errors import BayesUpdateError
    from bayesupdate.fe.reduced.certification import solve_count

    values = dict(rom.default_parameters())
    values.update(zip(names, map(float, point[0]), strict=True))
    row = np.array([[values[k] for k in rom.parameter_names]])
    if not (np.all(row >= rom.low) and np.all(row <= rom.high)) or not rom.certified:
        return row, None
    try:
        with phase("calibration: full solve at the best end", 1, "solves"):
            return row, rom.fe.solve(values, solve_count(rom))
    except (BayesUpdateError, np.linalg.LinAlgError):
        return row, None


def _certified_at(rom, row: np.ndarray, solution):
    """``rom.certify_at(row, enrich_above=0)`` (its full modes join the basis) on the full
    solve ``solution`` already made at ``row`` (1, n_params) (``solved_at``); NaN error and
    ``rom`` unchanged when that solve failed."""
    from bayesupdate.fe.reduced import certification

    if solution is None:
        return rom, float("nan")
    solved = (solution.frequencies_hz[None, :], solution.modes.shapes)
    checked, error = certification.certify_points(rom, row, True, 0.0, solved=solved)
    return replace(rom, certification=checked), error


def full_point(problem: CalibrationProblem, rom, theta: np.ndarray):
    """((1, k) point, its k names): ``theta`` (d,) with the problem's fixed values of ``rom``'s
    other parameters (the basis fills in defaults for names it is not given)."""
    fixed = tuple(k for k in problem.fixed if k in rom.parameter_names)
    row = np.concatenate([theta, [problem.fixed[k] for k in fixed]])
    return row[None, :], problem.names + fixed


def _named(problem: CalibrationProblem, theta: np.ndarray) -> str:
    """``theta`` (d,) as "name=value, ..." (SI) for a warning."""
    return ", ".join(f"{k}={v:.6g}" for k, v in zip(problem.names, theta, strict=True))


def evaluated_in_full(
    problem: CalibrationProblem, basis, result: CalibrationResult, solved=(None, None)
) -> tuple[CalibrationResult, float]:
    """(``result`` (found on ``basis``) with its objective, frequencies, mass and table from one
    full solve of ``problem`` at its optimum, the basis's relative frequency error there); a
    warning when that error exceeds the basis's tolerance.  When that full solve fails,
    (``result`` as found on the basis, NaN), with a one-line warning naming the point.
    solved : (theta (d,), ``FEResult`` there or None): a full solve already made (the best
    end's, ``basis_made_exact``); when the optimum is that point, bit for bit, its numbers are
    the optimum's (its lowest modes, to the Lanczos tolerance of a solve of those modes alone)
    and no second solve is made."""
    full_problem = _full_problem(problem, result.theta, *solved)
    if full_problem is problem:
        with phase("calibration: full solve at the optimum", 1, "solves"):
            evaluation = problem.evaluate(result.theta)
    else:  # the optimum is the point solved already: no solve, no phase
        evaluation = full_problem.evaluate(result.theta)
    if not evaluation.ok:
        warnings.warn(
            f"full solve failed at the optimum ({_named(problem, result.theta)}: "
            f"{evaluation.error}); the reported numbers are the reduced basis's",
            RuntimeWarning,
            stacklevel=2,
        )
        return result, float("nan")
    n_model = evaluation.all_frequencies_hz.size
    f_rom = basis.predict_frequencies_batch(*full_point(problem, basis, result.theta), n_model)[0]
    error = float(np.max(np.abs(f_rom / evaluation.all_frequencies_hz - 1.0)))
    if not error <= basis.tol:
        warnings.warn(
            f"reduced basis off by {error:.2e} at the optimum (tol {basis.tol:g}): the ends "
            "were polished on it; rerun with --full for a polish on full solves",
            RuntimeWarning,
            stacklevel=2,
        )
    full = replace(
        result,
        objective=float(np.sum(problem.residual_vector(evaluation) ** 2)),
        expr=float(problem.expr(evaluation.frequencies_hz)),
        mass_kg=evaluation.mass_kg,
        frequencies_hz=evaluation.frequencies_hz,
        table=problem.table(evaluation),
        evaluations=result.evaluations + 1,
    )
    return full, error


def _full_problem(problem: CalibrationProblem, theta: np.ndarray, point, solution):
    """``problem``, its model answering at ``theta`` (d,) from ``solution`` (the full solve at
    ``point`` (d,)) when the two points are the same bits (``SolvedPoint``)."""
    if solution is None or point is None or not np.array_equal(theta, point):
        return problem
    model = memo.SolvedPoint(problem.model, solution.parameters, solution)
    return replace(problem, model=model)
