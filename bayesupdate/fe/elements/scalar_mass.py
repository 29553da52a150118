"""Scalar masses: a mass on one DOF of a node, or between one DOF of each of two nodes (Nastran
CMASS1/CMASS2, MSC Nastran Quick Reference Guide: "scalar mass element ... between component C1
of G1 and C2 of G2"; G2 blank grounds it).

The element's two scalar coordinates are w_A = d_A . q_A and w_B = d_B . q_B, with d_X (6,) the
unit vector of the chosen component in the node's six DOFs (a translation or rotation axis of
the node's displacement frame, in global axes), and its mass matrix on (w_A, w_B) is

    [[m, -m], [-m, m]]   (MSC QRG CMASS2),

so on the node DOFs q = (q_A, q_B): M_e = m v v^T with v = (d_A, -d_B) (12,).  A grounded element
keeps v = (d_A, 0): M_e = m d_A d_A^T.  On a translation m is a mass [kg]; on a rotation it is a
rotary inertia [kg m^2] about that axis (a grounded one equals a point mass whose inertia tensor
is m n n^T, n the axis).  Under a rigid translation t the element's kinetic energy is
1/2 m ((d_A - d_B) . t)^2: an element between two nodes on the same axis carries no rigid-body
mass, a grounded one carries m along its axis only.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.fe.elements.base import ElementSettings, grounded_line_dofs, register


@register
@dataclass(frozen=True)
class ScalarMasses:
    """n scalar masses: nodes (n, 2) (second -1 = ground); direction (n, 2, 6) unit DOF vectors
    d_A, d_B in the nodes' six global DOFs (d_B zero when grounded); mass (n,) [kg on a
    translation, kg m^2 on a rotation]; part (n,) part indices.  An
    ``elements.base.ElementFamily`` (``Structure.scalar_masses``)."""

    #: registry name (a plain class attribute: not a dataclass field)
    family = "scalar_mass"

    nodes: np.ndarray
    direction: np.ndarray
    mass: np.ndarray
    part: np.ndarray

    @property
    def n_elements(self) -> int:
        return int(self.nodes.shape[0])

    def dofs(self) -> np.ndarray:
        """(n, 12) global DOF numbers (``base.grounded_line_dofs``)."""
        return grounded_line_dofs(self.nodes)

    def matrices(self, xyz: np.ndarray, settings: ElementSettings):
        """(K, M) (n, 12, 12): K = 0 and M_e = m v v^T, v = (d_A, -d_B) (the node positions and
        the settings play no part)."""
        v = self._v()
        M = self.mass[:, None, None] * v[:, :, None] * v[:, None, :]
        return np.zeros_like(M), M

    def has_mass(self) -> bool:
        """True if some element has a non-zero mass."""
        return bool(np.any(self.mass > 0))

    @classmethod
    def of(cls, structure) -> "ScalarMasses | None":
        return structure.scalar_masses

    def _v(self) -> np.ndarray:
        """(n, 12) v = (d_A, -d_B)."""
        return np.concatenate([self.direction[:, 0], -self.direction[:, 1]], axis=1)


def component_direction(component: int, frame) -> np.ndarray:
    """(6,) unit DOF vector of ``component`` (0-5: ux uy uz rx ry rz of the node's displacement
    frame) where ``frame`` (3, 3) has the frame's axes as rows in global coordinates."""
    d = np.zeros(6)
    block = 3 * (component // 3)
    d[block : block + 3] = np.asarray(frame, float)[component % 3]
    return d
