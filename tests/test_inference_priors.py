"""Priors: log densities against scipy.stats truncated distributions, and bad priors."""

import numpy as np
import pytest
from scipy import stats

from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference import Prior, prior_from_mapping

X = np.linspace(0.55, 2.9, 9)
BOUNDS = (0.5, 3.0)


def _scipy(prior: Prior):
    """The untruncated scipy.stats distribution a prior stands for."""
    p, (low, high) = prior.params, prior.bounds
    return {
        "uniform": lambda: stats.uniform(loc=low, scale=high - low),
        "normal": lambda: stats.norm(loc=p["mean"], scale=p["sd"]),
        "lognormal": lambda: stats.lognorm(s=p["sigma"], scale=np.exp(p["mu"])),
        "halfnormal": lambda: stats.halfnorm(scale=p["scale"]),
    }[prior.kind]()


def _truncated(dist, x, low, high):
    return dist.logpdf(x) - np.log(dist.cdf(high) - dist.cdf(low))


def test_uniform():
    prior = prior_from_mapping({"kind": "uniform"}, BOUNDS)
    np.testing.assert_allclose(prior.logpdf(X), stats.uniform(0.5, 2.5).logpdf(X), rtol=1e-12)


def test_normal_is_truncated_normal():
    prior = prior_from_mapping({"kind": "normal", "mean": 1.0, "sd": 0.4}, BOUNDS)
    a, b = (0.5 - 1.0) / 0.4, (3.0 - 1.0) / 0.4
    np.testing.assert_allclose(
        prior.logpdf(X), stats.truncnorm(a, b, loc=1.0, scale=0.4).logpdf(X), rtol=1e-10
    )


def test_lognormal_by_mu_sigma_of_the_log():
    prior = prior_from_mapping({"kind": "lognormal", "mu": 0.2, "sigma": 0.5}, BOUNDS)
    dist = stats.lognorm(s=0.5, scale=np.exp(0.2))
    np.testing.assert_allclose(prior.logpdf(X), _truncated(dist, X, *BOUNDS), rtol=1e-10)


def test_halfnormal_for_sigma():
    prior = prior_from_mapping({"kind": "halfnormal", "scale": 0.1}, (0.0, np.inf))
    x = np.array([0.001, 0.05, 0.2, 0.5])
    np.testing.assert_allclose(prior.logpdf(x), stats.halfnorm(scale=0.1).logpdf(x), rtol=1e-10)
    assert prior.logpdf(np.array([-0.01]))[0] == -np.inf


def test_outside_bounds_is_minus_infinity():
    prior = prior_from_mapping({"kind": "normal", "mean": 1.0, "sd": 0.4}, BOUNDS)
    assert np.all(prior.logpdf(np.array([0.49, 3.01])) == -np.inf)


def test_samples_follow_the_truncated_prior():
    prior = prior_from_mapping({"kind": "lognormal", "mu": 0.2, "sigma": 0.5}, BOUNDS)
    draws = prior.sample(np.random.default_rng(0), 20000)
    assert draws.min() >= 0.5 and draws.max() <= 3.0
    grid = np.linspace(0.5, 3.0, 20001)
    p = np.exp(prior.logpdf(grid))
    mean = np.trapezoid(grid * p, grid)
    assert draws.mean() == pytest.approx(mean, abs=0.01)


@pytest.mark.parametrize(
    "spec, bounds",
    [
        ({"kind": "uniform"}, BOUNDS),
        ({"kind": "normal", "mean": 1.0, "sd": 0.4}, BOUNDS),
        ({"kind": "lognormal", "mu": 0.2, "sigma": 0.5}, BOUNDS),
        ({"kind": "halfnormal", "scale": 0.1}, (0.0, np.inf)),
    ],
)
def test_closed_form_quantile_is_scipys_ppf_to_the_bit(spec, bounds):
    """Prior.quantile (the mixture proposal's prior draws) is scipy's ppf without its checks:
    the same numbers, so the same chains, including the ends 0 and 1."""
    prior = prior_from_mapping(spec, bounds)
    u = np.concatenate([[0.0, 1e-300, 1e-12, 0.5, 1 - 1e-12, 1.0], np.linspace(0.001, 0.999, 999)])
    assert np.array_equal(prior.quantile(u), _scipy(prior).ppf(u))


@pytest.mark.parametrize(
    "spec, bounds",
    [
        ({"kind": "uniform"}, BOUNDS),
        ({"kind": "uniform"}, (-2.5e-3, 7.25e4)),
        ({"kind": "normal", "mean": 1.0, "sd": 0.4}, BOUNDS),
        ({"kind": "normal", "mean": -3.0, "sd": 1e-3}, (-np.inf, np.inf)),
        ({"kind": "lognormal", "mu": 0.2, "sigma": 0.5}, BOUNDS),
        ({"kind": "lognormal", "mu": -1.0, "sigma": 2.0}, (0.0, np.inf)),
        ({"kind": "halfnormal", "scale": 0.1}, (0.0, np.inf)),
        ({"kind": "halfnormal", "scale": 3.0}, (0.5, 4.0)),
    ],
)
def test_closed_form_cdf_is_scipys_cdf_to_the_bit(spec, bounds):
    """Prior.cdf (the truncation constant of every prior) is scipy.stats' cdf without
    importing scipy.stats: the same numbers inside, at and outside the support and bounds."""
    prior = prior_from_mapping(spec, bounds)
    grid = np.linspace(-4.0, 6.0, 1001)
    x = np.concatenate([[-np.inf, -1.0, 0.0, 1e-300, *bounds, np.inf, np.nan], grid, 10.0**grid])
    dist = _scipy(prior)
    assert np.array_equal([prior.cdf(v) for v in x], dist.cdf(x), equal_nan=True)
    assert prior.cdf_range() == (dist.cdf(bounds[0]), dist.cdf(bounds[1]))


def test_prior_with_no_support_inside_bounds_is_an_error():
    with pytest.raises(BayesUpdateError, match="no support inside bounds"):
        prior_from_mapping({"kind": "normal", "mean": 50.0, "sd": 0.1}, BOUNDS, "t_hot_pipe")


@pytest.mark.parametrize(
    "spec, match",
    [
        ({"kind": "gamma"}, "unknown kind"),
        ({"kind": "normal", "mean": 1.0}, "missing"),
        ({"kind": "normal", "mean": 1.0, "sd": -1.0}, "sd must be > 0"),
        ({"kind": "uniform", "low": 1.0}, "unknown"),
        ({"mean": 1.0}, "kind"),
    ],
)
def test_bad_prior_specs(spec, match):
    with pytest.raises(BayesUpdateError, match=match):
        prior_from_mapping(spec, BOUNDS, "x")


def test_inverted_bounds_are_an_error():
    with pytest.raises(BayesUpdateError, match="low < high"):
        Prior("uniform", (2.0, 1.0))
