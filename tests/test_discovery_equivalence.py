"""Observational equivalence: the divergence D = min chi^2 / 2 between a noise-free truth and a
model's best fit is zero for the true model, and grows with the part of the truth's signature
the model cannot reproduce."""

import sys
from pathlib import Path

import numpy as np
import pytest
from test_discovery_workflow import TRUE_T, frame_model

from bayesupdate.correlation import mac_matrix
from bayesupdate.discovery.effects import Effect, extend_model, parse_effect_spec
from bayesupdate.errors import BayesUpdateError
from bayesupdate.modal_data import ModalData

# the study helper under test (studies/model_equivalence.py), imported as the studies do
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
from model_equivalence import fit_to_truth, noise_free_modes  # noqa: E402


@pytest.fixture(scope="module")
def frame():
    return frame_model()


def test_the_true_effect_is_equivalent_and_the_baseline_is_not(frame):
    truth_model = extend_model(frame, parse_effect_spec("added_mass@3:m=0.3"))
    truth = noise_free_modes(truth_model.predict({"t_a": TRUE_T}, 8))
    start = {"t_a": 1.5e-3}
    right = fit_to_truth(frame, truth, start, Effect("added_mass", "3"), 0.002, 0.03)
    assert right.divergence < 1e-6
    assert dict(zip(right.names, right.theta, strict=True)) == pytest.approx(
        {"t_a": TRUE_T, "added_mass@3:m": 0.3}, rel=1e-4
    )
    baseline = fit_to_truth(frame, truth, start, None, 0.002, 0.03)
    assert baseline.label == "baseline" and baseline.names == ("t_a",)
    # the reported residuals are those of the fitted point: an independent solve there gives
    # the same frequency errors and 1 - MAC against the truth's shapes
    again = frame.predict({"t_a": baseline.theta[0]}, 8)
    mac = np.max(mac_matrix(truth.shapes, again.shapes), axis=1)
    np.testing.assert_allclose(baseline.mac_deficit, 1 - mac, rtol=1e-6, atol=1e-12)
    z = (np.sort(again.frequencies_hz) - truth.frequencies_hz) / (0.002 * truth.frequencies_hz)
    np.testing.assert_allclose(baseline.frequency_z, z, rtol=1e-6)
    # a 0.3 kg mass moves frequencies by several % (noise 0.2 %): far from equivalent
    assert baseline.divergence > 1e3
    assert np.max(np.abs(baseline.frequency_z)) > 10
    # halving the noise quadruples D at the same best fit (whitening scales as 1 / noise)
    finer = fit_to_truth(frame, truth, start, None, 0.001, 0.015)
    assert finer.divergence == pytest.approx(4 * baseline.divergence, rel=0.02)


def test_a_slightly_longer_pipe_is_close_to_a_softer_pipe(frame):
    """pipe_b 1.25 % longer: a softer pipe_b reproduces it within a few nats (the test at 0.2 %
    frequency and 3 % shape noise cannot tell them apart per mode), the baseline does not."""
    truth = noise_free_modes(frame_model(1.62).predict({"t_a": TRUE_T}, 8))
    start = {"t_a": TRUE_T}
    softer = fit_to_truth(frame, truth, start, Effect("stiffness_change", "pipe_b"), 0.002, 0.03)
    baseline = fit_to_truth(frame, truth, start, None, 0.002, 0.03)
    assert softer.divergence < 10 < 100 < baseline.divergence
    assert np.max(np.abs(softer.frequency_z)) < 2.5
    assert softer.theta[1] == pytest.approx(0.95, abs=0.01)


def test_bad_inputs(frame):
    truth = noise_free_modes(frame.predict({"t_a": TRUE_T}, 8))
    with pytest.raises(BayesUpdateError, match="must be > 0"):
        fit_to_truth(frame, truth, {"t_a": TRUE_T}, None, 0.0, 0.03)
    with pytest.raises(BayesUpdateError, match="needs mode shapes"):
        fit_to_truth(frame, ModalData(truth.frequencies_hz), {"t_a": TRUE_T}, None)
