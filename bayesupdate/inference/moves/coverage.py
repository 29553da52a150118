"""How well a frozen proposal g covers the posterior p: the importance-weight ESS of draws from g.

With y_i ~ g (i = 1..n) and weights w_i = p(y_i) / g(y_i) (p unnormalized), Kish's effective
sample size fraction

    ess = (sum w)^2 / (n sum w^2)  ~  1 / E_g[(p / (Z g))^2] = 1 / E_p[p / (Z g)],

Z = E_g[w] (Kong 1992; Owen 2013, "Monte Carlo theory, methods and examples", sec. 9.3) is 1
when g = p and small when g misses part of p's mass.  For an independence Metropolis-Hastings
chain with proposal g it measures what matters: a walker at x leaves with probability about
E_g[min(1, w(y) / w(x))], about Z / w(x) where p / g is large, so E_p[w / Z] = 1 / ess is the
mean holding time scale of walkers in the regions g under-covers (Mengersen & Tweedie 1996:
the chain's convergence rate is 1 - Z / sup w).  It is computed before the kept run starts, from
draws independent of the chain, so deciding on it does not touch the chain's validity.
"""

import numpy as np

#: draws from g used to judge it
COVERAGE_DRAWS = 1000
#: w / Z above this: an independence proposal accepted less than about once in this many tries
STUCK_RATIO = 10.0


def _log_weights(log_p: np.ndarray, log_g: np.ndarray) -> np.ndarray:
    """log p - log g, -inf where either is not finite (a draw beyond a bound: -inf - -inf)."""
    with np.errstate(invalid="ignore"):
        return np.where(np.isfinite(log_p) & np.isfinite(log_g), log_p - log_g, -np.inf)


def importance_ess(log_p: np.ndarray, log_g: np.ndarray) -> float:
    """Kish's ESS fraction (module docstring) of log weights log_p - log_g, both (n,); non-finite
    log_p (a failed model or a point outside the support) is a zero weight; 0.0 when every
    weight is zero."""
    log_w = _log_weights(log_p, log_g)
    if not np.any(np.isfinite(log_w)):
        return 0.0
    w = np.exp(log_w - np.max(log_w))
    return float(w.sum() ** 2 / (w.size * np.sum(w**2)))


def stuck_share(log_p_chain, log_g_chain, log_p, log_g, ratio: float = STUCK_RATIO) -> float:
    """The share of chain draws x_j ~ p ((m,) log p and log g at them) where w(x_j) / Z >
    ``ratio``, Z = mean w over draws from g ((n,) log p and log g at them): where an
    independence proposal is accepted less than about once in ``ratio`` tries."""
    log_w = _log_weights(log_p, log_g)
    if not np.any(np.isfinite(log_w)):
        return 1.0
    top = np.max(log_w)
    log_z = top + np.log(np.mean(np.exp(log_w - top)))
    return float(np.mean(np.asarray(log_p_chain) - np.asarray(log_g_chain) - log_z > np.log(ratio)))


def proposal_coverage(
    proposal, log_density, seed: int, chain=None, n: int = COVERAGE_DRAWS
) -> dict | None:
    """{"ess": the importance ESS fraction of ``n`` draws from ``proposal``
    (``DefensiveProposal``, in the sampler's coordinates) against ``log_density`` ((n, d) ->
    (n,) log p in the same coordinates, or None when the run was stopped meanwhile: then None),
    "stuck": ``stuck_share`` of ``chain`` = (points (m, d), log p (m,)) or None}.  The draws
    come from their own seeded generator, so the chain's random stream is the same whether this
    runs or not."""
    y = proposal.sample(np.random.default_rng([seed, 11]), n)
    log_p = log_density(y)
    if log_p is None:
        return None
    log_p, log_g = np.asarray(log_p, dtype=float), proposal.logpdf(y)
    stuck = None
    if chain is not None:
        stuck = stuck_share(chain[1], proposal.logpdf(chain[0]), log_p, log_g)
    return {"ess": importance_ess(log_p, log_g), "stuck": stuck}
