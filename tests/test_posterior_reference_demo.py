"""The demo's posteriors against their importance-sampling references: the demo's
default sampler (``run_sampling`` with the demo's study) gives means within 0.05 sd and sds
within 5 % of the reference, every parameter.

The references (posterior_reference_demo_{seed,virtual,seed_shell}.json in tests/data, the
last two in bayesupdate/data, made by
studies/posterior_reference.py --case seed|virtual|seed-shell) are the posteriors ``bayesupdate
demo`` shows (its seed case on the shell exhaust, ``seed-shell``; its virtual test on the beam
exhaust; ``seed``: the beam exhaust's seed case, the demo's before the shell exhaust took its
place), built with the demo's own study and the calls ``run_sampling`` makes.  The seed case's
lower rho_catalyst tail (logit down to about -5.6) is where the demo's mixture proposal fails
its coverage check; the reference's defensive prior component and its refit on resampled draws
reach it (its weighted 0.5 % quantile is stored with the pilot's).
"""

import json
import os
import runpy
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data"
LONG = pytest.mark.skipif(
    not os.environ.get("BAYESUPDATE_LONG_TESTS"),
    reason="long: set BAYESUPDATE_LONG_TESTS=1 (docs/validation/posterior.md has more seeds)",
)


def _reference(case: str) -> dict:
    """The stored reference: the demo's two (package data, the demo judges its posteriors by
    them) or the beam seed case's (test data)."""
    name = f"posterior_reference_demo_{case.replace('-', '_')}.json"
    folder = DATA if case == "seed" else ROOT / "bayesupdate" / "data"
    return json.loads((folder / name).read_text())


def _study():
    """studies/posterior_reference.py's functions (the module's globals as attributes)."""
    return SimpleNamespace(**runpy.run_path(str(ROOT / "studies" / "posterior_reference.py")))


@pytest.mark.parametrize("case", ["seed", "virtual"])
def test_the_demo_references_are_precise_enough_to_judge_5_percent(case):
    ref = _reference(case)
    assert ref["case"] == case
    assert ref["ess"] >= 5000
    assert max(ref["mc_error_mean_in_sd"]) < 0.015
    assert max(ref["mc_error_sd_relative"]) < 0.01
    # no single draw dominates the estimate
    assert ref["max_weight_share"] < 0.01


def test_the_shell_seed_reference_is_precise_enough_to_judge_5_percent():
    """The shell seed case's posterior reaches up towards t_hot_pipe's 3 mm bound (logit 0.995
    quantile 3.0 against the DE pilot's 2.2, where the frequencies hardly see it), which the
    defensive prior component alone covers: at 30 % of the proposal and 300,000 draws
    (``SHELL_SETTINGS``) the Monte Carlo errors stay within 0.015 sd and 1.5 % on every
    parameter (at 10 % and 200,000 draws the hot pipe's sd had 4.9 %; docs/guide/
    exhaust-shell.md, "The demo's shell posterior against its reference")."""
    ref = _reference("seed-shell")
    assert ref["case"] == "seed-shell" and ref["names"][0] == "t_hot_pipe"
    assert ref["settings"]["prior_weight"] == 0.3 and ref["draws"] == 300_000
    assert ref["ess"] >= 15000 and ref["max_weight_share"] < 0.01
    assert max(ref["mc_error_mean_in_sd"]) < 0.015
    assert max(ref["mc_error_sd_relative"]) < 0.015
    # the tail the pilot did not reach
    (low, high), (pilot_low, pilot_high) = (
        np.array(ref["tail"][k])[:, 0]
        for k in ("y_quantiles_0.005_0.995", "pilot_y_quantiles_0.005_0.995")
    )
    assert high > pilot_high + 0.5 and abs(low - pilot_low) < 0.2


def test_the_weighted_moments_and_quantiles_of_known_weights():
    # draws 0, 1, 2 with weights 1, 2, 1: mean 1, var 0.5; Kish ESS 16 / 6
    study = _study()
    theta = np.array([[0.0], [1.0], [2.0]])
    log_w = np.log([1.0, 2.0, 1.0])
    moments = study.weighted_moments(theta, log_w)
    assert moments["mean"] == pytest.approx([1.0])
    assert moments["sd"] == pytest.approx([np.sqrt(0.5)])
    assert moments["ess"] == pytest.approx(16 / 6)
    # cdf 0.25, 0.75, 1.0: the 0.2 quantile is 0, the 0.5 is 1, the 0.9 is 2
    q = study.weighted_quantiles(theta, log_w, (0.2, 0.5, 0.9))
    assert q[:, 0].tolist() == [0.0, 1.0, 2.0]


def _two_dof_space():
    from bayesupdate.inference import LikelihoodSpec, LogPosterior, build_problem
    from bayesupdate.inference.sampling import sampler_space
    from bayesupdate.modal_data import ModalData
    from bayesupdate.models import get_model
    from bayesupdate.models.shear_building import shear_building_frequencies

    data = ModalData(frequencies_hz=shear_building_frequencies(np.array([1.1, 0.9])))
    bounds = {"theta_1": {"bounds": [0.2, 3.0]}, "theta_2": {"bounds": [0.2, 3.0]}}
    problem = build_problem(get_model("shear_building"), data, bounds, pairing="order")
    return sampler_space(LogPosterior(problem, LikelihoodSpec(sigma=0.05)))


def test_a_proposal_that_misses_part_of_p_is_repaired_before_the_kept_run():
    """The adaptation saw one mode of a bimodal p (in the sampler's coordinates): the frozen
    mixture fails the coverage check; the repair's importance-resampled draws (the prior
    component reaches the other mode) refit it to cover both, and it passes with fresh draws.
    Without repair rounds the same stage falls back to DE (tests/test_inference_moves.py)."""
    from bayesupdate.inference.moves import staged_proposal
    from bayesupdate.inference.moves.staged import MAX_STUCK, MIN_COVERAGE, REPAIR_ROUNDS

    space = _two_dof_space()
    a, b, sd = np.array([-1.0, 0.5]), np.array([1.0, -0.5]), 0.2

    def one_mode(y, centre=a):
        return -0.5 * np.sum(((y - centre) / sd) ** 2, axis=1)

    def two_modes(y):
        return np.logaddexp(one_mode(y), one_mode(y, b))

    seen = a + sd * np.random.default_rng(0).standard_normal((100, 16, 2))
    stage = (seen, one_mode(seen.reshape(-1, 2)).reshape(100, 16))
    args = (lambda moves, n: stage, [], space, True, 100)
    proposal, info = staged_proposal(*args, seed=0, log_density=two_modes)
    assert proposal is None and info["coverage"] < 0.05
    proposal, info = staged_proposal(
        *args, seed=0, log_density=two_modes, repair_rounds=REPAIR_ROUNDS
    )
    assert proposal is not None and info["fallback"] is None
    assert info["repairs"] == REPAIR_ROUNDS and info["first_check"][0] < 0.05
    # the refit kept is the one that passed its check with the highest importance ESS
    passed = [c for c, stuck in info["repair_checks"] if c >= MIN_COVERAGE and stuck <= MAX_STUCK]
    assert info["coverage"] == max(passed)
    # a fresh check passes, and the refit put weight at the missed mode: p has half its mass
    # there, the points refitted are the 1600 stage draws (all at a) and 4000 resampled ones
    # (about half at b), so about 2000 / 5600 = 0.36 of the mixture
    assert info["coverage"] >= MIN_COVERAGE
    centres = proposal.from_mixture_coordinates(proposal.mixture.means)  # in y
    near_b = np.linalg.norm(centres - b, axis=1) < 3 * sd
    assert 0.25 < proposal.mixture.weights[near_b].sum() < 0.5


def _demo_default_against(case: str, seed: int):
    from bayesupdate.pipelines.sample import SamplingOptions, run_sampling

    study, ref = _study(), _reference(case)
    log_post, calibration, _, prepared = study.demo_posterior(case)
    assert list(log_post.names) == ref["names"]
    sampler = prepared.study.sampler
    assert sampler.seed == seed  # the demo's own run
    run = run_sampling(prepared, SamplingOptions(), calibration)
    assert run.posterior.converged
    errors = study.compare(ref, run.posterior.samples())
    assert np.max(errors["mean_error_in_sd"]) <= 0.05, errors
    assert np.max(np.abs(errors["sd_error_relative"])) <= 0.05, errors
    return run


# the seed case: the demo's calibration and run_sampling to its convergence targets, 277 s wall
# on the shared machine (the three long tests of the two files: 267 s CPU in all)
@LONG
def test_the_demos_seed_case_posterior_matches_its_reference():
    run = _demo_default_against("seed", 1)
    # the mixture is kept, not DE (sds 5-11 % small here, docs/validation/posterior.md): with
    # logit coordinates only after a repair (first check 0.186 / 0.090); since the choice of
    # coordinates (moves.staged.proposal_coordinates) its first check passes
    moves = run.posterior.diagnostics["moves"]
    assert moves["kind"] == "mixture" and moves["fallback"] is None


# the virtual test: FRFs, identification, calibration and sampling, 68 s wall
@LONG
def test_the_demos_virtual_test_posterior_matches_its_reference():
    run = _demo_default_against("virtual", 1)
    assert run.posterior.diagnostics["moves"]["kind"] == "mixture"


@pytest.fixture(scope="module")
def shell_seed_case():
    """The demo's shell seed case as the demo prepares it (its certified basis and optimum)."""
    return _study().demo_posterior("seed-shell")


# the demo's seed case on the shell exhaust: the demo's own sampler seed 1 and seeds 5 and 9,
# which missed the reference (rho_catalyst's sd 6.7 % and 5.4 % small) while the mixture was
# fitted in the walkers' logit coordinates; with the unit box chosen (moves.staged
# proposal_coordinates) they meet it in 3,500 / 2,000 / 1,500 kept steps
# (docs/validation/posterior.md): run_sampling to its convergence targets
@LONG
@pytest.mark.parametrize("seed", [1, 5, 9])
def test_the_demos_shell_seed_case_posterior_matches_its_reference(shell_seed_case, seed):
    from dataclasses import replace

    from bayesupdate.pipelines.sample import SamplingOptions, run_sampling

    study, ref = _study(), _reference("seed-shell")
    log_post, calibration, _, prepared = shell_seed_case
    assert list(log_post.names) == ref["names"] and prepared.problem.model.name == "exhaust_shell"
    assert prepared.study.sampler.seed == 1  # the demo's own run
    sampler = replace(prepared.study.sampler, seed=seed)
    prepared = replace(prepared, study=replace(prepared.study, sampler=sampler))
    run = run_sampling(prepared, SamplingOptions(), calibration)
    assert run.posterior.converged
    assert run.posterior.diagnostics["moves"]["coordinates"][-1] == "unit box"
    errors = study.compare(ref, run.posterior.samples())
    assert np.max(errors["mean_error_in_sd"]) <= 0.05, errors
    assert np.max(np.abs(errors["sd_error_relative"])) <= 0.05, errors
