"""``inference.convergence`` against ArviZ (arviz-stats 1.x, the peer it reimplements): R-hat,
bulk and tail ESS and the HDI of chains that mix well, badly, stick (repeated values: ties in
the ranks) and disagree, to 1e-10."""

import arviz_stats
import numpy as np
import pytest

from bayesupdate.inference import convergence


def _chains(kind: str, seed: int = 0) -> np.ndarray:
    """(n_draws, n_walkers, d) = (301, 12, 3) chains (an odd draw count: the split drops one)."""
    rng = np.random.default_rng(seed)
    e = rng.standard_normal((301, 12, 3))
    if kind == "white":
        return e
    x = np.empty_like(e)
    x[0] = e[0]
    for t in range(1, 301):  # AR(1), rho = 0.9: tau ~ 19
        x[t] = 0.9 * x[t - 1] + np.sqrt(1 - 0.81) * e[t]
    if kind == "sticky":  # a rejected move repeats the draw: ties
        keep = rng.random(x.shape) < 0.7
        for t in range(1, 301):
            x[t] = np.where(keep[t], x[t - 1], x[t])
    if kind == "shifted":  # a third of the walkers elsewhere: R-hat far above 1
        x[:, :4] += 1.5
    return x


@pytest.mark.parametrize("kind", ["white", "ar1", "sticky", "shifted"])
def test_rhat_ess_and_hdi_equal_arviz(kind):
    chain = _chains(kind)
    by_chain = np.moveaxis(chain, 1, 0)
    rhat = arviz_stats.rhat(by_chain, chain_axis=0, draw_axis=1)
    bulk = arviz_stats.ess(by_chain, chain_axis=0, draw_axis=1)
    tail = arviz_stats.ess(by_chain, method="tail", prob=(0.05, 0.95), chain_axis=0, draw_axis=1)
    np.testing.assert_allclose(convergence.rank_rhat(chain), rhat, rtol=1e-10)
    np.testing.assert_allclose(convergence.bulk_ess(chain), bulk, rtol=1e-10)
    np.testing.assert_allclose(convergence.tail_ess(chain), tail, rtol=1e-10)
    flat = chain.reshape(-1, 3)
    for j in range(3):
        np.testing.assert_array_equal(
            convergence.hdi_nearest(flat[:, j], 0.9), arviz_stats.hdi(flat[:, j], prob=0.9)
        )


def test_the_statistics_say_what_the_chains_are():
    # independent draws: R-hat ~ 1, ESS ~ the draw count; AR(1) 0.9: ESS ~ S (1 - rho) / (1 + rho)
    white, ar1 = _chains("white"), _chains("ar1")
    assert np.all(convergence.rank_rhat(white) < 1.01)
    assert np.all(convergence.bulk_ess(white) > 0.8 * 300 * 12)
    s = 300 * 12 * (1 - 0.9) / (1 + 0.9)  # 189
    assert np.all((convergence.bulk_ess(ar1) > 0.6 * s) & (convergence.bulk_ess(ar1) < 1.6 * s))
    assert np.all(convergence.rank_rhat(_chains("shifted")) > 1.1)
    # too few draws or NaN: no statistic
    assert np.isnan(convergence.rank_rhat(white[:3])).all()
    nan = white.copy()
    nan[5, 2, 0] = np.nan
    assert np.isnan(convergence.bulk_ess(nan)[0]) and np.isfinite(convergence.bulk_ess(nan)[1])
    # a constant chain: ESS is its size, as ArviZ says
    constant = np.ones((40, 4, 1))
    assert convergence.bulk_ess(constant)[0] == 160
    assert arviz_stats.ess(np.moveaxis(constant, 1, 0), chain_axis=0, draw_axis=1)[0] == 160


@pytest.mark.parametrize("kind", ["white", "sticky"])
def test_average_ranks_are_scipys_rankdata_to_the_bit(kind):
    """The z-scale's ranks (ties averaged; a NaN anywhere makes all NaN) are scipy.stats'
    ``rankdata(method="average")`` without importing scipy.stats: the same numbers."""
    from scipy.stats import rankdata

    x = np.round(_chains(kind, seed=3)[:, :, 0], 2)  # rounded: many ties, sticky or not
    x[5, 2], x[9, 4] = np.inf, -0.0
    assert np.array_equal(convergence.average_ranks(x), rankdata(x).reshape(x.shape))
    x[7, 1] = np.nan
    assert np.array_equal(convergence.average_ranks(x), rankdata(x).reshape(x.shape), True)
