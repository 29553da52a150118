"""Which least-squares ends are Nelder-Mead polished (``inference.optimize._stationary``).

A smooth minimum (first-order optimality ~0) is left as it is; an end stopped on a kink of a
shape-tracked pairing, where the two residual branches swap, is polished, and the polish walks
along the kink to the constrained optimum, known in closed form here."""

import numpy as np
import pytest
from scipy import optimize as so

from bayesupdate.inference import optimize
from bayesupdate.inference.nelder_mead import SimplexSettings

LSQ = dict(method="trf", x_scale=1.0, xtol=1e-12, ftol=1e-12, gtol=1e-12)


def tracked(u: np.ndarray) -> np.ndarray:
    """Two "modes" a = 1 + u0 + u2 / 4, b = 1 + u1 + u2 / 4 paired with targets 1.2 and 1.5 by
    a "shape" that swaps where they cross (a tracked pairing at a veering): continuous, with a
    kink on u0 = u1.  Each branch's own minimum lies across the kink, so the optimum is on it:
    u0 = u1 = x, u2 = z with x + z / 4 = 0.35, objective 2 (0.15)^2 = 0.045."""
    a, b = 1 + u[0] + u[2] / 4, 1 + u[1] + u[2] / 4
    first, second = (a, b) if u[0] > u[1] else (b, a)
    return np.array([first - 1.2, second - 1.5])


def smooth(u: np.ndarray) -> np.ndarray:
    """A smooth zero-residual problem with its minimum at (0.3, 0.6, 0.45)."""
    return np.array([u[0] - 0.3, 2 * (u[1] - 0.6), u[0] * u[1] - 0.18, u[2] - 0.45])


def fit(residuals, u0):
    return so.least_squares(residuals, u0, bounds=(np.zeros(3), np.ones(3)), **LSQ)


def test_a_smooth_minimum_is_not_polished():
    result = fit(smooth, np.array([0.9, 0.1, 0.2]))
    np.testing.assert_allclose(result.x, [0.3, 0.6, 0.45], atol=1e-8)
    assert result.optimality < 1e-10
    assert optimize._stationary(result)


@pytest.mark.parametrize("u0", [[0.9, 0.1, 0.5], [0.05, 0.8, 0.9]])
def test_an_end_on_the_kink_is_polished_along_it(u0):
    result = fit(tracked, np.array(u0))
    value = float(np.sum(result.fun**2))
    # least squares stops on the kink above the optimum: not a smooth minimum
    assert abs(result.x[0] - result.x[1]) < 1e-6
    assert value > 0.045 * 1.1
    assert result.optimality > optimize.STATIONARY_GRADIENT
    assert not optimize._stationary(result)
    end, polished = optimize._nelder_mead_polish(
        tracked, result.x, value, SimplexSettings(max_evaluations=1200)
    )
    assert polished == pytest.approx(0.045, rel=1e-6)
    # on the kink the simplex stalls within ~1e-3 of the optimum (as on the exhaust's mode 6/7
    # kink, test_calibrate_basis_exact; measured 1.2e-4 here), the objective flat to 1e-6 there
    assert end[0] == pytest.approx(end[1], abs=1e-4)
    assert end[0] + end[2] / 4 == pytest.approx(0.35, abs=1e-3)
