"""Sampling: seeded reproducibility, resume after interruption, failures counted, bad inputs."""

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference import (
    CalibrationSettings,
    FunctionModel,
    LikelihoodSpec,
    LogPosterior,
    SamplerSettings,
    build_problem,
    calibrate,
    load_user_model,
    prior_from_mapping,
    read_sampler_state,
    sample_posterior,
    write_result,
)
from bayesupdate.modal_data import ModalData
from bayesupdate.models import get_model
from bayesupdate.models.shear_building import shear_building_frequencies

DATA = ModalData(frequencies_hz=shear_building_frequencies(np.array([1.1, 0.9])) * [1.01, 0.99])


@pytest.fixture(scope="module")
def setup():
    # theta_2 fixed: two frequencies, one parameter and sigma, so the residual is not zero
    problem = build_problem(get_model("shear_building"), DATA, {"theta_1": {}}, pairing="order")
    return problem, calibrate(problem, CalibrationSettings(starts=8, seed=0))


def _spec() -> LikelihoodSpec:
    sigma_prior = prior_from_mapping({"kind": "halfnormal", "scale": 0.1}, (0.0, np.inf), "sigma")
    return LikelihoodSpec(sigma=None, sigma_prior=sigma_prior)


def _settings(**kwargs) -> SamplerSettings:
    # short adaptation stages: these tests are about seeding and resuming, not accuracy
    options = dict(
        walkers=16, steps=300, seed=5, check_every=100, min_autocorr_times=1e9, adapt_steps=50
    )
    return SamplerSettings(**{**options, **kwargs})


def _run(problem, optimum, stop_request=None, **kwargs):
    return sample_posterior(
        LogPosterior(problem, _spec()), optimum, _settings(**kwargs), stop_request=stop_request
    )


def test_seeded_runs_are_identical_and_seeds_differ(setup):
    problem, optimum = setup
    a = _run(problem, optimum)
    b = _run(problem, optimum)
    assert a.chain.shape == (300, 16, 2)
    assert np.array_equal(a.chain, b.chain) and np.array_equal(a.log_prob, b.log_prob)
    c = _run(problem, optimum, seed=6)
    assert not np.array_equal(a.chain, c.chain)


class _InterruptAt(LogPosterior):
    """Raises KeyboardInterrupt (as Ctrl-C would) at the n-th call."""

    def __init__(self, problem, spec, at):
        super().__init__(problem, spec)
        self.calls, self.at = 0, at

    def __call__(self, theta):
        self.calls += 1
        if self.calls == self.at:
            raise KeyboardInterrupt
        return super().__call__(theta)


# the mixture's two adaptation stages (50 steps each) take ~110 log-posterior calls: interrupt
# inside the kept run
@pytest.mark.parametrize("moves, at", [("de", 333), ("mixture", 333)])
def test_resume_after_interruption_gives_the_identical_chain(setup, tmp_path, moves, at):
    problem, optimum = setup
    full = _run(problem, optimum, moves=moves)
    spec, settings = _spec(), _settings(moves=moves)
    broken = sample_posterior(_InterruptAt(problem, spec, at=at), optimum, settings)
    assert broken.interrupted and 0 < broken.chain.shape[0] < 300
    np.testing.assert_array_equal(broken.chain, full.chain[: broken.chain.shape[0]])
    # through the result file, as `sample --resume` does
    path = tmp_path / "partial.h5"
    write_result(path, problem, optimum, {"x": 1}, state=broken.state)
    state = read_sampler_state(path)
    resumed = sample_posterior(LogPosterior(problem, spec), optimum, settings, resume=state)
    assert np.array_equal(resumed.chain, full.chain)
    assert np.array_equal(resumed.log_prob, full.log_prob)
    assert resumed.diagnostics["moves"]["kind"] == moves


def test_a_signal_landing_in_the_step_bookkeeping_still_resumes_identically(setup, monkeypatch):
    """A SIGTERM's handler raises where it lands (``compute.stop.StopRequest.handler``).  Landing
    between a step's record in the chain and the run's state (made here at the 200th state
    ``_run_block`` records: the 50th kept step after three adaptation stages of 50) used to
    leave the step recorded but the state one step behind, so the resume drew that step twice;
    the bookkeeping is now deferred as a whole."""
    import sys

    import emcee

    from bayesupdate.compute.stop import StopRequest
    from bayesupdate.inference import sampling

    problem, optimum = setup
    full = _run(problem, optimum)
    request, made = StopRequest(), []

    state = emcee.State

    def state_then_signal(*args, **kwargs):
        if sys._getframe(1).f_code.co_name == "_run_block":
            made.append(1)
            if len(made) == 200:
                request.handler(15, None)  # the signal lands here
        return state(*args, **kwargs)

    monkeypatch.setattr(sampling.emcee, "State", state_then_signal)
    broken = _run(problem, optimum, stop_request=request)
    monkeypatch.undo()
    assert broken.interrupted and 0 < broken.chain.shape[0] < 300
    assert np.array_equal(broken.state.coords, broken.chain[-1])  # the state is the last step
    resumed = sample_posterior(
        LogPosterior(problem, _spec()), optimum, _settings(), resume=broken.state
    )
    assert np.array_equal(resumed.chain, full.chain)


def test_a_signal_landing_in_emcees_code_around_a_model_call_prints_nothing(
    setup, monkeypatch, capsys
):
    """emcee calls the log-density inside its own try, which prints "emcee: Exception while
    calling your likelihood function" and a traceback for any exception, a KeyboardInterrupt
    included.  A signal landing there (made here at the 500th call, before the guarded
    model call starts: what a Ctrl-C did once under load) only records the stop: emcee's steps
    run deferred and only the model call is interruptible (``StopRequest.interruptible``).
    The run stops at the end of that step, silently, and resumes to the uninterrupted chain."""
    from bayesupdate.compute.stop import StopRequest
    from bayesupdate.inference import sampling

    problem, optimum = setup
    full = _run(problem, optimum)
    request, calls = StopRequest(), []
    guard = sampling._guard

    def guard_then_signal(*args, **kwargs):
        guarded = guard(*args, **kwargs)

        def landing(x):
            calls.append(1)
            if len(calls) == 500:
                request.handler(2, None)  # SIGINT lands in emcee's code, outside the model
            return guarded(x)

        return landing

    monkeypatch.setattr(sampling, "_guard", guard_then_signal)
    broken = _run(problem, optimum, stop_request=request)
    monkeypatch.undo()
    captured = capsys.readouterr()
    assert "emcee" not in captured.out + captured.err and "Traceback" not in captured.err
    assert broken.interrupted and 0 < broken.chain.shape[0] < 300
    resumed = sample_posterior(
        LogPosterior(problem, _spec()), optimum, _settings(), resume=broken.state
    )
    assert np.array_equal(resumed.chain, full.chain)


def test_a_stop_request_raises_only_outside_deferred_blocks_or_inside_interruptible_ones():
    from bayesupdate.compute.stop import StopRequest

    request = StopRequest()
    with request.deferred():
        request.handler(2, None)  # recorded, not raised
        with pytest.raises(KeyboardInterrupt), request.interruptible():
            request.handler(2, None)
        request.handler(2, None)  # deferred again after the interruptible block
    assert request.requested()
    with pytest.raises(KeyboardInterrupt):
        request.handler(2, None)


def test_stopped_while_adapting_resumes_to_the_identical_chain(setup):
    """A stop inside the adaptation stages leaves an empty chain and no proposal; the resume
    starts again from the seed and ends with the uninterrupted chain."""
    problem, optimum = setup
    spec = LikelihoodSpec(sigma=0.05)
    settings = SamplerSettings(walkers=16, steps=100, seed=5, min_autocorr_times=1e9)
    whole = sample_posterior(LogPosterior(problem, spec), optimum, settings)
    broken = sample_posterior(_InterruptAt(problem, spec, at=20), optimum, settings)
    assert broken.interrupted and broken.chain.shape[0] == 0 and broken.state.moves is None
    resumed = sample_posterior(LogPosterior(problem, spec), optimum, settings, resume=broken.state)
    assert resumed.chain.shape == (100, 16, 1) and not resumed.interrupted
    assert np.array_equal(resumed.chain, whole.chain)
    assert resumed.diagnostics["moves"]["kind"] == "mixture"


def test_stops_at_fifty_autocorrelation_times(setup):
    problem, optimum = setup
    result = _run(problem, optimum, walkers=16, steps=20000, check_every=250, min_autocorr_times=50)
    assert result.converged
    assert result.chain.shape[0] >= 50 * np.max(result.autocorr_time)
    assert result.chain.shape[0] < 20000


def flaky(params):
    """Raises in one region and returns NaN in another (a user's fragile model)."""
    if params["a"] > 1.5:
        raise RuntimeError("solver diverged")
    if params["a"] < 0.7:
        return [np.nan, np.nan]
    return np.array([10.0 * params["a"], 25.0 * params["a"]])


def test_custom_model_failures_count_as_minus_infinity():
    model = FunctionModel(flaky, ("a",), (("a", 1.0),), (("a", (0.5, 2.0)),), label="flaky")
    problem = build_problem(model, ModalData(frequencies_hz=[10.0, 25.0]), pairing="order")
    log_post = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    lp = log_post(np.array([[1.0], [1.8], [0.6]]))
    assert np.isfinite(lp[0]) and lp[1] == -np.inf and lp[2] == -np.inf
    assert log_post.failed == 2 and log_post.evaluations == 3
    optimum = calibrate(problem, CalibrationSettings(starts=8, seed=0))
    assert optimum.parameters["a"] == pytest.approx(1.0, rel=1e-6)
    assert optimum.failed_evaluations > 0
    settings = SamplerSettings(walkers=8, steps=400, seed=1, min_autocorr_times=1e9)
    result = sample_posterior(log_post, optimum, settings)
    assert np.all(np.isfinite(result.log_prob))


def test_user_model_import(tmp_path, monkeypatch):
    (tmp_path / "my_beam.py").write_text(
        "def model(p):\n"
        "    return {'frequencies_hz': [5.0 * p['k'], 9.0 * p['k']], 'mass_kg': 2.0}\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    model = load_user_model("my_beam:model", {"k": {"bounds": [0.5, 2.0], "start": 1.0}})
    problem = build_problem(model, ModalData(frequencies_hz=[6.0, 10.8]))
    fit = calibrate(problem, CalibrationSettings(starts=4, seed=0))
    assert fit.parameters["k"] == pytest.approx(1.2, rel=1e-6)
    with pytest.raises(BayesUpdateError, match="does not import"):
        load_user_model("no_such_package.sub:model", {"k": {"bounds": [0.5, 2.0]}})
    with pytest.raises(BayesUpdateError, match="has no function"):
        load_user_model("my_beam:missing", {"k": {"bounds": [0.5, 2.0]}})


def test_parameter_outside_bounds_is_an_error():
    with pytest.raises(BayesUpdateError, match="outside bounds"):
        build_problem(get_model("shear_building"), DATA, {"theta_1": {"bounds": [0.2, 0.8]}})
    with pytest.raises(BayesUpdateError, match="unknown parameter"):
        build_problem(get_model("shear_building"), DATA, {"theta_9": {}})


def test_too_few_walkers_is_an_error(setup):
    problem, optimum = setup
    with pytest.raises(BayesUpdateError, match="too few"):
        _run(problem, optimum, walkers=3)


def test_a_block_continues_from_walkers_an_adaptation_stage_left_on_one_point():
    """emcee refuses to *start* from walkers that do not span the space; the sampler runs its
    blocks from states it reached itself, and after an adaptation stage of independence
    proposals several walkers can sit on one point (seed 12 of ``tests/test_reproducibility``'s
    study with 60-step stages stopped with an internal error before).  The first block of a
    run keeps emcee's check."""
    import emcee

    from bayesupdate.compute.stop import StopRequest
    from bayesupdate.inference.sampling import _NoBar, _Run, _run_block

    rng = np.random.default_rng(0)
    coords = np.repeat(rng.normal(size=(1, 2)), 8, axis=0)  # 8 walkers on one point
    coords[:3] += rng.normal(size=(1, 2))  # two distinct points: a line in 2 dimensions

    def log_p(x):
        return -0.5 * np.sum(x * x, axis=1)

    sampler = emcee.EnsembleSampler(8, 2, log_p, vectorize=True)
    run = _Run(emcee.State(coords, log_prob=log_p(coords)), [], [], np.zeros(8), 0.0)
    with pytest.raises(ValueError, match="large condition number"):
        _run_block(sampler, run, 5, StopRequest(), _NoBar())
    run.stepped = True
    out, lps, interrupted = _run_block(sampler, run, 5, StopRequest(), _NoBar())
    assert len(out) == 5 and not interrupted
    np.testing.assert_array_equal(run.state.log_prob, log_p(run.state.coords))
