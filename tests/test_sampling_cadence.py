"""When the sampler checks its stop rule: often enough that a run stops near the step count at
which its targets first hold (within ``CHECK_GROWTH``), at step counts fixed by the count alone
(so a resumed run checks where an uninterrupted one does), with checkpoints only at the
multiples of ``check_every``."""

import numpy as np
import pytest

from bayesupdate.inference import (
    CalibrationSettings,
    LikelihoodSpec,
    LogPosterior,
    SamplerSettings,
    build_problem,
    calibrate,
    sample_posterior,
)
from bayesupdate.inference.sampling import (
    CHECK_GROWTH,
    CHECK_MIN_STEPS,
    _stop_rule,
    check_schedule,
    stop_record,
)
from bayesupdate.modal_data import ModalData
from bayesupdate.models import get_model
from bayesupdate.models.shear_building import shear_building_frequencies

DATA = ModalData(frequencies_hz=shear_building_frequencies(np.array([1.1, 0.9])) * [1.01, 0.99])


def _checks(check_every: int, steps: int) -> list[int]:
    out, done = [], 0
    while done < steps:
        done = check_schedule(done, check_every, steps)
        out.append(done)
    return out


def test_checks_are_geometric_and_include_every_checkpoint():
    checks = _checks(500, 5000)
    assert checks[:3] == [20, 40, 60] and checks[-1] == 5000
    assert set(range(500, 5001, 500)) <= set(checks)
    # a stop lands at most 10 % (CHECK_MIN_STEPS early on) past the step the rule first holds
    for a, b in zip(checks[:-1], checks[1:], strict=True):
        assert a < b <= max(np.ceil(CHECK_GROWTH * a), a + CHECK_MIN_STEPS)
    assert len(checks) == 53  # 5,000 steps: blocks of 500 made 10 checks
    # the schedule depends on the step count alone: resuming at any count rejoins it
    assert _checks(500, 5000)[5:] == [c for c in checks if c > checks[4]]
    assert check_schedule(checks[7] - 3, 500, 5000) == checks[7]


def test_run_stops_within_ten_percent_of_the_first_step_where_its_targets_hold():
    """A one-parameter posterior with R-hat and ESS targets: the run's last step is a check at
    which the rule holds, and no step count more than 10 % (CHECK_MIN_STEPS early on) before
    it satisfies the rule already (replayed on the stored chain's prefixes: the chain up to any
    step is what the run had there)."""
    problem = build_problem(get_model("shear_building"), DATA, {"theta_1": {}}, pairing="order")
    optimum = calibrate(problem, CalibrationSettings(starts=8, seed=0))
    settings = SamplerSettings(
        walkers=16, steps=5000, seed=3, check_every=1000, min_autocorr_times=20,
        target_rhat=1.01, target_ess=800, adapt_steps=50,
    )  # fmt: skip
    post = sample_posterior(LogPosterior(problem, LikelihoodSpec(sigma=0.05)), optimum, settings)
    n = post.chain.shape[0]
    assert post.converged and n < 1000  # blocks of check_every would have run to 1000
    assert _stop_rule(post.chain, n, settings)[1]
    first = next(
        k for k in range(CHECK_MIN_STEPS, n + 1) if _stop_rule(post.chain[:k], k, settings)[1]
    )
    assert n <= max(np.ceil(CHECK_GROWTH * first), first + CHECK_MIN_STEPS)
    # the stop record: the run's last check, its least ESS (the rule's own, recomputed here)
    # over the target, and what held the run at the check before (one of the three criteria)
    stop = post.diagnostics["stop"]
    met, held, ess = _stop_rule(post.chain, n, settings)[1:]
    assert met and held is None and stop["steps"] == n and stop["ess_at_stop"] == round(ess, 1)
    assert stop["ess_over_target"] == round(ess / 800, 2) and stop["ess_over_target"] >= 1.0
    assert stop["held_before"] in ("tau", "r_hat", "ess")
    assert stop["checks"] == len([c for c in _checks(1000, 5000) if c <= n])


def test_stop_record_says_what_held_the_run_before_the_stop():
    checks = [(20, "tau", np.nan), (40, "r_hat", np.nan), (60, None, 1234.5)]
    assert stop_record(checks, 400.0) == {
        "checks": 3, "steps": 60, "held_before": "r_hat", "ess_at_stop": 1234.5,
        "ess_over_target": 3.09,
    }  # fmt: skip
    # never stopped (the budget ended it): no ESS at a stop
    never = stop_record(checks[:2], 400.0)
    assert never["held_before"] is None and never["ess_at_stop"] is None and never["steps"] == 40
    assert stop_record([(20, None, np.nan)], None)["ess_over_target"] is None


@pytest.mark.parametrize("check_every", [100, 7])
def test_checkpoints_only_at_multiples_of_check_every(check_every):
    problem = build_problem(get_model("shear_building"), DATA, {"theta_1": {}}, pairing="order")
    optimum = calibrate(problem, CalibrationSettings(starts=4, seed=0))
    settings = SamplerSettings(
        walkers=8, steps=250, seed=1, check_every=check_every, min_autocorr_times=1e9,
        moves="de",
    )  # fmt: skip
    seen = []
    log_post = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    sample_posterior(log_post, optimum, settings, checkpoint=lambda s: seen.append(s))
    done = [s.chain.shape[0] for s in seen]
    assert done == [*range(check_every, 250, check_every), 250]
    assert [s.finished for s in seen] == [False] * (len(done) - 1) + [True]
