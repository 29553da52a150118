"""Transitional Markov chain Monte Carlo (TMCMC; Ching & Chen 2007, J. Eng. Mech. 133, 816-832):
sequential Monte Carlo with likelihood tempering, the posterior and the model evidence.

The stage densities p_j(x) ∝ p(x) L(x)^beta_j run from the prior (beta_0 = 0) to the posterior
(beta_m = 1).  At each stage, with N equally weighted particles x_i from p_j:

1. beta_{j+1} = beta_j + db, db found by bisection so that the coefficient of variation of the
   plausibility weights w_i = L(x_i)^db is ``target_cov`` (1 in Ching & Chen, eq. 19), or
   beta_{j+1} = 1 when the step to 1 keeps it below that;
2. the evidence factor S_j = mean_i w_i, so log Z = sum_j log S_j (eq. 18; an unbiased
   estimate of Z);
3. systematic resampling by the normalized weights;
4. ``mcmc_steps`` Metropolis steps of every particle (vectorized over particles) targeting
   p_{j+1}, with a Gaussian proposal of covariance scale^2 Sigma_j, Sigma_j the weighted sample
   covariance of step 1's particles (eq. 21; Ching & Chen take scale = 0.2).  After every
   Metropolis step the scale is steered towards acceptance 0.234 (Roberts, Gelman & Gilks
   1997) from the whole population's acceptance a: scale <- scale clip(a / 0.234, 0.1, 2)
   (Betz, Papaioannou & Straub 2016, J. Eng. Mech. 142, 04016016, adapt it between stages).
   Each step is a Metropolis kernel with a fixed scale, so it leaves p_{j+1} invariant; the
   scale depends on the population's past only (adaptive SMC: Jasra, Stephens, Doucet &
   Tsagaris 2011, Scand. J. Stat. 38, 1-22).  On a rugged likelihood (the exhaust's MAC-paired
   shape block) a stage can start at acceptance ~0: a slower rule left the particles in place
   there and they lost the mode.

Particles whose log-likelihood is -inf (outside the prior, a failed model) get weight 0; the
CoV is taken over the particles with a finite log-likelihood, whose number caps the effective
sample size.  Stalls raise ``BayesUpdateError`` with one line: no particle with a finite
log-likelihood (effective sample size 0), or beta still below 1 after ``max_stages`` stages.
"""

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.special import logsumexp

from bayesupdate.compute.progress import phase
from bayesupdate.errors import BayesUpdateError

#: acceptance the proposal scale is steered to between stages
TARGET_ACCEPTANCE = 0.234


@dataclass(frozen=True)
class TMCMCSettings:
    """particles : N.  target_cov : CoV of the plausibility weights per stage (Ching & Chen: 1).
    mcmc_steps : Metropolis steps per particle per stage.  scale : initial proposal scale
    (None: 2.38 / sqrt(d), Gelman, Roberts & Gilks 1996).  max_stages : stall guard.
    seed : the one seed of every random draw."""

    particles: int = 1000
    target_cov: float = 1.0
    mcmc_steps: int = 5
    scale: float | None = None
    max_stages: int = 200
    seed: int = 0

    def __post_init__(self):
        if self.particles < 10:
            raise BayesUpdateError(f"tmcmc.particles: need >= 10, got {self.particles}")
        if not (self.target_cov > 0 and np.isfinite(self.target_cov)):
            raise BayesUpdateError(f"tmcmc.target_cov: must be > 0, got {self.target_cov}")
        if self.mcmc_steps < 1:
            raise BayesUpdateError(f"tmcmc.mcmc_steps: need >= 1, got {self.mcmc_steps}")
        if self.scale is not None and not self.scale > 0:
            raise BayesUpdateError(f"tmcmc.scale: must be > 0, got {self.scale}")
        if self.max_stages < 1:
            raise BayesUpdateError(f"tmcmc.max_stages: need >= 1, got {self.max_stages}")


@dataclass(frozen=True)
class TMCMCResult:
    """samples : (N, d) equally weighted posterior particles.  log_likelihood : (N,) theirs.
    log_evidence : log Z [nats].  betas : (m + 1,) tempering schedule, 0 ... 1.
    ess : (m,) effective sample size of each stage's weights (before resampling).
    acceptance : (m,) mean Metropolis acceptance of each stage.  scales : (m,) proposal scale
    at the start of each stage.  evaluations : log-likelihood evaluations."""

    samples: np.ndarray
    log_likelihood: np.ndarray
    log_evidence: float
    betas: np.ndarray
    ess: np.ndarray
    acceptance: np.ndarray
    scales: np.ndarray
    evaluations: int

    @property
    def stages(self) -> int:
        return int(self.ess.size)


def _cov_of_weights(dbeta: float, loglike: np.ndarray) -> float:
    """CoV of w = exp(dbeta (L - max L)) over the finite log-likelihoods ``loglike`` (n,)."""
    w = np.exp(dbeta * (loglike - loglike.max()))
    return float(np.std(w) / np.mean(w))


def next_beta(beta: float, loglike: np.ndarray, target_cov: float) -> float:
    """beta_{j+1} by bisection on db in (0, 1 - beta] (module docstring, step 1).
    loglike : (N,) log-likelihoods of the particles; only the finite ones count."""
    finite = loglike[np.isfinite(loglike)]
    if _cov_of_weights(1.0 - beta, finite) <= target_cov:
        return 1.0
    low, high = 0.0, 1.0 - beta
    for _ in range(100):  # CoV grows with db; 100 halvings reach the float resolution of db
        mid = 0.5 * (low + high)
        if _cov_of_weights(mid, finite) > target_cov:
            high = mid
        else:
            low = mid
    # low = 0 only if even the smallest tried step overshoots: take that step
    return beta + (low if low > 0 else high)


def _systematic(weights: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """(N,) indices by systematic resampling of normalized ``weights`` (N,)."""
    n = weights.size
    positions = (rng.uniform() + np.arange(n)) / n
    cumulative = np.cumsum(weights)
    cumulative[-1] = 1.0
    return np.searchsorted(cumulative, positions)


def _evaluate(log_prior, log_likelihood, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """(log prior (n,), log-likelihood (n,), evaluations): the likelihood only where the prior
    is positive; NaN counts as -inf."""
    lp = np.asarray(log_prior(x), dtype=float)
    ll = np.full(x.shape[0], -np.inf)
    inside = np.isfinite(lp)
    if np.any(inside):
        ll[inside] = np.asarray(log_likelihood(x[inside]), dtype=float)
    ll = np.where(np.isnan(ll), -np.inf, ll)
    return lp, ll, int(np.sum(inside))


def _metropolis(x, lp, ll, beta, chol, scale, steps, rng, log_prior, log_likelihood):
    """``steps`` vectorized random-walk Metropolis steps at temperature beta; x (N, d); the
    proposal sd scale chol (chol: Cholesky factor of the weighted covariance), the scale
    adapted after each step (module docstring).  Returns x, lp, ll, mean acceptance, the next
    stage's scale, evaluations."""
    accepted = 0
    evaluations = 0
    for _ in range(steps):
        proposal = x + scale * (rng.standard_normal(x.shape) @ chol.T)
        lp_new, ll_new, count = _evaluate(log_prior, log_likelihood, proposal)
        evaluations += count
        with np.errstate(invalid="ignore"):  # -inf - -inf where both are out: rejected
            log_ratio = (lp_new + beta * ll_new) - (lp + beta * ll)
        accept = np.log(rng.uniform(size=x.shape[0])) < np.nan_to_num(log_ratio, nan=-np.inf)
        x = np.where(accept[:, None], proposal, x)
        lp = np.where(accept, lp_new, lp)
        ll = np.where(accept, ll_new, ll)
        accepted += int(accept.sum())
        scale = scale * float(np.clip(accept.mean() / TARGET_ACCEPTANCE, 0.1, 2.0))
    return x, lp, ll, accepted / (steps * x.shape[0]), scale, evaluations


def _proposal_cholesky(x: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """Cholesky factor (d, d) of the weighted covariance of x (N, d) (eq. 21), with a
    relative jitter so a collapsed direction still moves."""
    mean = weights @ x
    centred = x - mean
    cov = (weights[:, None] * centred).T @ centred
    jitter = 1e-12 * (np.trace(cov) / cov.shape[0] + 1e-300)
    return np.linalg.cholesky(cov + jitter * np.eye(cov.shape[0]))


def tmcmc(
    prior_sample: Callable[[np.random.Generator, int], np.ndarray],
    log_prior: Callable[[np.ndarray], np.ndarray],
    log_likelihood: Callable[[np.ndarray], np.ndarray],
    settings: TMCMCSettings = TMCMCSettings(),
    progress: Callable[[int, float], None] | None = None,
) -> TMCMCResult:
    """TMCMC posterior and log evidence (module docstring).

    prior_sample(rng, n) -> (n, d) prior draws; log_prior (n, d) -> (n,) normalized log prior
    density (-inf outside its support); log_likelihood (n, d) -> (n,) (batched over particles).
    progress(stage, beta) is called after each stage when given; the stages are also the
    ``compute.progress`` phase "TMCMC: tempering stages".
    Seeded by ``settings.seed``: the same inputs give bit-identical results."""
    rng = np.random.default_rng(settings.seed)
    x = np.atleast_2d(np.asarray(prior_sample(rng, settings.particles), dtype=float))
    n, d = x.shape
    lp, ll, evaluations = _evaluate(log_prior, log_likelihood, x)
    scale = settings.scale if settings.scale is not None else 2.38 / np.sqrt(d)
    beta, log_z = 0.0, 0.0
    betas, ess, acceptance, scales = [0.0], [], [], []
    with phase("TMCMC: tempering stages", None, "stages") as shown:
        while beta < 1.0:
            _check_stage(beta, ll, len(ess), settings)
            new_beta = next_beta(beta, ll, settings.target_cov)
            log_w = np.where(np.isfinite(ll), (new_beta - beta) * ll, -np.inf)
            log_z += float(logsumexp(log_w) - np.log(n))
            weights = np.exp(log_w - logsumexp(log_w))
            ess.append(float(1.0 / np.sum(weights**2)))
            chol = _proposal_cholesky(x, weights)
            keep = _systematic(weights, rng)
            scales.append(scale)
            x, lp, ll, acc, scale, count = _metropolis(
                x[keep], lp[keep], ll[keep], new_beta, chol, scale, settings.mcmc_steps, rng,
                log_prior, log_likelihood,
            )  # fmt: skip
            evaluations += count
            acceptance.append(acc)
            beta = new_beta
            betas.append(beta)
            shown.advance()
            if progress is not None:
                progress(len(ess), beta)
    return TMCMCResult(
        samples=x,
        log_likelihood=ll,
        log_evidence=log_z,
        betas=np.array(betas),
        ess=np.array(ess),
        acceptance=np.array(acceptance),
        scales=np.array(scales),
        evaluations=evaluations,
    )


def _check_stage(beta: float, ll: np.ndarray, stages: int, settings: TMCMCSettings) -> None:
    """Refuse a tempering that stalls: ``stages`` done at ``beta`` reach ``max_stages``, or no
    particle's log-likelihood ``ll`` (n,) is finite."""
    if stages >= settings.max_stages:
        raise BayesUpdateError(
            f"tmcmc: tempering stalled at beta = {beta:.3g} after {stages} stages; "
            "raise tmcmc.max_stages or particles, or check the likelihood's scale"
        )
    if not np.any(np.isfinite(ll)):
        raise BayesUpdateError(
            f"tmcmc: tempering stalled at beta = {beta:.3g}: no particle has a finite "
            "log-likelihood (effective sample size 0); check the model and the prior bounds"
        )
