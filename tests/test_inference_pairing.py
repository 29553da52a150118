"""Pairing: a deliberate mode swap is detected by shape tracking and shown in the residual table.

Toy model (a user function): three fixed orthogonal shapes e1, e2, e3 with frequencies 10, 20 p,
30 Hz, returned in ascending order.  For p > 1.5 the second and third modes swap order.
"""

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference import (
    CalibrationSettings,
    FunctionModel,
    build_problem,
    calibrate,
    pair_modes,
)
from bayesupdate.modal_data import ModalData

SHAPES = np.eye(3)


def crossing_modes(params):
    f = np.array([10.0, 20.0 * params["p"], 30.0])
    order = np.argsort(f, kind="stable")
    return {"frequencies_hz": f[order], "shapes": SHAPES[:, order], "mass_kg": 1.0}


MODEL = FunctionModel(
    function=crossing_modes,
    parameter_names=("p",),
    defaults=(("p", 1.0),),
    bounds=(("p", (0.5, 2.0)),),
    dof_labels=("1V", "2V", "3V"),
    label="crossing",
)


def test_tracked_pairing_detects_the_swap():
    problem = build_problem(MODEL, ModalData(frequencies_hz=[10.0, 20.0, 30.0]), extra_modes=0)
    assert problem.pairing.method == "tracked"
    paired = pair_modes(MODEL.predict({"p": 1.6}, 3), problem.pairing)
    assert paired.model_index.tolist() == [0, 2, 1]
    assert paired.swapped
    np.testing.assert_allclose(paired.mac, 1.0)
    unswapped = pair_modes(MODEL.predict({"p": 1.2}, 3), problem.pairing)
    assert not unswapped.swapped


def test_calibration_with_a_swap_reports_it():
    # test modes listed in the reference order: the second one (shape e2) sits at 32 Hz
    data = ModalData(frequencies_hz=[10.0, 32.0, 30.0])
    fit = CalibrationSettings(starts=4, seed=0)
    tracked = calibrate(build_problem(MODEL, data, extra_modes=0), fit)
    assert tracked.parameters["p"] == pytest.approx(1.6, rel=1e-6)
    assert tracked.expr < 1e-12
    assert tracked.swapped
    assert tracked.table.model_mode.tolist() == [1, 3, 2]
    assert "swapped" in tracked.table.format()
    # by order, the same data cannot be fitted: the swap costs a residual
    ordered = calibrate(build_problem(MODEL, data, pairing="order", extra_modes=0), fit)
    assert ordered.expr > 1e-4
    assert not ordered.swapped


def test_order_pairing_still_reports_mac_against_reference():
    problem = build_problem(MODEL, ModalData(frequencies_hz=[10.0, 20.0, 30.0]), pairing="order")
    paired = pair_modes(MODEL.predict({"p": 1.6}, 3), problem.pairing)
    # in order, mode 2 is now e3: MAC 0 against the reference e2
    np.testing.assert_allclose(paired.mac, [1.0, 0.0, 0.0])


def test_mac_pairing_uses_test_shapes():
    data = ModalData(
        frequencies_hz=[10.0, 30.0], shapes=SHAPES[:, [0, 2]], dof_labels=("1V", "2V", "3V")
    )
    problem = build_problem(MODEL, data, extra_modes=1)
    assert problem.pairing.method == "mac"
    paired = pair_modes(MODEL.predict({"p": 1.0}, 3), problem.pairing)
    assert paired.model_index.tolist() == [0, 2]


def test_test_labels_not_in_model_are_an_error():
    data = ModalData(frequencies_hz=[10.0], shapes=np.ones((1, 1)), dof_labels=("9H",))
    with pytest.raises(BayesUpdateError, match="not model DOFs"):
        build_problem(MODEL, data)


def test_likelihood_can_use_the_tracked_pairing():
    from bayesupdate.inference import LikelihoodSpec, LogPosterior

    data = ModalData(frequencies_hz=[10.0, 32.0, 30.0])
    problem = build_problem(MODEL, data, extra_modes=0)
    tracked = LogPosterior(problem, LikelihoodSpec(sigma=0.01, pairing="problem"))
    ordered = LogPosterior(problem, LikelihoodSpec(sigma=0.01, pairing="order"))
    p = np.array([[1.6]])
    # tracked: exact fit, log L = -sum log(sqrt(2 pi) s_i) + log prior (uniform on [0.5, 2])
    expected = -3 * np.log(np.sqrt(2 * np.pi) * 0.01) - np.log(1.5)
    assert tracked(p)[0] == pytest.approx(expected, rel=1e-12)
    # in order, modes 2 and 3 are compared with the wrong test values (30 vs 32, 32 vs 30)
    e = np.array([2.0 / 32.0, 2.0 / 30.0]) / 0.01
    assert ordered(p)[0] == pytest.approx(expected - 0.5 * np.sum(e**2), rel=1e-12)
