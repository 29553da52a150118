"""The fixed-pattern solve route of small general models (``fe.general_plan``): the reduction
T^T K T as one sparse product of K's data, the shared pattern of K and M, and the band Cholesky
of K - sigma M formed from their data (``eigen_small.shifted``).

* The reduction equals the sparse products (``ConstraintTransform.reduce``) on the mAEWing1
  v3.3 deck (RBE2s, 756 -> 354 DOFs) to round-off, with the products' pattern.
* An entry that is zero at the first point and not at a later one is kept (the pattern grows).
* Closed form: a free-free chain of N masses m on springs k, with a massless node inside every
  link (M singular there), given with K and M on one pattern (M storing zeros): the Krylov's
  shared-pattern factorization gives lambda_j = (4 k / m) sin^2(j pi / (2 N)); and the whole
  route (``GeneralPlan.solve``) does on the same chain with its first mass split over two DOFs
  tied by T.
* The deck with three wing fields bound, at two points: the route's modes equal
  ``Assembler.solve``'s (the sparse products) to 1e-11 in frequency and 1 - 1e-12 in MAC, and
  dense LAPACK's as ``tests/test_fe_eigen_small.py`` holds them.
"""

import numpy as np
import pytest
import scipy.sparse as sp
from roundoff import frequency_roundoff
from test_nastran_deck_solve import BINDS, bound_v33

from bayesupdate.fe.eigen_small import KrylovSettings, krylov_modes, shifted
from bayesupdate.fe.general_plan import GeneralPlan, ReductionMap
from bayesupdate.fe.sparse_modal import ModalSettings

SIGMA = ModalSettings().shift


@pytest.fixture(scope="module")
def bound():
    """The bound v3.3 deck (three wing fields) of the deck-solve tests."""
    return bound_v33()


def point(model, factors):
    d = model.default_parameters()
    return {k: d[k] * f for k, f in zip(BINDS, factors, strict=True)}


def test_reduction_equals_the_sparse_products(bound):
    g = bound.general
    K, M = bound.matrices(point(bound, (1.1, 0.9, 1.25)))
    Kf, Mf = GeneralPlan(g).map.reduce(K.data, M.data)
    # one pattern for both
    np.testing.assert_array_equal(Kf.indices, Mf.indices)
    np.testing.assert_array_equal(Kf.indptr, Mf.indptr)
    assert Kf.shape == (354, 354)
    for mine, theirs in ((Kf, g.transform.reduce(K)), (Mf, g.transform.reduce(M))):
        diff = np.abs((mine - theirs).toarray()).max()
        assert diff <= 1e-15 * np.abs(theirs.toarray()).max()
    # the live pattern is the products' nonzeros (K's; M's lie inside it)
    nonzero = (g.transform.reduce(K) != 0).astype(int) + (g.transform.reduce(M) != 0)
    assert Kf.nnz == nonzero.nnz


def test_an_entry_that_becomes_nonzero_is_kept():
    # three DOFs, the third tied to the first two: u = T u_ind, u_2 = 0.5 (u_0 + u_1)
    T = sp.csr_matrix(np.array([[1.0, 0.0], [0.0, 1.0], [0.5, 0.5]]))
    rows, cols = np.divmod(np.arange(9), 3)
    red = ReductionMap(T, rows, cols)
    Kd = np.diag([2.0, 3.0, 0.0])
    Kf, _ = red.reduce(Kd.ravel(), np.eye(3).ravel())
    np.testing.assert_array_equal(Kf.toarray(), np.diag([2.0, 3.0]))
    Kd[2, 2] = 4.0  # now the tied DOF couples u_0 and u_1: T^T K T gets off-diagonal terms
    Kf, Mf = red.reduce(Kd.ravel(), np.eye(3).ravel())
    np.testing.assert_allclose(Kf.toarray(), [[3.0, 1.0], [1.0, 4.0]], rtol=1e-15)
    np.testing.assert_allclose(Mf.toarray(), [[1.25, 0.25], [0.25, 1.25]], rtol=1e-15)


def test_shared_pattern_chain_with_massless_links_matches_the_closed_form():
    n_mass, k, m, n_modes = 200, 2.0e6, 0.5, 16
    n = 2 * (n_mass - 1) + 1
    main = np.full(n, 4.0 * k)
    main[[0, -1]] = 2.0 * k
    K = sp.diags([main, np.full(n - 1, -2.0 * k), np.full(n - 1, -2.0 * k)], [0, 1, -1]).tocsr()
    mass = np.zeros(n)
    mass[::2] = m
    # M on K's pattern, storing zeros off the diagonal and on the massless nodes
    diagonal = K.indices == np.repeat(np.arange(n), np.diff(K.indptr))
    M = sp.csr_matrix((np.where(diagonal, mass[K.indices], 0.0), K.indices, K.indptr), K.shape)
    chol = shifted(K, M, SIGMA)
    assert chol.ok
    x = np.random.default_rng(3).standard_normal(n)
    np.testing.assert_allclose((K - SIGMA * M) @ chol.solve(x), x, rtol=0, atol=1e-9)
    r = np.ones((n, 1)) / np.sqrt(m * n_mass)
    lam, phi = krylov_modes(K, M, r, n_modes, SIGMA, KrylovSettings())
    j = np.arange(1, n_modes + 1)
    np.testing.assert_allclose(lam, 4 * k / m * np.sin(j * np.pi / (2 * n_mass)) ** 2, rtol=1e-10)
    np.testing.assert_allclose(phi.T @ (M @ phi), np.eye(n_modes), atol=1e-10)


def test_route_on_a_tied_chain_with_massless_links_matches_the_closed_form():
    """The whole route (reduction by T, shared pattern, rigid set, Krylov, expansion) on the
    chain with massless links whose first mass is split over two DOFs tied by T (u_d = u_0,
    half the mass each, no stiffness on d): T^T M T puts m back on DOF 0, and the free-free
    chain's lambda_j = (4 k / m) sin^2(j pi / (2 N)) follow."""
    from types import SimpleNamespace

    n_mass, k, m, n_modes = 150, 2.0e6, 0.5, 12
    n = 2 * (n_mass - 1) + 1  # independent DOFs; DOF n is the tied one
    chain = sp.diags([np.r_[2 * k, np.full(n - 2, 4 * k), 2 * k], np.full(n - 1, -2 * k),
                      np.full(n - 1, -2 * k)], [0, 1, -1], format="csr")  # fmt: skip
    # DOF n has no stiffness, but its diagonal is stored (every diagonal is in a pattern)
    indices = np.r_[chain.indices, n].astype(np.int32)
    indptr = np.r_[chain.indptr, chain.nnz + 1].astype(np.int32)
    K = sp.csr_matrix((np.r_[chain.data, 0.0], indices, indptr), shape=(n + 1, n + 1))
    rows = np.repeat(np.arange(n + 1), np.diff(K.indptr)).astype(np.int32)
    mass = np.zeros(n + 1)
    mass[1:n:2] = 0.0
    mass[2:n:2] = m
    mass[[0, n]] = m / 2
    M = sp.csr_matrix((np.where(rows == K.indices, mass[rows], 0.0), K.indices, K.indptr))
    T = sp.vstack([sp.eye(n), sp.csr_matrix(([1.0], ([0], [0])), shape=(1, n))]).tocsr()
    g = SimpleNamespace(transform=SimpleNamespace(T=T, independent=np.arange(n)), rows=rows,
                        cols=K.indices, indptr=K.indptr, rigid=np.ones((n, 1)))  # fmt: skip
    settings = ModalSettings(small_method="krylov")
    modes = GeneralPlan(g).solve(K, M, n_modes, settings)
    j = np.arange(1, n_modes + 1)
    exact = 4 * k / m * np.sin(j * np.pi / (2 * n_mass)) ** 2
    np.testing.assert_allclose(modes.eigenvalues, exact, rtol=1e-10)
    assert modes.n_rigid == 1
    np.testing.assert_array_equal(modes.shapes[n], modes.shapes[0])  # the tied DOF follows
    np.testing.assert_allclose(modes.shapes.T @ (M @ modes.shapes), np.eye(n_modes), atol=1e-10)


@pytest.mark.parametrize("factors", [(0.6, 1.8, 0.7), (1.9, 0.55, 1.4)])
def test_deck_route_equals_the_assembler_solve(bound, factors):
    p = point(bound, factors)
    new = bound.solve(p, 20)
    assert bound._plan.assembler is bound.general  # the route was taken
    g = bound.general
    K, M = bound.matrices(p)
    settings = ModalSettings(rigid_set="rigid_motions", small_method="krylov")
    old = g.solve(K, M, 20, settings=settings)
    # the two routes sum the reduction in another order: the same frequencies to each mode's
    # round-off scale (tests/roundoff.py: 3.7e-8 on the first mode, ~1e-11 on local ones;
    # measured 1.1e-12 and 1.1e-11 on two machines' BLAS)
    scale = frequency_roundoff(K, M, new.modes.shapes)
    assert np.all(np.abs(new.frequencies_hz / old.frequencies_hz - 1.0) <= scale)
    assert scale.min() < 1e-10
    assert new.modes.n_rigid == old.n_rigid == 6
    a, b = new.modes.shapes, old.shapes
    mac = np.einsum("ij,ij->j", a, M @ b) ** 2
    mac /= np.einsum("ij,ij->j", a, M @ a) * np.einsum("ij,ij->j", b, M @ b)
    assert np.all(mac > 1 - 1e-12)
    dense = bound.solve(p, 20, method="dense")
    np.testing.assert_allclose(new.frequencies_hz, dense.frequencies_hz, rtol=3e-8)
    np.testing.assert_allclose(new.mass_kg, dense.mass_kg, rtol=1e-14)
