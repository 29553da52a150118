"""The surrogate a pipeline calibrates and samples on: a built-in FE model gets a certified
reduced basis (``fe.reduced``) over the parameters' bounds, checked in full where it matters (the
optimum, the posterior mean), and a coarser basis inside it screens sampler proposals (delayed
acceptance).  Other models are used as they are.

Choosing the surrogate is orchestration: it needs the FE layer, which inference does not import
(inference sees any model only through ``model_protocol``).
"""

import warnings
from dataclasses import replace

import numpy as np

from bayesupdate.inference.likelihood import LikelihoodSpec, LogPosterior
from bayesupdate.inference.likelihood_blocks import SampledNoise, noise_model
from bayesupdate.inference.optimize import CalibrationResult
from bayesupdate.inference.problem import CalibrationProblem


def sampling_problem(
    problem: CalibrationProblem,
    calibration: CalibrationResult | None = None,
    reduced: bool = True,
    tol: float = 1e-4,
    seed: int = 0,
    executor=None,
) -> tuple[CalibrationProblem, object | None]:
    """The problem the sampler uses: a built-in FE model gets a certified reduced basis
    (``fe.reduced.reduced_model_for``) over the calibrated parameters' bounds, with the model
    modes the pairing needs (test modes + extra modes), certified again at the optimum.
    Fixed parameters keep a narrow box (+-0.1 %) around their value.  Returns (problem, rom);
    rom is None with ``reduced=False``, for other models, or when no certified basis exists
    (then a RuntimeWarning says full solves are used).  The basis's full solves run on
    ``executor`` (``compute.executors``; None: in this process)."""
    from bayesupdate.fe.model import FEModel
    from bayesupdate.fe.reduced import ReducedFEModel, reduced_model_for

    model = problem.model
    if not reduced or not isinstance(model, FEModel):
        return problem, None
    bounds = {p.name: p.bounds for p in problem.parameters}
    for name, value in problem.fixed.items():
        if name in model.parameter_names and value > 0:
            bounds[name] = (value * (1 - 1e-3), value * (1 + 1e-3))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rom = reduced_model_for(
            model, bounds, tol=tol, seed=seed, n_modes=problem.pairing.n_model, executor=executor
        )
    for w in caught:
        warnings.warn(str(w.message), RuntimeWarning, stacklevel=2)
    if not isinstance(rom, ReducedFEModel) or not rom.certified:
        return problem, None
    if calibration is not None:
        rom = certify_rom(rom, calibration.theta[None, :], problem.names, "the optimum")[0]
        if not rom.certified:
            return problem, None
    return replace(problem, model=rom), rom


def screening_posterior(
    problem: CalibrationProblem, rom, likelihood: LikelihoodSpec, tol: float = 1e-4
) -> LogPosterior | None:
    """The surrogate posterior for delayed-acceptance sampling (``inference.delayed_acceptance``).

    With a reduced model (``rom``): the same problem on a coarser basis inside it
    (``ReducedFEModel.coarsened``).  On full solves of a built-in FE model (``--full``): the
    certified reduced model itself, so the exact full-model posterior is sampled with full
    solves only for the proposals the reduced model lets through.  None for other models."""
    if rom is not None:
        return LogPosterior(replace(problem, model=rom.coarsened()), likelihood)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # no reduced model: plain sampling, nothing to warn about
        screen_problem, screen_rom = sampling_problem(problem, None, True, tol)
    if screen_rom is None:
        return None
    return LogPosterior(screen_problem, likelihood)


def screen_mismatch(screen: LogPosterior, calibration: CalibrationResult) -> str:
    """Why the screening posterior would not help, or "" when it would.

    A screen whose frequency error (``max_rel_error`` of its model) exceeds the likelihood's
    smallest relative sd rejects good proposals: on the NX FEMAP round trip with identified sds
    (5.5e-6 to 3.6e-4) the coarse basis's 2.9e-3 gave acceptance 0.053 against 0.60 unscreened,
    and the run did not converge.  That sd is taken at the optimum (``noise_model``: the fixed
    sigma, or the residuals' robust level when sigma is sampled, with the data's sds)."""
    error = getattr(screen.problem.model, "max_rel_error", None)
    if error is None:
        return ""
    problem, spec = screen.problem, screen.spec
    residual = calibration.table.error_pct / 100.0
    if not np.all(np.isfinite(residual[problem.weights > 0])):
        return ""
    noise = noise_model(problem.data, residual, len(problem.names), spec.sigma)
    smallest = float(np.min(noise.scale[noise.used]))
    if error <= smallest:
        return ""
    return (
        f"the screening model's frequency error {error:.1e} exceeds the likelihood's smallest "
        f"relative sd {smallest:.1e}: proposals are not screened"
    )


#: the reduced basis's error at the optimum allowed, as a share of the likelihood's smallest sd
BASIS_SHARE = 0.1


def basis_error_allowed(problem: CalibrationProblem, spec: LikelihoodSpec, calibration) -> float:
    """The reduced basis's relative frequency error above which it is enriched at the optimum:
    ``BASIS_SHARE`` x the smallest relative sd the likelihood gives a used mode there.

    The basis's error is one-sided (Rayleigh-Ritz: reduced frequencies >= full), so it biases
    the posterior; below a tenth of a mode's sd the bias is a tenth of an sd or less.  The sd is
    the likelihood's, s_i^2 = sigma^2 / w_i + the data's relative sd_i^2 (``SampledNoise``), at
    the fixed sigma, or, with sigma sampled, at the sigma that maximizes the likelihood of the
    optimum's residuals (``sigma_at_optimum``): near 0 when the identification sds explain the
    scatter (the NX round trip: posterior sigma 8e-6, basis error 4e-6 against sds from 5.5e-6),
    the model error's level when the model misses physics (a hidden 0.4 kg mass on the exhaust:
    4 %, so that basis is not enlarged for nothing).  inf when the residuals are not finite."""
    residual = calibration.table.error_pct / 100.0
    used = problem.weights > 0
    if not np.all(np.isfinite(residual[used])):
        return float("inf")
    data = problem.data
    sds = [
        None if v is None else v[used] for v in (data.frequency_sd_hz, data.identification_sd_hz)
    ]
    noise = SampledNoise.of(data.frequencies_hz[used], problem.weights[used], *sds)
    level = spec.sigma if spec.sigma is not None else sigma_at_optimum(noise, residual[used])
    return BASIS_SHARE * float(np.sqrt(np.min(noise.variance(np.array([level]))[0])))


def sigma_at_optimum(noise: SampledNoise, residual: np.ndarray) -> float:
    """The noise level sigma that maximizes the likelihood (eq. 1) of the relative residuals
    (n,) under ``noise``, on a log grid 1e-9 to 1 (121 points): 1e-9 stands for 0."""
    grid = np.logspace(-9.0, 0.0, 121)
    ll = noise.log_likelihood(np.broadcast_to(residual, (grid.size, residual.size)), grid)
    return float(grid[int(np.argmax(ll))])


def certify_rom(
    rom, theta: np.ndarray, names: tuple[str, ...], where: str, enrich_above: float | None = None
) -> tuple:
    """Full solve(s) at theta (k, len(names)); the basis is enriched there when its error
    exceeds ``enrich_above`` (``basis_error_allowed``) or its tolerance; warn (suggesting
    --full) when it then misses its tolerance.  Returns (the checked ROM, its ``summary()``
    plus ``error_at``, the error at theta after any enrichment)."""
    rom, err = rom.certify_at(theta, names, enrich_above=enrich_above)
    if not rom.certified or not err <= rom.tol:
        warnings.warn(
            f"reduced model not certified at {where} (relative frequency error {err:.2e}, tol "
            f"{rom.tol:g}); the posterior may carry reduced-basis error: rerun with --full",
            RuntimeWarning,
            stacklevel=2,
        )
    return rom, {**rom.summary(), "error_at": float(err)}
