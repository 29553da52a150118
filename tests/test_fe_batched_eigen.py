"""Threaded batched eigen-solve of reduced free-free pencils (bayesupdate.fe.batched_eigen),
checked against dense LAPACK on the pencils with the rigid coordinates kept, and against the
independent dsygvd path of tests/reference_eigen.py."""

import numpy as np
import pytest
import scipy.linalg as sl
from reference_eigen import sygvd_elastic_eigenvalues

from bayesupdate.fe.batched_eigen import (
    THREADS_VARIABLE,
    batched_elastic_eigenvalues,
    solver_threads,
)

N_RIGID, N_ELASTIC, N_MODES, BATCH = 6, 30, 10, 24


@pytest.fixture(scope="module")
def pencils():
    """A batch of reduced free-free pencils: K with a 6-dimensional null space in the first
    coordinates (rigid motions), M positive definite and coupling rigid and elastic
    coordinates (as a reduced mass matrix does)."""
    rng = np.random.default_rng(5)
    r = N_RIGID + N_ELASTIC
    A = rng.standard_normal((BATCH, N_ELASTIC, N_ELASTIC))
    K_ww = A @ A.transpose(0, 2, 1) * 1e4 + 1e3 * np.eye(N_ELASTIC)
    Bm = rng.standard_normal((BATCH, r, r))
    M = Bm @ Bm.transpose(0, 2, 1) / r + np.eye(r)
    return K_ww, M


def dense_reference(K_ww, M, n_modes):
    r = M.shape[-1]
    out = np.empty((K_ww.shape[0], n_modes))
    for i in range(K_ww.shape[0]):
        K = np.zeros((r, r))
        K[N_RIGID:, N_RIGID:] = K_ww[i]
        lam = sl.eigh(K, M[i], eigvals_only=True)
        assert np.all(np.abs(lam[:N_RIGID]) < 1e-8 * lam[-1])  # the six rigid-body zeros
        out[i] = lam[N_RIGID : N_RIGID + n_modes]
    return out


def test_eigenvalues_match_dense_lapack_and_dsygvd(pencils):
    K_ww, M = pencils
    lam = batched_elastic_eigenvalues(K_ww, M, N_RIGID, N_MODES, threads=1)
    np.testing.assert_allclose(lam, dense_reference(K_ww, M, N_MODES), rtol=1e-10)
    np.testing.assert_allclose(
        lam, sygvd_elastic_eigenvalues(K_ww, M, N_RIGID, N_MODES), rtol=1e-11
    )


@pytest.mark.parametrize("threads", [2, 3, 8])
def test_result_does_not_depend_on_the_thread_count(pencils, threads):
    K_ww, M = pencils
    one = batched_elastic_eigenvalues(K_ww, M, N_RIGID, N_MODES, threads=1)
    many = batched_elastic_eigenvalues(K_ww, M, N_RIGID, N_MODES, threads=threads)
    assert np.array_equal(one, many)  # each matrix gets the same LAPACK calls: bit for bit
    lam1, y1 = batched_elastic_eigenvalues(K_ww, M, N_RIGID, N_MODES, vectors=True, threads=1)
    lam2, y2 = batched_elastic_eigenvalues(K_ww, M, N_RIGID, N_MODES, True, threads=threads)
    assert np.array_equal(lam1, lam2) and np.array_equal(y1, y2)


def test_vectors_solve_the_pencil_and_are_mass_normalized(pencils):
    K_ww, M = pencils
    lam, y = batched_elastic_eigenvalues(K_ww, M, N_RIGID, N_MODES, vectors=True, threads=2)
    r = M.shape[-1]
    K = np.zeros((BATCH, r, r))
    K[:, N_RIGID:, N_RIGID:] = K_ww
    residual = K @ y - (M @ y) * lam[:, None, :]
    assert np.max(np.abs(residual)) <= 1e-9 * np.max(lam)
    gram = y.transpose(0, 2, 1) @ M @ y
    np.testing.assert_allclose(gram, np.broadcast_to(np.eye(N_MODES), gram.shape), atol=1e-10)


def test_indefinite_mass_raises(pencils):
    K_ww, M = pencils
    bad = M.copy()
    bad[3] = -np.eye(M.shape[-1])
    with pytest.raises(np.linalg.LinAlgError):
        batched_elastic_eigenvalues(K_ww, bad, N_RIGID, N_MODES, threads=2)


def test_thread_count_from_the_environment(monkeypatch):
    monkeypatch.setenv(THREADS_VARIABLE, "3")
    assert solver_threads() == 3
    monkeypatch.setenv(THREADS_VARIABLE, "0")
    assert solver_threads() == 1
    monkeypatch.setenv(THREADS_VARIABLE, "many")
    assert solver_threads() == 1
    monkeypatch.delenv(THREADS_VARIABLE)
    assert solver_threads() == 1
