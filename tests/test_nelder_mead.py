"""The lockstep Nelder-Mead (``inference.nelder_mead``) against scipy's bounded adaptive one.

Given the same objective, each polish must make scipy's points bit for bit: the same end, value
and evaluation count, in every branch (expansion, both contractions, shrink, the box's clipping
and reflection, and a budget that ends the run inside a step)."""

import numpy as np
import pytest
from scipy import optimize

from bayesupdate.inference.nelder_mead import SimplexSettings, minimize_together, simplex_steps


def rosenbrock(u: np.ndarray) -> float:
    """Rosenbrock's valley shifted so that its minimum (0 at x = 1.3) lies outside [0, 1]^d:
    the bounded optimum sits on the box's face, where clipping acts."""
    x = 2.0 * np.asarray(u) - 0.7
    return float(np.sum(100.0 * (x[1:] - x[:-1] ** 2) ** 2 + (1.0 - x[:-1]) ** 2))


def kinked(u: np.ndarray) -> float:
    """A piecewise-smooth objective (the smaller of two quadratics): a kink like the tracked
    pairing's, where Nelder-Mead shrinks."""
    u = np.asarray(u)
    return float(min(np.sum((u - 0.3) ** 2) + 0.1, np.sum((u - 0.8) ** 2 * [1, 3, 5, 7, 9])))


def scipy_polish(f, u0, settings: SimplexSettings):
    calls = []

    def counted(u):
        calls.append(1)
        return f(u)

    fit = optimize.minimize(
        counted,
        u0,
        method="Nelder-Mead",
        bounds=[(0.0, 1.0)] * len(u0),
        options={"xatol": settings.xatol, "fatol": settings.fatol,
                 "maxfev": settings.max_evaluations, "adaptive": True},
    )  # fmt: skip
    return fit.x, float(fit.fun), len(calls)


def ours(f, u0, settings: SimplexSettings):
    ends, values, used = minimize_together(
        lambda u: np.array([f(row) for row in u]), np.asarray(u0)[None, :], settings
    )
    return ends[0], float(values[0]), used


STARTS = [
    np.array([0.1, 0.2, 0.3, 0.4, 0.5]),
    np.array([0.0, 0.99, 0.5, 1.0, 0.0]),  # a zero coordinate and the upper face: reflection
    np.array([0.97, 0.96, 0.98, 0.99, 0.965]),
]


@pytest.mark.parametrize("f", [rosenbrock, kinked])
@pytest.mark.parametrize("u0", STARTS)
@pytest.mark.parametrize("budget", [2000, 3, 7, 23, 61])
def test_same_points_as_scipy(f, u0, budget):
    settings = SimplexSettings(max_evaluations=budget)
    x_ref, f_ref, n_ref = scipy_polish(f, u0, settings)
    x, value, n = ours(f, u0, settings)
    assert n == n_ref
    assert np.array_equal(x, x_ref)
    assert value == f_ref


def test_converges_to_the_known_minimum():
    # interior minimum of a convex quadratic at 0.25 + 0.1 k: within xatol of it
    target = 0.25 + 0.1 * np.arange(4)
    x, value, _ = ours(
        lambda u: float(np.sum((u - target) ** 2)), np.full(4, 0.9), SimplexSettings()
    )
    assert np.max(np.abs(x - target)) < 1e-6
    assert value < 1e-12


def test_lockstep_equals_one_at_a_time():
    settings = SimplexSettings(max_evaluations=500)
    batches = []

    def batched(u):
        batches.append(u.shape[0])
        return np.array([kinked(row) for row in u])

    ends, values, total = minimize_together(batched, np.array(STARTS), settings)
    alone = [ours(kinked, u0, settings) for u0 in STARTS]
    for k, (x, value, _) in enumerate(alone):
        assert np.array_equal(ends[k], x)
        assert values[k] == value
    assert total == sum(a[2] for a in alone)
    # the first round evaluates the three initial simplices as one batch of 3 (d + 1)
    assert batches[0] == 3 * 6
    assert len(batches) < total / 2


def test_generator_yields_the_initial_simplex_first():
    steps = simplex_steps(np.array([0.5, 0.0]))
    first = next(steps)
    assert np.array_equal(first, [[0.5, 0.0], [0.525, 0.0], [0.5, 0.00025]])
