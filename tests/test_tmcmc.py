"""TMCMC (``inference.tmcmc``): evidence and posterior against closed forms, mode weights,
stalls, seeded reproducibility."""

import numpy as np
import pytest
from scipy import stats

from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference import TMCMCSettings, tmcmc


def _linear_gaussian():
    """y = A x + e, x ~ N(0, s0^2 I), e ~ N(0, s^2 I): closed-form evidence N(y; 0, C) with
    C = s0^2 A A^T + s^2 I, and posterior N(mu, P) (Bishop 2006 eqs. 2.113-2.117, 3.86)."""
    rng = np.random.default_rng(42)
    d, m, s0, s = 3, 8, 2.0, 0.3
    a = rng.normal(size=(m, d))
    y = a @ np.array([0.7, -0.4, 1.1]) + s * rng.normal(size=m)
    log_z = stats.multivariate_normal(np.zeros(m), s0**2 * a @ a.T + s**2 * np.eye(m)).logpdf(y)
    cov = np.linalg.inv(np.eye(d) / s0**2 + a.T @ a / s**2)
    mean = cov @ a.T @ y / s**2

    def prior_sample(rng, n):
        return rng.normal(0.0, s0, size=(n, d))

    def log_prior(x):
        return np.sum(stats.norm(0.0, s0).logpdf(x), axis=1)

    def log_like(x):
        r = (y - x @ a.T) / s
        return -0.5 * np.sum(r**2, axis=1) - m * np.log(s) - 0.5 * m * np.log(2 * np.pi)

    return (prior_sample, log_prior, log_like), log_z, mean, np.sqrt(np.diag(cov))


def test_linear_gaussian_evidence_and_posterior():
    problem, log_z, mean, sd = _linear_gaussian()
    runs = [tmcmc(*problem, TMCMCSettings(particles=1000, seed=seed)) for seed in range(4)]
    values = np.array([r.log_evidence for r in runs])
    # the information gain is ~9 nats: several stages, each weight CoV 1
    assert all(r.stages >= 4 for r in runs)
    assert np.all(np.diff(runs[0].betas) > 0) and runs[0].betas[-1] == 1.0
    # MC error of one run (sd over seeds 0-15 at N = 1000, measured: 0.13 nats; their mean
    # -0.035 +- 0.033): each run within 3 sd, the mean of 4 within 3 sd / sqrt(4)
    assert np.all(np.abs(values - log_z) < 0.4)
    assert abs(values.mean() - log_z) < 0.2
    for r in runs:
        assert np.all(np.abs(r.samples.mean(axis=0) - mean) < 0.15 * sd)
        # measured over seeds 0-15: |mean error| <= 0.09 sd, |sd ratio - 1| <= 0.078
        assert np.all(np.abs(r.samples.std(axis=0) / sd - 1) < 0.09)


def test_bimodal_weights():
    """Uniform prior on [-5, 5], L a 0.3 / 0.7 mixture of narrow Gaussians at -2 and 2:
    Z = 1/10, posterior mass 0.7 on x > 0."""

    def log_like(x):
        x = x[:, 0]
        return np.logaddexp(
            np.log(0.3) + stats.norm(-2.0, 0.3).logpdf(x),
            np.log(0.7) + stats.norm(2.0, 0.3).logpdf(x),
        )

    def log_prior(x):
        return np.where(np.all(np.abs(x) <= 5.0, axis=1), -np.log(10.0), -np.inf)

    def prior_sample(rng, n):
        return rng.uniform(-5.0, 5.0, size=(n, 1))

    shares, values = [], []
    for seed in range(3):
        r = tmcmc(prior_sample, log_prior, log_like, TMCMCSettings(particles=2000, seed=seed))
        shares.append(np.mean(r.samples[:, 0] > 0))
        values.append(r.log_evidence)
        # every particle sits in one of the modes
        assert np.max(np.abs(np.abs(r.samples[:, 0]) - 2.0)) < 1.5
    # binomial sd at N = 2000 is 0.010; resampling and correlated moves inflate it ~2x
    assert abs(np.mean(shares) - 0.7) < 0.03
    assert all(abs(s - 0.7) < 0.06 for s in shares)
    assert abs(np.mean(values) - np.log(0.1)) < 0.1


def _gaussian_problem():
    def prior_sample(rng, n):
        return rng.normal(size=(n, 2))

    def log_prior(x):
        return np.sum(stats.norm.logpdf(x), axis=1)

    return prior_sample, log_prior


def test_stall_no_finite_likelihood_is_one_line_error():
    prior_sample, log_prior = _gaussian_problem()

    def nowhere(x):
        return np.full(x.shape[0], np.nan)  # a model that fails everywhere

    with pytest.raises(BayesUpdateError, match="effective sample size 0") as info:
        tmcmc(prior_sample, log_prior, nowhere, TMCMCSettings(particles=50))
    assert "\n" not in str(info.value)


def test_stall_max_stages_is_one_line_error():
    prior_sample, log_prior = _gaussian_problem()

    def sharp(x):
        return -0.5 * np.sum(((x - 0.5) / 1e-4) ** 2, axis=1)

    with pytest.raises(BayesUpdateError, match="stalled at beta") as info:
        tmcmc(prior_sample, log_prior, sharp, TMCMCSettings(particles=50, max_stages=3))
    assert "\n" not in str(info.value)


def test_bad_settings():
    with pytest.raises(BayesUpdateError, match="tmcmc.particles"):
        TMCMCSettings(particles=2)
    with pytest.raises(BayesUpdateError, match="tmcmc.target_cov"):
        TMCMCSettings(target_cov=0.0)


def test_seeded_reproducibility():
    problem, *_ = _linear_gaussian()
    a = tmcmc(*problem, TMCMCSettings(particles=300, seed=7))
    b = tmcmc(*problem, TMCMCSettings(particles=300, seed=7))
    c = tmcmc(*problem, TMCMCSettings(particles=300, seed=8))
    assert a.log_evidence == b.log_evidence
    assert np.array_equal(a.samples, b.samples) and np.array_equal(a.betas, b.betas)
    assert not np.array_equal(a.samples, c.samples)


def test_sample_tmcmc_shear_building_matches_quadrature():
    """The pipeline on the two-DOF shear building (Beck & Au 2002; bimodal posterior, see
    test_inference_shear_building): log Z, mode mass and means against quadrature."""
    from bayesupdate.config import StudyConfig
    from bayesupdate.inference import LikelihoodSpec, LogPosterior, build_problem
    from bayesupdate.modal_data import ModalData
    from bayesupdate.models import get_model
    from bayesupdate.models.shear_building import shear_building_frequencies
    from bayesupdate.pipelines.sample_tmcmc import sample_tmcmc, tmcmc_json
    from bayesupdate.pipelines.study import PreparedStudy

    data = ModalData(frequencies_hz=shear_building_frequencies(np.array([1.0, 1.0])))
    bounds = {"theta_1": {"bounds": [0.2, 3.0]}, "theta_2": {"bounds": [0.2, 3.0]}}
    problem = build_problem(get_model("shear_building"), data, bounds, pairing="order")
    spec = LikelihoodSpec(sigma=0.05)
    grid = np.linspace(0.2, 3.0, 701)
    t1, t2 = np.meshgrid(grid, grid, indexing="ij")
    lp = LogPosterior(problem, spec)(np.column_stack([t1.ravel(), t2.ravel()]))
    log_z = float(np.logaddexp.reduce(lp) + 2 * np.log(grid[1] - grid[0]))
    p = np.exp(lp - lp.max()).reshape(t1.shape)
    p /= p.sum()
    mass = float(np.sum(p * (t2 > 0.75)))
    mean = np.array([np.sum(p * t1), np.sum(p * t2)])
    prepared = PreparedStudy(StudyConfig(), problem, spec)
    run = sample_tmcmc(prepared, TMCMCSettings(particles=2000, seed=0))
    out = tmcmc_json(run)
    assert run.names == ("theta_1", "theta_2") and run.failed == 0
    # measured, seeds 0-3: log Z 0.76-0.95 against 0.863, mode mass within 0.023 of 0.459,
    # means within 1.3 %
    assert abs(out["log_evidence"] - log_z) < 0.3
    assert abs(np.mean(run.result.samples[:, 1] > 0.75) - mass) < 0.04
    got = np.array([out["parameters"][k]["mean"] for k in run.names])
    np.testing.assert_allclose(got, mean, rtol=0.03)
