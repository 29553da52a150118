"""Linear tetrahedra (Nastran CTETRA with four GRIDs, PSOLID, isotropic MAT1): the constant-strain
solid, vectorized over elements.

With the linear shape functions N_a (a = 1..4) of the element's corners x_a, the strain is the
same everywhere in the element, eps = B u (B (6, 12): Voigt order xx, yy, zz, xy, yz, zx with
engineering shears, u the corner translations), so the stiffness is exact in closed form,

    K_e = V B^T D B,   V = |det J| / 6,   J = [x_2 - x_1, x_3 - x_1, x_4 - x_1]^T

(Zienkiewicz, Taylor & Zhu, *The Finite Element Method: Its Basis and Fundamentals*, 7th ed.,
2013, sec. 6.5; D the isotropic elasticity matrix of E and nu, eq. 6.14).  The mass of a solid
of density rho is consistent, rho V / 20 (1 + delta_ab) I_3 between corners a and b (the same
reference), or lumped, rho V / 4 on each corner's translations (PARAM COUPMASS < 1, Nastran's
default; for this element every lumping rule gives the quarter).  A solid has no rotations: the
rows of its corners' rotations are empty, and a GRID that only solids use has its rotations held
by AUTOSPC, as Nastran holds them.  SI units; K [N/m], M [kg], each (n, 12, 12) on the corners'
translations in global axes (``dofs``).
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.fe.elements.base import ElementSettings, in_elements, register

#: d N_a / d (xi, eta, zeta) of the four corners' linear shape functions (3, 4)
_REFERENCE_GRADIENT = np.hstack([-np.ones((3, 1)), np.eye(3)])


@register
@dataclass(frozen=True)
class Tetrahedra:
    """n linear tetrahedra: nodes (n, 4) corner node indices; E [Pa], nu [-], rho [kg/m^3]
    (n,); lumped (n,) bool (mass lumped at the corners, else consistent); part (n,) part
    indices.  An ``elements.base.ElementFamily`` held in ``Structure.elements``."""

    #: registry name (a plain class attribute: not a dataclass field)
    family = "tetrahedron"

    nodes: np.ndarray
    E: np.ndarray
    nu: np.ndarray
    rho: np.ndarray
    lumped: np.ndarray
    part: np.ndarray

    @property
    def n_elements(self) -> int:
        return int(self.nodes.shape[0])

    def dofs(self) -> np.ndarray:
        """(n, 12) global DOF numbers: the three translations of corners 1-4."""
        return (6 * self.nodes[:, :, None] + np.arange(3)).reshape(-1, 12)

    def matrices(self, xyz: np.ndarray, settings: ElementSettings):
        """(K, M) (n, 12, 12) on nodes xyz (N, 3) [m] (module docstring; a solid has neither
        beam shear nor rotary inertia to set)."""
        volume, gradient = shape_gradients(xyz[self.nodes])
        B = strain_matrix(gradient)
        K = volume[:, None, None] * np.einsum("eji,ejk,ekl->eil", B, elasticity(self.E, self.nu), B)
        return K, mass_matrix(self.rho * volume, self.lumped)

    def has_mass(self) -> bool:
        return bool(np.any(self.rho > 1e-200))

    @classmethod
    def of(cls, structure) -> "Tetrahedra | None":
        return in_elements(cls, structure)


def shape_gradients(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(V (n,) [m^3], d N_a / d x (n, 3, 4) [1/m]) of tetrahedra with corners (n, 4, 3) [m]; V is
    the volume whatever the corners' order (a zero volume gives non-finite gradients: the
    caller refuses such an element)."""
    jac = np.einsum("ia,eaj->eij", _REFERENCE_GRADIENT, corners)
    volume = np.abs(np.linalg.det(jac)) / 6.0
    return volume, np.linalg.solve(jac, np.broadcast_to(_REFERENCE_GRADIENT, (len(jac), 3, 4)))


def strain_matrix(gradient: np.ndarray) -> np.ndarray:
    """(n, 6, 12) B of the constant strain (xx, yy, zz, xy, yz, zx; engineering shears) from the
    shape-function gradients (n, 3, 4): column 3a + j is corner a's translation j."""
    B = np.zeros((gradient.shape[0], 6, 12))
    for a in range(4):
        gx, gy, gz = gradient[:, 0, a], gradient[:, 1, a], gradient[:, 2, a]
        c = 3 * a
        B[:, 0, c], B[:, 3, c], B[:, 5, c] = gx, gy, gz
        B[:, 1, c + 1], B[:, 3, c + 1], B[:, 4, c + 1] = gy, gx, gz
        B[:, 2, c + 2], B[:, 4, c + 2], B[:, 5, c + 2] = gz, gy, gx
    return B


def elasticity(E: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """(n, 6, 6) isotropic D [Pa] in the Voigt order of ``strain_matrix``: Lame's lambda =
    E nu / ((1 + nu)(1 - 2 nu)) and mu = E / (2 (1 + nu)) (-1 < nu < 0.5)."""
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    mu = E / (2 * (1 + nu))
    D = np.zeros((len(E), 6, 6))
    D[:, :3, :3] = lam[:, None, None]
    idx = np.arange(3)
    D[:, idx, idx] += 2 * mu[:, None]
    D[:, idx + 3, idx + 3] = mu[:, None]
    return D


def mass_matrix(mass: np.ndarray, lumped: np.ndarray) -> np.ndarray:
    """(n, 12, 12) mass matrices of elements of total mass (n,) [kg]: lumped (n,) bool, a
    quarter on each corner's translations, else consistent m / 20 (1 + delta_ab) I_3."""
    consistent = np.kron((np.ones((4, 4)) + np.eye(4)) / 20.0, np.eye(3))
    weights = np.where(lumped[:, None, None], np.eye(12) / 4.0, consistent)
    return mass[:, None, None] * weights
