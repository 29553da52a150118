"""The shared likelihood blocks against closed forms (scipy's Gaussian densities), and calibration's
and discovery's compositions of them against each other where their noise models coincide."""

import numpy as np
import pytest
from scipy import stats

from bayesupdate.inference import LikelihoodSpec, LogPosterior, ObjectiveSpec, build_problem
from bayesupdate.inference.likelihood_blocks import (
    FixedNoiseLikelihood,
    SampledNoise,
    ShapeBlock,
    gaussian_log_likelihood,
    gaussian_log_likelihood_var,
    mass_log_likelihood,
    noise_model,
    shape_residuals,
)
from bayesupdate.modal_data import ModalData
from bayesupdate.models import get_model


def test_residual_and_variance_forms_are_the_same_gaussian():
    rng = np.random.default_rng(0)
    scale = rng.uniform(0.001, 0.05, size=7)
    e = scale * rng.normal(size=7)
    exact = np.sum(stats.norm.logpdf(e, scale=scale))
    assert gaussian_log_likelihood(e / scale, scale) == pytest.approx(exact, rel=1e-12)
    by_var = gaussian_log_likelihood_var(e[None, :], scale[None, :] ** 2)
    assert by_var.shape == (1,) and by_var[0] == pytest.approx(exact, rel=1e-12)


def test_sampled_noise_adds_the_known_sd_in_quadrature_and_weights_the_level():
    f_test = np.array([10.0, 25.0, 40.0])
    weights = np.array([1.0, 4.0, 0.25])
    sd_hz = np.array([0.02, 0.0, 0.1])
    noise = SampledNoise.of(f_test, weights, sd_hz)
    sigma = np.array([0.01, 0.03])
    e = np.array([[0.004, -0.002, 0.01], [0.0, 0.05, -0.03]])
    var = sigma[:, None] ** 2 / weights + (sd_hz / f_test) ** 2
    exact = np.sum(stats.norm.logpdf(e, scale=np.sqrt(var)), axis=1)
    np.testing.assert_allclose(noise.log_likelihood(e, sigma), exact, rtol=1e-12)
    no_sd = SampledNoise.of(f_test, weights, None)
    np.testing.assert_array_equal(no_sd.sd_rel2, 0.0)


def test_mass_block_is_the_relative_mass_error_gaussian():
    mass = np.array([31.0, 29.5, 30.0])
    expected = stats.norm.logpdf((mass - 30.0) / 30.0, scale=0.02)
    np.testing.assert_allclose(mass_log_likelihood(mass, 30.0, 0.02), expected, rtol=1e-12)


def test_shape_block_is_gaussian_on_the_complement_of_the_model_shape():
    """d_i = t_i - a_i p_i lies in the (n - 1)-dimensional complement of p_i; the block's log
    density is that of n - 1 independent N(0, sigma_i^2) coordinates there."""
    rng = np.random.default_rng(1)
    n, k = 9, 3
    test = rng.normal(size=(n, k))
    test /= np.linalg.norm(test, axis=0)
    model = 5.0 * (test + 0.05 * rng.normal(size=(n, k)))  # any scaling of the model shape
    block = ShapeBlock(np.arange(k), test, np.array([0.01, 0.02, 0.005]))
    r = block.residuals(model)
    per_mode = block.log_likelihood(r)
    d = shape_residuals(test, model)
    for i in range(k):
        basis = np.linalg.qr(np.column_stack([model[:, i], rng.normal(size=(n, n - 1))]))[0]
        coords = basis[:, 1:].T @ d[:, i]  # d in an orthonormal basis of the complement
        assert np.linalg.norm(coords) == pytest.approx(np.linalg.norm(d[:, i]), rel=1e-10)
        exact = np.sum(stats.norm.logpdf(coords, scale=block.scale[i]))
        assert per_mode[i] == pytest.approx(exact, rel=1e-10)
    np.testing.assert_allclose(block.rss(r), np.sum(d * d, axis=0), rtol=1e-12)


def test_pointwise_by_mode_partitions_the_log_likelihood():
    """LOO's per-mode terms (each mode's frequency and shape together) add up to log L."""
    rng = np.random.default_rng(2)
    data = ModalData(np.array([5.0, 9.0, 14.0, 20.0]), weights=np.array([1.0, 0.0, 2.0, 1.0]))
    noise = noise_model(data, np.zeros(4), 0, sigma=0.01)
    test = rng.normal(size=(6, 4))
    test /= np.linalg.norm(test, axis=0)
    shapes = ShapeBlock(np.array([0, 3]), test[:, [0, 3]], np.array([0.02, 0.03]))
    likelihood = FixedNoiseLikelihood(noise, shapes)
    r = likelihood.residual_vector(
        0.01 * rng.normal(size=4), test + 0.02 * rng.normal(size=test.shape)
    )
    assert r.shape == (likelihood.size,) == (3 + 12,)
    pointwise = likelihood.pointwise_by_mode(r[None, :])
    assert pointwise.shape == (1, 3)
    assert np.sum(pointwise) == pytest.approx(likelihood.log_likelihood(r), rel=1e-12)
    # the middle used mode (test mode 3) has no shape term
    scale = 0.01 / np.sqrt(2.0)
    assert pointwise[0, 1] == pytest.approx(stats.norm.logpdf(r[1] * scale, scale=scale))


def _shear_problem(weights=None, sd=None, objective=None):
    data = ModalData(frequencies_hz=[4.0, 11.5], weights=weights, frequency_sd_hz=sd)
    return build_problem(
        get_model("shear_building"), data, None, pairing="order", objective=objective
    )


def test_calibration_and_discovery_compose_the_same_frequency_block():
    """At a fixed sigma the calibration posterior's likelihood (variance form) and discovery's
    (residual form, fixed levels s_i = sigma / sqrt(w_i)) are the same Gaussian."""
    problem = _shear_problem(weights=[1.0, 4.0])
    log_post = LogPosterior(problem, LikelihoodSpec(sigma=0.03))
    f = problem.evaluate(np.array([1.1, 0.9])).frequencies_hz
    calibration = log_post.log_likelihood(f[None, :], np.array([0.03]), np.array([np.nan]))[0]
    noise = noise_model(problem.data, np.zeros(2), 2, sigma=0.03)
    e = (f - problem.data.frequencies_hz) / problem.data.frequencies_hz
    discovery = FixedNoiseLikelihood(noise).log_likelihood(noise.residuals(e))
    assert calibration == pytest.approx(discovery, rel=1e-12)


def test_calibration_posterior_adds_the_mass_block():
    objective = ObjectiveSpec(mass_target_kg=30000.0, mass_weight=0.0)
    problem = _shear_problem(objective=objective)
    spec = LikelihoodSpec(sigma=0.02, mass_sd_rel=0.01)
    log_post = LogPosterior(problem, spec)
    f = problem.evaluate(np.array([1.0, 1.0])).frequencies_hz
    mass = np.array([32600.0])
    ll = log_post.log_likelihood(f[None, :], np.array([0.02]), mass)[0]
    e = (f - [4.0, 11.5]) / [4.0, 11.5]
    expected = np.sum(stats.norm.logpdf(e, scale=0.02)) + stats.norm.logpdf(
        2600.0 / 30000.0, scale=0.01
    )
    assert ll == pytest.approx(expected, rel=1e-12)


def test_a_proposal_of_density_zero_is_minus_inf_without_a_floating_point_warning():
    """sigma = 0 (inside a half-normal prior's support) and a proposal far out (z^2 overflows)
    have posterior density 0: -inf, and no RuntimeWarning reaches the user's terminal."""
    import warnings

    from bayesupdate.inference.priors import Prior

    model = get_model("shear_building")
    data = ModalData(frequencies_hz=np.array([4.3, 10.8]))
    problem = build_problem(model, data, {"theta_1": {"bounds": [0.2, 3.0]}}, pairing="order")
    halfnormal = Prior("halfnormal", (0.0, np.inf), (("scale", 0.1),), "sigma")
    post = LogPosterior(problem, LikelihoodSpec(sigma=None, sigma_prior=halfnormal))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        lp = post(np.array([[1.0, 0.0], [1.0, 1e200], [1.0, 0.05]]))
    assert lp[0] == -np.inf and lp[1] == -np.inf and np.isfinite(lp[2])
