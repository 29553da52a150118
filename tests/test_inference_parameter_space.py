"""The parameter space against closed forms: the maps between theta, z, u and y invert each other,
the log-Jacobians equal finite differences, the prior is a normalized density in every coordinate,
and a failed model gets the documented residual in every fit."""

import numpy as np
import pytest
from scipy import integrate

from bayesupdate.discovery.evidence import FitSpace
from bayesupdate.discovery.flagging import NoiseModel
from bayesupdate.discovery.shape_evidence import ShapeEvidence
from bayesupdate.inference.parameter_space import (
    FAILED_RELATIVE_ERROR,
    EvaluationCount,
    ParameterSpace,
    ParameterSpec,
    natural_axis,
    unit_box_residuals,
)
from bayesupdate.inference.priors import prior_from_mapping


def _spec(name, bounds, prior=None, **kw):
    return ParameterSpec(name, bounds, prior_from_mapping(prior, bounds, name), **kw)


#: two-sided (logit), lower bound only (log), upper only (-log), none (identity)
FOUR = ParameterSpace(
    (
        _spec("t", (0.4e-3, 3e-3)),
        _spec("sigma", (0.0, np.inf), {"kind": "halfnormal", "scale": 0.1}),
        _spec("drop", (-np.inf, 2.0), {"kind": "normal", "mean": 0.0, "sd": 1.0}),
        _spec("free", (-np.inf, np.inf), {"kind": "normal", "mean": 0.0, "sd": 1.0}),
    )
)


def test_unconstrained_round_trip_and_jacobian():
    y = np.array([[-2.0, 0.3, 5.0, 1.0], [1.5, -4.0, -1.0, -2.0], [30.0, 2.0, 0.0, 0.5]])
    theta = FOUR.theta_from_y(y)
    assert np.all(theta[:, 0] > 0.4e-3) and np.all(theta[:, 0] <= 3e-3)
    assert np.all(theta[:, 1] > 0.0) and np.all(theta[:, 2] < 2.0)
    np.testing.assert_array_equal(theta[:, 3], y[:, 3])
    np.testing.assert_allclose(FOUR.y_from_theta(theta[:2], margin=0.0), y[:2], rtol=1e-9)
    # log |d theta / d y| against central differences (the map is diagonal)
    h = 1e-6
    for row in y[:2]:
        step = np.eye(4) * h
        d = [(FOUR.theta_from_y(row + e) - FOUR.theta_from_y(row - e))[k] / (2 * h)
             for k, e in enumerate(step)]  # fmt: skip
        assert FOUR.log_jacobian_y(row[None, :])[0] == pytest.approx(np.sum(np.log(d)), rel=1e-6)
    assert np.isfinite(FOUR.log_jacobian_y(y[2:]))[0]


def test_points_on_a_bound_move_inside_by_the_margin():
    space = ParameterSpace((_spec("t", (1.0, 3.0)),))
    y = space.y_from_theta(np.array([[1.0], [3.0]]), margin=1e-3)
    np.testing.assert_allclose(space.theta_from_y(y)[:, 0], [1.0 + 2e-3, 3.0 - 2e-3], rtol=1e-12)


@pytest.mark.parametrize(
    "bounds, prior",
    [
        ((1e2, 1e6), {"kind": "lognormal", "mu": float(np.log(1e4)), "sigma": 2.0}),
        ((0.5, 3.0), {"kind": "normal", "mean": 1.0, "sd": 0.4}),
    ],
)
def test_the_prior_is_a_normalized_density_in_theta_z_and_y(bounds, prior):
    """The Jacobians are right exactly when each density integrates to one in its coordinate."""
    space = ParameterSpace((_spec("p", bounds, prior),))
    lo, hi = space.z_low[0], space.z_high[0]
    in_z = integrate.quad(lambda z: np.exp(space.log_prior_z(np.array([[z]]))[0]), lo, hi)[0]
    in_y = integrate.quad(lambda y: np.exp(space.log_prior_y(np.array([[y]]))[0]), -60, 60)[0]
    in_theta = integrate.quad(
        lambda t: np.exp(space.log_prior(np.array([[t]]))[0]), *bounds, points=[1e3, 1e4, 1e5]
    )[0]
    assert in_z == pytest.approx(1.0, abs=1e-7)
    assert in_y == pytest.approx(1.0, abs=1e-7)
    assert in_theta == pytest.approx(1.0, abs=1e-6)


def test_halfnormal_noise_level_is_normalized_in_its_log_coordinate():
    space = ParameterSpace((FOUR.parameters[1],))
    in_y = integrate.quad(lambda y: np.exp(space.log_prior_y(np.array([[y]]))[0]), -40, 5)[0]
    assert in_y == pytest.approx(1.0, abs=1e-7)


def test_natural_axis_is_log_from_two_decades():
    assert natural_axis((1e2, 1e6)) == "log"
    assert natural_axis((0.1, 10.0)) == "log"  # exactly 100
    assert natural_axis((0.4e-3, 3e-3)) == "linear"
    assert natural_axis((0.0, 2.0)) == "linear"  # an added mass starts at zero
    assert _spec("k", (1e2, 1e6)).axis == "log"
    assert _spec("k", (1e2, 1e6), axis="linear").axis == "linear"
    with pytest.raises(ValueError, match="axis"):
        _spec("k", (1e2, 1e6), axis="logit")


def test_unit_box_on_linear_and_log_axes():
    space = ParameterSpace((_spec("t", (0.4e-3, 3e-3)), _spec("k", (1e2, 1e6))))
    theta = space.theta_from_u(np.array([[0.25, 0.5], [1.7, -0.2]]))
    assert theta[0, 0] == 0.4e-3 + 0.25 * (3e-3 - 0.4e-3)
    assert theta[0, 1] == pytest.approx(1e4, rel=1e-12)  # the geometric midpoint
    np.testing.assert_allclose(theta[1], [3e-3, 1e2], rtol=1e-12)  # clipped to the box
    np.testing.assert_allclose(space.u_from_theta(theta[0]), [0.25, 0.5], rtol=1e-12)
    # the optimizer's box is linear in theta on every axis
    assert space.linear().theta_from_u(np.array([0.5, 0.5]))[1] == 0.5 * (1e2 + 1e6)
    z = space.z_from_theta(theta[0])
    assert z[1] == pytest.approx(np.log(1e4))
    np.testing.assert_allclose(space.theta_from_z(z), theta[0], rtol=1e-15)


def test_a_failure_gets_a_thousand_percent_error_in_the_residual_units():
    space = ParameterSpace((_spec("a", (0.5, 2.0)),))
    outcome = {0.0: None, 0.5: np.array([np.nan, 1.0, 2.0]), 1.0: np.array([0.1, 0.2, 0.3])}
    count = EvaluationCount()
    units = np.array([1.0, 0.01, 0.002])
    residuals = unit_box_residuals(space, lambda t: outcome[(t[0] - 0.5) / 1.5], units, count)
    np.testing.assert_array_equal(residuals(np.array([1.0])), [0.1, 0.2, 0.3])
    for u in (0.0, 0.5):
        np.testing.assert_allclose(residuals(np.array([u])), [10.0, 1000.0, 5000.0], rtol=1e-15)
    assert FAILED_RELATIVE_ERROR == 10.0
    assert (count.evaluations, count.failed) == (3, 2)


class _FailingProblem:
    """A calibration problem whose model fails everywhere (the ``evaluate`` contract)."""

    class data:
        frequencies_hz = np.array([10.0, 20.0, 30.0])

    def evaluate(self, theta):
        from bayesupdate.inference.problem import Evaluation

        nan = np.full(3, np.nan)
        return Evaluation(False, nan, nan, error="diverged")


def test_discovery_refits_measure_a_failure_in_noise_units():
    """Frequency levels 0.2 % and 1 % (the third mode unused), shape level 3 % on 4 DOFs: a
    failure is 10 / s in each component, worse than any working point (|r| <= 1 / s there)."""
    noise = NoiseModel(np.array([0.002, 0.01, 1.0]), np.array([1.0, 1.0, 0.0]), False, "fixed", 0)
    test = np.eye(4)[:, :2]
    shapes = ShapeEvidence(np.arange(2), test, np.array([0.03, 0.03]) / 2.0)
    space = FitSpace(_FailingProblem(), (_spec("a", (0.5, 2.0)),), noise, shapes)
    count = EvaluationCount()
    r = space.unit_box_residuals(count)(np.array([0.3]))
    expected = np.concatenate([[5000.0, 1000.0], np.full(8, 10.0 / 0.015)])
    np.testing.assert_allclose(r, expected, rtol=1e-15)
    assert count.failed == 1 and r.size == space.size
