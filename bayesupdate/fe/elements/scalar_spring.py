"""Scalar springs: a stiffness between one DOF of a node and one DOF of another node, or between
one DOF and ground, whatever the two DOFs' directions (Nastran CELAS1/CELAS2, MSC Nastran Quick
Reference Guide: "scalar spring element ... between component C1 of G1 and component C2 of G2";
C1 and C2 may differ, and G2 blank grounds it).

The element's two scalar coordinates are w_A = d_A . q_A and w_B = d_B . q_B, with d_X (6,) the
unit vector of the chosen component in the node's six DOFs (a translation or rotation axis of
the node's displacement frame, in global axes), and its stiffness on (w_A, w_B) is

    k [[1, -1], [-1, 1]]   (MSC QRG CELAS2: the force is k (u_1 - u_2)),

so on the node DOFs q = (q_A, q_B): K_e = k v v^T with v = (d_A, -d_B) (12,), the strain energy
1/2 k (d_A . q_A - d_B . q_B)^2.  A grounded element keeps v = (d_A, 0).  The element has no
mass.  A spring joining two unlike DOFs (x of one node, a rotation of another) strains under
rigid motions of the structure, as Nastran's does: its rigid-body modes are those the springs
leave free.  Units: k in N/m between translations, N/rad between a translation and a rotation,
N m/rad between rotations (SI in, SI out).
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.fe.elements.base import (
    ElementSettings,
    grounded_line_dofs,
    in_elements,
    register,
)


@register
@dataclass(frozen=True)
class ScalarSprings:
    """n scalar springs: nodes (n, 2) (second -1 = ground); direction (n, 2, 6) unit DOF vectors
    d_A, d_B in the nodes' six global DOFs (d_B zero when grounded); stiffness (n,) >= 0; part
    (n,) part indices.  An ``elements.base.ElementFamily`` held in ``Structure.elements``."""

    #: registry name (a plain class attribute: not a dataclass field)
    family = "scalar_spring"

    nodes: np.ndarray
    direction: np.ndarray
    stiffness: np.ndarray
    part: np.ndarray

    @property
    def n_elements(self) -> int:
        return int(self.nodes.shape[0])

    def dofs(self) -> np.ndarray:
        """(n, 12) global DOF numbers (``base.grounded_line_dofs``)."""
        return grounded_line_dofs(self.nodes)

    def matrices(self, xyz: np.ndarray, settings: ElementSettings):
        """(K, M) (n, 12, 12): K_e = k v v^T, v = (d_A, -d_B), and M = 0 (the node positions
        and the settings play no part)."""
        v = np.concatenate([self.direction[:, 0], -self.direction[:, 1]], axis=1)
        K = self.stiffness[:, None, None] * v[:, :, None] * v[:, None, :]
        return K, np.zeros_like(K)

    def has_mass(self) -> bool:
        return False

    @classmethod
    def of(cls, structure) -> "ScalarSprings | None":
        return in_elements(cls, structure)
