"""The adaptation stages of a screened run sample the delayed-acceptance surrogate alone
(``inference.sampling._adaptation_stage``): no exact evaluation inside a stage, and the kept
chain still carries the exact log posterior of every one of its points."""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from bayesupdate.inference import (  # noqa: E402
    CalibrationSettings,
    LikelihoodSpec,
    LogPosterior,
    SamplerSettings,
    build_problem,
    calibrate,
    sample_posterior,
)
from bayesupdate.inference.moves.staged import STAGE_PRIOR_WEIGHTS  # noqa: E402
from bayesupdate.modal_data import ModalData  # noqa: E402
from bayesupdate.models import get_model  # noqa: E402
from bayesupdate.models.shear_building import shear_building_frequencies  # noqa: E402

WALKERS, ADAPT = 16, 60


@pytest.fixture(scope="module")
def shear():
    data = ModalData(frequencies_hz=shear_building_frequencies(np.array([1.1, 0.9])) * [1.01, 0.99])
    bounds = {"theta_1": {"bounds": [0.2, 3.0]}, "theta_2": {"bounds": [0.2, 3.0]}}
    problem = build_problem(get_model("shear_building"), data, bounds, pairing="order")
    return problem, calibrate(problem, CalibrationSettings(starts=8, seed=0))


def _screened_run(shear, steps: int):
    """(exact posterior, its surrogate (sigma 4 % larger: a different density), the result)."""
    problem, optimum = shear
    exact = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    surrogate = LogPosterior(problem, LikelihoodSpec(sigma=0.052))
    settings = SamplerSettings(
        walkers=WALKERS, steps=steps, seed=4, check_every=100, adapt_steps=ADAPT,
        min_autocorr_times=1e9,
    )  # fmt: skip
    return exact, surrogate, sample_posterior(exact, optimum, settings, screen=surrogate)


@pytest.fixture(scope="module")
def one_step(shear):
    return _screened_run(shear, steps=1)


def test_the_adaptation_stages_spend_no_exact_evaluation(one_step):
    exact, _, post = one_step
    assert post.diagnostics["moves"]["kind"] == "mixture"
    stages = len(STAGE_PRIOR_WEIGHTS)
    # exact: the start (initial_walkers' two batches, the first log-density), the walkers
    # re-scored after each stage, and one kept step; delayed acceptance inside the stages
    # spent 1583 here (each stage-1 survivor)
    assert exact.evaluations <= WALKERS * (2 + 1 + stages + 1)
    # the surrogate sees every walker at every adaptation step
    assert post.screen_evaluations >= WALKERS * ADAPT * stages


def _exact_and_surrogate_at(exact, surrogate, post) -> tuple[np.ndarray, np.ndarray]:
    """(p, q) at every chain point, shaped as ``post.log_prob``, from fresh posteriors."""
    points = post.chain.reshape(-1, post.chain.shape[-1])
    p = LogPosterior(exact.problem, exact.spec)(points)
    q = LogPosterior(surrogate.problem, surrogate.spec)(points)
    return p.reshape(post.log_prob.shape), q.reshape(post.log_prob.shape)


@pytest.mark.parametrize("steps", [1, 20])
def test_the_kept_chain_holds_the_exact_log_posterior_of_its_points(shear, one_step, steps):
    """A walker whose first kept proposal is refused keeps the log-density the stages left it:
    had that been the surrogate's, the chain's log_prob would be q's there, and the MH ratios
    of its next proposals wrong."""
    exact, surrogate, post = one_step if steps == 1 else _screened_run(shear, steps)
    p, q = _exact_and_surrogate_at(exact, surrogate, post)
    np.testing.assert_allclose(post.log_prob, p, rtol=0, atol=1e-12)
    # the check could fail: the surrogate's values there differ by far more than that
    assert np.max(np.abs(q - p)) > 0.05
    if steps == 1:  # some walkers refused the one kept step: they carry the stages' values
        assert np.any(post.acceptance == 0)
