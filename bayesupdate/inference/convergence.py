"""Rank-normalized split R-hat, bulk and tail ESS and the nearest-sample HDI, in numpy.

Vehtari, Gelman, Simpson, Carpenter & Buerkner (2021), "Rank-normalization, folding, and
localization: an improved R-hat for assessing convergence of MCMC", Bayesian Analysis 16(2)
667-718: every statistic below is that paper's, computed as ArviZ computes it (the arviz-stats
1.x array functions ``rhat(method="rank")``, ``ess(method="bulk" | "tail")``, ``hdi(method=
"nearest")``; ``tests/test_inference_convergence.py`` holds them to ArviZ's values to 1e-10).

Why not ArviZ itself: the sampler checks its stop rule tens of times a run, and importing
arviz-stats (xarray, pandas) cost ~1 s of a ~25 s exhaust posterior on the development machine,
so ``bayesupdate sample`` no longer imports it (exporting a result to ArviZ still does,
``results.to_datatree``).

Chains are rows: x (n_chains, n_draws) for one parameter; ``rank_rhat`` / ``bulk_ess`` /
``tail_ess`` of a chain (n_draws, n_walkers, d) loop over the d parameters.

- z-scale: ranks over all draws (ties averaged), r -> Phi^-1((r - 3/8) / (S + 1/4)) (Blom 1958).
- split: the first and last n_draws // 2 draws of each chain as two chains.
- R-hat of chains with n draws: sqrt((B / W + n - 1) / n), B = n var(chain means), W the mean
  chain variance; the rank R-hat is the larger of the split z-scaled draws' and the split
  z-scaled |draws - median|'s.
- ESS: S / tau with tau = -1 + 2 sum rho_t by Geyer's initial positive and monotone sequences
  over the chains' mean autocovariance (FFT), tau at least 1 / log10(S); bulk on the split
  z-scaled draws, tail the smaller of the quantile ESS (indicator draws <= the 5 % and 95 %
  quantiles, split) at the two probabilities.
"""

import numpy as np
from scipy.fft import irfft, next_fast_len, rfft
from scipy.special import ndtri


def average_ranks(x: np.ndarray) -> np.ndarray:
    """Ranks 1..S of all S entries of x, ties given their mean rank, same shape as x; all NaN
    if any entry is NaN.  ``scipy.stats.rankdata(x, method="average")`` (the same numbers: each
    rank is an integer or half-integer, exact in float64) without importing scipy.stats."""
    flat = np.ravel(x)
    if np.isnan(flat).any():
        return np.full(x.shape, np.nan)
    order = np.argsort(flat, kind="stable")
    ordered = flat[order]
    starts = np.r_[True, ordered[1:] != ordered[:-1]]  # where a group of ties begins
    first = np.flatnonzero(starts)  # each group's first place, 0-based
    last = np.r_[first[1:], flat.size]  # its last place, 1-based
    ranks = np.empty(flat.size)
    ranks[order] = (0.5 * (first + 1 + last))[np.cumsum(starts) - 1]
    return ranks.reshape(x.shape)


def z_scale(x: np.ndarray) -> np.ndarray:
    """Rank-normalized draws, same shape as x: ranks over all of x, ties averaged."""
    return ndtri((average_ranks(x) - 0.375) / (x.size + 0.25))


def split_chains(x: np.ndarray) -> np.ndarray:
    """(2 m, n // 2): each of the m chains of x (m, n) cut into its first and last halves."""
    half = x.shape[1] // 2
    return np.vstack((x[:, :half], x[:, -half:]))


def basic_rhat(x: np.ndarray) -> float:
    """R-hat of chains x (m, n) as they are (no split, no ranks)."""
    n = x.shape[1]
    between = n * np.var(np.mean(x, axis=1), ddof=1)
    within = np.mean(np.var(x, axis=1, ddof=1))
    return float(np.sqrt((between / within + n - 1) / n))


def _valid(x: np.ndarray, min_chains: int) -> bool:
    return x.shape[0] >= min_chains and x.shape[1] >= 4 and not np.isnan(x).any()


def rank_rhat_of(x: np.ndarray) -> float:
    """Rank-normalized split R-hat of chains x (m, n) (module docstring); NaN for fewer than 2
    chains or 4 draws, or NaN draws."""
    if not _valid(x, 2):
        return np.nan
    split = split_chains(x)
    bulk = basic_rhat(z_scale(split))
    tail = basic_rhat(z_scale(np.abs(split - np.median(split))))
    return max(bulk, tail)


def _autocov(x: np.ndarray) -> np.ndarray:
    """(m, n) autocovariance of each chain at every lag (FFT, biased: divided by n)."""
    n = x.shape[1]
    centred = x - x.mean(axis=1, keepdims=True)
    f = rfft(centred, n=next_fast_len(2 * n), axis=1)
    return irfft(f * np.conjugate(f), n=next_fast_len(2 * n), axis=1)[:, :n] / n


def basic_ess(x: np.ndarray) -> float:
    """ESS of chains x (m, n) as they are: Geyer's initial positive, then monotone sequence
    (module docstring)."""
    x = np.asarray(x, dtype=float)
    if np.max(x) - np.min(x) < np.finfo(float).resolution:
        return float(x.size)
    m, n = x.shape
    acov = _autocov(x).mean(axis=0)
    mean_var = acov[0] * n / (n - 1.0)
    var_plus = mean_var * (n - 1.0) / n
    if m > 1:
        var_plus += np.var(x.mean(axis=1), ddof=1)
    rho = np.zeros(n)
    rho[0] = even = 1.0
    rho[1] = odd = 1.0 - (mean_var - acov[1]) / var_plus
    t = 1
    while t < n - 3 and even + odd > 0.0:
        even = 1.0 - (mean_var - acov[t + 1]) / var_plus
        odd = 1.0 - (mean_var - acov[t + 2]) / var_plus
        if even + odd >= 0:
            rho[t + 1], rho[t + 2] = even, odd
        t += 2
    max_t = t - 2
    if even > 0:
        rho[max_t + 1] = even
    t = 1
    while t <= max_t - 2:
        if rho[t + 1] + rho[t + 2] > rho[t - 1] + rho[t]:
            rho[t + 1] = rho[t + 2] = (rho[t - 1] + rho[t]) / 2.0
        t += 2
    tau = -1.0 + 2.0 * np.sum(rho[: max_t + 1]) + np.sum(rho[max_t + 1 : max_t + 2])
    tau = max(tau, 1.0 / np.log10(m * n))
    return np.nan if np.isnan(rho).any() else float(m * n / tau)


def bulk_ess_of(x: np.ndarray) -> float:
    """Bulk ESS of chains x (m, n): ``basic_ess`` of the split, z-scaled draws."""
    if not _valid(x, 1):
        return np.nan
    return basic_ess(z_scale(split_chains(x)))


def tail_ess_of(x: np.ndarray, prob: tuple[float, float] = (0.05, 0.95)) -> float:
    """Tail ESS of chains x (m, n): the smaller quantile ESS at the two probabilities."""
    if not _valid(x, 1):
        return np.nan
    return min(basic_ess(split_chains(x <= np.quantile(x, p))) for p in prob)


def _per_parameter(function, chain: np.ndarray) -> np.ndarray:
    """(d,) ``function`` of each parameter's walkers as chains, chain (n_draws, n_walkers, d)."""
    by_chain = np.moveaxis(np.asarray(chain, dtype=float), 1, 0)  # (walkers, draws, d)
    return np.array([function(by_chain[:, :, j]) for j in range(by_chain.shape[-1])])


def rank_rhat(chain: np.ndarray) -> np.ndarray:
    """(d,) rank-normalized split R-hat, walkers as chains, chain (n_draws, n_walkers, d)."""
    return _per_parameter(rank_rhat_of, chain)


def bulk_ess(chain: np.ndarray) -> np.ndarray:
    """(d,) bulk ESS, walkers as chains, chain (n_draws, n_walkers, d)."""
    return _per_parameter(bulk_ess_of, chain)


def tail_ess(chain: np.ndarray, prob: tuple[float, float] = (0.05, 0.95)) -> np.ndarray:
    """(d,) tail ESS at ``prob``, walkers as chains, chain (n_draws, n_walkers, d)."""
    return _per_parameter(lambda x: tail_ess_of(x, prob), chain)


def hdi_nearest(draws: np.ndarray, prob: float) -> np.ndarray:
    """(2,) the narrowest interval between two draws holding floor(prob n) + 1 of the n draws
    (ArviZ's "nearest" HDI of a unimodal sample)."""
    x = np.sort(np.ravel(draws))
    n = x.size
    inc = min(int(np.floor(prob * n)), n - 1)
    widths = x[inc:] - x[: n - inc]
    k = int(np.argmin(widths))
    return np.array([x[k], x[k + inc]])
