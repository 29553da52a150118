"""The identification's frequency sd (``ModalData.identification_sd_hz``, written by
``identify``) adds to the model-error level in quadrature; it never replaces it.

Closed forms (scipy's Gaussian densities) for calibration's posterior, and discovery's noise
model: with identified sds every mode's scale is at least the inferred level (so a null test
cannot turn significant through tiny sds), while a stated ``frequency_sd_hz`` still replaces
the level as before.
"""

import numpy as np
import pytest
from scipy import stats

from bayesupdate.inference import LikelihoodSpec, LogPosterior, build_problem
from bayesupdate.inference.likelihood_blocks import noise_model
from bayesupdate.modal_data import ModalData
from bayesupdate.models import get_model

F_TEST = np.array([4.0, 11.5])
SD_ID = np.array([4e-4, 2.3e-2])  # relative 1e-4 and 2e-3


def _problem(**data):
    modal = ModalData(frequencies_hz=F_TEST, **data)
    return build_problem(get_model("shear_building"), modal, None, pairing="order")


@pytest.mark.parametrize("sigma", [0.03, 1e-4])
def test_posterior_adds_the_identification_sd_to_sigma(sigma):
    problem = _problem(identification_sd_hz=SD_ID)
    log_post = LogPosterior(problem, LikelihoodSpec(sigma=sigma))
    f = problem.evaluate(np.array([1.1, 0.9])).frequencies_hz
    ll = log_post.log_likelihood(f[None, :], np.array([sigma]), np.array([np.nan]))[0]
    e = (f - F_TEST) / F_TEST
    scale = np.sqrt(sigma**2 + (SD_ID / F_TEST) ** 2)
    assert ll == pytest.approx(np.sum(stats.norm.logpdf(e, scale=scale)), rel=1e-12)


def test_stated_and_identified_sds_both_add():
    stated = np.array([0.01, 0.05])
    problem = _problem(identification_sd_hz=SD_ID, frequency_sd_hz=stated)
    log_post = LogPosterior(problem, LikelihoodSpec(sigma=0.002))
    e = np.array([[0.001, -0.004]])
    var = 0.002**2 + (stated / F_TEST) ** 2 + (SD_ID / F_TEST) ** 2
    expected = np.sum(stats.norm.logpdf(e[0], scale=np.sqrt(var)))
    assert log_post.noise.log_likelihood(e, np.array([0.002]))[0] == pytest.approx(expected)


def test_discovery_level_is_inferred_and_the_identified_sd_added():
    residual = np.array([3e-4, -5e-4])
    plain = noise_model(ModalData(F_TEST), residual, 1)
    with_id = noise_model(ModalData(F_TEST, identification_sd_hz=SD_ID), residual, 1)
    assert with_id.inferred and with_id.source == "inferred (robust) + identification sd"
    assert with_id.sigma == plain.sigma  # the level is the one the residuals give
    expected = np.sqrt(plain.sigma**2 + (SD_ID / F_TEST) ** 2)
    np.testing.assert_allclose(with_id.scale, expected, rtol=1e-12)
    # never below the level: tiny identified sds cannot make a misfit look significant
    assert np.all(with_id.scale >= plain.scale)
    # a stated sd (the whole error) still replaces the level
    stated = noise_model(ModalData(F_TEST, frequency_sd_hz=SD_ID), residual, 1)
    assert stated.source == "data sd"
    np.testing.assert_allclose(stated.scale, SD_ID / F_TEST, rtol=1e-12)
