"""A cheap a-posteriori error indicator of a reduced basis, to choose where to enrich it.

For a reduced eigenpair (lambda_h, u_h = V y) at theta the residual in the full model is
r = (K(theta) - lambda_h M(theta)) u_h.  Its dual norm in the energy of the box centre,
||r||_*^2 = r^T A0^-1 r with A0 = K(theta_c) - sigma M(theta_c) (sigma < 0: the free body's K is
singular), bounds the eigenvalue error up to the spectral gap: lambda_h - lambda <~ ||r||_*^2 /
gap (Quarteroni, Manzoni & Negri, *Reduced Basis Methods for PDEs*, 2016, on residual-based a
posteriori estimates; Pau, *Reduced basis method for quantum models of crystalline solids*, PhD
thesis, MIT, 2007: for eigenproblems the eigenvalue error is quadratic in the residual).  The
indicator is

    eta(theta) = max_i ||r_i||_*^2 / lambda_h,i         (dimensionless, mode i of n_modes)

and it only ranks points: the build full-solves where it is largest (a weak greedy, QMN 2016),
and the certificate still rests on full solves at fresh points
(``reduced.certification``).  Its cost per point: an assembly of K and M, the reduced eigen-solve
with vectors, two sparse products and one back-substitution of n_modes right-hand sides with the
one factorization at the centre; no eigen-solve of the full model.
"""

from collections.abc import Mapping

import numpy as np

from bayesupdate.fe.model import FEModel
from bayesupdate.fe.reduced.basis import ReducedBasis
from bayesupdate.fe.reduced.sensitivity import SHIFT
from bayesupdate.fe.sparse_modal import factorize


class ResidualIndicator:
    """eta(theta) of the module docstring for bases of ``fe``, with the factorization of A0 at
    ``centre`` (all parameters, SI) made once."""

    def __init__(self, fe: FEModel, centre: Mapping[str, float]):
        K0, M0 = fe.matrices(centre)
        g = fe.general
        self.fe = fe
        self.T = None if g is None else g.transform.T
        A = K0 - SHIFT * M0
        self.solve = factorize((A if self.T is None else self.T.T @ (A @ self.T)).tocsc())

    def _dual_norms(self, R: np.ndarray) -> np.ndarray:
        """(m,) r^T A0^-1 r of the residuals R (n_dof, m) (constrained: T^T r)."""
        Rq = R if self.T is None else np.asarray(self.T.T @ R)
        return np.einsum("ij,ij->j", Rq, self.solve(Rq))

    def __call__(
        self, basis: ReducedBasis, theta: np.ndarray, names: tuple[str, ...], n_modes: int
    ) -> np.ndarray:
        """(B,) eta at theta (B, len(names)) (all parameters, SI) for ``basis``; inf where the
        reduced solve fails."""
        lam, y = basis.eigen(theta, n_modes, vectors=True)
        out = np.full(theta.shape[0], np.inf)
        for b, row in enumerate(theta):
            K, M = self.fe.matrices(dict(zip(names, map(float, row), strict=True)))
            U = basis.V @ y[b]
            R = K @ U - (M @ U) * lam[b]
            out[b] = float(np.max(self._dual_norms(R) / np.abs(lam[b])))
        return out
