"""Where the walkers start (``inference.walker_start``): inside a narrow posterior, not tens of
sds out; and a walker that never moves gives no RuntimeWarning but a "not converged" reason.

A plate-like model (12 modes, two thicknesses in the FEMAP exhaust's bounds) with identified
frequency sds of 1e-5 relative: its posterior is ~4e-7 wide in a 0.04 box, as on the exhaust.
"""

import types
import warnings

import numpy as np
import pytest

from bayesupdate.inference import (
    CalibrationSettings,
    FunctionModel,
    LikelihoodSpec,
    LogPosterior,
    SamplerSettings,
    build_problem,
    calibrate,
    prior_from_mapping,
    sample_posterior,
)
from bayesupdate.inference.diagnostics import convergence_report
from bayesupdate.inference.sampling import _autocorr, initial_walkers
from bayesupdate.inference.walker_start import axis_sd, sigma_start
from bayesupdate.modal_data import ModalData

W = np.linspace(0.1, 0.9, 12)
C = 100.0 * np.arange(1, 13)
TRUTH = {"t_3": 0.0595, "t_9": 0.0592}


def _plate(p):
    return C * np.sqrt(W * p["t_3"] ** 2 + (1 - W) * p["t_9"] ** 2) / 0.06


MODEL = FunctionModel(
    _plate,
    ("t_3", "t_9"),
    (("t_3", 0.06), ("t_9", 0.06)),
    (("t_3", (0.04, 0.08)), ("t_9", (0.04, 0.09))),
    label="plate",
)
SIGMA_PRIOR = prior_from_mapping({"kind": "halfnormal", "scale": 0.01}, (0.0, np.inf), "sigma")


def _posterior(rel_sd: float | None, noise: float, sigma_prior: bool = True):
    f = _plate(TRUTH)
    e = np.random.default_rng(0).standard_normal(f.size)
    sd = None if rel_sd is None else rel_sd * f
    data = ModalData(frequencies_hz=f * (1 + noise * e), identification_sd_hz=sd)
    problem = build_problem(MODEL, data, None, pairing="order")
    spec = (
        LikelihoodSpec(sigma=None, sigma_prior=SIGMA_PRIOR)
        if sigma_prior
        else LikelihoodSpec(sigma=1e-5)
    )
    optimum = calibrate(problem, CalibrationSettings(starts=2, seed=0))
    return LogPosterior(problem, spec), optimum


def test_axis_sd_is_a_gaussians_sd_off_its_mode_and_capped():
    sd = np.array([3e-7, 2e-3, 5.0])
    mode = np.array([0.06, 0.05, 1.0])

    def density(x):
        return -0.5 * np.sum(((x - mode) / sd) ** 2, axis=1)

    centre = mode + 0.7 * sd * np.array([1, -1, 1])  # the gradient cancels in the differences
    cap = np.full(3, 0.01)
    np.testing.assert_allclose(axis_sd(density, centre, cap), [3e-7, 2e-3, 0.01], rtol=1e-6)
    # no density at the centre: nothing measured, the cap stays
    np.testing.assert_array_equal(axis_sd(lambda x: np.full(len(x), -np.inf), centre, cap), cap)


def test_walkers_start_inside_a_narrow_posterior():
    log_post, optimum = _posterior(rel_sd=1e-5, noise=1e-5)
    walkers = initial_walkers(log_post, optimum, 32, np.random.default_rng(1))
    lp = log_post(walkers)
    # the best point near the optimum: sigma at its grid start, thicknesses at the optimum
    best = log_post(np.append(optimum.theta, walkers[0, -1])[None, :])[0]
    # each of the 3 coordinates ~1 conditional sd: a drop of about chi2_3 / 2 (99.9 %: 8.1
    # nats; 32 walkers and the thicknesses' correlation: up to twice that)
    assert np.all(best - lp < 16.0), best - lp
    # the ball of 1e-3 of the bounds alone (the start before) is ~100 sd out: drops of ~1e4
    width = np.append(log_post.problem.upper - log_post.problem.lower, 0.0)
    old = walkers[0] + 1e-3 * width * np.random.default_rng(1).standard_normal((32, 3))
    assert np.median(best - log_post(old)) > 1e3
    # the model error is ~0 here (the identified sds explain the scatter): sigma starts far
    # below the old start of 1e-3
    assert np.all(walkers[:, -1] < 1e-4)


def test_sigma_start_keeps_the_old_start_where_it_was_right():
    # a 1 % scatter and no identified sds: the rms residual (the old start) is the level
    log_post, optimum = _posterior(rel_sd=None, noise=1e-2)
    s0 = float(np.sqrt(optimum.expr / 12))
    assert sigma_start(log_post, optimum.theta, s0) == s0
    # tiny identified sds: the grid's best is far below the rms of 1e-3
    log_post, optimum = _posterior(rel_sd=1e-5, noise=1e-5)
    assert sigma_start(log_post, optimum.theta, 1e-3) < 1e-4


def test_a_walker_that_never_moves_gives_no_warning_and_is_not_converged():
    chain = np.random.default_rng(0).standard_normal((400, 8, 2)).cumsum(axis=0) * 0.01
    chain[:, 3, :] = 0.5  # one stuck walker: emcee's acf / acf[0] is 0 / 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tau = _autocorr(chain)
    assert np.all(np.isnan(tau))
    result = types.SimpleNamespace(chain=chain, autocorr_time=tau, converged=False)
    summary = {"a": {"r_hat": 1.0, "ess_bulk": 1e4}, "b": {"r_hat": 1.0, "ess_bulk": 1e4}}
    report = convergence_report(result, summary, 1.01, 400.0, 50.0)
    assert not report["converged"]
    assert "autocorrelation time undefined: a walker never moved" in report["reason"]


@pytest.mark.parametrize("sigma_prior", [True, False])
def test_seeded_start_is_reproducible(sigma_prior):
    log_post, optimum = _posterior(rel_sd=1e-5, noise=1e-5, sigma_prior=sigma_prior)
    a = initial_walkers(log_post, optimum, 16, np.random.default_rng(3))
    b = initial_walkers(log_post, optimum, 16, np.random.default_rng(3))
    assert np.array_equal(a, b)
    assert log_post.evaluations == 2 * 2 * 16  # the probes are not counted, the start's are


def test_tight_identified_sds_sample_to_the_truth_within_its_posterior_sd():
    # one mode identified 30 x worse than the rest (the exhaust's 110.4 Hz mode): its sd
    # weights it down, so the thicknesses come back within their (honest) posterior sd
    f = _plate(TRUTH)
    sd = 1e-5 * f
    sd[5] = 3e-4 * f[5]
    e = np.random.default_rng(0).standard_normal(f.size)
    data = ModalData(frequencies_hz=f + sd * e, identification_sd_hz=sd)
    problem = build_problem(MODEL, data, None, pairing="order")
    optimum = calibrate(problem, CalibrationSettings(starts=2, seed=0))
    log_post = LogPosterior(problem, LikelihoodSpec(sigma=None, sigma_prior=SIGMA_PRIOR))
    post = sample_posterior(log_post, optimum, SamplerSettings(seed=1, progress=False))
    assert post.converged
    x = post.samples()
    z = (x[:, :2].mean(axis=0) - [TRUTH["t_3"], TRUTH["t_9"]]) / x[:, :2].std(axis=0)
    # the truth within 2 sd of each thickness (measured: -0.58, +0.55)
    assert np.all(np.abs(z) < 2.0), z
    # and narrow: measured 4.3e-7 and 4.4e-7 (the good modes' 1e-5 is 6e-7 of a thickness);
    # with one level for all modes (the sds ignored) it is 1.5e-6, 3.5 x wider
    assert np.all(x[:, :2].std(axis=0) < 1e-6)
