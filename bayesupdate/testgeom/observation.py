"""The observation of test DOFs on a model: which model DOFs, with which weights, give the
displacement of a test point along its test direction.

A test point at p sits at the foot f of an element (``locate.Location``) with shape-function
weights N_i at its nodes; p is carried by the element as by a rigid arm r = p - f (an
accelerometer on a beam's surface, off its axis), so its displacement is
u_p = sum_i N_i (u_i + theta_i x r), and along the unit direction d

    d . u_p = sum_i N_i (d . u_i + (r x d) . theta_i)        (d . (theta x r) = theta . (r x d))

A point paired with a node has r = 0 (the distance is a pairing misfit, not an arm).  Model DOFs
are the structure's: 6 per node (ux uy uz rx ry rz), DOF = 6 * node + i.
"""

import numpy as np
import scipy.sparse as sp

from bayesupdate.testgeom.locate import Location


def read_weights(location: Location, direction, point) -> tuple[np.ndarray, np.ndarray]:
    """(model DOFs (6k,), weights (6k,)) of one test DOF: direction (3,) unit vector and the
    aligned test point (3,), both in the model's frame."""
    d = np.asarray(direction, dtype=float)
    arm = np.zeros(3) if location.kind == "node" else np.asarray(point) - location.foot
    per_node = np.concatenate([d, np.cross(arm, d)])  # (6,)
    dofs = 6 * location.nodes[:, None] + np.arange(6)[None, :]
    weights = location.weights[:, None] * per_node[None, :]
    return dofs.ravel(), weights.ravel()


def padded(reads) -> tuple[np.ndarray, np.ndarray]:
    """Stack ``read_weights`` results into (n, K) DOFs and weights, zero-padded (DOF 0, weight 0)
    to the longest: the form ``Structure.sensor_read`` holds."""
    K = max((len(d) for d, _ in reads), default=6)
    dofs = np.zeros((len(reads), K), np.int64)
    weights = np.zeros((len(reads), K))
    for row, (d, w) in enumerate(reads):
        dofs[row, : len(d)], weights[row, : len(w)] = d, w
    return dofs, weights


def observation_matrix(dofs, weights, n_dof: int) -> sp.csr_matrix:
    """(n_test_dofs, n_dof) sparse H with H[j, dofs[j, k]] = sum weights[j, k]: test DOF
    readings = H @ model shapes."""
    rows = np.repeat(np.arange(len(dofs)), dofs.shape[1])
    H = sp.csr_matrix((weights.ravel(), (rows, dofs.ravel())), shape=(len(dofs), n_dof))
    H.eliminate_zeros()
    return H
