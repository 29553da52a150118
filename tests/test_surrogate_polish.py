"""The polish's stopping rule on a surrogate (``inference.optimize.SURROGATE_POLISH``: the
simplex 1e-5 wide in the unit box, no test on the values).  Where the best vertex sits on a jump
of the objective (a flip of the tracked pairing) the values' spread stays the jump until the
simplex collapses onto that vertex in floating point (or the budget ends), so a test on the
values (fatol 1e-8) only adds evaluations there; on a smooth minimum the values meet 1e-8 before
the points meet 1e-5, and the two rules make the same steps to the same end."""

import numpy as np

from bayesupdate.inference import optimize as opt
from bayesupdate.inference.nelder_mead import SimplexSettings, minimize_together

CENTRE = np.array([0.3, 0.6, 0.45])
#: the objective's jump (the shell exhaust's end on a flip: 1.1e-2)
JUMP = 1.1e-2


def _smooth(u: np.ndarray) -> np.ndarray:
    return np.sum((u - CENTRE) ** 2 * np.array([1.0, 3.0, 0.5]), axis=1)


def _jump(u: np.ndarray) -> np.ndarray:
    """The smooth bowl plus ``JUMP`` everywhere but at its centre: the polish starts at a
    minimum where the objective jumps in every direction (the shell exhaust's end on a flip of
    the tracked pairing that no polish step improved, seed 51)."""
    return _smooth(u) + JUMP * np.any(u != CENTRE, axis=1)


def test_no_value_test_saves_the_collapse_on_a_jump():
    start = CENTRE[None, :]
    ends, values, used = minimize_together(_jump, start, SimplexSettings(*opt.SURROGATE_POLISH))
    _, values_f, used_f = minimize_together(_jump, start, SimplexSettings(1e-5, 1e-8))
    # the start is the minimum: both keep it, to the bit
    np.testing.assert_array_equal(ends[0], CENTRE)
    assert values[0] == values_f[0] == 0.0
    assert used < used_f


def test_on_a_smooth_minimum_both_rules_end_alike():
    start = np.array([[0.35, 0.55, 0.5], [0.2, 0.7, 0.4]])
    ends, values, used = minimize_together(_smooth, start, SimplexSettings(*opt.SURROGATE_POLISH))
    ends_f, values_f, used_f = minimize_together(_smooth, start, SimplexSettings(1e-5, 1e-8))
    np.testing.assert_array_equal(ends, ends_f)
    np.testing.assert_array_equal(values, values_f)
    assert used == used_f
    assert np.max(np.abs(ends - CENTRE)) <= 2e-5
