"""Posterior sampling with emcee: mixture or DE moves, start around the optimum, stop at 50 tau,
resume.

Moves (``SamplerSettings.moves``).  "mixture" (default): a frozen defensive Gaussian-mixture
independence proposal (0.8) with DE (0.2), fitted in stages before the kept run
(``inference.moves.staged``, which says why the kept chain is valid): the DE moves alone
under-estimate the exhaust posterior's sds by 4-10 % (docs/validation/posterior.md).  When the
mixture cannot be fitted (too few distinct points) or covers the posterior poorly (the coverage
check before the kept run, ``moves.coverage``) and its refits do too (below
``moves.staged.LOW_COVERAGE`` or with walkers stuck) the run uses the DE moves and says so
(``diagnostics["moves"]``).  A screened run's adaptation stages sample the delayed-acceptance
surrogate alone (``_adaptation_stage``), and a posterior with a mass term takes its masses from
their polynomial verified to round-off (``LogPosterior.use_fitted_mass``).  Given an executor
with local worker processes, batches of 10 walkers or more are evaluated half here, half on a
worker, with the serial run's values bit for bit (``evaluators.split_densities``).
"de": differential evolution (ter Braak 2006) 70 %, DE with gamma = 1 10 % (ter Braak's
mode-jumping step: x_i + (x_j - x_k) carries a walker from one mode to the other exactly when x_j,
x_k sit in different modes), DE snooker (ter Braak & Vrugt 2008) 20 %.  The stretch move is not
used: it misweights multi-modal posteriors.

Walkers start in small balls around the distinct optima of the multi-start fit (so every mode
found by the optimizer holds walkers from the start; the DE moves then set the weights).  The run
is cut in blocks of ``check_every`` steps; after each block the integrated autocorrelation time
tau is estimated (emcee) and the run stops once steps >= ``min_autocorr_times`` * max(tau) and,
when asked for, the convergence targets hold (``target_rhat``: rank-normalized split R-hat of
every parameter at most this; ``target_ess``: bulk ESS at least this, the smaller of ArviZ's and
emcee's n_draws * n_walkers / tau, after the warm-up ``burn_in``), or the step budget ends.
Why both: R-hat <= 1.01 needs each walker ~100 tau long whatever the number of walkers, while
ESS grows with the walkers, so the targets, not 50 tau, decide when the run has converged.

When the stop rule is checked: at the checkpoints (multiples of ``check_every``) and, between
them, each time the chain has grown by ``CHECK_GROWTH`` (10 %; the steps of ``check_schedule``,
fixed by the step count alone).  The targets are reached at a step count the run cannot know in
advance, so a check every 500 steps stopped the exhaust up to 500 steps (there: twice the 50 tau
the targets needed beyond the first check) past the step the targets first held; checks at a
fixed ratio end a run at most 10 % of its length past it, for a number of checks that grows with
the logarithm of the length (28 up to 1,000 steps, of which the ~12 after 50 tau compute
R-hat: about 0.1-0.5 s each on the exhaust's 32 x 750 x 5 chain, against 0.06-0.24 s a step).
R-hat, the costlier diagnostic and the one that binds on the exhaust, is computed first and the
ESS only when it holds.  What held the run at each check, and the ESS at the stop over its
target, are in ``diagnostics["stop"]`` (``stop_record``).  With R-hat <= 1.01 binding, the ESS
at the stop (~100 per walker: about 50 independent draws per split half-walker for R-hat - 1 <=
0.01) is what R-hat needs, not an overshoot of the checks.  Checkpoints are written at the
multiples of ``check_every`` only.  All block boundaries depend on the step count alone, and the
emcee random state is saved with each checkpoint, so an interrupted run resumed with
``resume=`` ends with exactly the chain of an uninterrupted run.
"""

import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import partial

import emcee
import numpy as np

from bayesupdate.compute import progress
from bayesupdate.compute.stop import StopRequest
from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference import convergence, walker_start
from bayesupdate.inference.delayed_acceptance import ScreenedLogDensity, delayed_acceptance_moves
from bayesupdate.inference.evaluators import SplitDensity, split_densities
from bayesupdate.inference.likelihood import LogPosterior
from bayesupdate.inference.move_kinds import check_adapt_steps, check_moves
from bayesupdate.inference.moves import DefensiveProposal, mixture_moves, staged_proposal
from bayesupdate.inference.moves.staged import REPAIR_ROUNDS
from bayesupdate.inference.optimize import CalibrationResult
from bayesupdate.inference.parameter_space import ParameterSpace, ParameterSpec
from bayesupdate.inference.walker_start import axis_sd, uncounted

#: wall-time parts of a run in ``diagnostics["timings"]`` [s]: the adaptation stages (their
#: evaluations count in the next two as well), exact and screening log-posterior calls, and
#: the convergence checks
TIMED = ("adapt_s", "exact_s", "screen_s", "check_s")
#: points per log-density call off the chain (``_checked``)
CHECK_BATCH = 500
#: the stop rule is checked each time the chain has grown by this factor (module docstring)
CHECK_GROWTH = 1.1
#: first check, and the least number of steps between checks (``emcee.autocorr`` needs 20)
CHECK_MIN_STEPS = 20
#: steps of each adaptation stage (``moves.staged``).  Tried on 2026-11-29 and not kept: 100
#: (the three stages of 250 x 32 walkers of screen solves are a quarter of ``sample --model
#: exhaust --data paper:ema``'s CPU).  The frozen proposals covered the posterior less well
#: (importance ESS 0.41 against 0.49 on the user's command, 0.37 against 0.41 on the demo's
#: seed case, seed 1 both); the seed case's kept chain took 1,249 steps (tau 11.8) instead
#: of 702 (tau 6.4), and the user's command, seed 1, once ran its 5,000-step budget without
#: converging (R-hat 1.013; 168 s CPU against 52 s) (docs/guide/calibrate-sample.md)
ADAPT_STEPS = 250


def default_moves() -> list:
    """DE 0.7, DE with gamma = 1 (mode jumps) 0.1, DE snooker 0.2 (see module docstring)."""
    return [
        (emcee.moves.DEMove(), 0.7),
        (emcee.moves.DEMove(gamma0=1.0), 0.1),
        (emcee.moves.DESnookerMove(), 0.2),
    ]


def sampler_space(log_posterior: LogPosterior) -> ParameterSpace:
    """The parameters a LogPosterior samples: the problem's, then sigma (bounds of its prior) when
    it is sampled.  Walking in their unconstrained coordinates y (``transform="logit"``,
    ``ParameterSpace.theta_from_y``) matters: the exhaust's posterior piles against its bounds
    and spans a decade in thickness and density; in theta about 2/3 of the DE proposals fell
    outside the box and tau was ~100-130 steps, in y every proposal is valid and tau is ~40
    (same data, 32 walkers)."""
    parameters = tuple(log_posterior.problem.parameters)
    if log_posterior.spec.infer_sigma:
        prior = log_posterior.spec.sigma_prior
        parameters += (ParameterSpec("sigma", prior.bounds, prior),)
    return ParameterSpace(parameters)


@dataclass(frozen=True)
class SamplerState:
    """What resuming needs: the chain so far and the state after its last step.

    chain : (n_steps, n_walkers, d); log_prob : (n_steps, n_walkers); coords (n_walkers, d) and
    last_log_prob (n_walkers,) are the last step *in the sampler's coordinates* (y and the
    log-density in y with ``transform="logit"``, so a resume continues bit for bit);
    random_state : emcee's MT19937 state tuple.  moves : the move scheme of the kept run,
    ``{"kind", "requested", "fallback", "components", "adapt_steps", "proposal"}`` (proposal: the
    frozen ``DefensiveProposal.to_dict()``, or None), None for caller-given moves.
    """

    chain: np.ndarray
    log_prob: np.ndarray
    coords: np.ndarray
    last_log_prob: np.ndarray
    random_state: tuple
    accepted: np.ndarray
    evaluations: int
    failed: int
    wall_s: float
    finished: bool = False
    moves: dict | None = None


@dataclass(frozen=True)
class PosteriorResult:
    """A finished (or interrupted) sampling run.

    chain : (n_steps, n_walkers, d) all steps, names order; log_prob : (n_steps, n_walkers).
    burn : steps discarded as warm-up.  autocorr_time : (d,) tau per parameter [steps].
    diagnostics : see ``diagnostics.summarize``.  predictions : see ``posterior_predictive``.
    """

    names: tuple[str, ...]
    chain: np.ndarray
    log_prob: np.ndarray
    burn: int
    autocorr_time: np.ndarray
    acceptance: np.ndarray
    evaluations: int
    failed_evaluations: int
    wall_s: float
    converged: bool
    interrupted: bool
    state: SamplerState
    seed: int
    diagnostics: dict = field(default_factory=dict)
    predictions: dict = field(default_factory=dict)
    screen_evaluations: int = 0

    def samples(self) -> np.ndarray:
        """Post-burn-in draws flattened over walkers, (n_draws, d)."""
        return self.chain[self.burn :].reshape(-1, self.chain.shape[-1])


def initial_walkers(
    log_posterior: LogPosterior,
    calibration: CalibrationResult,
    n_walkers: int,
    rng: np.random.Generator,
    ball: float = 1e-3,
    sigma_start: float | None = None,
) -> np.ndarray:
    """Walker positions (n_walkers, d) in balls around the distinct optima, all with finite lp.

    ball : radius as a fraction of each parameter's bounds width, capped by the posterior's sd
    along each axis at the best optimum (``walker_start.axis_sd``: a ball wider than the
    posterior starts the walkers tens of sds out when the data are precise).  The sigma column
    (if sampled) starts near the rms relative error at the optimum (or ``sigma_start``), within
    its prior, or at the best sigma of a log grid when that is clearly better
    (``walker_start.sigma_start``).
    """
    problem = log_posterior.problem
    low, high = problem.lower, problem.upper
    centres = calibration.end_points[list(calibration.distinct_optima or (0,))]
    d = log_posterior.ndim
    columns = []
    if log_posterior.spec.infer_sigma:
        prior = log_posterior.spec.sigma_prior
        rms = np.sqrt(calibration.expr / max(problem.data.n_modes, 1))
        s0 = sigma_start if sigma_start is not None else rms
        s0 = float(np.clip(max(s0, 1e-3), *prior.bounds))
        if sigma_start is None:
            with uncounted(log_posterior):
                s0 = walker_start.sigma_start(log_posterior, centres[0], s0)
        if not np.isfinite(prior.logpdf(s0)):
            s0 = float(prior.sample(rng, 1)[0])
        columns.append(s0)
    width = np.concatenate([high - low, np.abs(columns) + 1e-3])[:d]
    with uncounted(log_posterior):
        sd = axis_sd(log_posterior, np.concatenate([centres[0], columns]), ball * width)
    positions = np.empty((n_walkers, d))
    for attempt in range(100):
        which = np.arange(n_walkers) % centres.shape[0]
        base = (
            np.hstack([centres[which], np.tile(columns, (n_walkers, 1))])
            if columns
            else (centres[which])
        )
        scale = np.minimum(ball * width, sd)
        trial = base + scale * rng.standard_normal((n_walkers, d))
        trial[:, : low.size] = np.clip(trial[:, : low.size], low, high)
        if columns:
            trial[:, -1] = np.abs(trial[:, -1])
        lp = log_posterior(trial)
        ok = np.isfinite(lp)
        positions = np.where(ok[:, None], trial, positions) if attempt else trial
        if np.all(np.isfinite(log_posterior(positions))):
            return positions
        ball *= 0.5
    raise BayesUpdateError(
        "sampler: cannot start walkers with finite log-posterior near the optimum; "
        f"check priors and the model (last model error: {log_posterior.last_error})"
    )


def _autocorr(chain: np.ndarray) -> np.ndarray:
    """Integrated autocorrelation time per parameter (emcee, walker-averaged), (d,)."""
    if chain.shape[0] < 20:
        return np.full(chain.shape[-1], np.inf)
    # emcee logs a warning for short chains even with quiet=True; our stopping rule handles it
    logger = logging.getLogger("emcee.autocorr")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        # a walker that never moved has a zero-variance chain: emcee's acf /= acf[0] is 0 / 0
        # there and tau NaN, which the stop rule and the convergence report read as "not
        # converged" (``diagnostics.convergence_report``); the warning itself says no more
        with np.errstate(invalid="ignore", divide="ignore"):
            tau = emcee.autocorr.integrated_time(chain, c=5, quiet=True)
        return np.asarray(tau, dtype=float)
    finally:
        logger.setLevel(level)


def burn_in(n_steps: int, tau: np.ndarray) -> int:
    """Warm-up steps: 5 tau (emcee's advice is "a few times tau"), never more than half."""
    burn = n_steps // 2
    tau = np.asarray(tau, dtype=float)
    if tau.size and np.all(np.isfinite(tau)):
        burn = int(min(burn, np.ceil(5 * np.max(tau))))
    return burn


def rhat_and_ess(post: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, ...]:
    """(r_hat, ess_arviz, ess_autocorr), each (d,), of a post-warm-up chain (n_draws, n_walkers,
    d), walkers as chains (Vehtari et al. 2021, ArviZ): rank-normalized split R-hat, ArviZ's
    bulk ESS, and emcee's n_draws * n_walkers / tau (NaN where tau is not finite)."""
    return (_rhat(post), *_ess(post, tau))


def _rhat(post: np.ndarray) -> np.ndarray:
    """(d,) rank-normalized split R-hat of a chain (n_draws, n_walkers, d), walkers as chains
    (``inference.convergence``: ArviZ's, without importing ArviZ)."""
    return convergence.rank_rhat(post)


def _ess(post: np.ndarray, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """((d,) bulk ESS (``inference.convergence``: ArviZ's), (d,) emcee's n_draws * n_walkers /
    tau) of a chain (n_draws, n_walkers, d)."""
    ess = convergence.bulk_ess(post)
    tau = np.asarray(tau, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        ess_tau = np.where(
            np.isfinite(tau) & (tau > 0), post.shape[0] * post.shape[1] / tau, np.nan
        )
    return ess.astype(float), ess_tau


@dataclass(frozen=True)
class SamplerSettings:
    """How a sampling run goes (module docstring), validated once when made.

    walkers : ensemble size (>= 4 and >= 2 d; the latter checked by ``sample_posterior``).
    steps : step budget per walker.  seed : seeds the start (walker balls) and emcee's MT19937.
    min_autocorr_times : stop once steps >= this * max(tau) [tau in steps].
    check_every : block length [steps] between tau estimates and checkpoints.
    transform : "none" (walk in theta) or "logit" (walk in the unconstrained coordinates y of
    ``sampler_space``; the chain and log_prob are returned in theta all the same); a resume must
    use the same.  target_rhat, target_ess : convergence targets (None: not checked).
    progress : show a progress bar.  moves : "mixture" (default) or "de" (module docstring).
    adapt_steps : steps of each of the three adaptation stages of "mixture" (not kept;
    ``ADAPT_STEPS``).
    """

    walkers: int = 32
    steps: int = 5000
    seed: int = 1
    min_autocorr_times: float = 50.0
    check_every: int = 500
    transform: str = "none"
    target_rhat: float | None = None
    target_ess: float | None = None
    progress: bool = False
    moves: str = "mixture"
    adapt_steps: int = ADAPT_STEPS

    def __post_init__(self) -> None:
        check_moves(self.moves)
        check_adapt_steps(self.adapt_steps)
        if self.transform not in ("none", "logit"):
            raise BayesUpdateError(f"sampler.transform: {self.transform!r}; use 'none' or 'logit'")
        if self.walkers < 4:
            raise BayesUpdateError(f"sampler.walkers: {self.walkers} is too few; use at least 4")
        if self.steps < 1 or self.check_every < 1:
            raise BayesUpdateError("sampler.steps and sampler.check_every must be >= 1")
        if self.target_rhat is not None and not self.target_rhat >= 1.0:
            raise BayesUpdateError(f"sampler.target_rhat: must be >= 1, got {self.target_rhat}")
        if self.target_ess is not None and not self.target_ess > 0:
            raise BayesUpdateError(f"sampler.target_ess: must be > 0, got {self.target_ess}")

    def check_walkers(self, ndim: int) -> None:
        """Raise unless there are at least 2 walkers per sampled parameter (ndim of them)."""
        if self.walkers < 2 * ndim:
            raise BayesUpdateError(
                f"sampler.walkers: {self.walkers} is too few for {ndim} parameters; "
                f"use at least {max(2 * ndim, 4)}"
            )


def _to_theta(space: ParameterSpace | None, x: np.ndarray) -> np.ndarray:
    """Sampler coordinates (..., d) -> theta (..., d) (identity without a transform)."""
    return x if space is None else space.theta_from_y(x)


def _log_jacobian(space: ParameterSpace | None, x: np.ndarray) -> np.ndarray:
    """log |d theta / d y| at sampler coordinates (..., d) -> (...) (0 without a transform)."""
    return np.zeros(np.shape(x)[:-1]) if space is None else space.log_jacobian_y(x)


def _guard(
    density: LogPosterior,
    space: ParameterSpace | None,
    request: StopRequest,
    clock: dict | None = None,
    key: str = "exact_s",
) -> Callable[[np.ndarray], np.ndarray]:
    """The log-density emcee sees, (n_walkers, d) sampler coordinates -> (n_walkers,): in y
    with the log-Jacobian added when ``space`` is given; after a stop request (a Ctrl-C)
    -inf, and after a BayesUpdateError (``request.fail``, raised by ``_raise_failure``).  The
    wall time of each call is added to ``clock[key]`` [s] when ``clock`` is given."""

    def guarded(x: np.ndarray) -> np.ndarray:
        # Ctrl-C inside the model: finish the step without evaluating (it is discarded
        # below); raising through emcee would print every walker's parameters and a traceback
        if not request.requested():
            t0 = time.perf_counter()
            try:
                with request.interruptible():  # only here: emcee's code around it is deferred
                    if space is None:
                        return density(x)
                    return density(space.theta_from_y(x)) + space.log_jacobian_y(x)
            except KeyboardInterrupt:
                request.request()
            except BayesUpdateError as exc:  # e.g. the Dask scheduler lost: stop, then say it
                request.fail(exc)
            finally:
                if clock is not None:
                    clock[key] += time.perf_counter() - t0
        return np.full(np.shape(x)[0], -np.inf)

    return guarded


def _fitted_screen(screen: LogPosterior | None, d: int) -> LogPosterior | None:
    """The ``screen`` posterior with its mass term from a verified polynomial
    (``inference.mass_fit``): a screen only decides which proposals get an exact evaluation, so
    the target stays exact (a screen that is not a ``LogPosterior`` has no mass term to fit);
    None without one."""
    if screen is None:
        return None
    if screen.ndim != d:
        raise BayesUpdateError("sampler: the screening posterior has other parameters")
    fitted = getattr(screen, "with_fitted_mass", None)
    return screen if fitted is None else fitted(seed=0)


def _screened(screen, guarded, guard) -> ScreenedLogDensity | None:
    """The delayed-acceptance surrogate (``inference.delayed_acceptance``) of a ``screen``
    posterior (``_fitted_screen``), shared by every sampler of the run; None without one."""
    if screen is None:
        return None
    return ScreenedLogDensity(guard(screen, key="screen_s"), guarded)


def _split_record(densities: tuple) -> dict | None:
    """``diagnostics["split"]``: {"batches": batches evaluated in two parts at once, "stopped":
    why splitting stopped, or ""}; None when nothing was split (``evaluators.SplitDensity``)."""
    split = [d for d in densities if isinstance(d, SplitDensity)]
    if not split:
        return None
    return {
        "batches": sum(d.splits for d in split),
        "stopped": "; ".join(sorted({d.stopped for d in split if d.stopped})),
    }


def _ensemble(walkers: int, d: int, guarded, moves: list, screened: ScreenedLogDensity | None):
    """An emcee sampler with the moves, wrapped for delayed acceptance when ``screened``."""
    if screened is not None:
        moves = delayed_acceptance_moves(moves, screened)
    return emcee.EnsembleSampler(walkers, d, guarded, moves=moves, vectorize=True)


@dataclass
class _Run:
    """The run so far, grown block by block (the sampling loop's accumulator, hence mutable).

    state : emcee.State after the last step (sampler coordinates).  chain_parts : blocks
    (n_i, n_walkers, d) in theta; lp_parts : (n_i, n_walkers) log-posterior of theta.
    accepted : (n_walkers,) accepted proposals.  wall_before [s] : earlier runs' wall time;
    t0 : ``time.perf_counter()`` when this run's sampling began.
    """

    state: emcee.State
    chain_parts: list
    lp_parts: list
    accepted: np.ndarray
    wall_before: float
    t0: float = 0.0
    moves_info: dict | None = None
    clock: dict = field(default_factory=lambda: dict.fromkeys(TIMED, 0.0))
    #: this process's stop-rule checks: (step, what held the run: "tau", "r_hat", "ess" or
    #: None when the rule held, the least bulk ESS where computed, else NaN)
    checks: list = field(default_factory=list)
    #: whether a step was taken in this process: emcee's check that the walkers span the space
    #: is for a chain's initial state; a state the run reached (an adaptation stage's end,
    #: where the independence proposals may have left several walkers on one point) is not one
    stepped: bool = False

    @property
    def done(self) -> int:
        """Steps in the chain so far."""
        return sum(part.shape[0] for part in self.chain_parts)

    def snapshot(self, log_posterior: LogPosterior, finished: bool) -> SamplerState:
        """The SamplerState of the run so far (copies)."""
        return SamplerState(
            chain=np.concatenate(self.chain_parts),
            log_prob=np.concatenate(self.lp_parts),
            coords=self.state.coords.copy(),
            last_log_prob=np.asarray(self.state.log_prob).copy(),
            random_state=self.state.random_state,
            accepted=self.accepted.copy(),
            evaluations=log_posterior.evaluations,
            failed=log_posterior.failed,
            wall_s=self.wall_before + time.perf_counter() - self.t0,
            finished=finished,
            moves=self.moves_info,
        )


def _resumed_run(resume: SamplerState, log_posterior: LogPosterior, walkers: int) -> _Run:
    """The run continued from a checkpoint (same walkers and parameters)."""
    d = log_posterior.ndim
    if resume.coords.shape != (walkers, d):
        raise BayesUpdateError(
            f"resume: checkpoint has {resume.coords.shape} walkers x parameters, "
            f"settings give {(walkers, d)}; resume with the same study"
        )
    state = emcee.State(
        resume.coords.copy(),
        log_prob=resume.last_log_prob.copy(),
        random_state=resume.random_state,
    )
    # the checkpoint's counts are those of the chain so far: set, not add (a LogPosterior
    # reused from the interrupted run has counted them already)
    log_posterior.evaluations = resume.evaluations
    log_posterior.failed = resume.failed
    run = _Run(state, [resume.chain], [resume.log_prob], resume.accepted.copy(), resume.wall_s)
    run.moves_info = resume.moves
    return run


def _fresh_run(
    log_posterior: LogPosterior,
    calibration: CalibrationResult | None,
    initial: np.ndarray | None,
    settings: SamplerSettings,
    space: ParameterSpace | None,
) -> _Run:
    """A new run: walkers (``initial``, or balls around the calibration's optima) and emcee's
    MT19937 state, both from ``settings.seed``.  In the unconstrained coordinates the walkers
    are spread by 0.01, or by the posterior's sd along each axis there where that is smaller
    (``walker_start.axis_sd`` at the first walker)."""
    walkers, d, seed = settings.walkers, log_posterior.ndim, settings.seed
    rng = np.random.default_rng(seed)
    if initial is None:
        if calibration is None:
            raise BayesUpdateError("sampler: give a calibration result or initial walkers")
        initial = initial_walkers(log_posterior, calibration, walkers, rng)
    mt = np.random.RandomState(np.random.MT19937(np.random.SeedSequence([seed, 7])))
    initial = np.asarray(initial, dtype=float)
    if space is not None:
        # walkers clipped onto a bound would coincide in y: spread them a little
        y = space.y_from_theta(initial)
        density = partial(_guard, space=space, request=StopRequest())(log_posterior)
        with uncounted(log_posterior):
            spread = axis_sd(density, y[0], np.full(d, 0.01))
        initial = y + spread * rng.standard_normal(initial.shape)
    state = emcee.State(initial, random_state=mt.get_state())
    chain_parts, lp_parts = [np.empty((0, walkers, d))], [np.empty((0, walkers))]
    return _Run(state, chain_parts, lp_parts, np.zeros(walkers), 0.0)


def _raise_failure(
    request: StopRequest, run: _Run | None = None, checkpoint=None, density=None
) -> None:
    """Raise the BayesUpdateError a density call met (``_guard``), if any, after a checkpoint of
    ``run``'s complete steps when ``checkpoint`` is given: ``resume`` continues from them."""
    error = request.error
    if error is None:
        return
    if checkpoint is not None and run is not None and run.done:
        checkpoint(run.snapshot(density, finished=False))
    raise error


def _start(run: _Run, guarded, request: StopRequest) -> None:
    """Fill in the initial log-density, check it and start the clock."""
    if run.state.log_prob is None:
        # what emcee would compute first; done here so a checkpoint always has it (no RNG use)
        run.state.log_prob = guarded(run.state.coords)
        _raise_failure(request)
    if not np.all(np.isfinite(run.state.log_prob)):
        raise BayesUpdateError("sampler: some initial walkers have zero posterior density")
    run.t0 = time.perf_counter()


def _run_block(
    sampler, run: _Run, block: int, request: StopRequest, bar
) -> tuple[list, list, bool]:
    """``block`` emcee steps from ``run.state``: (coords (n_walkers, d) per completed step,
    log-densities (n_walkers,) per step, interrupted).  ``run.state`` follows each step."""
    coords, lps = [], []
    try:
        sampler.reset()
        if request.requested():  # arrived during the previous block's bookkeeping
            raise KeyboardInterrupt
        steps = sampler.sample(
            run.state, iterations=block, store=True, skip_initial_state_check=run.stepped
        )
        # emcee's steps run deferred (a stop is recorded, the step's remaining model calls
        # return -inf at once, ``_guard``, and the step ends); only the model calls themselves
        # are cut where the signal lands (``StopRequest.interruptible``).  Each completed step
        # is copied, with its three records together or not at all: emcee updates its state
        # in place during the next step, and a signal landing between the records left the
        # step in the chain but run.state one step behind (the resume drew that step twice)
        with request.deferred():
            for step in steps:
                if request.requested():
                    raise KeyboardInterrupt
                coords.append(step.coords.copy())
                lps.append(np.asarray(step.log_prob).copy())
                run.state = emcee.State(
                    coords[-1].copy(), log_prob=lps[-1].copy(), random_state=step.random_state
                )
                run.stepped = True
                bar.update(1)
    except KeyboardInterrupt:
        return coords, lps, True
    return coords, lps, False


def _append(run: _Run, sampler, coords: list, lps: list, space: ParameterSpace | None) -> None:
    """Add a block's steps to the run, stored in theta with the log-posterior of theta (the
    Jacobian taken off), and its acceptances."""
    if coords:
        block_coords = np.array(coords)
        run.chain_parts.append(_to_theta(space, block_coords))
        run.lp_parts.append(np.array(lps) - _log_jacobian(space, block_coords))
        run.accepted += sampler.backend.accepted


def check_schedule(done: int, check_every: int, steps: int) -> int:
    """The next step count (> done, <= steps) at which the stop rule is checked: the next
    multiple of ``check_every`` or of the geometric schedule c_0 = CHECK_MIN_STEPS,
    c_k+1 = max(c_k + CHECK_MIN_STEPS, ceil(CHECK_GROWTH c_k)), whichever comes first; fixed by
    the step counts alone, so a resumed run checks where an uninterrupted one does."""
    c = CHECK_MIN_STEPS
    while c <= done:
        c = max(c + CHECK_MIN_STEPS, int(np.ceil(CHECK_GROWTH * c)))
    return min(c, (done // check_every + 1) * check_every, steps)


def _stop_rule(chain: np.ndarray, done: int, settings: SamplerSettings):
    """(tau (d,) [steps], converged, what held the run: "tau", "r_hat", "ess" or None, the least
    bulk ESS or NaN where not computed): steps >= min_autocorr_times * max(tau) and the
    convergence targets of ``settings`` hold for the chain (n_steps, n_walkers, d) after its
    ``burn_in``: R-hat first, then the bulk ESS (the smaller of ArviZ's and emcee's: walkers of
    an ensemble are not independent) only where R-hat holds."""
    tau = _autocorr(chain)
    converged = bool(np.all(np.isfinite(tau)) and done >= settings.min_autocorr_times * np.max(tau))
    target_rhat, target_ess = settings.target_rhat, settings.target_ess
    if not converged:
        return tau, False, "tau", np.nan
    if target_rhat is None and target_ess is None:
        return tau, True, None, np.nan
    post = chain[burn_in(chain.shape[0], tau) :]
    if post.shape[0] < 4:
        return tau, False, "tau", np.nan
    if target_rhat is not None and not np.all(_rhat(post) <= target_rhat):
        return tau, False, "r_hat", np.nan
    if target_ess is not None:
        ess, ess_tau = _ess(post, tau)
        least = float(np.min(np.minimum(ess, np.nan_to_num(ess_tau, nan=0.0))))
        return tau, least >= target_ess, None if least >= target_ess else "ess", least
    return tau, True, None, np.nan


def stop_record(checks: list, target_ess: float | None) -> dict:
    """``diagnostics["stop"]`` of a run's stop-rule checks ((step, what held, least ESS)):
    {"checks", "steps", "held_before" (what held the run at the check before the stop: "tau",
    "r_hat", "ess"; None when the first check stopped it or it never stopped), "ess_at_stop"
    (least bulk ESS at the stop, None when the rule never held or had no ESS target),
    "ess_over_target" (that / target_ess)}.  The stop lands at most ``CHECK_GROWTH`` past the
    step the rule first holds (``check_schedule``); when "r_hat" held the run before, the ESS
    at the stop is what R-hat <= target needed, not an overshoot of the checks."""
    stopped = bool(checks) and checks[-1][1] is None
    ess = checks[-1][2] if stopped and np.isfinite(checks[-1][2]) else None
    return {
        "checks": len(checks),
        "steps": int(checks[-1][0]) if checks else 0,
        "held_before": checks[-2][1] if stopped and len(checks) > 1 else None,
        "ess_at_stop": None if ess is None else round(ess, 1),
        "ess_over_target": None if ess is None or not target_ess else round(ess / target_ess, 2),
    }


def _sample_blocks(
    sampler,
    run: _Run,
    log_posterior: LogPosterior,
    settings: SamplerSettings,
    checkpoint: Callable[[SamplerState], None] | None,
    space: ParameterSpace | None,
    request: StopRequest,
) -> tuple[bool, bool, np.ndarray]:
    """Blocks up to the next check (``check_schedule``) until the stop rule, the budget or a stop
    request: (interrupted, converged, tau (d,) [steps]).  ``checkpoint`` gets a SamplerState at
    every multiple of ``check_every`` and at the end."""
    from tqdm.auto import tqdm

    steps = settings.steps
    # under a ``reporting`` context (the CLI) the phase below is the bar: one bar, not two
    own_bar = settings.progress and progress.active() is None
    bar = tqdm(total=steps, initial=run.done, disable=not own_bar, desc="sampling", unit="step")
    with progress.phase("sampling: kept chain", steps - run.done, "steps") as shown:
        outcome = _blocks_until_stop(
            sampler, run, log_posterior, settings, checkpoint, space, request, _Tee(bar, shown),
        )  # fmt: skip
    bar.close()
    return outcome


def _blocks_until_stop(
    sampler, run, log_posterior, settings, checkpoint, space, request, bar
) -> tuple[bool, bool, np.ndarray]:
    """The loop of ``_sample_blocks`` (same arguments; ``bar.update(1)`` per step)."""
    steps, check_every = settings.steps, settings.check_every
    interrupted = converged = False
    tau = np.full(log_posterior.ndim, np.inf)
    while run.done < steps:
        done = run.done
        block = check_schedule(done, check_every, steps) - done
        coords, lps, interrupted = _run_block(sampler, run, block, request, bar)
        # bookkeeping and the checkpoint run to the end; a stop request arriving meanwhile is
        # recorded by the CLI's handler and acted on at the next block (StopRequest.deferred)
        with request.deferred():
            _append(run, sampler, coords, lps, space)
            if interrupted:
                break
            t0 = time.perf_counter()
            tau, converged, held, ess = _stop_rule(
                np.concatenate(run.chain_parts), run.done, settings
            )
            run.checks.append((run.done, held, ess))
            run.clock["check_s"] += time.perf_counter() - t0
            finished = converged or run.done >= steps
            if checkpoint is not None and (finished or run.done % check_every == 0):
                checkpoint(run.snapshot(log_posterior, finished=finished))
        if converged:
            break
    return interrupted, converged, tau


class _Tee:
    """Steps counted on a tqdm bar and a ``compute.progress`` phase at once."""

    def __init__(self, bar, shown: progress.Phase):
        self.bar, self.shown = bar, shown

    def update(self, n: int) -> None:
        self.bar.update(n)
        self.shown.advance(n)


def _posterior_result(
    run: _Run,
    log_posterior: LogPosterior,
    outcome: tuple[bool, bool, np.ndarray],
    seed: int,
    screened: ScreenedLogDensity | None,
    target_ess: float | None = None,
) -> PosteriorResult:
    """The PosteriorResult of a finished or interrupted run; ``outcome`` is
    ``_sample_blocks``'s (interrupted, converged, tau)."""
    interrupted, converged, tau = outcome
    final = run.snapshot(log_posterior, finished=not interrupted)
    chain = final.chain
    if chain.shape[0] >= 20:
        tau = _autocorr(chain)
    burn = burn_in(chain.shape[0], tau)
    return PosteriorResult(
        names=log_posterior.names,
        chain=chain,
        log_prob=final.log_prob,
        burn=burn,
        autocorr_time=tau,
        acceptance=final.accepted / max(chain.shape[0], 1),
        evaluations=log_posterior.evaluations,
        failed_evaluations=log_posterior.failed,
        wall_s=final.wall_s,
        converged=converged,
        interrupted=interrupted,
        state=final,
        seed=seed,
        diagnostics={
            "moves": _public(run.moves_info),
            "timings": {k: round(v, 3) for k, v in run.clock.items()},
            "stop": stop_record(run.checks, target_ess),
        },
        screen_evaluations=0 if screened is None else screened.screen_evaluations,
    )


def _public(moves_info: dict | None) -> dict | None:
    """The move scheme as reported (``sample --json`` "moves"): without the fitted proposal."""
    if moves_info is None:
        return None
    return {k: v for k, v in moves_info.items() if k != "proposal"}


class _NoBar:
    """A progress bar that shows nothing (the adaptation stages are not counted as steps)."""

    def update(self, n: int) -> None:
        pass


def _stopped_while_adapting(resume: SamplerState, moves, settings: SamplerSettings) -> bool:
    """Whether ``resume`` is a run stopped before its mixture proposal was frozen."""
    return (
        moves is None
        and settings.moves == "mixture"
        and resume.moves is None
        and resume.chain.shape[0] == 0
    )


def _kept_moves(
    moves: list | None,
    settings: SamplerSettings,
    run: _Run,
    log_posterior: LogPosterior,
    run_steps: Callable[[list, int], tuple | None],
    log_density: Callable[[np.ndarray], np.ndarray | None] | None = None,
) -> list | None:
    """The kept run's (move, weight) pairs; sets ``run.moves_info``.  Caller-given ``moves`` as
    they are; "de": ``default_moves()``; "mixture": the proposal of a resumed run, else the
    staged adaptation (``moves.staged``) from ``run.state``, or DE when it cannot be fitted or
    covers the posterior poorly (``log_density``: the log-density in the sampler's
    coordinates, the surrogate's when the run screens (``_checked``), None after a stop).  None
    when a stop request ended the adaptation."""
    if moves is not None:
        return moves
    if settings.moves == "de":
        run.moves_info = {"kind": "de", "requested": "de", "fallback": None, "proposal": None}
        return default_moves()
    if not hasattr(log_posterior, "problem"):  # a bare log-density: no prior to defend with
        reason = "the target has no priors for the mixture's defensive component; DE moves used"
        run.moves_info = {
            "kind": "de",
            "requested": "mixture",
            "fallback": reason,
            "proposal": None,
        }
        return default_moves()
    space = sampler_space(log_posterior)
    if run.moves_info is None:  # a fresh run, or one stopped while adapting: adapt from here
        logit = settings.transform == "logit"
        proposal, info = staged_proposal(
            run_steps, default_moves(), space, logit, settings.adapt_steps, settings.seed,
            log_density, REPAIR_ROUNDS,
        )  # fmt: skip
        if info.pop("interrupted"):
            return None
        kind = "de" if proposal is None else "mixture"
        fitted = None if proposal is None else proposal.to_dict()
        run.moves_info = {"kind": kind, "requested": "mixture", **info, "proposal": fitted}
    fitted = run.moves_info.get("proposal")
    if fitted is None:
        return default_moves()
    return mixture_moves(DefensiveProposal.from_dict(fitted, space))


def _adaptation_stage(
    run: _Run,
    walkers: int,
    d: int,
    guarded,
    screened,
    step_moves: list,
    n: int,
    request: StopRequest,
) -> tuple[np.ndarray, np.ndarray] | None:
    """An adaptation stage: n steps with ``step_moves`` from ``run.state``; nothing is kept but
    the walkers' positions (n, walkers, d) and log-densities (n, walkers) in the sampler's
    coordinates, None when stopped.  Timed in ``run.clock``.

    With a delayed-acceptance surrogate (``screened``) the stage samples the surrogate q itself,
    with no exact evaluation, and its log-densities are q's: a stage only chooses the frozen
    proposal and the kept run's starting points, and any fixed proposal and any start leave the
    kept chain's target the exact p (``moves.staged``: the stages are a burn-in; the coverage
    check's draws are q's already, ``_checked``).  On the exhaust (seed Table 2, the weighed
    mass) the stages' exact solves were about half of their cost (``moves.staged``), the stages
    half of the run's steps.  ``run.state`` holds the exact log p of its walkers again after
    the stage."""
    t0 = time.perf_counter()
    if screened is None:
        stage = _ensemble(walkers, d, guarded, step_moves, None)
    else:
        stage = emcee.EnsembleSampler(walkers, d, screened, moves=step_moves, vectorize=True)
        run.state = _rescored(run.state, screened)
    with progress.phase("sampling: adaptation stage", n, "steps") as shown:
        coords, lps, interrupted = _run_block(stage, run, n, request, _Tee(_NoBar(), shown))
    if screened is not None:
        run.state = _rescored(run.state, guarded)
    run.clock["adapt_s"] += time.perf_counter() - t0
    return None if interrupted else (np.array(coords), np.array(lps))


def _rescored(state: emcee.State, density) -> emcee.State:
    """``state`` with the log-densities of ``density`` at its walkers (its random state kept)."""
    coords = state.coords.copy()
    return emcee.State(coords, log_prob=density(coords), random_state=state.random_state)


def _checked(density, request: StopRequest, x: np.ndarray) -> np.ndarray | None:
    """The log-density (n,) at points x (n, d) off the chain (the coverage check,
    ``moves.coverage``, and the repair's 4000 draws), in batches of ``CHECK_BATCH`` points: in
    one batch of 4000 the exhaust's reduced solves (74 x 74 pencils, ~175 MB per stacked array,
    several arrays) cost 0.96 ms a point against 0.59 ms in batches of 1000; None after a stop
    request.

    ``density`` is the delayed-acceptance surrogate when the run has one (``sample_posterior``):
    these values only choose the frozen proposal, and any fixed proposal leaves the kept chain's
    target exact, while the surrogate is 4-5 times cheaper a point (the exhaust: 0.07 against
    0.30 ms in batches of 1000) and close to p (its delayed-acceptance second stage passes 99 %
    of what its first stage lets through).  A repair's 10,000 points then cost 0.7 s, not 3 s."""
    parts = []
    for start in range(0, x.shape[0], CHECK_BATCH):
        parts.append(density(x[start : start + CHECK_BATCH]))
        if request.requested():
            return None
    return np.concatenate(parts) if parts else np.empty(0)


def _first_run(log_posterior, calibration, initial, settings, space, resume, moves) -> _Run:
    """The run to continue: ``resume``'s, or a fresh one (also when ``resume`` was stopped
    while adapting: nothing was kept, so starting again from the seed gives the uninterrupted
    chain)."""
    if resume is not None and not _stopped_while_adapting(resume, moves, settings):
        return _resumed_run(resume, log_posterior, settings.walkers)
    return _fresh_run(log_posterior, calibration, initial, settings, space)


def _fit_masses(log_posterior) -> None:
    """The mass term's masses from their verified polynomial, in place (the target moves by
    < 3e-8 in log p, ``LogPosterior.use_fitted_mass``): an eighth of an exact batch otherwise;
    a density without a mass term (a user's callable, a test's screen) is left as it is."""
    fit_mass = getattr(log_posterior, "use_fitted_mass", None)
    if fit_mass is not None:
        fit_mass(seed=0)


def sample_posterior(
    log_posterior: LogPosterior,
    calibration: CalibrationResult | None = None,
    settings: SamplerSettings = SamplerSettings(),
    *,
    initial: np.ndarray | None = None,
    resume: SamplerState | None = None,
    checkpoint: Callable[[SamplerState], None] | None = None,
    screen: LogPosterior | None = None,
    moves: list | None = None,
    stop_request: StopRequest | None = None,
    executor=None,
) -> PosteriorResult:
    """Run emcee until steps >= min_autocorr_times * max(tau) and the convergence targets hold
    (``settings.target_rhat``, ``settings.target_ess``; None: not checked), or ``settings.steps``
    steps.

    log_posterior : vectorized, (n_walkers, d) -> (n_walkers,).  calibration : point optimum
    (walkers start around its distinct optima) unless ``initial`` (n_walkers, d) is given.
    settings : SamplerSettings (walkers, steps, seed, stop rule, transform, progress bar).
    checkpoint : called with a SamplerState after every block (write it to disk there).
    resume : a SamplerState from an interrupted run with the same settings.
    Ctrl-C (KeyboardInterrupt) ends the run after the last complete step: the result has
    ``interrupted=True`` and its ``state`` resumes it.
    executor : local worker processes (``compute.executors``) that evaluate half of each batch
    of 10 walkers or more while this process does the rest (``evaluators.split_densities``;
    other executors: every batch here); the chain is the serial run's bit for bit.
    screen : a cheap surrogate of ``log_posterior`` (same parameters; e.g. a coarser basis):
    delayed acceptance (``inference.delayed_acceptance``), only the proposals it passes get an
    exact evaluation, the chain still targets ``log_posterior`` exactly (``evaluations``:
    exact ones, ``screen_evaluations``: the surrogate's).  moves : emcee moves for the whole run (no
    adaptation; default: ``settings.moves``, see the module docstring); the scheme used is in
    ``diagnostics["moves"]``.
    stop_request : the run's ``compute.stop.StopRequest`` (set by a signal handler, checked
    between steps; a checkpoint write is not cut in half); None: nobody can stop this run.
    A mass term's masses come from their verified polynomial from here on (``_fit_masses``).
    """
    settings.check_walkers(log_posterior.ndim)
    _fit_masses(log_posterior)
    # one stop record: a signal (the handler), a Ctrl-C in the model or a density's error
    request = stop_request or StopRequest()
    space = sampler_space(log_posterior) if settings.transform == "logit" else None
    d = log_posterior.ndim
    split = split_densities((log_posterior, _fitted_screen(screen, d)), executor)
    run = _first_run(log_posterior, calibration, initial, settings, space, resume, moves)
    guarded, screened = _guarded(split, space, request, run.clock)
    _start(run, guarded, request)
    stage = partial(_adaptation_stage, run, settings.walkers, d, guarded, screened, request=request)
    checked = partial(_checked, guarded if screened is None else screened, request)
    kept = _kept_moves(moves, settings, run, log_posterior, stage, checked)
    if kept is None:  # stopped while adapting: an empty chain; a resume starts again
        _raise_failure(request)
        outcome = (True, False, np.full(d, np.inf))
    else:
        sampler = _ensemble(settings.walkers, d, guarded, kept, screened)
        outcome = _sample_blocks(sampler, run, log_posterior, settings, checkpoint, space, request)
        _raise_failure(request, run, checkpoint, log_posterior)
    result = _posterior_result(run, log_posterior, outcome, settings.seed, screened,
                               settings.target_ess)  # fmt: skip
    return _with_split_record(result, split)


def _guarded(split: tuple, space, request: StopRequest, clock):
    """(the exact density's guarded batch function, the screen's or None): each density of
    ``split`` (exact, screen or None) wrapped by ``_guard`` (the sampler's space, the stop
    request, timed in ``clock``)."""
    guard = partial(_guard, space=space, request=request, clock=clock)
    guarded = guard(split[0])
    return guarded, _screened(split[1], guarded, guard)


def _with_split_record(result: PosteriorResult, split) -> PosteriorResult:
    """``result`` with the split batches' record (``_split_record``) in its diagnostics
    ("split"), when the run split its batches."""
    record = _split_record(split)
    if record is None:
        return result
    return replace(result, diagnostics={**result.diagnostics, "split": record})
