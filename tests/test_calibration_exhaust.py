"""Calibration checks on the exhaust (seed Table 2), run on the certified reduced model so they are
fast: shape-tracked batched pairing, the mass-kept optimum, the joint nuisance option."""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from bayesupdate.fe.reduced import reduced_model_for  # noqa: E402
from bayesupdate.inference import (  # noqa: E402
    CalibrationSettings,
    LikelihoodSpec,
    LogPosterior,
    ObjectiveSpec,
    build_problem,
    calibrate,
    load_modal_data,
)
from bayesupdate.inference.pairing import pair_batch  # noqa: E402
from bayesupdate.models import get_model  # noqa: E402
from bayesupdate.models.exhaust import JOINTS, joint_parameter  # noqa: E402
from bayesupdate.models.exhaust_paper import (  # noqa: E402
    DESIGN_VARIABLES,
    MEASURED_MASS_KG,
    TABLE3_INITIAL_SI,
    TABLE3_OPTIMUM_SI,
)
from bayesupdate.pipelines.surrogates import sampling_problem  # noqa: E402


@pytest.fixture(scope="module")
def rom():
    # 14 modes: the 12 test modes + the 2 extra modes the tracked pairing computes
    return reduced_model_for(get_model("exhaust"), tol=1e-4, seed=0, n_modes=14)


@pytest.fixture(scope="module")
def mass_kept(rom):
    """The seed's calibration with the mass kept: search on the reduced model, every end near the
    best polished on the full model (the result is the full model's)."""
    data = load_modal_data("paper:ema")
    objective = ObjectiveSpec(MEASURED_MASS_KG, mass_weight=10.0)
    search = build_problem(rom, data, objective=objective)
    problem = build_problem(get_model("exhaust"), data, objective=objective)
    return problem, calibrate(search, CalibrationSettings(starts=8, seed=0), refine=problem)


@pytest.fixture(scope="module")
def sampled():
    """(full problem, its sampling problem, the certified ROM): the sampler's reduced basis of
    the default exhaust problem, built once for the tests that read it."""
    problem = build_problem(get_model("exhaust"), load_modal_data("paper:ema"))
    reduced_problem, rom = sampling_problem(problem)
    return problem, reduced_problem, rom


def test_pair_batch_equals_hungarian_per_point():
    rng = np.random.default_rng(4)
    reference = rng.standard_normal((10, 4))
    # current shapes: the reference permuted, noisy, with two extra modes
    perm = np.array([1, 0, 3, 2, 5, 4])
    shapes = np.empty((6, 10, 6))
    for b in range(6):
        base = np.hstack([reference, rng.standard_normal((10, 2))])[:, np.roll(perm, b)]
        shapes[b] = base + 0.3 * rng.standard_normal(base.shape)
    index, mac = pair_batch(reference, shapes)
    from bayesupdate.correlation import pair_by_mac

    for b in range(6):
        expected, expected_mac = pair_by_mac(reference, shapes[b])
        np.testing.assert_array_equal(index[b], expected)
        np.testing.assert_allclose(mac[b], expected_mac, rtol=1e-12)


def test_batched_shape_pairing_equals_per_point_tracking(rom):
    """The vectorized likelihood pairs every walker as build_problem's tracked pairing does, and
    on the exhaust's prior box a large share of points pair differently from the order."""
    problem = build_problem(rom, load_modal_data("paper:ema"))
    assert problem.pairing.method == "tracked"
    batched = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    assert batched.mode == "shape-batch"
    rng = np.random.default_rng(0)
    theta = problem.lower + rng.random((24, 5)) * (problem.upper - problem.lower)
    freqs, _ = batched.predict_frequencies(theta)
    for k, point in enumerate(theta):
        evaluation = problem.evaluate(point)
        np.testing.assert_allclose(freqs[k], evaluation.frequencies_hz, rtol=1e-8)
    # order pairing would compare swapped modes at these points
    assert batched.pair_checked == 24
    assert batched.pair_differs_fraction >= 0.25


def test_mass_kept_optimum_table2(mass_kept):
    """Seed Table 2 with the measured mass as a response: what this beam model reaches.

    The paper's 0.0406 is out of reach with the mass kept (its point lies below our front of
    Expr vs mass error, see studies/paper_optimum.py); the largest residuals are modes 5 and 9
    (shell/joint physics the beam model lumps)."""
    problem, opt = mass_kept
    assert 0.0406 < opt.expr <= 0.068
    assert abs(opt.mass_kg / MEASURED_MASS_KG - 1.0) <= 0.015
    assert not opt.table.swapped
    np.testing.assert_array_equal(opt.table.model_mode, np.arange(1, 13))
    # every design variable moves the way seed Table 3 does (initial -> optimum)
    for name in DESIGN_VARIABLES:
        paper = np.sign(TABLE3_OPTIMUM_SI[name] - TABLE3_INITIAL_SI[name])
        ours = np.sign(opt.parameters[name] - TABLE3_INITIAL_SI[name])
        assert ours == paper, name
    # modes 5 (+13 %) and 9 (-12 %) dominate; 4, 10 and 11 follow at 7-8 %
    worst = np.argsort(-np.abs(opt.table.error_pct))[:2] + 1
    assert set(worst) == {5, 9}


def test_mass_kept_starts_reach_one_optimum_on_the_mode_6_7_kink(mass_kept):
    """The starts end in two separate basins: the optimum (within 2 % of the best) or a local
    optimum >= 10 % worse, nothing in between; at least half of them reach the optimum.  The
    optimum lies on the boundary where the tracked pairing of modes 6 and 7 flips (their shapes
    veer: MAC to the reference ~0.5 / ~0.3; 11 and 12 veer too), so a 1 % step of some variable
    flips that pair: the kink on which gradient steps stall and the Nelder-Mead polish walks,
    which is why ends in the optimum's basin spread over ~1 %.  The best end is swap-free; an
    end in its basin may have crossed a veering pair's boundary (6 / 7, 11 / 12: the pairs a
    1 % step flips, asserted last), but no other pair.

    On an AMD EPYC machine (2026-11-25, the same code as a run that passed elsewhere) one of the
    7 in-basin ends, at 1.0026 x the best, paired 11 and 12 the other way round (MAC 0.92 /
    0.96): where the polish ends on a kink depends on the last bits of the BLAS in use.

    Measured (calibrate seeds 0-5 on the seed-0 basis, seed 0 on a seed-1 basis; numpy 2.5.5,
    scipy 1.18.1): the best objective agrees to 0.012 % across the 7 runs; in-basin ends reach
    1.0000-1.0110 x the best, the other basin 1.1161 x (once 4.10 x); 6-8 of 9 starts end in the
    optimum's basin.  The former assertion (>= 80 % within 1 %) sat on the 1.009-1.011 ends and
    failed on another machine with 7 of 9."""
    problem, opt = mass_kept
    ratio = opt.end_objectives / opt.objective
    close = ratio <= 1.02
    assert not np.any((ratio > 1.02) & (ratio < 1.10))  # two basins, nothing in between
    assert close.sum() >= (opt.starts + 1) // 2
    span = problem.upper - problem.lower
    here = problem.evaluate(opt.theta)
    assert not here.paired.swapped
    for end in opt.end_points[close]:
        moved = problem.evaluate(end).paired.model_index != np.arange(12)
        assert set((np.flatnonzero(moved) + 1).tolist()) <= {6, 7, 11, 12}
    flips = set()
    for k in range(5):
        for h in (-0.01, 0.01):
            step = np.clip(opt.theta + h * span[k] * np.eye(5)[k], problem.lower, problem.upper)
            moved = problem.evaluate(step).paired.model_index
            flips |= set((np.flatnonzero(moved != here.paired.model_index) + 1).tolist())
    assert {6, 7} <= flips <= {6, 7, 11, 12}


def test_sampling_problem_uses_certified_rom_and_full_on_request(sampled):
    problem, reduced_problem, rom = sampled
    fe = problem.model
    full_problem, none = sampling_problem(problem, reduced=False)
    assert none is None and full_problem.model is fe
    assert rom.certified and rom.max_rel_error <= 1e-4 and rom.n_modes == 14
    assert LogPosterior(reduced_problem, LikelihoodSpec(sigma=0.05)).mode == "shape-batch"
    full = LogPosterior(full_problem, LikelihoodSpec(sigma=0.05))
    reduced = LogPosterior(reduced_problem, LikelihoodSpec(sigma=0.05))
    assert full.mode == "points"
    # the same pairing and frequencies (to the ROM tolerance) per point, in full and reduced
    rng = np.random.default_rng(2)
    theta = problem.lower + rng.random((6, 5)) * (problem.upper - problem.lower)
    f_full, _ = full.predict_frequencies(theta)
    f_rom, _ = reduced.predict_frequencies(theta)
    np.testing.assert_allclose(f_rom, f_full, rtol=1e-4)
    assert full.pair_checked == reduced.pair_checked == 6
    assert full.pair_differs == reduced.pair_differs


def test_joint_nuisance_option():
    base = get_model("exhaust")
    model = get_model("exhaust", joint_nuisance=True)
    names = [joint_parameter(p) for p in JOINTS]
    assert names[0] == "k_hot_pipe__catalyst"
    assert set(names) <= set(model.parameter_names)
    assert set(base.parameter_names) == set(DESIGN_VARIABLES)
    f0 = base.predict({}, 12).frequencies_hz
    np.testing.assert_allclose(model.predict({}, 12).frequencies_hz, f0, rtol=1e-12)
    assert model.default_bounds()[names[4]] == (0.1, 10.0)
    # softer springs can only lower eigenvalues (Rayleigh quotient, same mass)
    soft = model.predict({names[4]: 0.3}, 12).frequencies_hz
    assert np.all(soft <= f0 * (1 + 1e-9))
    assert np.min(soft / f0 - 1) < -0.1


def test_screening_posteriors_for_reduced_and_full_sampling(rom, sampled):
    from bayesupdate.pipelines.surrogates import screening_posterior

    problem, reduced_problem, _ = sampled
    spec = LikelihoodSpec(sigma=0.05)
    exact = LogPosterior(reduced_problem, spec)
    coarse = screening_posterior(reduced_problem, reduced_problem.model, spec)
    # the coarse basis lives inside the certified one: smaller, within its own stated error
    assert coarse.problem.model.size < reduced_problem.model.size
    assert coarse.problem.model.max_rel_error <= 5e-3  # coarsened()'s default tolerance
    rng = np.random.default_rng(4)
    theta = problem.lower + rng.random((8, 5)) * (problem.upper - problem.lower)
    f_exact, _ = exact.predict_frequencies(theta)
    f_coarse = coarse.problem.model.predict_frequencies_batch(theta, problem.names, 12)
    f_fine = reduced_problem.model.predict_frequencies_batch(theta, problem.names, 12)
    # Rayleigh-Ritz inside Rayleigh-Ritz: the coarse values bound the certified ones from above
    assert np.all(f_coarse >= f_fine * (1 - 1e-9))
    # fresh points: within the error measured on the coarsening's own check points (+ 50 %)
    assert np.max(f_coarse / f_fine - 1) <= 1.5 * coarse.problem.model.max_rel_error
    assert np.all(np.isfinite(f_exact))
    # on full solves (--full) the screen is the certified reduced model itself
    full_screen = screening_posterior(problem, None, spec)
    assert full_screen.problem.model.certified and full_screen.problem.model.size == rom.size


def _sum_of_priors(priors, theta):
    """The joint log prior as the plain sum of each prior's own logpdf (the definition)."""
    return sum(prior.logpdf(theta[:, j]) for j, prior in enumerate(priors))


def test_vectorized_prior_equals_the_sum_of_priors():
    problem = build_problem(get_model("exhaust"), load_modal_data("paper:ema"))
    lp = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    rng = np.random.default_rng(1)
    span = problem.upper - problem.lower
    theta = problem.lower - 0.1 * span + rng.random((50, 5)) * 1.2 * span  # some outside
    expected = _sum_of_priors(lp.priors, theta)
    assert np.array_equal(np.isfinite(lp.log_prior(theta)), np.isfinite(expected))
    ok = np.isfinite(expected)
    assert 0 < ok.sum() < 50
    np.testing.assert_allclose(lp.log_prior(theta)[ok], expected[ok], rtol=1e-12)
    # a non-uniform prior goes through its own logpdf
    params = {name: {} for name in problem.names}
    params["t_hot_pipe"] = {"prior": {"kind": "normal", "mean": 1e-3, "sd": 2e-4}}
    mixed = build_problem(get_model("exhaust"), load_modal_data("paper:ema"), params)
    lp_mixed = LogPosterior(mixed, LikelihoodSpec(sigma=0.05))
    assert lp_mixed.priors[0].kind == "normal"
    expected = _sum_of_priors(lp_mixed.priors, theta)
    np.testing.assert_allclose(lp_mixed.log_prior(theta)[ok], expected[ok], rtol=1e-12)
    assert not np.allclose(expected[ok], _sum_of_priors(lp.priors, theta)[ok])


def test_a_screen_coarser_than_the_likelihood_is_dropped(sampled):
    """The screen stays for seed Table 2 (sigma fixed at 0.05, or sampled: residuals of a few %)
    and is dropped for noise-free data with identified sds of 1e-5 (the NX FEMAP round trip's
    case: screened acceptance 0.053 against 0.60, not converged), where the coarse basis's error
    is above the likelihood's smallest relative sd (the robust level's floor, 1e-4)."""
    from bayesupdate.modal_data import ModalData
    from bayesupdate.pipelines.surrogates import screen_mismatch, screening_posterior

    _, reduced_problem, rom = sampled
    fit = calibrate(reduced_problem, CalibrationSettings(starts=1, seed=0))
    halfnormal = LikelihoodSpec(sigma=None, sigma_prior=_halfnormal(0.01))
    for spec in (LikelihoodSpec(sigma=0.05), halfnormal):
        screen = screening_posterior(reduced_problem, rom, spec)
        assert 1e-4 < screen.problem.model.max_rel_error <= 5e-3
        assert screen_mismatch(screen, fit) == ""
    f_model = rom.predict_frequencies_batch(fit.theta[None, :], reduced_problem.names, 12)[0]
    exact = ModalData(f_model, identification_sd_hz=1e-5 * f_model)
    exact_problem = build_problem(rom, exact)
    exact_fit = calibrate(exact_problem, CalibrationSettings(starts=1, seed=0))
    assert np.max(np.abs(exact_fit.table.error_pct)) < 1e-3
    screen = screening_posterior(exact_problem, rom, halfnormal)
    why = screen_mismatch(screen, exact_fit)
    assert why.startswith("the screening model's frequency error")
    assert "smallest relative sd 1.0e-04" in why


def test_the_basis_error_allowed_is_a_tenth_of_the_smallest_sd(sampled):
    """``basis_error_allowed``: 0.1 x min_i sqrt(sigma^2 + sd_i^2), at the fixed sigma, or at the
    sigma that best explains the optimum's residuals: ~0 when the identification sds do (the
    round trip's case: enrich), the model error's level when the data are 2 % off (do not)."""
    from bayesupdate.modal_data import ModalData
    from bayesupdate.pipelines.surrogates import basis_error_allowed

    _, reduced_problem, rom = sampled
    f_model = rom.predict_frequencies_batch(rom.centre()[None, :], None, 12)[0]
    sd_rel = np.linspace(2e-5, 4e-4, 12)
    halfnormal = LikelihoodSpec(sigma=None, sigma_prior=_halfnormal(0.01))
    exact = build_problem(rom, ModalData(f_model, identification_sd_hz=sd_rel * f_model))
    fit = calibrate(exact, CalibrationSettings(starts=1, seed=0))
    assert np.max(np.abs(fit.table.error_pct)) < 1e-4  # residuals far below the sds
    assert basis_error_allowed(exact, halfnormal, fit) == pytest.approx(2e-6, rel=1e-6)
    fixed = basis_error_allowed(exact, LikelihoodSpec(sigma=1e-3), fit)
    assert fixed == pytest.approx(0.1 * np.hypot(1e-3, 2e-5), rel=1e-12)
    scatter = 1 + 0.02 * np.random.default_rng(0).standard_normal(12)
    off = ModalData(f_model * scatter, identification_sd_hz=sd_rel * f_model)
    off_problem = build_problem(rom, off)
    off_fit = calibrate(off_problem, CalibrationSettings(starts=1, seed=0))
    rms = float(np.sqrt(np.mean((off_fit.table.error_pct / 100) ** 2)))
    allowed = basis_error_allowed(off_problem, halfnormal, off_fit)
    assert 0.1 * 0.8 * rms < allowed < 0.1 * 1.25 * rms  # sigma at the residuals' level


def _halfnormal(scale):
    from bayesupdate.inference.priors import prior_from_mapping

    return prior_from_mapping({"kind": "halfnormal", "scale": scale}, (0.0, np.inf), "sigma")
