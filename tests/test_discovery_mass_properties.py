"""Measured mass properties as data in discovery (``discovery.mass_block``): the same Gaussian
term ``calibrate``'s likelihood has, so an added mass that fits the frequencies pays for the
weight it adds.

A small frame (``test_discovery_workflow.frame_model``) whose design variable is pipe_a's
modulus (it moves no mass), a virtual test with a hidden 0.3 kg at test point 5 and 0.2 %
frequency noise, and the measured weight given three ways: not at all, the weight with the
mass (the truth), and the model's own weight (a scale that says nothing was added), each with
a 1 % sd.  The mass term is Gaussian in the relative weight error, so with the design variable
leaving the weight alone every number below is a closed form of the weights."""

import dataclasses

import numpy as np
import pytest
from test_discovery_workflow import FAST, NOISE, frame_model

from bayesupdate.discovery.effects import extend_model, parse_effect_spec
from bayesupdate.discovery.evidence import FitSpace
from bayesupdate.discovery.mass_block import MassBlock
from bayesupdate.discovery.settings import LibraryScan
from bayesupdate.discovery.workflow import discover
from bayesupdate.fe import Binding, FEModel
from bayesupdate.inference.likelihood_blocks import LOG_2PI, NoiseModel, mass_log_likelihood
from bayesupdate.inference.problem import ObjectiveSpec
from bayesupdate.modal_data import noisy_modes

HIDDEN = 0.3  # kg at test point 5
#: masses and stiffness changes only (the test is about the weight), to keep it fast
SETTINGS = dataclasses.replace(FAST, scan=LibraryScan(kinds=("added_mass", "stiffness_change")))
SD_REL = 0.01  # the scale's relative sd


@pytest.fixture(scope="module")
def case():
    frame = frame_model()
    model = FEModel(
        frame.structure,
        {"E_a": Binding("pipe_a", "modulus_factor")},
        {"E_a": 1.0},
        {"E_a": (0.5, 2.0)},
        name="frame",
    )
    truth = extend_model(model, parse_effect_spec(f"added_mass@5:m={HIDDEN}"))
    data = noisy_modes(
        truth.predict({"E_a": 1.1}, 8), NOISE, 0.0, np.random.default_rng(1), "synthetic"
    )
    weight = model.total_mass()[0]
    runs = {}
    for label, measured in (("none", None), ("truth", weight + HIDDEN), ("model", weight)):
        given, objective = data, None
        if measured is not None:
            given = dataclasses.replace(data, mass_kg=measured, mass_sd_kg=SD_REL * measured)
            objective = ObjectiveSpec(mass_target_kg=measured, mass_weight=10.0)
        runs[label] = discover(model, given, SETTINGS, objective=objective)
    return weight, runs


def _ln_bf(result, kind="added_mass", location="5") -> tuple[float, float]:
    (fit,) = [f for f in result.fits if (f.kind, f.location) == (kind, location)]
    return result.log_bayes_factor(fit), fit.effect_parameters["m"]


def test_the_baseline_pays_the_closed_form_mass_term(case):
    """The baseline adds no mass, so its evidence moves by exactly the Gaussian term of its
    weight error: -r^2/2 - ln sd - ln(2 pi)/2 with r = (m - m_T) / m_T / sd."""
    weight, runs = case
    base = runs["none"].baseline.log_evidence
    for label, measured in (("truth", weight + HIDDEN), ("model", weight)):
        r = (weight - measured) / measured / SD_REL
        expected = base - 0.5 * r**2 - np.log(SD_REL) - 0.5 * LOG_2PI
        assert runs[label].baseline.log_evidence == pytest.approx(expected, abs=1e-6)


def test_an_added_mass_that_breaks_the_measured_weight_loses_evidence(case):
    """Without a weight the hidden mass is named (ln BF ~ 965).  Given the model's own weight
    (the scale says nothing was added) the same candidate, whose frequencies want 0.3 kg, loses
    the Gaussian penalty of the weight it adds, 0.5 (m / (W sd))^2 = 12.8 nats at its fitted
    mass, against the baseline that keeps the weight; given the true weight it gains the
    baseline's own penalty instead, 0.5 (0.3 / (W + 0.3) / sd)^2 = 12.0 nats."""
    weight, runs = case
    free, m_free = _ln_bf(runs["none"])
    wrong, m_wrong = _ln_bf(runs["model"])
    right, m_right = _ln_bf(runs["truth"])
    assert m_free == pytest.approx(HIDDEN, rel=0.02)
    penalty = 0.5 * (m_wrong / weight / SD_REL) ** 2
    assert free - wrong == pytest.approx(penalty, rel=0.1)
    assert free - wrong > 10.0
    gain = 0.5 * (HIDDEN / (weight + HIDDEN) / SD_REL) ** 2
    assert right - free == pytest.approx(gain, rel=0.05)
    assert m_right == pytest.approx(HIDDEN, rel=0.02)


def test_mass_block_terms_match_calibrates_likelihood():
    """The block's log-density of a weight is ``mass_log_likelihood``, calibrate's term."""
    block = MassBlock(10.0, 0.02, None)
    for mass in (9.5, 10.0, 10.7):
        r = block.residuals(block.values(mass, None))
        expected = mass_log_likelihood(np.array([mass]), 10.0, 0.02)[0]
        assert block.log_likelihood(r) == pytest.approx(expected, rel=1e-12)
    noise = NoiseModel(np.full(3, 0.01), np.ones(3), False, "fixed", 0.01)
    space = FitSpace(None, (), noise, None, block)
    r = space.residual_vector(np.array([0.01, -0.02, 0.0]), None, block.values(10.5, None))
    assert r.tolist() == pytest.approx([1.0, -2.0, 0.0, 2.5])
    assert space.likelihood.pointwise_by_mode(r[None]).shape == (1, 4)
