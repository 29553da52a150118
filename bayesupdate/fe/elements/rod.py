"""Axial rods and trusses (Nastran CROD/CONROD/PROD): axial and optional torsional stiffness,
consistent or lumped mass, vectorized over elements.

With e the unit axis, the stiffness couples the end translations along e and the end rotations
about e: K = [[P, -P], [-P, P]] (x) EA / L on the translations and the same with GJ / L on the
rotations, P = e e^T.  The mass is that of a line of m = rho A + nsm [kg/m] that moves with the
end translations in every direction: consistent m L / 6 [[2, 1], [1, 2]] (x) I_3 (linear
interpolation, Cook et al., *Concepts and Applications of FEA*, 4th ed., sec. 11.3) or lumped
m L / 2 I_3 at each end.  A rod has no bending stiffness: a truss joint needs its rotations held
(or its bending taken by other elements).  SI units; results (n, 12, 12) in global axes.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.fe.elements.base import ElementSettings, LineElements, register


@register
@dataclass(frozen=True)
class Rods(LineElements):
    """Rod elements (n): nodes (n, 2), part (n,), E, G [Pa], rho [kg/m^3], area [m^2],
    torsion J [m^4] (0: no twist stiffness), nsm [kg/m], lumped (n,) bool.  An
    ``elements.base.ElementFamily`` (``Structure.rods``)."""

    #: registry name (a plain class attribute: not a dataclass field)
    family = "rod"

    nodes: np.ndarray
    part: np.ndarray
    E: np.ndarray
    G: np.ndarray
    rho: np.ndarray
    area: np.ndarray
    torsion: np.ndarray
    nsm: np.ndarray
    lumped: np.ndarray

    def mass_per_length(self) -> np.ndarray:
        """(n,) rho A + nsm [kg/m]."""
        return self.rho * self.area + self.nsm

    def matrices(self, xyz: np.ndarray, settings: ElementSettings):
        """Global (K, M) (n, 12, 12) on nodes xyz (N, 3) [m] (``rod_matrices``; a rod has no
        shear or rotary inertia to set)."""
        return rod_matrices(xyz, self)

    @classmethod
    def of(cls, structure) -> "Rods | None":
        return structure.rods


def rod_matrices(xyz: np.ndarray, r: Rods):
    """Global (K, M) (n, 12, 12) of rods ``r`` on nodes xyz (N, 3) [m]."""
    d = xyz[r.nodes[:, 1]] - xyz[r.nodes[:, 0]]
    L = np.linalg.norm(d, axis=1)
    e = d / L[:, None]
    P = e[:, :, None] * e[:, None, :]
    sign = np.array([[1.0, -1.0], [-1.0, 1.0]])
    K = np.zeros((len(L), 12, 12))
    for i, j in np.ndindex(2, 2):
        K[:, 6 * i : 6 * i + 3, 6 * j : 6 * j + 3] = (
            sign[i, j] * (r.E * r.area / L)[:, None, None] * P
        )
        K[:, 6 * i + 3 : 6 * i + 6, 6 * j + 3 : 6 * j + 6] = (
            sign[i, j] * (r.G * r.torsion / L)[:, None, None] * P
        )
    m = (r.rho * r.area + r.nsm) * L
    weights = np.where(
        r.lumped[:, None, None], np.diag([0.5, 0.5]), np.array([[2.0, 1.0], [1.0, 2.0]]) / 6
    )
    M = np.zeros_like(K)
    for i, j in np.ndindex(2, 2):
        M[:, 6 * i : 6 * i + 3, 6 * j : 6 * j + 3] = (m * weights[:, i, j])[:, None, None] * np.eye(
            3
        )
    return K, M
