"""The banded shift-invert block Krylov of ``fe.eigen_small`` (the small pencils' solver of the
general path for ``ModalSettings.small_method = "krylov"``, ``NastranModel``'s choice).

* Closed form: a free-free chain of N equal masses m on springs k has
  lambda_j = (4 k / m) sin^2(j pi / (2 N)), j = 0..N-1 (j = 0 the rigid translation); with a
  massless node inside every link (two springs 2k in series, M singular on those DOFs) the
  chain's eigenvalues are the same.
* Dense LAPACK (``sparse_modal._dense_modes``) on a constrained pencil whose rigid motion
  carries energy (a chain on a soft spring to ground, the rigid set "rigid_motions" as a Nastran
  SUPORT makes it).
* The mAEWing1 v3.3 deck with three wing fields bound, at two points: today's dense LAPACK
  answer to 1e-8 in frequencies and 1 - 1e-8 in MAC (measured 8e-9 and 1e-14; the dense
  eigenvalue of mode 1 is itself 1.3e-8 off the extended-precision Rayleigh quotient of its
  own vector, ``benchmarks/deck_eigen_routes.py``).
* A mechanism is still reported (the iteration does not converge on it and dense LAPACK
  names the moving DOFs).
"""

from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.eigen_small import KrylovSettings, krylov_modes
from bayesupdate.fe.sparse_modal import (
    ModalSettings,
    _dense_modes,
    solve_reduced_modes,
)

SIGMA = ModalSettings().shift
FEM = Path(__file__).resolve().parents[2] / "shared" / "data" / "gvt_maewing1" / "fem"
V33 = FEM / "v3.3_hati" / "sol103_mAEWing1_Hati_FEMv3p3.bdf"
BINDS = {"i1_1003": "PBEAM 1003 I1", "i1_1004": "PBEAM 1004 I1", "a_1005": "PBEAM 1005 A"}


def chain(n_mass: int, k: float, m: float, massless_links: bool, ground: float = 0.0):
    """(K, M) sparse of a free-free chain of n_mass masses m on springs k, each link made of two
    springs 2k through a massless node when ``massless_links``; ``ground`` a spring to ground on
    the first mass."""
    step = 2 if massless_links else 1
    n = step * (n_mass - 1) + 1
    ks = 2.0 * k if massless_links else k
    rows, cols, vals = [], [], []
    for a in range(n - 1):
        rows += [a, a, a + 1, a + 1]
        cols += [a, a + 1, a, a + 1]
        vals += [ks, -ks, -ks, ks]
    K = sp.csr_matrix((vals, (rows, cols)), shape=(n, n)).tolil()
    K[0, 0] += ground
    mass = np.zeros(n)
    mass[::step] = m
    return K.tocsr(), sp.diags(mass).tocsr()


def rigid_translation(M) -> np.ndarray:
    r = np.ones((M.shape[0], 1))
    return r / np.sqrt(r.T @ (M @ r))


@pytest.mark.parametrize("massless_links", [False, True])
def test_free_chain_matches_the_closed_form(massless_links):
    n_mass, k, m, n_modes = 300, 2.0e6, 0.5, 20
    K, M = chain(n_mass, k, m, massless_links)
    out = krylov_modes(K, M, rigid_translation(M), n_modes, SIGMA, KrylovSettings())
    assert out is not None
    lam, phi = out
    j = np.arange(1, n_modes + 1)
    exact = 4 * k / m * np.sin(j * np.pi / (2 * n_mass)) ** 2
    np.testing.assert_allclose(lam, exact, rtol=1e-10)
    np.testing.assert_allclose(phi.T @ (M @ phi), np.eye(n_modes), atol=1e-10)
    # the constraint: M-orthogonal to the rigid translation
    assert np.abs(rigid_translation(M).T @ (M @ phi)).max() < 1e-10


def test_constrained_pencil_matches_dense_lapack():
    """A rigid motion with energy (a soft ground spring): the SUPORT convention's problem on
    its M-orthogonal complement, not the free eigenproblem."""
    K, M = chain(120, 1.0e5, 0.2, True, ground=50.0)
    Rm = rigid_translation(M)
    assert (Rm.T @ (K @ Rm)).item() > 1.0  # the rigid motion is no eigenvector
    lam, phi = krylov_modes(K, M, Rm, 12, SIGMA, KrylovSettings())
    lam_d, phi_d = _dense_modes(K, M, Rm, 12, SIGMA)
    np.testing.assert_allclose(lam, lam_d, rtol=1e-10)
    mac = (np.einsum("ij,ij->j", phi, M @ phi_d)) ** 2
    assert np.all(mac > 1 - 1e-10)


def test_mechanism_is_still_reported():
    """Two chains not joined: a zero-energy relative motion beyond the one rigid translation."""
    K1, M1 = chain(60, 1.0e5, 0.2, False)
    K, M = sp.block_diag([K1, K1]).tocsr(), sp.block_diag([M1, M1]).tocsr()
    Rm = rigid_translation(M)
    assert krylov_modes(K, M, Rm, 10, SIGMA, KrylovSettings()) is None
    settings = ModalSettings(n_modes=10, small_method="krylov")
    with pytest.raises(BayesUpdateError, match="mechanism"):
        solve_reduced_modes(K, M, Rm, settings, np.arange(K.shape[0]))


def test_unknown_small_method_is_refused():
    with pytest.raises(BayesUpdateError, match="small_method"):
        ModalSettings(small_method="qr")


@pytest.fixture(scope="module")
def bound():
    from bayesupdate.nastran import load_nastran_model

    if not V33.exists():
        pytest.skip(f"shared data not found: {V33}")
    return load_nastran_model(str(V33), {n: {"binds": b} for n, b in BINDS.items()})


@pytest.mark.parametrize("factors", [(1.1, 0.9, 1.25), (1.9, 0.55, 1.4)])
def test_deck_modes_equal_dense_lapack(bound, factors):
    d = bound.default_parameters()
    p = {k: d[k] * f for k, f in zip(BINDS, factors, strict=True)}
    assert bound.small_method == "krylov"
    new, old = bound.solve(p, 20), bound.solve(p, 20, method="dense")
    # the reference is each mode's Rayleigh quotient in extended precision (its error is
    # quadratic in the shape's, so both solvers' quotients agree to 7.7e-13, measured).  The
    # frequencies the solvers report carry the double-precision round-off of this deck
    # (E = 6.66e10 beside foam-covered beams): measured against the quotients, dense LAPACK
    # 5.5e-9 and 1.7e-8, the Krylov solve 1.6e-9 and 1.4e-8 at these two points, so both are
    # held to the same 3e-8: the Krylov solve is as accurate as LAPACK, not more
    Kx, Mx = (X.toarray().astype(np.longdouble) for X in bound.matrices(p))

    def quotient_hz(x):
        x = x.astype(np.longdouble)
        lam = np.einsum("ij,ij->j", x, Kx @ x) / np.einsum("ij,ij->j", x, Mx @ x)
        return np.sqrt(lam).astype(float) / (2 * np.pi)

    f_new, f_old = quotient_hz(new.modes.shapes), quotient_hz(old.modes.shapes)
    np.testing.assert_allclose(f_new, f_old, rtol=1e-11)
    np.testing.assert_allclose(new.frequencies_hz, f_new, rtol=3e-8)
    np.testing.assert_allclose(old.frequencies_hz, f_old, rtol=3e-8)
    assert new.modes.n_rigid == old.modes.n_rigid == 6
    M = bound.matrices(p)[1]
    a, b = new.modes.shapes, old.modes.shapes
    mac = np.einsum("ij,ij->j", a, M @ b) ** 2
    mac /= np.einsum("ij,ij->j", a, M @ a) * np.einsum("ij,ij->j", b, M @ b)
    assert np.all(mac > 1 - 1e-8)
    # the iteration itself converged on the deck (no silent fall-back to LAPACK), on the
    # matrices the solve reduced once per assembler (``fe.general_plan``)
    g = bound.general
    K, M = bound.matrices(p)
    Kf, Mf = bound._plan.map.reduce(K.data, M.data)
    from bayesupdate.fe.sparse_modal import _rigid_modes

    Rm, _ = _rigid_modes(Kf, Mf, g.rigid, 1e-10, "rigid_motions")
    Rm = Rm / np.sqrt(np.einsum("ij,ij->j", Rm, Mf @ Rm))
    out = krylov_modes(Kf, Mf, Rm, 20, SIGMA, KrylovSettings())
    assert out is not None
    np.testing.assert_array_equal(np.sqrt(out[0]) / (2 * np.pi), new.frequencies_hz)
