"""Starts that end at one point are checked on the exact model once (``inference.optimize``):
the check is deterministic, so sharing it changes no number, and its cost (up to 60 d exact
solves per end) no longer grows with the number of starts that reach one corner of the box."""

import numpy as np
import pytest

from bayesupdate.config import parse_study
from bayesupdate.inference import CalibrationSettings, calibrate
from bayesupdate.models.shear_building import shear_building_frequencies
from bayesupdate.pipelines.study import prepare


def _corner_problem():
    """The two-storey shear building against storeys twice as stiff as the upper bound 1.5
    allows: every start ends on the corner (1.5, 1.5)."""
    f = shear_building_frequencies(np.array([2.0, 2.0]))
    study = parse_study(
        {
            "model": {"source": "shear_building"},
            "data": {"frequencies_hz": [float(v) for v in f]},
            "parameters": {n: {"bounds": [0.2, 1.5]} for n in ("theta_1", "theta_2")},
        }
    )
    return prepare(study).problem


def test_coinciding_ends_are_checked_once():
    problem = _corner_problem()
    cost = {}
    for starts in (2, 6):
        settings = CalibrationSettings(starts=starts, seed=0)
        alone = calibrate(problem, settings)
        checked = calibrate(problem, settings, refine=problem)
        # the corner to the last bits: trust-region reflective keeps its iterates strictly
        # inside the box (one ulp from it here), and an end at a smooth minimum is not polished
        assert checked.parameters == pytest.approx({"theta_1": 1.5, "theta_2": 1.5}, abs=1e-12)
        assert checked.expr == alone.expr
        cost[starts] = checked.evaluations - alone.evaluations
    # the exact check of one shared end: the same whether 2 or 6 starts reached it
    assert cost[2] == cost[6] > 0
