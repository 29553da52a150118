"""The calibrate pipeline: a prepared study -> its multi-start point optimum (seed eq. 19)."""

from bayesupdate.inference.optimize import CalibrationResult, CalibrationSettings, calibrate
from bayesupdate.pipelines.study import PreparedStudy
from bayesupdate.pipelines.surrogates import sampling_problem


def run_calibration(prepared: PreparedStudy, executor=None) -> CalibrationResult:
    """Multi-start optimum.  Built-in FE models search on their certified reduced basis and
    polish every end point on the full model (``calibrate(..., refine=...)``), so the result is
    the full model's; ``sampler.reduced = false`` (``--full``) searches on full solves.  The
    reduced basis's full solves, the starts and the polishes run on ``executor``
    (``compute.executors``; None: here)."""
    opt = prepared.study.optimizer
    cfg = prepared.study.sampler
    search, rom = sampling_problem(
        prepared.problem, None, cfg.reduced, cfg.reduced_tol, executor=executor
    )
    settings = CalibrationSettings(
        starts=opt.starts, seed=opt.seed, method=opt.method, design=opt.design, polish=opt.polish
    )
    refine = None if rom is None else prepared.problem
    return calibrate(search, settings, refine=refine, executor=executor)
