"""Design-sensitivity vectors of a snapshot's modes, from one factorization at the snapshot.

Differentiating (K - lambda_i M) phi_i = 0 in a parameter theta_j gives (Nelson, AIAA J. 14,
1976)

    (K - lambda_i M) dphi_i/dtheta_j = -(dK_j - lambda_i dM_j) phi_i + (dlambda_i/dtheta_j) M phi_i,

so the derivative of a mode lies in the span of the mode itself, the other modes and the static
response to the pseudo-load (dK_j - lambda_i dM_j) phi_i.  The static correction

    X_ij = (K - sigma M)^-1 (dK_j - lambda_i dM_j) phi_i   (sigma < 0: a free body has singular K)

at the snapshot point adds that response: with the snapshot's modes it spans the first-order
change of every mode in every parameter (the modal-acceleration form of the derivative: Wang,
AIAA J. 29, 1991; Fox & Kapoor, AIAA J. 6, 1968).  One factorization and one back-substitution
of n_modes right-hand sides per parameter, against the factorization, shift-invert Lanczos and
assembly of a full solve; a snapshot then informs a neighbourhood of its point, not the point
alone, so fewer snapshots span the box (measured in ``docs/validation/shells-reduced.md``).

dK_j and dM_j come from the affine decomposition (``reduced.affine``): d/dtheta_j of the term
coefficients, by a central difference (exact to ~(h/theta)^2 on the polynomial shell terms), times
the fixed term matrices, applied to the modes directly (no matrix is assembled).
"""

from collections.abc import Mapping

import numpy as np

from bayesupdate.fe.model import FEModel
from bayesupdate.fe.reduced.affine import AffineDecomposition
from bayesupdate.fe.reduced.shell_terms import SparsePart
from bayesupdate.fe.sparse_modal import factorize

#: the shift of the factorization [rad^2/s^2], that of the full solver (``ModalSettings.shift``)
SHIFT = -((2 * np.pi * 1.0) ** 2)
#: relative step of the central difference of the coefficients
REL_STEP = 1e-5


def apply_terms(stacks, weights: np.ndarray, X: np.ndarray) -> np.ndarray:
    """sum_k weights[k] X_k @ X for the term stacks of an ``AffineDecomposition`` (n_terms),
    weights (n_terms,), X (n_dof, m) -> (n_dof, m); terms of weight 0 are skipped."""
    out = np.zeros_like(X)
    for w, parts in zip(weights, stacks, strict=True):
        if w == 0.0:
            continue
        for part in parts:
            if isinstance(part, SparsePart):
                out[part.dofs] += w * (part.matrix @ X[part.dofs])
                continue
            dofs, mats = part
            if mats.shape[0]:
                y = np.einsum("eij,ejm->eim", mats, X[dofs])
                np.add.at(out, dofs.ravel(), w * y.reshape(-1, X.shape[1]))
    return out


def coefficient_derivatives(
    decomposition: AffineDecomposition, theta: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(n_params, n_k_terms), (n_params, n_m_terms): d coefficient / d theta_j [per SI unit] at
    theta (n_params,) (all parameters, SI), central differences of ``coefficients``."""
    n = theta.size
    h = REL_STEP * np.maximum(np.abs(theta), 1e-30)
    plus = theta[None, :] + np.diag(h)
    minus = theta[None, :] - np.diag(h)
    cK, cM = decomposition.coefficients(np.concatenate([plus, minus]))
    return (cK[:n] - cK[n:]) / (2 * h[:, None]), (cM[:n] - cM[n:]) / (2 * h[:, None])


def static_corrections(
    fe: FEModel,
    decomposition: AffineDecomposition,
    params: Mapping[str, float],
    eigenvalues: np.ndarray,
    shapes: np.ndarray,
    solve=None,
) -> np.ndarray:
    """(n_dof, n_params * m) static corrections X_ij of the module docstring at ``params``
    (all parameters, SI) for the modes ``shapes`` (n_dof, m) with ``eigenvalues`` (m,)
    [rad^2/s^2]; full-DOF vectors that satisfy the supports and rigid elements (u = T q).
    solve : the factorization of T^T (K - SHIFT M) T at ``params`` that the snapshot's eigen-solve
    made (``sparse_modal.factorize``; None: made here)."""
    theta = np.array([params[k] for k in decomposition.names], dtype=float)
    dK, dM = coefficient_derivatives(decomposition, theta)
    g = fe.general
    T = None if g is None else g.transform.T
    if solve is None:
        K, M = fe.matrices(params)
        A = K - SHIFT * M if T is None else T.T @ ((K - SHIFT * M) @ T)
        solve = factorize(A.tocsc())
    out = []
    for j in range(theta.size):
        load = apply_terms(decomposition.k_stacks, dK[j], shapes)
        load -= apply_terms(decomposition.m_stacks, dM[j], shapes) * eigenvalues
        if not np.any(load):
            continue  # a parameter that does not act here
        q = solve(load if T is None else np.asarray(T.T @ load))
        out.append(q if T is None else np.asarray(T @ q))
    return np.concatenate(out, axis=1) if out else np.zeros((shapes.shape[0], 0))
