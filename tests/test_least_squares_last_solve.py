"""The least squares' Jacobian on a reduced basis reuses the eigen-solve of the residuals at the
same point (``inference.reduced_jacobian.LastSolve``): scipy's trust-region method asks for J(x)
right after r(x) at each accepted step.  On the beam exhaust's certified basis (seed Table 2
data, mass kept, tracked pairing, 3 Sobol starts) the starts end at the same points with the
same objectives and evaluation counts, bit for bit, as when every Jacobian solves again, and
every Jacobian is served by the kept solve: one eigen-solve fewer per Jacobian.  The einsum
contraction orders found once per basis give the same bits as numpy's search on each call."""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from dataclasses import replace  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import bayesupdate.inference.reduced_jacobian as reduced_jacobian  # noqa: E402
from bayesupdate.fe.reduced import basis as reduced_basis  # noqa: E402
from bayesupdate.fe.reduced import reduced_model_for  # noqa: E402
from bayesupdate.inference import ObjectiveSpec, build_problem, load_modal_data  # noqa: E402
from bayesupdate.inference import optimize as opt  # noqa: E402
from bayesupdate.models import get_model  # noqa: E402
from bayesupdate.models.exhaust_paper import MEASURED_MASS_KG  # noqa: E402


@pytest.fixture(scope="module")
def job():
    rom = reduced_model_for(get_model("exhaust"), tol=1e-4, seed=0, n_modes=14)
    objective = ObjectiveSpec(MEASURED_MASS_KG, mass_weight=10.0)
    search = build_problem(rom, load_modal_data("paper:ema"), objective=objective)
    fits = opt._Fits(search, opt._residual_count(search), None, 0,
                     mass_fit=opt._exact_mass_fit(search))  # fmt: skip
    return replace(fits, least_squares_tolerance=opt.SURROGATE_LEAST_SQUARES)


def _starts(job, monkeypatch, keep: bool):
    """(ends, objectives, smooth flags, evaluations, eigen-solves, Jacobians, Jacobians served
    by the kept solve) of 3 Sobol starts (seed 0), least squares only."""
    solves, jacobians, served = [], [], []
    eigen = reduced_basis.ReducedBasis.eigen
    derivatives = reduced_jacobian.eigen_derivatives

    def counted_eigen(self, theta_full, n_modes, vectors=False):
        solves.append(theta_full.shape[0])
        return eigen(self, theta_full, n_modes, vectors)

    def counted_derivatives(basis, full, columns, n_modes, solved=None, paths=None):
        jacobians.append(1)
        served.extend([1] if solved is not None else [])
        return derivatives(basis, full, columns, n_modes, solved, paths)

    monkeypatch.setattr(reduced_basis.ReducedBasis, "eigen", counted_eigen)
    monkeypatch.setattr(reduced_jacobian, "eigen_derivatives", counted_derivatives)
    if not keep:
        monkeypatch.setattr(opt, "_last_solve", lambda problem: None)
    starts = opt.space_filling_starts(3, len(job.problem.parameters), 0)
    counter = opt.EvaluationCount()
    u, values, smooth = opt._run_fits(job, [(u0, False) for u0 in starts], counter, None)
    monkeypatch.undo()
    return np.array(u), np.array(values), smooth, counter.evaluations, solves, jacobians, served


def test_the_kept_solve_gives_the_same_ends_with_fewer_solves(job, monkeypatch):
    u0, f0, smooth0, n0, solves0, jac0, served0 = _starts(job, monkeypatch, keep=False)
    u1, f1, smooth1, n1, solves1, jac1, served1 = _starts(job, monkeypatch, keep=True)
    np.testing.assert_array_equal(u1, u0)
    np.testing.assert_array_equal(f1, f0)
    assert smooth1 == smooth0 and n1 == n0
    assert len(jac1) == len(jac0) > 3 and not served0
    # each Jacobian follows the residuals at its point: all are served, one solve fewer each
    assert len(served1) == len(jac1)
    assert len(solves1) == len(solves0) - len(jac1)


def test_the_contraction_orders_found_once_give_the_same_bits(job):
    """``reduced_jacobian.contraction_paths``: einsum's own order, found once per basis, makes
    the same products as the search on every call (``optimize=True``)."""
    model, basis = reduced_jacobian.reduced_basis_of(job.problem)
    columns = [model.parameter_names.index(n) for n in job.problem.names]
    paths = reduced_jacobian.contraction_paths(basis, 14, len(columns))
    u = np.random.default_rng(3).random((4, len(model.parameter_names)))
    for full in model.scale(u):
        searched = reduced_jacobian.eigen_derivatives(basis, full[None, :], columns, 14)
        found = reduced_jacobian.eigen_derivatives(basis, full[None, :], columns, 14, None, paths)
        for a, b in zip(searched, found, strict=True):
            np.testing.assert_array_equal(a, b)
        assert np.all(np.abs(found[2]) > 0)  # every mode moves with every parameter
