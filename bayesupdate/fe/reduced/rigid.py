"""Rigid motions that carry strain energy: the reduced elastic pencil of a SUPORT deck.

The reduced model solves the elastic modes on the M(theta)-orthogonal complement of the rigid
motions R, as the full solve does (``fe.sparse_modal``: the rigid set is every allowed rigid
motion with MSC Nastran's SUPORT, the zero-energy ones otherwise).  With the basis [R, W] an
elastic vector is x = W y + R z with R^T M x = 0, i.e. z = -G y, G = M_rr^-1 M_rw, so

    x = V T y,   T = [-G; I],   K_e = T^T K_r T,   M_e = T^T M_r T = M_ww - M_wr M_rr^-1 M_rw.

For a free structure K R = 0 and K_e is the block K_ww (``fe.batched_eigen`` uses it as it is).
A SUPORT deck may keep soft springs to ground (the mAEWing1's 0.1 lbf/in at its SUPORT grid):
then K R != 0, and dropping K_wr and K_rr removes the springs' energy from every elastic mode:
the reduced frequencies fall below the full ones (Rayleigh-Ritz bounds the *compressed* pencil
only; measured on the mAEWing1 v3.3 deck: -3.7e-5 on the first mode, ``tests/
test_reduced_suport.py``).  ``compressed_stiffness`` forms K_e exactly for such a basis.
"""

import numpy as np

#: the projected K's rigid rows count as round-off below this fraction of its largest entry.
#: Measured (M-orthonormal basis of 8 modes): the free exhaust beam model 4.9e-17, the mAEWing1
#: v3.3 deck (SUPORT, 0.1 lbf/in springs to ground) 3.1e-8
RIGID_ENERGY_TOL = 1e-12


def rigid_energy(K_terms: np.ndarray, n_rigid: int) -> bool:
    """True when the rigid motions carry strain energy in some projected K term: K_terms
    (n_terms, r, r), the first ``n_rigid`` coordinates the rigid motions."""
    if n_rigid == 0:
        return False
    scale = np.abs(K_terms).max(initial=0.0)
    return bool(np.abs(K_terms[:, :n_rigid, :]).max(initial=0.0) > RIGID_ENERGY_TOL * scale)


def compressed_stiffness(K: np.ndarray, M: np.ndarray, n_rigid: int) -> np.ndarray:
    """(B, r_e, r_e) K_e = T^T K T of reduced pencils K, M (B, r, r) (module docstring), the
    first ``n_rigid`` coordinates the rigid motions; the pencil (K_e, T^T M T) has the elastic
    Rayleigh-Ritz values of the full solve's M-orthogonal complement."""
    nr = n_rigid
    G = np.linalg.solve(M[:, :nr, :nr], M[:, :nr, nr:])  # (B, nr, r_e)
    K_rw = K[:, :nr, nr:]
    cross = K_rw.transpose(0, 2, 1) @ G
    Ke = K[:, nr:, nr:] - cross - cross.transpose(0, 2, 1)
    Ke += G.transpose(0, 2, 1) @ (K[:, :nr, :nr] @ G)
    return 0.5 * (Ke + Ke.transpose(0, 2, 1))
