"""A posterior's draws judged by a stored reference (``inference.reference_check``): the numbers,
when a reference applies, and ``run_sampling``'s use of it (the demo passes its two)."""

import json
from importlib import resources

import numpy as np
import pytest

from bayesupdate.config import parse_study
from bayesupdate.inference.reference_check import (
    SAME_POSTERIOR_TOLERANCE,
    accuracy_against,
    reference_errors,
    within_tolerance,
)
from bayesupdate.pipelines.sample import SamplingOptions, run_sampling
from bayesupdate.pipelines.study import prepare

NAMES = ("a", "b")


def _gaussian(points: np.ndarray) -> np.ndarray:
    return -0.5 * np.sum(np.atleast_2d(points) ** 2, axis=1)


def _reference(mean, sd, density=_gaussian) -> dict:
    points = np.array([[0.0, 0.0], [0.5, -0.5], [1.0, 2.0]])
    return {
        "case": "toy", "names": list(NAMES), "mean": mean, "sd": sd,
        "check_points": points.tolist(), "check_log_p": density(points).tolist(),
    }  # fmt: skip


def test_errors_are_the_mean_offset_in_reference_sds_and_the_relative_sd():
    # draws 0 and 2: mean 1, sd (n - 1) sqrt(2)
    samples = np.array([[0.0, 10.0], [2.0, 14.0]])
    errors = reference_errors({"mean": [0.9, 12.0], "sd": [1.0, 4.0]}, samples)
    assert errors["mean_error_in_sd"] == pytest.approx([0.1, 0.0])
    assert errors["sd_error_relative"] == pytest.approx([np.sqrt(2) - 1, np.sqrt(8) / 4 - 1])


@pytest.mark.parametrize(
    "mean_error, sd_error, ok",
    [(0.05, 0.05, True), (0.0501, 0.0, False), (0.0, -0.0501, False), (0.049, -0.049, True)],
)
def test_the_criterion_is_005_sd_and_5_percent(mean_error, sd_error, ok):
    errors = {"mean_error_in_sd": [0.0, mean_error], "sd_error_relative": [sd_error, 0.0]}
    assert within_tolerance(errors) is ok


def test_a_reference_judges_only_the_posterior_it_was_made_for():
    rng = np.random.default_rng(3)
    draws = rng.standard_normal((4000, 2)) * [1.0, 0.9]
    ref = _reference([0.0, 0.0], [1.0, 1.0])
    same = accuracy_against(ref, _gaussian, draws, NAMES)
    assert same["applies"] and same["gap"] == 0.0
    # b's sd is 10 % small: not met, and b is named as the worst
    assert not same["accurate"] and same["worst"].startswith("b:")
    assert same["sd_error_relative"][1] == pytest.approx(-0.1, abs=0.03)
    # another posterior (its mean moved by 0.1 in a): the check points tell
    other = accuracy_against(ref, lambda x: _gaussian(np.atleast_2d(x) - [0.1, 0.0]), draws, NAMES)
    assert not other["applies"] and other["gap"] > SAME_POSTERIOR_TOLERANCE
    assert "accurate" not in other
    assert not accuracy_against(ref, _gaussian, draws, ("a", "c"))["applies"]
    assert not accuracy_against({**ref, "check_points": []}, _gaussian, draws, NAMES)["applies"]


@pytest.mark.parametrize("case", ["seed_shell", "virtual"])
def test_the_demo_references_carry_their_check_points(case):
    name = f"data/posterior_reference_demo_{case}.json"
    ref = json.loads(resources.files("bayesupdate").joinpath(name).read_text())
    points, log_p = np.array(ref["check_points"]), np.array(ref["check_log_p"])
    assert points.shape == (3, len(ref["names"])) and np.all(np.isfinite(log_p))
    # the mean and the mean -/+ half a reference sd
    np.testing.assert_allclose(points[0], ref["mean"])
    np.testing.assert_allclose(points[2] - points[1], ref["sd"], rtol=1e-12)


STUDY = {
    "model": {"source": "shear_building"},
    "data": {"frequencies_hz": [4.30, 10.80]},
    "parameters": {"theta_1": {"bounds": [0.2, 3.0]}, "theta_2": {"bounds": [0.2, 3.0]}},
    "optimizer": {"starts": 2},
    "sampler": {"walkers": 8, "steps": 60, "check_every": 30, "predictive_draws": 5},
}


def test_run_sampling_judges_its_draws_by_a_reference_of_its_posterior():
    prepared = prepare(parse_study(STUDY, where="test"))
    first = run_sampling(prepared)
    post = first.posterior
    # the chain's own log densities are the posterior's: a reference built on them applies
    points = post.chain[-1, :3]
    samples = post.samples()
    ref = {
        "case": "shear", "names": list(post.names), "mean": samples.mean(axis=0).tolist(),
        "sd": samples.std(axis=0, ddof=1).tolist(), "check_points": points.tolist(),
        "check_log_p": post.log_prob[-1, :3].tolist(),
    }  # fmt: skip
    judged = run_sampling(prepared, SamplingOptions(reference=ref), first.calibration).posterior
    verdict = judged.diagnostics["reference"]
    assert verdict["applies"] and verdict["gap"] < 1e-9
    # the same seed gives the same chain: errors zero, criterion met
    assert max(verdict["mean_error_in_sd"]) < 1e-12 and verdict["accurate"]
    moved = {**ref, "check_log_p": (np.array(ref["check_log_p"]) + 1.0).tolist()}
    other = run_sampling(prepared, SamplingOptions(reference=moved), first.calibration)
    other = other.posterior
    assert not other.diagnostics["reference"]["applies"]
    assert "reference" not in first.posterior.diagnostics
