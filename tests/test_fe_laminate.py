"""Classical lamination theory (``fe.laminate``) against Jones's closed forms (*Mechanics of
Composite Materials*, 2nd ed., 1999): the transformed ply stiffness, and A, B, D of the
two-ply antisymmetric cross-ply."""

import numpy as np
import pytest

from bayesupdate.fe.laminate import (
    SHEAR_FACTOR,
    Ply,
    laminate,
    ply_stiffness,
    section_per_unit_thickness,
    shear_rotation,
    strain_rotation,
)

E1, E2, NU12, G12 = 140e9, 10e9, 0.3, 5e9


def test_transformed_stiffness_is_jones_at_45_and_90_degrees():
    """Qbar = T^T Q T at +45 degrees is Jones's eq. 2.85: Qbar11 = (Q11 + 2 (Q12 + 2 Q66) + Q22)
    / 4, Qbar16 = (Q11 - Q22) / 4 (> 0 for a fibre turned counter-clockwise), Qbar66 =
    (Q11 + Q22 - 2 Q12) / 4; at 90 degrees Q11 and Q22 swap."""
    Q = ply_stiffness(E1, E2, NU12, G12)
    q11, q22, q12, q66 = Q[0, 0], Q[1, 1], Q[0, 1], Q[2, 2]
    T = strain_rotation(np.radians(45.0))
    Qb = T.T @ Q @ T
    assert Qb[0, 0] == pytest.approx((q11 + 2 * (q12 + 2 * q66) + q22) / 4, rel=1e-14)
    assert Qb[0, 2] == pytest.approx((q11 - q22) / 4, rel=1e-14)
    assert Qb[2, 2] == pytest.approx((q11 + q22 - 2 * q12) / 4, rel=1e-14)
    T = strain_rotation(np.radians(90.0))
    assert np.allclose(T.T @ Q @ T, [[q22, q12, 0], [q12, q11, 0], [0, 0, q66]], atol=1e-3)


def test_two_ply_cross_ply_has_jones_coupling():
    """[0/90], each ply h/2 (Jones sec. 4.5.3): A11 = A22 = (Q11 + Q22) h / 2, B11 = -B22 =
    (Q22 - Q11) h^2 / 8, B12 = B66 = 0, D11 = D22 = (Q11 + Q22) h^3 / 24; the transverse shear
    is the energy-equivalent one (``transverse_shear``), here against the same energy summed
    over 4,000 sub-layers (the midpoint rule, 1e-6)."""
    h = 2e-3
    plies = [Ply(E1, E2, NU12, G12, 5e9, 3.5e9, 1600.0, h / 2, np.radians(a)) for a in (0, 90)]
    A, B, D, H = laminate(plies)
    Q = ply_stiffness(E1, E2, NU12, G12)
    q11, q22 = Q[0, 0], Q[1, 1]
    assert A[0, 0] == pytest.approx((q11 + q22) * h / 2, rel=1e-14)
    assert B[0, 0] == pytest.approx((q22 - q11) * h**2 / 8, rel=1e-12)
    assert B[1, 1] == pytest.approx(-B[0, 0], rel=1e-12)
    assert abs(B[0, 1]) + abs(B[2, 2]) < 1e-12 * abs(B[0, 0])
    assert D[0, 0] == pytest.approx((q11 + q22) * h**3 / 24, rel=1e-12)
    assert np.allclose(H, _energy_shear_by_sublayers(plies), rtol=1e-6)
    section = section_per_unit_thickness(A, B, D, H, h)
    assert section.coupling[0, 0, 0] == pytest.approx((q22 - q11) / 8, rel=1e-12)
    symmetric = laminate([plies[0], plies[1], plies[1], plies[0]])
    assert section_per_unit_thickness(*symmetric, 2 * h).coupling is None


def _energy_shear_by_sublayers(plies, n=2000) -> np.ndarray:
    """H of the cylindrical-bending energy equivalence (``transverse_shear``'s docstring) by
    brute force: each ply in n sub-layers, f_i(z) summed up the stack, the energy by the
    midpoint rule."""
    t = np.repeat([p.thickness / n for p in plies], n)
    z = np.concatenate([[0.0], np.cumsum(t)]) - t.sum() / 2
    mid = 0.5 * (z[1:] + z[:-1])
    Q = ply_stiffness(*(np.array([getattr(p, a) for p in plies]) for a in ("E1", "E2", "nu12",
                                                                            "G12")))  # fmt: skip
    T = strain_rotation(np.array([p.angle for p in plies]))
    Qb = np.repeat(np.einsum("kai,kab,kbj->kij", T, Q, T), n, axis=0)[:, [0, 1], [0, 1]]
    A, B = (Qb * (z[1:, None] ** k - z[:-1, None] ** k) / k for k in (1, 2))
    zn = B.sum(0) / A.sum(0)
    Dstar = (Qb * (z[1:, None] ** 3 - z[:-1, None] ** 3) / 3).sum(0) - B.sum(0) ** 2 / A.sum(0)
    f = np.cumsum(Qb * (mid[:, None] - zn) * t[:, None], axis=0) - 0.5 * Qb * (
        mid[:, None] - zn) * t[:, None]  # fmt: skip
    G = np.repeat([[p.G1Z, p.G2Z] for p in plies], n, axis=0)
    R = shear_rotation(np.repeat([p.angle for p in plies], n))
    S = np.einsum("kai,ka,kaj->kij", R, 1.0 / G, R)
    F = f / Dstar
    return np.linalg.inv(np.einsum("k,ki,kij,kj->ij", t, F, S, F))


def test_transverse_shear_of_a_homogeneous_stack_is_reissners():
    """Four equal plies at 30 degrees: H = 5/6 h R^T diag(G1Z, G2Z) R, the full 2 x 2, to
    1e-12 (the energy equivalence reduces to Reissner's factor)."""
    h, angle = 2e-3, np.radians(30.0)
    plies = [Ply(E1, E2, NU12, G12, 5e9, 3.5e9, 1600.0, h / 4, angle) for _ in range(4)]
    R = shear_rotation(angle)
    expected = SHEAR_FACTOR * h * R.T @ np.diag([5e9, 3.5e9]) @ R
    assert np.allclose(laminate(plies)[3], expected, rtol=1e-12, atol=1e-12 * expected.max())


def test_a_sandwichs_shear_is_its_cores():
    """Faces 0.5 mm (aluminium, G 26.9 GPa) on a 10 mm core (G 40 MPa): H is the classical
    sandwich shear stiffness G_c d^2 / t_c (d between the faces' mid-planes; Allen, *Analysis
    and Design of Structural Sandwich Panels*, 1969) to 0.1 %, where the plies' 5/6 sum G t
    would be 52 times stiffer; a face that is rigid in shear (MAT8 G1Z, G2Z blank) changes it
    by 5e-5."""
    tf, tc, Gc = 0.5e-3, 10e-3, 0.04e9
    face = Ply(70e9, 70e9, 0.3, 26.9e9, 26.9e9, 26.9e9, 2700.0, tf, 0.0)
    core = Ply(0.1e9, 0.1e9, 0.3, Gc, Gc, Gc, 50.0, tc, 0.0)
    H = laminate([face, core, face])[3]
    classical = Gc * (tc + tf) ** 2 / tc
    assert H[0, 0] == pytest.approx(classical, rel=1.5e-3) and H[1, 1] == H[0, 0]
    assert SHEAR_FACTOR * (2 * 26.9e9 * tf + Gc * tc) / H[0, 0] > 50
    rigid = Ply(70e9, 70e9, 0.3, 26.9e9, np.inf, np.inf, 2700.0, tf, 0.0)
    assert laminate([rigid, core, rigid])[3][0, 0] == pytest.approx(H[0, 0], rel=2e-4)
    assert np.allclose(H, _energy_shear_by_sublayers([face, core, face]), rtol=1e-6)
