"""Reference path for ``bayesupdate.fe.batched_eigen`` (a test and benchmark helper).

``sygvd_elastic_eigenvalues`` shares no code with the threaded path: the Schur complement is
formed explicitly and LAPACK dsygvd solves each pencil.  Used by tests/test_fe_batched_eigen.py
and benchmarks/likelihood_speed.py.
"""

import numpy as np
from scipy.linalg.lapack import dsygvd as _dsygvd


def sygvd_elastic_eigenvalues(K_ww: np.ndarray, M_full: np.ndarray, n_rigid: int, n_modes: int):
    """Eigenvalues only of ``batched_eigen.batched_elastic_eigenvalues``: K_ww (B, r_e, r_e),
    M_full (B, r, r) with the first ``n_rigid`` coordinates rigid -> (B, n_modes) [rad^2/s^2].
    The Schur complement S = M_ww - M_wr M_rr^-1 M_rw formed explicitly, then LAPACK dsygvd
    (Cholesky of S, reduction to standard form, divide and conquer) per point."""
    nr = n_rigid
    M_full = 0.5 * (M_full + M_full.transpose(0, 2, 1))
    M_rw = M_full[:, :nr, nr:]
    S = M_full[:, nr:, nr:] - M_rw.transpose(0, 2, 1) @ np.linalg.solve(M_full[:, :nr, :nr], M_rw)
    lam = np.empty((K_ww.shape[0], n_modes))
    for i in range(K_ww.shape[0]):
        out = _dsygvd(K_ww[i], S[i], jobz="N")  # (w, [a,] info)
        w, info = out[0], out[-1]
        if info != 0:
            raise np.linalg.LinAlgError(f"reduced pencil not definite (LAPACK info {info})")
        lam[i] = w[:n_modes]
    return lam
