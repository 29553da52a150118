"""A mass term in the likelihood keeps the batched, shape-paired evaluation (the demo's seed case:
Table 2 with the weighed mass on the reduced exhaust): the same log-posterior as one
``problem.evaluate`` per point, mass included."""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from bayesupdate.fe.reduced import reduced_model_for  # noqa: E402
from bayesupdate.inference import (  # noqa: E402
    LikelihoodSpec,
    LogPosterior,
    ObjectiveSpec,
    build_problem,
    load_modal_data,
)
from bayesupdate.inference.likelihood import mass_function  # noqa: E402
from bayesupdate.models import get_model  # noqa: E402
from bayesupdate.models.exhaust_paper import MEASURED_MASS_KG  # noqa: E402


@pytest.fixture(scope="module")
def problem():
    rom = reduced_model_for(get_model("exhaust"), tol=1e-4, seed=0, n_modes=14)
    objective = ObjectiveSpec(MEASURED_MASS_KG, mass_weight=10.0)
    return build_problem(rom, load_modal_data("paper:ema"), objective=objective)


def test_mass_term_is_batched_and_equals_the_per_point_posterior(problem):
    batched = LogPosterior(problem, LikelihoodSpec(sigma=0.05, mass_sd_rel=0.01))
    # "problem": the problem's own pairing, one problem.evaluate per point
    points = LogPosterior(problem, LikelihoodSpec(sigma=0.05, mass_sd_rel=0.01, pairing="problem"))
    assert batched.mode == "shape-batch" and points.mode == "points"
    rng = np.random.default_rng(3)
    theta = problem.lower + rng.random((12, 5)) * (problem.upper - problem.lower)
    _, masses = batched.predict_frequencies(theta)
    expected = [problem.evaluate(point).mass_kg for point in theta]
    np.testing.assert_allclose(masses, expected, rtol=1e-12)
    # the masses span the box (~9-16 kg here): the mass term is not a constant
    assert np.ptp(masses) > 1.0
    np.testing.assert_allclose(batched(theta), points(theta), rtol=1e-9)
    no_mass = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    assert np.all(np.abs(batched(theta) - no_mass(theta)) > 1e-6)


def test_a_model_without_a_mass_keeps_per_point_evaluation(problem):
    assert mass_function(problem.model) is not None
    assert mass_function(object()) is None
