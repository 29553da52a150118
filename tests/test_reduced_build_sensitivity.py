"""A faster first build of the reduced basis (``fe.reduced``): design-sensitivity vectors of the
snapshots' modes (``reduced.sensitivity``), the residual indicator that chooses where to enrich
(``reduced.estimator``) and the build with both, certified on full solves at fresh points as
before, with fewer full solves."""

import numpy as np
import pytest
from scipy.stats import qmc
from test_reduced_shells import box_model, clamped_plate_model

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.model import FEModel
from bayesupdate.fe.reduced import ReducedFEModel, ReducedSettings
from bayesupdate.fe.reduced.affine import decompose
from bayesupdate.fe.reduced.basis import full_solves, pod_basis
from bayesupdate.fe.reduced.certification import GREEDY_BATCH, compare
from bayesupdate.fe.reduced.estimator import ResidualIndicator
from bayesupdate.fe.reduced.sensitivity import static_corrections
from bayesupdate.fe.reduced.settings import GREEDY_TRAIN, LARGE_MODEL_DOFS

N_MODES = 8


def _aligned(shapes, ref, M):
    return shapes * np.sign(np.einsum("ij,ij->j", shapes, M @ ref))


def _unexplained(dphi, B):
    """Per column, the share of dphi (n, m) outside span(B)."""
    Q = np.linalg.qr(B)[0]
    r = dphi - Q @ (Q.T @ dphi)
    return np.linalg.norm(r, axis=0) / np.linalg.norm(dphi, axis=0)


def test_static_corrections_span_the_mode_derivatives():
    """Central differences of full solves: d phi_i / d theta_j lies in span(modes, X) (Nelson's
    equation), not in the span of the modes alone."""
    fe = clamped_plate_model()
    d = fe.default_parameters()
    dec = decompose(fe, fe.default_bounds(), 1e-9)
    sol = fe.solve(d, N_MODES).modes
    X = static_corrections(fe, dec, d, sol.eigenvalues, sol.shapes)
    assert X.shape == (sol.shapes.shape[0], len(fe.parameter_names) * N_MODES)
    M = fe.matrices(d)[1]
    for name in fe.parameter_names:
        h = 1e-4 * d[name]
        up = _aligned(fe.solve({**d, name: d[name] + h}, N_MODES).modes.shapes, sol.shapes, M)
        down = _aligned(fe.solve({**d, name: d[name] - h}, N_MODES).modes.shapes, sol.shapes, M)
        dphi = (up - down) / (2 * h)
        alone = _unexplained(dphi, sol.shapes)
        with_x = _unexplained(dphi, np.hstack([sol.shapes, X]))
        assert np.median(alone) > 0.2 and alone.max() > 0.5
        # measured: median <= 1e-3, largest 0.046 (mode 7 in the mass factor)
        assert np.median(with_x) < 1e-2 and with_x.max() < 0.1


def test_residual_indicator_vanishes_on_the_span_and_ranks_the_errors():
    """eta = 0 (round-off) where the basis holds the exact modes (a snapshot point), and it
    orders fresh points as their true errors do (Spearman rank correlation)."""
    fe = box_model()
    model = ReducedFEModel(fe, None, ReducedSettings(n_modes=N_MODES))
    dec = decompose(fe, model.bounds, 1e-9)
    names = model.parameter_names
    centre = model.mapping(model.centre())
    snap = model.scale(qmc.Sobol(len(names), scramble=True, seed=1).random(4))
    shapes = full_solves(fe, names, snap, N_MODES + 4)[1]
    basis = pod_basis(fe, dec, centre, shapes, 0.0, N_MODES)
    indicator = ResidualIndicator(fe, centre)
    fresh = model.scale(qmc.Sobol(len(names), scramble=True, seed=2).random(16))
    eta_snap = indicator(basis, snap[:1], names, N_MODES)
    eta = indicator(basis, fresh, names, N_MODES)
    f_full = full_solves(fe, names, fresh, N_MODES)[0]
    err = np.array([compare(basis, t[None], f[None], N_MODES).max_rel_error
                    for t, f in zip(fresh, f_full, strict=True)])  # fmt: skip
    assert eta_snap[0] < 1e-9 * eta.min()
    rank = np.corrcoef(np.argsort(np.argsort(eta)), np.argsort(np.argsort(err)))[0, 1]
    assert rank > 0.6


@pytest.fixture
def solve_counter(monkeypatch):
    count = {"n": 0}
    solve = FEModel.solve

    def counted(self, *args, **kwargs):
        count["n"] += 1
        return solve(self, *args, **kwargs)

    monkeypatch.setattr(FEModel, "solve", counted)
    monkeypatch.setenv("BAYESUPDATE_NO_CACHE", "1")
    return count


def test_build_with_sensitivities_needs_fewer_full_solves(solve_counter):
    """Same box, tolerance and validation set size: the plain build (16 snapshots), the build
    with sensitivities (4 snapshots, the large-model default) and the same with the residual
    greedy; all certified on 16 fresh full solves, the second with less than half the full
    solves of the first (measured 64, 20 and 24), and Rayleigh-Ritz upper bounds within the
    tolerance at fresh points."""
    fe = box_model()
    common = dict(n_modes=N_MODES, tol=5e-5, seed=0, n_validation=16)
    plain = ReducedSettings(**common, n_snapshots=16, sensitivities=False, greedy_train=0)
    sensitive = ReducedSettings(**common, n_snapshots=4, sensitivities=True, greedy_train=0)
    greedy = ReducedSettings(**common, n_snapshots=4, sensitivities=True, greedy_train=32)
    models, solves = [], []
    for settings in (plain, sensitive, greedy):
        solve_counter["n"] = 0
        models.append(ReducedFEModel(fe, None, settings).build())
        solves.append(solve_counter["n"])
    assert all(m.certified and m.max_rel_error <= 5e-5 for m in models)
    assert all(m.certificate.n_points == 16 for m in models)  # the certificate: fresh solves
    assert solves[1] < 0.5 * solves[0]
    # both pass their first validation round: the greedy adds only its own steps' solves
    assert solves[2] > solves[1] and (solves[2] - solves[1]) % GREEDY_BATCH == 0
    theta = models[1].scale(np.random.default_rng(3).random((5, 4)))
    f_full = fe.predict_frequencies_batch(theta, fe.parameter_names, N_MODES)
    for model in models[1:]:
        rel = model.predict_frequencies_batch(theta) / f_full - 1
        assert np.abs(rel).max() <= 1e-4 and rel.min() > -1e-9


def test_settings_fill_in_the_strategy_by_model_size():
    small = ReducedSettings().resolved(LARGE_MODEL_DOFS - 1)
    large = ReducedSettings().resolved(LARGE_MODEL_DOFS)
    assert (small.sensitivities, small.n_snapshots, small.greedy_train) == (False, 32, 0)
    assert (large.sensitivities, large.n_snapshots, large.greedy_train) == (True, 8, GREEDY_TRAIN)
    mine = ReducedSettings(n_snapshots=5, sensitivities=False, greedy_train=3).resolved(10**6)
    assert (mine.sensitivities, mine.n_snapshots, mine.greedy_train) == (False, 5, 3)
    with pytest.raises(BayesUpdateError, match="greedy_train"):
        ReducedSettings(greedy_train=-1)
    with pytest.raises(BayesUpdateError, match="n_snapshots"):
        ReducedSettings(n_snapshots=0)
