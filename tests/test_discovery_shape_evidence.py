"""Mode shapes as discovery evidence: the residual is the MAC deficit spread over the sensors, each
mode's level is fixed before the fit (the stated sd floored at 1 %, raised to the misfit at the
frequency-only baseline only where that misfit rejects it), and the Laplace evidence of a linear
model with a shape block equals the quadrature of its exact marginal."""

import numpy as np
import pytest
from scipy import integrate, optimize, stats

from bayesupdate.correlation import mac_matrix
from bayesupdate.discovery.evidence import FitSpace, laplace
from bayesupdate.discovery.flagging import ShapeTests, flag_modes
from bayesupdate.discovery.shape_evidence import (
    SHAPE_SD_FLOOR_REL,
    STATED_REJECTION,
    ShapeEvidence,
    shape_evidence,
    unit_real_shapes,
)
from bayesupdate.inference.likelihood_blocks import NoiseModel, shape_residuals
from bayesupdate.inference.parameter_space import ParameterSpec
from bayesupdate.inference.priors import prior_from_mapping
from bayesupdate.modal_data import ModalData, noisy_modes
from bayesupdate.model_protocol import Prediction


def test_shape_residual_norm_is_the_mac_deficit_for_any_model_scaling():
    rng = np.random.default_rng(0)
    test = unit_real_shapes(rng.normal(size=(15, 4)))
    model = test + 0.2 * rng.normal(size=(15, 4))
    mac = np.diag(mac_matrix(test, model))
    for scaling in (1.0, -3.0, 1e-4):  # mass normalization and sign do not matter
        d = shape_residuals(test, scaling * model)
        np.testing.assert_allclose(np.sum(d * d, axis=0), 1.0 - mac, rtol=1e-10)
        # the residual is orthogonal to the model shape (least-squares scale factor)
        np.testing.assert_allclose(np.sum(d * model, axis=0), 0.0, atol=1e-12)


def test_unit_real_shapes_undo_a_complex_rotation():
    rng = np.random.default_rng(1)
    real = rng.normal(size=(12, 3))
    rotated = real * np.exp(1j * np.array([0.3, -2.0, 1.2]))[None, :]
    unit = unit_real_shapes(rotated)
    expected = real / np.linalg.norm(real, axis=0)
    np.testing.assert_allclose(np.abs(np.sum(unit * expected, axis=0)), 1.0, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(unit, axis=0), 1.0, atol=1e-12)


def test_without_a_stated_sd_the_level_is_the_floor_or_the_baseline_misfit():
    """No ``shape_sd_rel``: the 1 % floor is the stated level (source "floor"); a mode whose
    baseline misfit rejects it is raised to that misfit, so its chi^2 there is exactly dof."""
    rng = np.random.default_rng(2)
    shapes = rng.normal(size=(10, 3))
    data = ModalData(np.array([5.0, 9.0, 14.0]), shapes=shapes, dof_labels=tuple("abcdefghij"))
    model = shapes + np.array([0.05, 0.0, 1e-4]) * rng.normal(size=shapes.shape)
    used = np.array([True, False, True])
    ev = shape_evidence(data, model, used)
    assert ev.source == "floor"
    np.testing.assert_array_equal(ev.modes, [0, 2])
    np.testing.assert_array_equal(ev.raised, [True, False])
    deficit = 1 - np.diag(mac_matrix(shapes, model))[[0, 2]]
    assert deficit[1] < (SHAPE_SD_FLOOR_REL**2) / 10  # mode 3 fits far inside the floor
    np.testing.assert_allclose(
        ev.scale, [np.sqrt(deficit[0] / 9), SHAPE_SD_FLOOR_REL / np.sqrt(10)], rtol=1e-10
    )
    r = ev.residuals(model)
    assert r.shape == (20,)
    np.testing.assert_allclose(ev.chi2(r)[0], 9.0, rtol=1e-10)
    assert ev.chi2(r)[1] < 1.0
    np.testing.assert_allclose(ev.rss(r), deficit, rtol=1e-10, atol=1e-14)  # 1 - MAC round-off
    assert shape_evidence(ModalData(np.array([5.0])), None, np.array([True])) is None


def test_a_biased_mode_cannot_drag_the_fit_beyond_dof_over_two_nats():
    """A mode 1 - MAC = 2e-2 off at the baseline, against a stated 1e-3: raised to its own misfit,
    so a model that removed the bias entirely would gain dof / 2 nats from it, not the
    ~R / (2 s^2) ~ 8,000 nats of the stated level; an honest mode keeps its stated level."""
    rng = np.random.default_rng(6)
    n = 40
    truth = rng.normal(size=(n, 2))
    test = truth.copy()
    bias = rng.normal(size=n)
    bias -= truth[:, 0] * (bias @ truth[:, 0]) / (truth[:, 0] @ truth[:, 0])
    test[:, 0] += np.sqrt(0.02 / 0.98) * np.linalg.norm(truth[:, 0]) * bias / np.linalg.norm(bias)
    labels = tuple(f"{i}V" for i in range(n))
    data = ModalData(np.array([5.0, 9.0]), shapes=test, dof_labels=labels, shape_sd_rel=[1e-3] * 2)
    ev = shape_evidence(data, truth, np.ones(2, bool))
    np.testing.assert_array_equal(ev.raised, [True, False])
    gain = np.sum(ev.log_likelihood(ev.residuals(test))) - np.sum(
        ev.log_likelihood(ev.residuals(truth))
    )
    assert gain == pytest.approx((n - 1) / 2, rel=1e-9)
    np.testing.assert_allclose(ev.scale[1], SHAPE_SD_FLOOR_REL / np.sqrt(n))  # 1e-3 -> floor


def test_known_shape_noise_is_a_fixed_gaussian_block():
    """With ``shape_sd_rel`` the level is the data's (sd / sqrt(n) on a unit shape), not fitted:
    the block's log-likelihood is Gaussian with dof = n - 1 terms per mode, and a shape misfit
    that no noise level absorbs shows as chi^2 >> dof."""
    rng = np.random.default_rng(5)
    n, sd = 16, 0.03
    truth = rng.normal(size=(n, 3))
    prediction = Prediction(np.array([5.0, 9.0, 14.0]), truth, tuple(f"{i}V" for i in range(n)))
    data = noisy_modes(prediction, 0.001, sd, rng, "known")
    np.testing.assert_array_equal(data.shape_sd_rel, sd)
    ev = shape_evidence(data, truth, np.ones(3, bool))
    assert ev.source == "data sd" and not np.any(ev.raised)  # the truth does not reject it
    np.testing.assert_allclose(ev.scale, sd / np.sqrt(n))
    r = ev.residuals(truth)
    noise = NoiseModel(np.full(3, 0.001), np.ones(3), False, "data sd", 0.001)
    likelihood = FitSpace(None, (), noise, ev).likelihood
    r_f = np.zeros(3)
    expected = np.sum(stats.norm.logpdf(0.001 * r_f, scale=0.001)) + np.sum(
        -0.5 * ev.rss(r) / ev.scale**2 - (n - 1) * (np.log(ev.scale) + 0.5 * np.log(2 * np.pi))
    )
    assert likelihood.log_likelihood(np.concatenate([r_f, r])) == pytest.approx(expected, rel=1e-12)
    # under the truth chi^2 per mode is ~ chi^2(15): all three within its 0.1 %-99.9 % range
    assert np.all((ev.chi2(r) > 3.5) & (ev.chi2(r) < 38))
    np.testing.assert_array_equal(likelihood.curvature_weights(np.concatenate([r_f, r]))[3:], 1.0)
    # a model shape 1 - MAC = 2e-2 off (22x the noise's 9e-4) in mode 2 is flagged
    off = truth.copy()
    bias = rng.normal(size=n)
    bias -= truth[:, 1] * (bias @ truth[:, 1]) / (truth[:, 1] @ truth[:, 1])
    off[:, 1] += np.sqrt(0.02 / 0.98) * np.linalg.norm(truth[:, 1]) * bias / np.linalg.norm(bias)
    chi2 = ev.chi2(ev.residuals(off))
    assert chi2[1] > 200 and chi2[1] > 10 * max(chi2[0], chi2[2])
    r_off = ev.residuals(off)
    rejected = ev.stated_rejections(r_off)
    np.testing.assert_array_equal(rejected, [False, True, False])
    tests = ShapeTests(stats.chi2.sf(chi2, ev.dof), rejected, 0.3)  # one rejection: plausible
    flags = flag_modes(np.zeros(3), noise, 0, shapes=tests)
    assert flags.flagged_modes == [2]
    assert flags.chi2_dof == 3 and flags.chi2 == 0.0  # the global test is the frequencies'
    assert flags.shape_p_value[1] < 1e-10 < flags.shape_p_value[0]
    # a count beyond the identification failure rate flags every rejecting mode, even at a
    # per-mode p-value that passes (a raised level)
    raised = ShapeTests(np.array([0.5, 0.5, 0.5]), np.array([True, True, False]), 1e-4)
    assert flag_modes(np.zeros(3), noise, 0, shapes=raised).flagged_modes == [1, 2]


def _space_with_shapes(k=2, n_dof=8, level=0.02, seed=3):
    rng = np.random.default_rng(seed)
    m_f = 4
    noise = NoiseModel(np.full(m_f, 0.01), np.ones(m_f), False, "fixed", 0.01)
    test = unit_real_shapes(rng.normal(size=(n_dof, k)))
    shapes = ShapeEvidence(np.arange(k), test, np.full(k, level))
    axis = ParameterSpec(
        "p",
        (-50.0, 50.0),
        prior_from_mapping({"kind": "normal", "mean": 0.0, "sd": 3.0}, (-50.0, 50.0)),
        axis="linear",
    )
    return FitSpace(None, (axis,), noise, shapes), rng


def test_raise_threshold_is_the_stated_chi2_quantile():
    """The level is raised exactly where the baseline misfit's chi^2 at the stated level passes
    the 1 - STATED_REJECTION quantile of chi^2(n - 1)."""
    n = 25
    # R at the threshold, stated sd 2 %
    edge = stats.chi2.isf(STATED_REJECTION, n - 1) * (0.02**2 / n)
    truth = np.eye(n)[:, :2]
    test = truth.copy()
    for j, rss in enumerate((0.99 * edge, 1.01 * edge)):
        test[:, j] = np.sqrt(1 - rss) * truth[:, j] + np.sqrt(rss) * np.eye(n)[:, 5 + j]
    labels = tuple(f"{i}V" for i in range(n))
    data = ModalData(np.array([5.0, 9.0]), shapes=test, dof_labels=labels, shape_sd_rel=[0.02] * 2)
    ev = shape_evidence(data, truth, np.ones(2, bool))
    np.testing.assert_array_equal(ev.raised, [False, True])


def test_laplace_with_a_shape_block_matches_the_exact_marginal_of_a_linear_model():
    """One parameter p, frequency residuals r_f = a p + b (known unit noise), shape residuals
    d = c p + e (levels fixed).  The exact evidence is a 1-D integral over p of the
    likelihood times the prior; Laplace uses the
    Gauss-Newton Hessian of both blocks at the optimum.  They agree to the Laplace error, which
    shrinks as the data grow."""
    space, rng = _space_with_shapes(k=2, n_dof=30, level=0.02)
    shapes = space.shapes
    n_f, n_s = space.n_frequency, shapes.size
    a, b = rng.normal(size=n_f), rng.normal(size=n_f)
    c = 0.002 * rng.normal(size=n_s)
    e = 0.02 * rng.normal(size=n_s)
    scale = np.repeat(shapes.scale, shapes.n_dof)

    def residual(p):
        return np.concatenate([a * p + b, (c * p + e) / scale])

    def log_post(p):
        log_like = space.likelihood.log_likelihood(residual(p))
        return log_like + float(space.log_prior_z(np.array([[p]]))[0])

    grid = np.linspace(-20, 20, 4001)
    values = np.array([log_post(p) for p in grid])
    top = values.max()
    exact = np.log(integrate.trapezoid(np.exp(values - top), grid)) + top
    p_star = grid[np.argmax(values)]
    p_star = optimize.minimize_scalar(lambda p: -log_post(p), bracket=(p_star - 1, p_star + 1)).x
    jac = np.concatenate([a, c / scale])[:, None]
    result = laplace(space, np.array([p_star]), residual(p_star), jac)
    assert result.log_evidence == pytest.approx(exact, abs=0.05)
    # and the curvature is the sum over blocks: sum a^2 + sum_i |c_i|^2 / sigma_i^2
    c_blocks = c.reshape(shapes.scale.size, shapes.n_dof)
    expected = np.sum(a * a) + np.sum(np.sum(c_blocks**2, axis=1) / shapes.scale**2) + 1 / 9.0
    assert result.hessian[0, 0] == pytest.approx(expected, rel=1e-4)


def test_noisy_modes_sets_the_mac_deficit_and_lists_modes_by_frequency():
    rng = np.random.default_rng(4)
    shapes = rng.normal(size=(400, 3))
    truth = Prediction(np.array([10.0, 10.01, 30.0]), shapes, tuple(f"{i}V" for i in range(400)))
    data = noisy_modes(truth, 0.003, 0.03, rng, "virtual")
    assert np.all(np.diff(data.frequencies_hz) > 0)
    np.testing.assert_allclose(data.frequency_sd_hz, 0.003 * data.frequencies_hz)
    mac = mac_matrix(shapes, data.shapes).max(axis=0)
    # 1 - MAC ~ shape_noise^2 (400 DOFs: chi^2 scatter ~7 %)
    np.testing.assert_allclose(1 - mac, 0.03**2, rtol=0.25)
    assert noisy_modes(truth, 0.003, 0.0, rng, "virtual").shapes is None
