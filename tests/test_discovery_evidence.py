"""Evidence maths of discovery against closed forms: Laplace = exact evidence of a linear-Gaussian
model, the sigma-marginal likelihood = quadrature, PSIS-LOO = exact leave-one-out predictive."""

from dataclasses import replace

import numpy as np
import pytest
from scipy import stats

from bayesupdate.discovery.evidence import (
    FitSpace,
    ModelFit,
    laplace,
    laplace_loo,
)
from bayesupdate.discovery.flagging import flag_modes
from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.likelihood_blocks import SIGMA_FLOOR, NoiseModel, noise_model
from bayesupdate.inference.parameter_space import ParameterSpec
from bayesupdate.inference.priors import prior_from_mapping
from bayesupdate.modal_data import ModalData

TAU = 2.0


def _linear_case(seed=0, m=10, d=2):
    """y = J theta + noise (unit sd), prior theta_j ~ N(0, TAU^2) on a wide box (+-40 TAU)."""
    rng = np.random.default_rng(seed)
    jac = rng.normal(size=(m, d))
    y = jac @ rng.normal(scale=TAU, size=d) + rng.normal(size=m)
    axes = tuple(
        ParameterSpec(
            f"p{j}",
            (-40 * TAU, 40 * TAU),
            prior_from_mapping({"kind": "normal", "mean": 0.0, "sd": TAU}, (-40 * TAU, 40 * TAU)),
            axis="linear",
        )
        for j in range(d)
    )
    noise = NoiseModel(np.ones(m), np.ones(m), False, "fixed", 1.0)
    space = FitSpace(None, axes, noise)
    a = jac.T @ jac + np.eye(d) / TAU**2
    theta_map = np.linalg.solve(a, jac.T @ y)
    return space, jac, y, theta_map


def test_laplace_is_exact_for_a_linear_gaussian_model():
    space, jac, y, theta_map = _linear_case()
    r = jac @ theta_map - y  # residuals are model - data
    result = laplace(space, theta_map, r, jac)
    m = y.size
    exact = stats.multivariate_normal(np.zeros(m), np.eye(m) + TAU**2 * jac @ jac.T).logpdf(y)
    assert result.log_evidence == pytest.approx(exact, abs=1e-6)


def test_laplace_caps_an_unconstrained_parameter_at_its_prior_volume():
    """A parameter the data do not see contributes log(1) = 0: its prior integrates to one."""
    space, jac, y, theta_map = _linear_case(d=2)
    blind = np.column_stack([jac[:, 0], np.zeros(y.size)])  # second parameter has no effect
    a = blind.T @ blind + np.eye(2) / TAU**2
    theta = np.linalg.solve(a, blind.T @ y)
    one = laplace(
        FitSpace(None, space.axes[:1], space.noise),
        theta[:1],
        blind[:, :1] @ theta[:1] - y,
        blind[:, :1],
    )
    two = laplace(space, theta, blind @ theta - y, blind)
    assert two.log_evidence == pytest.approx(one.log_evidence, abs=1e-6)


def test_inferred_noise_is_a_fixed_gaussian_at_the_robust_level():
    """The inferred level is fixed (plug-in): log L is the Gaussian density at that level, so
    moving every residual from 0.2 to 8 levels costs m (8^2 - 0.2^2) / 2 nats, not the
    m/2 ln(R ratio) of a level integrated out at every point (module docstring)."""
    rng = np.random.default_rng(3)
    m = 12
    f = np.linspace(10.0, 100.0, m)
    e0 = 2e-5 * rng.choice([-1.0, 1.0], size=m)  # identified null data: 0.002 % errors
    noise = noise_model(ModalData(f), e0, n_params=5)
    assert noise.inferred and noise.sigma == SIGMA_FLOOR  # the robust level is floored
    likelihood = FitSpace(None, (), noise).likelihood
    r0 = noise.residuals(e0)
    expected = np.sum(stats.norm.logpdf(e0, scale=SIGMA_FLOOR))
    assert likelihood.log_likelihood(r0) == pytest.approx(expected, rel=1e-12)
    dragged = noise.residuals(np.full(m, -8e-4))
    cost = likelihood.log_likelihood(r0) - likelihood.log_likelihood(dragged)
    assert cost == pytest.approx(0.5 * m * (64 - 0.04), rel=1e-9)
    assert cost > 10 * 0.5 * m * np.log(64)


def test_laplace_loo_matches_exact_leave_one_out():
    space, jac, y, theta_map = _linear_case(seed=5, m=12)
    r = jac @ theta_map - y
    best = laplace(space, theta_map, r, jac)
    fit = ModelFit(
        "linear",
        None,
        None,
        ("p0", "p1"),
        theta_map,
        r,
        y,
        0.0,
        [best],
        best.log_evidence,
        0,
        0.0,
        space,
    )
    loo = laplace_loo(fit, draws=4000, seed=1)
    exact = 0.0
    for i in range(y.size):
        keep = np.arange(y.size) != i
        a = jac[keep].T @ jac[keep] + np.eye(2) / TAU**2
        cov = np.linalg.inv(a)
        mean = cov @ jac[keep].T @ y[keep]
        var = 1.0 + jac[i] @ cov @ jac[i]
        exact += stats.norm.logpdf(y[i], jac[i] @ mean, np.sqrt(var))
    assert loo["elpd"] == pytest.approx(exact, abs=0.15)
    assert loo["pareto_k_max"] < 0.7
    # PSIS smooths the largest fifth of the ratios, at least 5: 25 draws is the fewest
    assert laplace_loo(fit, draws=25, seed=1)["draws"] == 25
    with pytest.raises(BayesUpdateError, match="draws must be >= 25, got 24"):
        laplace_loo(fit, draws=24, seed=1)
    # a Laplace covariance 1e16 times too wide: every draw is clipped to a corner of the box,
    # the importance ratios have no tail, and the LOO is reported as not available (the
    # discover run goes on; ArviZ's ValueError was an internal error)
    wide = replace(best, hessian=best.hessian * 1e-16)
    loo = laplace_loo(replace(fit, optima=[wide]), draws=25, seed=1)
    assert loo["elpd"] is None and loo["draws"] == 25
    assert "not available: PSIS found no tail to smooth" in loo["method"]


def test_noise_model_sources_and_flags():
    f = np.array([10.0, 20.0, 30.0, 40.0, 50.0, 60.0])
    with_sd = ModalData(f, frequency_sd_hz=0.01 * f)
    e = np.array([0.0, 0.01, -0.01, 0.05, 0.0, 0.005])
    noise = noise_model(with_sd, e, n_params=1)
    assert noise.source == "data sd" and noise.scale == pytest.approx(np.full(6, 0.01))
    flags = flag_modes(e, noise, n_params=1)
    # z = 5 for mode 4: p = 5.7e-7 < 0.05 / 6; z = 1 elsewhere is not flagged
    assert flags.flagged_modes == [4]
    assert flags.z[3] == pytest.approx(5.0)
    assert flags.chi2 == pytest.approx(1 + 1 + 25 + 0.25)
    inferred = noise_model(ModalData(f), e, n_params=1)
    # robust: 1.4826 * median(|e|) * sqrt(6 / 5); median of |e| = 0.0075
    assert inferred.sigma == pytest.approx(1.4826 * 0.0075 * np.sqrt(6 / 5))
    assert inferred.inferred
    fixed = noise_model(ModalData(f, weights=np.array([1, 1, 4, 1, 1, 0.0])), e, 1, sigma=0.02)
    assert fixed.scale[2] == pytest.approx(0.01) and not fixed.used[5]
