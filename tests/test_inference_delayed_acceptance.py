"""Delayed-acceptance sampling (bayesupdate.inference.delayed_acceptance): the chain targets the
exact posterior, not the surrogate, and spends exact evaluations only on screened proposals."""

import numpy as np
import pytest

from bayesupdate.inference.sampling import SamplerSettings, sample_posterior

MEAN = np.array([1.0, -2.0])
COV = np.array([[1.0, 0.6], [0.6, 2.0]])


class Gaussian:
    """A vectorized Gaussian log-density with the attributes the sampler reads."""

    names = ("a", "b")
    ndim = 2

    def __init__(self, mean, cov):
        self.mean, self.prec = np.asarray(mean), np.linalg.inv(cov)
        self.evaluations = self.failed = 0

    def __call__(self, x):
        x = np.atleast_2d(x)
        self.evaluations += x.shape[0]
        r = x - self.mean
        return -0.5 * np.einsum("ni,ij,nj->n", r, self.prec, r)


def _run(target, screen, seed=3, steps=3000):
    rng = np.random.default_rng(seed)
    start = MEAN + 0.1 * rng.standard_normal((16, 2))
    # DE moves: these targets have no priors to build the mixture's defensive component
    settings = SamplerSettings(
        walkers=16,
        steps=steps,
        seed=seed,
        min_autocorr_times=1e9,
        check_every=min(1000, steps // 3),
        moves="de",
    )
    return sample_posterior(target, settings=settings, initial=start, screen=screen)


def test_delayed_acceptance_targets_the_exact_posterior():
    # the surrogate is off by 0.5 sd in the mean and 50 % in the covariance
    exact = Gaussian(MEAN, COV)
    surrogate = Gaussian(MEAN + np.array([0.5, -0.7]), 1.5 * COV)
    result = _run(exact, surrogate)
    draws = result.samples()
    n_eff = draws.shape[0] / np.max(result.autocorr_time)
    se = np.sqrt(np.diag(COV) / n_eff)
    assert np.all(np.abs(draws.mean(axis=0) - MEAN) < 4 * se)
    np.testing.assert_allclose(np.cov(draws.T), COV, rtol=0.12, atol=0.08)
    proposals = result.chain.shape[0] * result.chain.shape[1]
    # every proposal is screened; only the stage-1 survivors are evaluated exactly
    assert result.screen_evaluations >= proposals
    assert exact.evaluations < 0.7 * proposals


def test_the_surrogate_alone_gives_the_wrong_mean():
    # the check above can fail: sampling the surrogate itself lands on its shifted mean
    surrogate = Gaussian(MEAN + np.array([0.5, -0.7]), 1.5 * COV)
    draws = _run(surrogate, None).samples()
    assert np.abs(draws.mean(axis=0)[0] - MEAN[0]) > 0.3


def test_seeded_delayed_acceptance_is_reproducible():
    # 300 steps: screened and exact accept/reject decisions at every step, three checks
    a = _run(Gaussian(MEAN, COV), Gaussian(MEAN + 0.3, COV), seed=9, steps=300)
    b = _run(Gaussian(MEAN, COV), Gaussian(MEAN + 0.3, COV), seed=9, steps=300)
    assert np.array_equal(a.chain, b.chain)
    assert np.all(np.any(a.chain[-1] != a.chain[0], axis=1))  # every walker moved


def test_surrogate_failing_where_the_posterior_is_finite_falls_back_to_exact():
    exact = Gaussian(MEAN, COV)

    class Broken(Gaussian):
        def __call__(self, x):
            out = super().__call__(x)
            return np.where(np.atleast_2d(x)[:, 0] > MEAN[0], -np.inf, out)

    result = _run(exact, Broken(MEAN, COV))
    draws = result.samples()
    # walkers on the broken side still move: both halves are visited in the right proportion
    assert np.mean(draws[:, 0] > MEAN[0]) == pytest.approx(0.5, abs=0.06)


def test_interrupted_screened_run_resumes_to_the_identical_chain():
    class InterruptAt(Gaussian):
        def __init__(self, mean, cov, at):
            super().__init__(mean, cov)
            self.calls, self.at = 0, at

        def __call__(self, x):
            self.calls += 1
            if self.calls == self.at:
                raise KeyboardInterrupt
            return super().__call__(x)

    rng = np.random.default_rng(3)
    start = MEAN + 0.1 * rng.standard_normal((16, 2))
    settings = SamplerSettings(
        walkers=16, steps=600, seed=4, min_autocorr_times=1e9, check_every=100, moves="de"
    )
    surrogate = Gaussian(MEAN + 0.3, COV)
    whole = sample_posterior(
        Gaussian(MEAN, COV), settings=settings, initial=start, screen=surrogate
    )
    broken = sample_posterior(
        InterruptAt(MEAN, COV, at=700),
        settings=settings,
        initial=start,
        screen=Gaussian(MEAN + 0.3, COV),
    )
    assert broken.interrupted and 0 < broken.chain.shape[0] < 600
    resumed = sample_posterior(
        Gaussian(MEAN, COV),
        settings=settings,
        screen=Gaussian(MEAN + 0.3, COV),
        resume=broken.state,
    )
    assert np.array_equal(resumed.chain, whole.chain)


class _Model:
    """What ``_two_stage`` reads of an emcee sampler: its random state and exact log-density."""

    def __init__(self, exact, seed):
        self.random = np.random.RandomState(seed)
        self.compute_log_prob_fn = lambda x: (exact(x), None)


def test_proposals_the_move_calls_impossible_are_not_screened():
    """A proposal with log factor -inf (the independence move's draw outside the unit box) fails
    stage 1 whatever the surrogate says: it is not screened, and the decisions and the random
    stream are those of screening it."""
    from bayesupdate.inference.delayed_acceptance import ScreenedLogDensity, _two_stage

    rng = np.random.default_rng(4)
    current, proposal = rng.normal(size=(12, 2)), rng.normal(size=(12, 2))
    factors = np.where(np.arange(12) % 3 == 0, -np.inf, rng.normal(scale=0.3, size=12))
    exact = Gaussian(MEAN, COV)
    screened = []

    def counting(x):
        screened.append(np.atleast_2d(x).shape[0])
        return Gaussian(MEAN + 0.2, COV)(x)

    screen = ScreenedLogDensity(counting, exact)
    screen.remember(current, screen(current))  # the walkers' values, as the move keeps them
    screened.clear()
    model = _Model(exact, seed=8)
    ok, p = _two_stage(model, screen, current, proposal, factors, exact(current))
    assert screened == [8]  # the 4 impossible proposals of 12 were not screened
    # the same decisions as screening all 12 (stage 1 compares with -inf there)
    q_all = Gaussian(MEAN + 0.2, COV)(proposal)
    q_now = Gaussian(MEAN + 0.2, COV)(current)
    reference = np.random.RandomState(8)
    stage1 = factors + q_all - q_now > np.log(reference.rand(12))
    p_all = np.where(stage1, exact(proposal), -np.inf)
    with np.errstate(invalid="ignore"):
        stage2 = p_all - exact(current) - (q_all - q_now) > np.log(reference.rand(12))
    assert np.array_equal(ok, stage1 & stage2) and np.array_equal(p, p_all)
    assert not np.any(ok[factors == -np.inf]) and np.any(ok)
    assert np.array_equal(model.random.rand(3), reference.rand(3))  # the same stream after
