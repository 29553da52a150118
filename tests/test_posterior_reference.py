"""The default sampler against the importance-sampling reference of the exhaust posterior (issue
21): means within 0.05 sd and sds within 5 % of the reference, every parameter.

The reference (tests/data/posterior_reference_exhaust.json, made by
studies/posterior_reference.py) has Monte Carlo errors of about 0.009 sd in the means and 0.6 %
in the sds.  DE moves alone fail this check (sds 4-10 % small; the study's pilot DE run
is 5-9 % small).  One seed here; the study's ``--check 5`` and benchmarks/posterior_speed.py
report five (docs/validation/posterior.md).
"""

import importlib.util
import json
import os
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.inference import SamplerSettings, sample_posterior

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = json.loads((ROOT / "tests" / "data" / "posterior_reference_exhaust.json").read_text())


def _study():
    spec = importlib.util.spec_from_file_location(
        "posterior_reference", ROOT / "studies" / "posterior_reference.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_reference_is_precise_enough_to_judge_5_percent():
    assert REFERENCE["ess"] >= 5000
    assert max(REFERENCE["mc_error_mean_in_sd"]) < 0.015
    assert max(REFERENCE["mc_error_sd_relative"]) < 0.01


# about 90 s of CPU (526 s wall on the loaded development machine): beyond the suite's 5-minute
# budget, so it runs on request; benchmarks/posterior_speed.py checks five seeds the same way
@pytest.mark.skipif(
    not os.environ.get("BAYESUPDATE_LONG_TESTS"),
    reason="long: set BAYESUPDATE_LONG_TESTS=1 (benchmarks/posterior_speed.py runs five seeds)",
)
def test_default_sampler_matches_the_reference():
    study = _study()
    log_post, calibration, screen, _ = study.exhaust_posterior()
    assert list(log_post.names) == REFERENCE["names"]
    # the benchmark's run (benchmarks/posterior_speed.py) with the default moves, run on to a
    # bulk ESS of 2000 so the sampler's own Monte Carlo error (~0.02 sd, ~2-3 % in sd for
    # t_cold_pipe's heavy tail) leaves room inside the 5 % tolerance
    settings = SamplerSettings(
        walkers=16, steps=20000, seed=1, check_every=250, transform="logit",
        target_rhat=1.01, target_ess=2000,
    )  # fmt: skip
    post = sample_posterior(log_post, calibration, settings, screen=screen)
    assert post.converged and post.diagnostics["moves"]["kind"] == "mixture"
    errors = study.compare(REFERENCE, post.samples())
    assert np.max(errors["mean_error_in_sd"]) <= 0.05, errors
    assert np.max(np.abs(errors["sd_error_relative"])) <= 0.05, errors
