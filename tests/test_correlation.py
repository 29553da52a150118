"""Correlation maths (``bayesupdate.correlation``) against hand cases and closed forms: the
Hungarian pairing recovers a permutation and names its swaps, a threshold refuses a shape that
is not there, COMAC of identical sets is 1, and a SEREP TAM of a spring-mass chain reproduces
its retained modes exactly (O'Callahan, Avitabile & Riemer 1989)."""

import numpy as np
import pytest
from scipy.linalg import eigh

from bayesupdate.correlation import (
    auto_mac,
    comac,
    cross_orthogonality,
    mac_matrix,
    pair_in_order,
    pair_modes,
    pseudo_orthogonality,
    serep_expand,
    serep_mass,
    serep_tam,
    serep_transformation,
)


def _shapes(n_dof=12, m=5, seed=101):
    return np.random.default_rng(seed).normal(size=(n_dof, m))


def test_a_permuted_scaled_set_pairs_back_to_its_permutation_and_names_the_swaps():
    model = _shapes()
    perm = np.array([0, 2, 1, 3, 4])  # test mode 1 is model mode 2 and the other way round
    test = model[:, perm] * np.array([1.0, -2.0, 0.5, 3.0, -1.0])  # sign and scale: MAC blind
    pairs = pair_modes(mac_matrix(test, model))
    assert pairs.test.tolist() == [0, 1, 2, 3, 4]
    assert pairs.model.tolist() == perm.tolist()
    np.testing.assert_allclose(pairs.mac, 1.0, atol=1e-12)
    assert pairs.swapped == ((1, 2), (2, 1))
    assert pairs.unpaired_test == () and pairs.unpaired_model == () and pairs.refused == ()


def test_a_test_mode_the_model_lacks_is_refused_and_an_extra_model_mode_left_unpaired():
    model = _shapes(m=6)
    other = _shapes(seed=102)[:, :1]
    # a shape orthogonal to every model mode: MAC 0 with all of them
    q, _ = np.linalg.qr(model)
    other = other - q @ (q.T @ other)
    test = np.column_stack([model[:, 0], other[:, 0], model[:, 2], model[:, 3]])
    pairs = pair_modes(mac_matrix(test, model), threshold=0.6)
    assert pairs.test.tolist() == [0, 2, 3] and pairs.model.tolist() == [0, 2, 3]
    assert pairs.unpaired_test == (1,)
    assert pairs.refused[0][0] == 1 and pairs.refused[0][2] < 1e-20
    # model mode 1 is missing from the test: not a swap, an unpaired model mode
    assert pairs.swapped == ()
    assert pairs.unpaired_model == (1, 4, 5)  # the refused pair's model mode is one of them


def test_pairing_in_order_pairs_the_first_modes_and_leaves_the_rest():
    pairs = pair_in_order(4, 6)
    assert pairs.model.tolist() == [0, 1, 2, 3] and pairs.unpaired_model == (4, 5)
    assert np.isnan(pairs.mac).all() and pairs.method == "order"


def test_comac_of_identical_sets_is_one_and_a_corrupted_dof_is_the_lowest():
    a = _shapes()
    np.testing.assert_allclose(comac(a, -3.0 * a), 1.0, atol=1e-12)
    b = a.copy()
    b[7] = np.random.default_rng(103).normal(size=a.shape[1])  # one sensor reads nonsense
    values = comac(a, b)
    assert np.argmin(values) == 7 and values[7] < 0.9
    np.testing.assert_allclose(np.diag(auto_mac(a)), 1.0)


def _chain(n=6):
    """A chain of n springs (k = 1000 N/m, the first to ground) and masses 1..n kg."""
    k = 1000.0
    K = np.diag(np.r_[np.full(n - 1, 2 * k), k]) - k * (np.eye(n, k=1) + np.eye(n, k=-1))
    M = np.diag(np.arange(1.0, n + 1))
    return K, M


def test_serep_tam_of_a_spring_mass_chain_reproduces_its_retained_modes_exactly():
    K, M = _chain()
    lam, phi = eigh(K, M)  # mass-normalized
    retained, at = [0, 1, 2], [1, 3, 5]  # three modes seen at three DOFs
    phi_r = phi[:, retained]
    phi_a = phi_r[at]
    T = serep_transformation(phi_r, phi_a)
    K_a, M_a = serep_tam(T, K, M)
    # the TAM's eigenvalues are the full model's retained ones, its modes the retained shapes
    np.testing.assert_allclose(eigh(K_a, M_a, eigvals_only=True), lam[retained], rtol=1e-10)
    np.testing.assert_allclose(phi_a.T @ M_a @ phi_a, np.eye(3), atol=1e-10)
    np.testing.assert_allclose(phi_a.T @ K_a @ phi_a, np.diag(lam[retained]), atol=1e-7)
    # for mass-normalized modes T^T M T is (Phi_a^+)^T Phi_a^+
    np.testing.assert_allclose(serep_mass(phi_a), M_a, atol=1e-10)
    np.testing.assert_allclose(pseudo_orthogonality(phi_a, M_a), np.eye(3), atol=1e-10)
    # expanding the retained shapes from the test DOFs gives them back at every DOF
    np.testing.assert_allclose(serep_expand(T, phi_a), phi_r, atol=1e-12)


def test_cross_orthogonality_is_the_identity_for_the_model_itself_and_sees_a_mix():
    K, M = _chain()
    _, phi = eigh(K, M)
    phi_a = phi[[0, 2, 4, 5], :3]
    M_a = serep_mass(phi_a)
    np.testing.assert_allclose(cross_orthogonality(phi_a, phi_a, M_a), np.eye(3), atol=1e-10)
    # a test mode that is mode 1 and mode 2 mixed at 45 degrees: 0.707 on both
    mixed = (phi_a[:, [1]] + phi_a[:, [2]]) / np.sqrt(2)
    x = cross_orthogonality(mixed, phi_a, M_a)
    np.testing.assert_allclose(x, [[0.0, np.sqrt(0.5), np.sqrt(0.5)]], atol=1e-10)


def test_pseudo_orthogonality_shows_modes_too_few_sensors_cannot_separate():
    K, M = _chain()
    _, phi = eigh(K, M)
    phi_a = phi[[5], :2]  # two modes, one sensor: Phi_a has rank 1
    poc = pseudo_orthogonality(phi_a, serep_mass(phi_a))
    assert np.trace(poc) == pytest.approx(1.0)  # a rank-1 projector, not the identity
    assert abs(poc[0, 1]) > 0.1
