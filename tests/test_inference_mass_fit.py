"""The screen's mass polynomial (``inference.mass_fit``): exact for polynomial masses (closed
forms and the reduced exhaust's own masses), refused for masses it cannot reproduce, and the
screened posterior it gives equal to the one with the model's per-point masses."""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from math import comb  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from bayesupdate.errors import BayesUpdateError  # noqa: E402
from bayesupdate.fe.reduced import reduced_model_for  # noqa: E402
from bayesupdate.inference import (  # noqa: E402
    LikelihoodSpec,
    LogPosterior,
    ObjectiveSpec,
    build_problem,
    load_modal_data,
)
from bayesupdate.inference.mass_fit import (  # noqa: E402
    DEGREE,
    fit_mass_polynomial,
    monomial_exponents,
)
from bayesupdate.models import get_model  # noqa: E402
from bayesupdate.models.exhaust_paper import MEASURED_MASS_KG  # noqa: E402


def tube_mass(theta: np.ndarray) -> float:
    """Two steel tubes (outer diameter 50 mm, lengths 1.2 and 0.8 m), wall thicknesses
    theta[0:2] [m], the second's density theta[2] [kg/m^3], and a point mass: rho pi (D t - t^2)
    L + m, degree 3 in theta."""
    t1, t2, rho2 = theta
    area = lambda t: np.pi * (0.05 * t - t**2)  # noqa: E731
    return 7850.0 * area(t1) * 1.2 + rho2 * area(t2) * 0.8 + 3.5


BOX = (np.array([1e-3, 1e-3, 5e3]), np.array([4e-3, 3e-3, 9e3]))


def test_monomials_of_total_degree_at_most_four_are_all_there_once():
    e = monomial_exponents(5)
    assert e.shape == (comb(5 + DEGREE, DEGREE), 5)  # 126
    assert len({tuple(row) for row in e}) == e.shape[0]
    assert e.sum(axis=1).max() == DEGREE and np.all(e[0] == 0)


def test_a_polynomial_mass_is_reproduced_to_round_off_away_from_the_fit_points():
    fit = fit_mass_polynomial(tube_mass, *BOX, seed=1)
    assert fit is not None and fit.max_rel_error < 1e-11
    rng = np.random.default_rng(7)
    theta = BOX[0] + (BOX[1] - BOX[0]) * rng.random((50, 3))
    expected = np.array([tube_mass(row) for row in theta])
    np.testing.assert_allclose(fit(theta), expected, rtol=1e-11)


def test_masses_it_cannot_reproduce_are_refused():
    # not a polynomial: exp(5 t1 / 1 mm) misses the check points by far more than 1e-9
    assert fit_mass_polynomial(lambda th: np.exp(th[0] / 2e-4) + tube_mass(th), *BOX) is None
    # degree 5 in one variable: beyond DEGREE
    assert fit_mass_polynomial(lambda th: 1.0 + (th[0] / 4e-3) ** 5, *BOX) is None

    def rejects(theta):
        if theta[0] > 3e-3:
            raise BayesUpdateError("thickness too large")
        return tube_mass(theta)

    assert fit_mass_polynomial(rejects, *BOX) is None
    assert fit_mass_polynomial(tube_mass, BOX[0], np.array([4e-3, np.inf, 9e3])) is None


@pytest.fixture(scope="module")
def problem():
    rom = reduced_model_for(get_model("exhaust"), tol=1e-4, seed=0, n_modes=14)
    objective = ObjectiveSpec(MEASURED_MASS_KG, mass_weight=10.0)
    return build_problem(rom, load_modal_data("paper:ema"), objective=objective)


def test_the_screened_exhaust_posterior_keeps_its_masses_and_values(problem):
    post = LogPosterior(problem, LikelihoodSpec(sigma=0.05, mass_sd_rel=0.01))
    fitted = post.with_fitted_mass()
    assert fitted is not post and fitted._mass_fit is not None
    rng = np.random.default_rng(5)
    theta = problem.lower + rng.random((40, 5)) * (problem.upper - problem.lower)
    names = problem.names + post.fixed_names
    full = np.hstack([theta, np.tile(post.fixed_values, (40, 1))])
    # the reduced exhaust's masses span ~9-16 kg over the box; the fit is the model's to 1e-11
    masses = post._masses(full, names)
    np.testing.assert_allclose(fitted._masses(full, names), masses, rtol=1e-11)
    assert np.ptp(masses) > 1.0
    # with the mass term at 1 % its values agree to far below the screen's own basis error
    np.testing.assert_allclose(fitted(theta), post(theta), rtol=0, atol=1e-6)
    # a point outside the box takes the model's own mass (the prior is -inf there anyway)
    outside = full[:1].copy()
    outside[0, 0] = problem.upper[0] * 1.5
    assert np.isfinite(fitted._masses(outside, names)).all()


def test_without_a_mass_term_the_posterior_is_returned_as_it_is(problem):
    post = LogPosterior(problem, LikelihoodSpec(sigma=0.05))
    assert post.with_fitted_mass() is post


def test_the_exact_posterior_takes_its_masses_from_the_fit_only_to_round_off(problem):
    """``LogPosterior.use_fitted_mass`` (what the sampler does with its exact posterior): in
    place, only when the fit reproduces the model to EXACT_MASS_REL_TOL, and the log posterior
    then moves by far less than the reduced basis's own error does."""
    from bayesupdate.inference.likelihood import EXACT_MASS_REL_TOL

    spec = LikelihoodSpec(sigma=0.05, mass_sd_rel=0.01)
    post, model_masses = LogPosterior(problem, spec), LogPosterior(problem, spec)
    assert post.use_fitted_mass() and post._mass_fit is not None
    assert post._mass_fit.max_rel_error <= EXACT_MASS_REL_TOL
    rng = np.random.default_rng(11)
    theta = problem.lower + rng.random((200, 5)) * (problem.upper - problem.lower)
    names = problem.names + post.fixed_names
    full = np.hstack([theta, np.tile(post.fixed_values, (200, 1))])
    # fresh points, not the fit's: the exhaust's masses to a few 1e-12 (2.3e-12 at 2000)
    np.testing.assert_allclose(
        post._masses(full, names), model_masses._masses(full, names), rtol=1e-11
    )
    # masses up to ~50 sds off the weighed one at the box's corners: |z| e / 1 % < 1e-7 there
    # (1.5e-8 seen), where the log posterior is ~-1e4; within the posterior (|z| < 3) < 1e-9
    np.testing.assert_allclose(post(theta), model_masses(theta), rtol=0, atol=1e-7)
    assert not LogPosterior(problem, LikelihoodSpec(sigma=0.05)).use_fitted_mass()


def test_the_monomials_are_the_term_by_term_powers_to_the_bit():
    fit = fit_mass_polynomial(tube_mass, *BOX, seed=1)
    rng = np.random.default_rng(3)
    theta = BOX[0] + (BOX[1] - BOX[0]) * rng.random((32, 3))
    u = 2.0 * (theta - BOX[0]) / (BOX[1] - BOX[0]) - 1.0
    naive = np.array([[np.prod(row**e) for e in fit.exponents] for row in u])
    assert np.array_equal(fit.design(theta), naive)
