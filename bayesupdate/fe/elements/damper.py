"""Viscous dampers as data: six-component dashpots between two nodes or to ground.

A normal-modes analysis ignores them (K and M only); they are kept on the ``Structure`` so that a
user can form the viscous damping matrix C for FRF synthesis or complex modes,

    f = C v,   C_e = T^T [[c, -c], [-c, c]] T,   c = diag(c_x, c_y, c_z, c_rx, c_ry, c_rz),

with c in N s/m (translations) and N m s/rad (rotations) along the rows of the damper's frame R
(3x3, rows = its axes in global coordinates), T = blockdiag(R, R) per node (the same element form
as a spring, ``fe.elements.spring``, including its location: a damper whose ends are apart acts at
a point
rigidly linked to both, as Nastran's CBUSH B); a grounded damper keeps only the [[c]] block on its
first node.
"""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from bayesupdate.fe.elements.spring import two_node_matrices


@dataclass(frozen=True)
class Dampers:
    """n dampers: nodes (n, 2) (second -1 = ground), damping (n, 6) [N s/m, N m s/rad] along the
    rows of frame (n, 3, 3), part (n,) part indices; offset None (at the nodes) or (n, 2, 3) [m]
    from node A and node B to the damper's location."""

    nodes: np.ndarray
    damping: np.ndarray
    frame: np.ndarray
    part: np.ndarray
    offset: np.ndarray | None = None

    def element_matrices(self) -> np.ndarray:
        """(n, 12, 12) damper matrices on [node_a DOFs, node_b DOFs] in global axes, acting at
        each damper's location (``offset`` (n, 2, 3) [m] from its nodes, ``fe.elements.spring``)."""
        return two_node_matrices(self.damping, self.frame, self.nodes[:, 1] < 0, self.offset)


def damping_matrix(dampers: Dampers | None, n_nodes: int) -> sp.csr_matrix:
    """C (6 n_nodes, 6 n_nodes) CSR [N s/m, N m s/rad] of all dampers (zero without any)."""
    n = 6 * n_nodes
    if dampers is None:
        return sp.csr_matrix((n, n))
    nodes = np.where(dampers.nodes >= 0, dampers.nodes, dampers.nodes[:, :1])
    dofs = (6 * nodes[:, :, None] + np.arange(6)).reshape(-1, 12)
    C_e = dampers.element_matrices()
    rows = np.repeat(dofs, 12, axis=1).ravel()
    cols = np.tile(dofs, (1, 12)).ravel()
    return sp.coo_matrix((C_e.ravel(), (rows, cols)), shape=(n, n)).tocsr()
