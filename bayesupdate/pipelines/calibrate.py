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
there (a warning above its tolerance: ``evaluated_in_full``).  A full solve that fails at the
best end or at the optimum gives a one-line warning naming the point.  The whole step
(``calibrate_on_exact_basis``) is pure functions and frozen records; its result is kept on disk
and recalled by the same command again (``pipelines.calibration_memo``).  This is the
trust-region idea of reduced-basis optimisation: optimise on the surrogate, make it exact at the
iterate and check it there in full (Yue & Meerbergen, SIAM J. Optim. 23 (2013) 1344; Qian,
Grepl, Veroy & Willcox, SIAM J. Sci. Comput. 39 (2017) S434).
"""

import warnings
from dataclasses import dataclass, replace

import numpy as np

from bayesupdate.compute.cache import ArrayStore
from bayesupdate.inference.optimize import CalibrationResult, CalibrationSettings, calibrate
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
    memo.keep(store, key, run.result, run.error_at_optimum)
    return run.result


def large_fe_model(model) -> bool:
    """Whether ``model`` is an ``FEModel`` of ``fe.reduced.settings.LARGE_MODEL_DOFS`` DOFs or
    more (its calibration is kept on disk: ``pipelines.calibration_memo``)."""
    from bayesupdate.fe.model import FEModel
    from bayesupdate.fe.reduced.settings import LARGE_MODEL_DOFS

    return isinstance(model, FEModel) and model.structure.n_dof >= LARGE_MODEL_DOFS


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
    """

    basis: object
    point: np.ndarray
    error: float


@dataclass(frozen=True)
class ExactBasisCalibration:
    """A large model's calibration (``calibrate_on_exact_basis``): the result (the full model's
    numbers at the optimum), the basis the ends were polished on, and that basis's relative
    frequency error at the optimum against the full solve there (NaN when that solve failed)."""

    result: CalibrationResult
    made_exact: BasisMadeExact
    error_at_optimum: float


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
    result, error = evaluated_in_full(problem, made[-1].basis, result)
    return ExactBasisCalibration(result, made[-1], error)


def basis_made_exact(
    problem: CalibrationProblem, rom, ends: np.ndarray, objectives: np.ndarray
) -> BasisMadeExact:
    """``rom`` made exact at the best of ``ends`` (n, d) (SI) by ``objectives`` (n,): its full
    modes join the basis and every point it was certified on is re-verified
    (``ReducedFEModel.certify_at``).  The basis as built when the enlarged one misses its
    tolerance or size, or when the full solve at that point fails (a one-line warning naming
    the point, either way)."""
    best = np.asarray(ends[int(np.argmin(objectives))], dtype=float)
    point, names = full_point(problem, rom, best)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        checked, error = rom.certify_at(point, names, enrich_above=0.0)
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
        return BasisMadeExact(rom, best, error)
    return BasisMadeExact(checked, best, error)


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
    problem: CalibrationProblem, basis, result: CalibrationResult
) -> tuple[CalibrationResult, float]:
    """(``result`` (found on ``basis``) with its objective, frequencies, mass and table from one
    full solve of ``problem`` at its optimum, the basis's relative frequency error there); a
    warning when that error exceeds the basis's tolerance.  When that full solve fails,
    (``result`` as found on the basis, NaN), with a one-line warning naming the point."""
    evaluation = problem.evaluate(result.theta)
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
