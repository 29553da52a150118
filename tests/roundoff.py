"""Round-off scale of an eigenvalue (a test helper): how far two correct solves of one pencil may
differ when their matrices or their arithmetic differ in the last bits.

Two terms, both relative to the eigenvalue lambda of an M-normalized mode phi:

* the matrices: a perturbation dK with |dK| <= eps |K| entry by entry (a product or sum taken in
  another order, another BLAS kernel) moves lambda by at most eps |phi|^T |K| |phi| to first
  order, i.e. by eps * kappa relative, with the mode's strain-energy condition
  kappa = |phi|^T |K| |phi| / phi^T K phi: the first elastic mode of a stiff deck is a small
  difference of large element energies (kappa ~1.7e8 on the bound mAEWing1 v3.3 deck, so
  eps * kappa = 3.7e-8), a local mode is not (kappa ~1e5);
* the solver: a backward-stable dense solve of the whole pencil (LAPACK) errs by about
  eps * lambda_max absolutely, eps * lambda_max / lambda relative (a shift-inverted solve
  cancels nothing there, so its callers pass no lambda_max).

``frequency_roundoff`` gives eps * (kappa + lambda_max / lambda) in frequency: twice the
first-order term (a frequency moves by half its eigenvalue's relative change), for the several
sums a route takes.  Machines differ inside it: the two routes of the bound deck agreed to better
than 1e-11 on the earlier development machine and to 1.1e-11 with OpenBLAS's SkylakeX kernels
(2026-11-29) on its first mode, whose scale is 3.7e-8; an error in the mathematics is far above
it (a reduced basis that left the springs' energy out: -3.7e-5, tests/test_reduced_suport.py).
"""

import numpy as np
import scipy.sparse as sp


def frequency_roundoff(K, M, shapes: np.ndarray, lam_max: float = 0.0) -> np.ndarray:
    """(m,) relative frequency difference two correct solves of the pencil (K, M) (n, n, sparse
    or dense) may show at the modes ``shapes`` (n, m): eps * (kappa + lam_max / lambda) (module
    docstring); lam_max [rad^2/s^2]: the pencil's largest eigenvalue for a dense solve, else 0."""
    absK = abs(K) if sp.issparse(K) else np.abs(K)
    a = np.abs(shapes)
    energy = np.einsum("ij,ij->j", shapes, K @ shapes)
    kappa = np.einsum("ij,ij->j", a, absK @ a) / energy
    lam = energy / np.einsum("ij,ij->j", shapes, M @ shapes)
    return np.finfo(float).eps * (kappa + lam_max / lam)


def largest_eigenvalue(K, M) -> float:
    """The largest eigenvalue [rad^2/s^2] of a small pencil (K, M) with M positive definite
    (dense LAPACK)."""
    from scipy.linalg import eigh

    dense = [X.toarray() if sp.issparse(X) else np.asarray(X) for X in (K, M)]
    n = dense[0].shape[0]
    return float(eigh(*dense, eigvals_only=True, subset_by_index=[n - 1, n - 1])[0])
