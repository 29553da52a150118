"""A certified basis enriched for a local change of the structure (an added effect).

A model extended by one effect (a softer connection, an added mass, a stiffer body:
``discovery.effects``) differs from the model by a term affine in the effect's value p:
K(theta, p) = K(theta, p0) + (p - p0) dK, likewise M.  Its modes then lie near the span of the
unchanged model's modes plus the static and dynamic response to the forces the change exerts
(modal truncation augmentation: Dickens, Nakagawa & Wittbrodt, Comput. Struct. 62, 1997;
for a low-rank change the span of (K(p) + s M)^-1 dK is the same for every p, by the
Sherman-Morrison-Woodbury identity).  Here:

    B = [dK Phi, dM Phi],  X_1 = A^-1 B,  X_j = A^-1 M X_{j-1}  (j = 2..levels),
    A = K(theta*, p0) + s M(theta*, p0)  (s > 0: a free-free structure's K is singular),

on the independent DOFs of the constrained structure (``ConstraintTransform``: u = T q, forces
T^T f), Phi the model's modes at the design theta* (n_dof, k).  The enriched basis is the design
basis's vectors plus X, compressed as any snapshots (``basis.pod_basis``, no truncation), and
projected on the extended model's own affine terms (``affine.decompose``), so it is exact in
the design variables and in p wherever the span is good enough.

It has no validation set of its own: its ``Certificate`` holds the points checked by full
solves so far (none at first, ``n_points`` 0); the caller checks it where the numbers it reports
are computed (``ReducedFEModel.certify_at``, which enriches on a miss).
"""

from collections.abc import Mapping

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from bayesupdate.fe.model import FEModel
from bayesupdate.fe.reduced.affine import decompose
from bayesupdate.fe.reduced.basis import pod_basis
from bayesupdate.fe.reduced.certification import Certificate, Certification, _check_free_free
from bayesupdate.fe.reduced.model import ReducedFEModel
from bayesupdate.fe.reduced.settings import ReducedSettings

#: right-hand sides below this fraction of the largest singular value are dropped
RANK_TOL = 1e-10


class ShiftedSolver:
    """(K + s M)^-1 on the independent DOFs of ``fe`` at ``params`` (one sparse LU), applied to
    full-DOF forces F (n_dof, k) -> full-DOF displacements (n_dof, k) that satisfy the
    constraints.  s [rad^2/s^2] > 0 makes the free-free pencil definite."""

    def __init__(self, fe: FEModel, params: Mapping[str, float], shift: float):
        K, M = fe.matrices(params)
        g = fe.general
        self.T = sp.identity(K.shape[0], format="csr") if g is None else g.transform.T
        self.M = M
        A = self.T.T @ ((K + shift * M) @ self.T)
        self.lu = splu(sp.csc_matrix(A))

    def __call__(self, F: np.ndarray) -> np.ndarray:
        return self.T @ self.lu.solve(np.asarray(self.T.T @ F))


def _orthonormal(X: np.ndarray) -> np.ndarray:
    """Orthonormal columns spanning X (n, k) in the Euclidean norm, numerically dependent ones
    dropped (singular values <= ``RANK_TOL`` x the largest)."""
    if X.shape[1] == 0:
        return X
    U, s, _ = np.linalg.svd(X, full_matrices=False)
    keep = s > RANK_TOL * s[0] if s.size and s[0] > 0 else np.zeros(0, bool)
    return U[:, keep]


def attachment_vectors(
    solver: ShiftedSolver, dK, dM, modes: np.ndarray, levels: int = 3
) -> np.ndarray:
    """(n_dof, k) vectors X_1 ... X_levels of the module docstring for the change (dK, dM)
    (sparse (n_dof, n_dof)) and the modes (n_dof, m) at the design point."""
    B = _orthonormal(np.concatenate([dK @ modes, dM @ modes], axis=1))
    blocks = []
    X = B
    for _ in range(levels):
        if X.shape[1] == 0:
            break
        X = _orthonormal(solver(X if not blocks else solver.M @ X))
        blocks.append(X)
    return np.concatenate(blocks, axis=1) if blocks else np.zeros((modes.shape[0], 0))


def effect_change(fe: FEModel, params: Mapping[str, float], name: str, step: float):
    """(dK, dM) of parameter ``name`` per unit [per SI unit]: the difference of the assembled
    matrices at params[name] + step and at params (exact for a parameter entering affinely)."""
    K0, M0 = fe.matrices(params)
    K1, M1 = fe.matrices({**params, name: params[name] + step})
    return (K1 - K0) / step, (M1 - M0) / step


def enriched_model(
    fe: FEModel,
    bounds: Mapping[str, tuple[float, float]],
    settings: ReducedSettings,
    vectors: np.ndarray,
    outer=None,
) -> ReducedFEModel:
    """A ``ReducedFEModel`` of ``fe`` over ``bounds`` on the span of ``vectors`` (n_dof, k): the
    design basis's vectors and the effect's attachment vectors (the rigid part is removed and the
    rigid motions added, as for snapshots), with the affine terms of ``fe`` itself.  Its
    certificate lists no checked point yet (module docstring).  Raises ``BayesUpdateError`` when
    ``fe`` is not free-free (a spring to ground strains its rigid motions)."""
    model = ReducedFEModel(fe, bounds, settings, outer)
    centre = model.mapping(model.centre())
    _check_free_free(fe, centre)  # raises: e.g. a spring to ground
    decomposition = decompose(fe, model.bounds, settings.interp_tol)
    basis = pod_basis(fe, decomposition, centre, vectors, 0.0, settings.n_modes)
    unchecked = Certificate(0.0, 0.0, 0)
    certification = Certification(basis, unchecked, True, 0.0)
    return ReducedFEModel(fe, bounds, settings, outer, certification=certification)
