"""The calibrate pipeline: a prepared study -> its multi-start point optimum (seed eq. 19).

Built-in FE models search on their certified reduced basis (``pipelines.surrogates``), and the
ends are checked on the exact model (``calibrate(..., refine=...)``).  Where a full solve is
cheap (beam models: milliseconds) the ends near the best are polished on full solves.  On a
large model (``fe.reduced.settings.LARGE_MODEL_DOFS`` DOFs or more: the shell exhaust's
28,386 DOFs cost ~1.5 s of CPU per solve) that polish, 60 d Nelder-Mead evaluations per end,
would be thousands of full solves; there the basis is instead made exact at the best end (its
full modes join the basis, ``ReducedFEModel.certify_at``, every checked point re-verified), the
ends are polished on that basis, and the optimum is evaluated by one full solve, which gives the
reported objective, frequencies and table, and the basis's error there (a warning above its
tolerance).  This is the trust-region idea of reduced-basis optimisation: optimise on the
surrogate, make it exact at the iterate and check it there in full (Yue & Meerbergen, SIAM J.
Optim. 23 (2013) 1344; Qian, Grepl, Veroy & Willcox, SIAM J. Sci. Comput. 39 (2017) S434).
"""

import warnings
from dataclasses import dataclass, replace

import numpy as np

from bayesupdate.inference.optimize import CalibrationResult, CalibrationSettings, calibrate
from bayesupdate.inference.problem import CalibrationProblem
from bayesupdate.pipelines.study import PreparedStudy
from bayesupdate.pipelines.surrogates import sampling_problem


def run_calibration(prepared: PreparedStudy, executor=None) -> CalibrationResult:
    """Multi-start optimum.  Built-in FE models search on their certified reduced basis and
    check the ends on the full model (module docstring), so the reported optimum is the full
    model's; ``sampler.reduced = false`` (``--full``) searches on full solves.  The reduced
    basis's full solves, the starts and the polishes run on ``executor``
    (``compute.executors``; None: here)."""
    opt = prepared.study.optimizer
    cfg = prepared.study.sampler
    search, rom = sampling_problem(
        prepared.problem, None, cfg.reduced, cfg.reduced_tol, executor=executor
    )
    settings = CalibrationSettings(
        starts=opt.starts, seed=opt.seed, method=opt.method, design=opt.design, polish=opt.polish
    )
    if rom is None:
        return calibrate(search, settings, executor=executor)
    if not large_model(rom):
        return calibrate(search, settings, refine=prepared.problem, executor=executor)
    exact = BasisMadeExact(prepared.problem, rom)
    result = calibrate(search, settings, refine=exact, executor=executor)
    return exact.evaluated_in_full(result)


def large_model(rom) -> bool:
    """Whether ``rom``'s FE model is large enough that a full solve takes seconds
    (``fe.reduced.settings.LARGE_MODEL_DOFS`` DOFs or more)."""
    from bayesupdate.fe.reduced.settings import LARGE_MODEL_DOFS

    return rom.fe.structure.n_dof >= LARGE_MODEL_DOFS


@dataclass
class BasisMadeExact:
    """The refine step of a large model (module docstring), called by ``calibrate`` when the
    starts have ended: ``problem`` (the exact one) on ``rom`` made exact at the best end.
    ``checked`` holds the basis it made (None before the call)."""

    problem: CalibrationProblem
    rom: object
    checked: object = None

    def __call__(self, ends: np.ndarray, objectives: np.ndarray) -> CalibrationProblem:
        """The problem on the basis enriched at the best of ``ends`` (n, d) (SI) by
        ``objectives`` (n,); on the basis as it was when the enlarged one misses its tolerance
        or size (a warning then says so)."""
        best, names = self._full_point(ends[int(np.argmin(objectives))])
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            checked = self.rom.certify_at(best, names, enrich_above=0.0)[0]
        if not checked.certified:
            for w in caught:
                warnings.warn(
                    f"{w.message} (the ends are polished on the basis as built)",
                    RuntimeWarning,
                    stacklevel=2,
                )
            checked = self.rom
        self.checked = checked
        return replace(self.problem, model=checked)

    def _full_point(self, theta: np.ndarray) -> tuple[np.ndarray, tuple[str, ...]]:
        """(1, k) point and its k names: ``theta`` (d,) with the problem's fixed values of the
        model's other parameters (the basis fills in defaults for names it is not given)."""
        fixed = tuple(k for k in self.problem.fixed if k in self.rom.parameter_names)
        row = np.concatenate([theta, [self.problem.fixed[k] for k in fixed]])
        return row[None, :], self.problem.names + fixed

    def evaluated_in_full(self, result: CalibrationResult) -> CalibrationResult:
        """``result`` (found on the basis) with its objective, frequencies, mass and table from
        one full solve at its optimum; a warning when the basis's relative frequency error there
        exceeds its tolerance."""
        problem = self.problem
        evaluation = problem.evaluate(result.theta)
        if not evaluation.ok:
            return result
        basis = self.rom if self.checked is None else self.checked
        n_model = evaluation.all_frequencies_hz.size
        f_rom = basis.predict_frequencies_batch(*self._full_point(result.theta), n_model)[0]
        error = float(np.max(np.abs(f_rom / evaluation.all_frequencies_hz - 1.0)))
        if not error <= basis.tol:
            warnings.warn(
                f"reduced basis off by {error:.2e} at the optimum (tol {basis.tol:g}): the ends "
                "were polished on it; rerun with --full for a polish on full solves",
                RuntimeWarning,
                stacklevel=2,
            )
        return replace(
            result,
            objective=float(np.sum(problem.residual_vector(evaluation) ** 2)),
            expr=float(problem.expr(evaluation.frequencies_hz)),
            mass_kg=evaluation.mass_kg,
            frequencies_hz=evaluation.frequencies_hz,
            table=problem.table(evaluation),
            evaluations=result.evaluations + 1,
        )
