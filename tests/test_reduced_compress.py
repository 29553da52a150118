"""The compression of projected affine terms (``fe.reduced.basis.compress_terms``) drops no
more than a plain SVD truncated at ``rel`` x the largest singular value, whether the low rank
is found by the randomized range finder or the matrix is full rank (plain SVD)."""

import numpy as np

from bayesupdate.fe.reduced.basis import SKETCH, _range_finder, compress_terms


def graded(n: int, m: int, sv: np.ndarray, seed: int) -> np.ndarray:
    """(n, m) matrix with singular values ``sv`` and random orthonormal singular vectors."""
    rng = np.random.default_rng(seed)
    U = np.linalg.qr(rng.standard_normal((n, sv.size)))[0]
    V = np.linalg.qr(rng.standard_normal((m, sv.size)))[0]
    return (U * sv) @ V.T


def test_low_rank_terms_keep_what_the_plain_svd_keeps():
    # singular values 1 ... 1e-20 over 25 values: 17 above 1e-14, 18 above 0.5e-14
    sv = 10.0 ** -np.linspace(0, 20, 25)
    T = graded(600, 900, sv, seed=3)
    assert _range_finder(T, 0.5e-14) is not None  # the sketch, not the fallback
    C, B = compress_terms(T)
    exact = np.linalg.svd(T, compute_uv=False)
    # it keeps every value the plain truncation keeps, and those within a factor 2 below it
    assert int(np.sum(exact > 1e-14 * exact[0])) == 17
    assert C.shape[1] == int(np.sum(exact > 0.5e-14 * exact[0])) == 18
    # the dropped part is no larger than the plain truncation's bound rel x s0
    assert np.linalg.norm(T - C @ B, 2) <= 1e-14 * exact[0]


def test_full_rank_terms_fall_back_to_the_plain_svd():
    rng = np.random.default_rng(4)
    T = rng.standard_normal((3 * SKETCH, 5 * SKETCH))
    assert _range_finder(T, 0.5e-14) is None
    C, B = compress_terms(T)
    assert C.shape[1] == 3 * SKETCH
    assert np.abs(C @ B - T).max() < 1e-12 * np.abs(T).max()


def test_pattern_parts_hold_each_rows_matrix():
    from types import SimpleNamespace

    from bayesupdate.fe.reduced.shell_terms import pattern_parts

    rng = np.random.default_rng(5)
    n_dof = 30
    dense = rng.random((n_dof, n_dof)) < 0.2
    rows, cols = np.nonzero(dense)  # a CSR pattern: unique (row, col) pairs in order
    g = SimpleNamespace(rows=rows, cols=cols)
    data = rng.standard_normal((4, rows.size))
    data[:, rng.random(rows.size) < 0.5] = 0.0  # entries no row touches
    data[1, : rows.size // 3] = 0.0  # and entries one row does not touch
    V = rng.standard_normal((n_dof, 3))
    for row, part in zip(data, pattern_parts(g, data), strict=True):
        full = np.zeros((n_dof, n_dof))
        full[rows, cols] = row
        sub = np.zeros((n_dof, n_dof))
        sub[np.ix_(part.dofs, part.dofs)] = part.matrix.toarray()
        assert np.array_equal(sub, full)
        assert np.allclose(part.project(V), V.T @ full @ V, rtol=0, atol=1e-13)
