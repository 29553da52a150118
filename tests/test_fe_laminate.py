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
    is 5/6 of the plies' mean G1Z, G2Z, turned."""
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
    assert np.allclose(H, SHEAR_FACTOR * h / 2 * np.diag([5e9 + 3.5e9] * 2), rtol=1e-14)
    section = section_per_unit_thickness(A, B, D, H, h)
    assert section.coupling[0, 0, 0] == pytest.approx((q22 - q11) / 8, rel=1e-12)
    symmetric = laminate([plies[0], plies[1], plies[1], plies[0]])
    assert section_per_unit_thickness(*symmetric, 2 * h).coupling is None
