"""Two-DOF shear building (Beck & Au 2002): model, multi-start optimum, bimodal posterior.

Both frequencies at theta = (1, 1) are the data.  The characteristic equation fixes
theta_1 theta_2 and theta_1 / m1 + theta_2 (1/m1 + 1/m2), so a second exact solution exists,
(theta_1, theta_2) = (1 / r, r) with r = (1/m1) / (1/m1 + 1/m2) = 0.49387: the posterior has two
modes.  Reference: the same log-posterior integrated by quadrature on a 1401 x 1401 grid.
"""

import numpy as np
import pytest
from scipy.linalg import eigh

from bayesupdate.inference import (
    CalibrationSettings,
    LikelihoodSpec,
    LogPosterior,
    SamplerSettings,
    build_problem,
    calibrate,
    sample_posterior,
    summarize,
)
from bayesupdate.modal_data import ModalData
from bayesupdate.models import get_model
from bayesupdate.models.shear_building import FLOOR_MASSES_KG, shear_building_frequencies

M1, M2 = FLOOR_MASSES_KG
R = (1 / M1) / (1 / M1 + 1 / M2)
SECOND_MODE = np.array([1 / R, R])
BOUNDS = {"theta_1": {"bounds": [0.2, 3.0]}, "theta_2": {"bounds": [0.2, 3.0]}}
SIGMA = 0.05


@pytest.fixture(scope="module")
def problem():
    model = get_model("shear_building")
    data = ModalData(frequencies_hz=shear_building_frequencies(np.array([1.0, 1.0])))
    return build_problem(model, data, BOUNDS, pairing="order")


def test_frequencies_match_generalized_eigenproblem():
    theta = np.array([1.3, 0.7])
    k = theta * 29.7e6
    lam = eigh(
        np.array([[k[0] + k[1], -k[1]], [-k[1], k[1]]]), np.diag([M1, M2]), eigvals_only=True
    )
    np.testing.assert_allclose(
        shear_building_frequencies(theta), np.sqrt(lam) / (2 * np.pi), rtol=1e-12
    )
    model = get_model("shear_building")
    pred = model.predict({"theta_1": 1.3, "theta_2": 0.7}, n_modes=2)
    np.testing.assert_allclose(pred.frequencies_hz, np.sqrt(lam) / (2 * np.pi), rtol=1e-12)
    # mass-normalized shapes: Phi^T M Phi = I
    np.testing.assert_allclose(
        pred.shapes.T @ np.diag([M1, M2]) @ pred.shapes, np.eye(2), atol=1e-12
    )
    batch = model.predict_frequencies_batch(
        np.array([[1.3, 0.7], [1.0, 1.0]]), ("theta_1", "theta_2"), 2
    )
    np.testing.assert_allclose(batch[0], np.sqrt(lam) / (2 * np.pi), rtol=1e-12)


def test_batch_shapes_are_the_generalized_eigenvectors_and_pair_in_one_batch():
    """``predict_batch_with_shapes``: the closed-form shapes are scipy's eigenvectors of
    (K, M) up to scale (roof positive), a factor <= 0 gives NaN, and a likelihood that pairs by
    shape takes the batched path (one call per walker batch, not one per point)."""
    model = get_model("shear_building")
    theta = np.array([[1.3, 0.7], [0.4, 2.5], [1.0, -1.0]])
    freqs, shapes = model.predict_batch_with_shapes(theta, ("theta_1", "theta_2"), 2)
    for row, f, phi in zip(theta[:2], freqs, shapes, strict=False):
        k = row * 29.7e6
        lam, vec = eigh(np.array([[k[0] + k[1], -k[1]], [-k[1], k[1]]]), np.diag([M1, M2]))
        np.testing.assert_allclose(f, np.sqrt(lam) / (2 * np.pi), rtol=1e-12)
        vec = vec * np.sign(vec[1])
        np.testing.assert_allclose(phi / phi[1], vec / vec[1], rtol=1e-12)
    assert np.all(np.isnan(freqs[2])) and np.all(np.isnan(shapes[2]))
    data = ModalData(
        frequencies_hz=freqs[0], shapes=shapes[0], dof_labels=model.sensor_labels, source="x"
    )
    posterior = LogPosterior(build_problem(model, data, BOUNDS), LikelihoodSpec(sigma=SIGMA))
    assert posterior.mode == "shape-batch"
    assert posterior(np.array([[1.3, 0.7], [1.2, 0.8]]))[0] > posterior(np.array([[1.2, 0.8]]))[0]


def test_second_solution_reproduces_the_data():
    np.testing.assert_allclose(
        shear_building_frequencies(SECOND_MODE), shear_building_frequencies(np.ones(2)), rtol=1e-12
    )


def test_multistart_finds_both_exact_optima(problem):
    result = calibrate(problem, CalibrationSettings(starts=16, seed=0))
    assert result.expr < 1e-14
    optima = result.end_points[list(result.distinct_optima)]
    assert len(optima) == 2
    found = sorted(optima.tolist())
    np.testing.assert_allclose(found[0], [1.0, 1.0], atol=1e-5)
    np.testing.assert_allclose(found[1], SECOND_MODE, atol=1e-5)
    assert result.converged_starts == result.starts  # both optima are exact (Expr = 0)


def _quadrature(log_post):
    grid = np.linspace(0.2, 3.0, 1401)
    t1, t2 = np.meshgrid(grid, grid, indexing="ij")
    lp = log_post(np.column_stack([t1.ravel(), t2.ravel()])).reshape(t1.shape)
    p = np.exp(lp - lp.max())
    p /= p.sum()
    mean = np.array([np.sum(p * t1), np.sum(p * t2)])
    sd = np.sqrt([np.sum(p * (t1 - mean[0]) ** 2), np.sum(p * (t2 - mean[1]) ** 2)])
    # the two modes are separated by theta_2 = 0.75 (modes at 1.0 and 0.49)
    return mean, sd, float(np.sum(p * (t2 > 0.75)))


def test_bimodal_posterior_matches_quadrature(problem):
    log_post = LogPosterior(problem, LikelihoodSpec(sigma=SIGMA))
    mean_q, sd_q, mass_q = _quadrature(log_post)
    assert 0.3 < mass_q < 0.7  # really two modes of comparable weight
    optimum = calibrate(problem, CalibrationSettings(starts=16, seed=0))
    settings = SamplerSettings(
        walkers=48, steps=2500, seed=3, check_every=500, min_autocorr_times=150
    )
    result = sample_posterior(log_post, optimum, settings)
    draws = result.samples()
    np.testing.assert_allclose(draws.mean(axis=0), mean_q, rtol=0.03)
    np.testing.assert_allclose(draws.std(axis=0), sd_q, rtol=0.03)
    assert abs(np.mean(draws[:, 1] > 0.75) - mass_q) < 0.03
    summary = summarize(result)
    assert all(summary[name]["r_hat"] < 1.02 for name in ("theta_1", "theta_2"))
    assert result.failed_evaluations == 0
