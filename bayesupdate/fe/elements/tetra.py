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
by AUTOSPC, as Nastran holds them.  A parametric family: a factor on E scales K and a factor
on rho scales M, each exactly linearly (the reduced basis takes them as affine terms).  SI
units; K [N/m], M [kg], each (n, 12, 12) on the corners' translations in global axes
(``dofs``).
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.fe.elements.base import ElementSettings, register_parametric
from bayesupdate.fe.elements.solid import Solids, elasticity, factors, strain_matrix

#: d N_a / d (xi, eta, zeta) of the four corners' linear shape functions (3, 4)
_REFERENCE_GRADIENT = np.hstack([-np.ones((3, 1)), np.eye(3)])


@register_parametric
@dataclass(frozen=True)
class Tetrahedra(Solids):
    """n linear tetrahedra: nodes (n, 4) corner node indices; corners (n, 4, 3) their
    positions [m]; E [Pa], nu [-], rho [kg/m^3] (n,); lumped (n,) bool (mass lumped at the
    corners, else consistent); part (n,) part indices.  An ``elements.base.ParametricFamily``
    held in ``Structure.elements``: K is linear in the factor ``solid_modulus_scale`` on E (the
    parameter ``solid_modulus_factor``), M in ``solid_density_scale`` on rho
    (``solid_density_factor``)."""

    #: registry name; the ``ElementProperties`` fields and the properties a parameter binds
    #: (``fe.model.Binding``) on a part's solids
    family = "tetrahedron"
    fields, properties = factors("solid", "solids")

    def matrices(self, props, settings: ElementSettings, elements=None):
        """(K, M) (n_e, 12, 12) of ``elements`` (default all) at the factors of ``props``
        (module docstring; a solid has neither beam shear nor rotary inertia to set)."""
        e = slice(None) if elements is None else elements
        volume, gradient = shape_gradients(self.corners[e])
        B = strain_matrix(gradient)
        D = elasticity(self.E[e] * props.solid_modulus_scale[e], self.nu[e])
        K = volume[:, None, None] * np.einsum("eji,ejk,ekl->eil", B, D, B)
        mass = self.rho[e] * props.solid_density_scale[e] * volume
        return K, mass_matrix(mass, self.lumped[e])

    def masses(self, props, xyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n,) element masses [kg] at ``props`` and (n, 3) their centroids [m], on the
        elements' own ``corners`` as ``matrices`` (the nodes xyz are the same points)."""
        mass = self.rho * props.solid_density_scale * volumes(self.corners)
        return mass, self.corners.mean(axis=1)


def volumes(corners: np.ndarray) -> np.ndarray:
    """(n,) volumes [m^3] of tetrahedra with corners (n, 4, 3) [m], |det J| / 6 whatever the
    corners' order."""
    return np.abs(np.linalg.det(corners[:, 1:] - corners[:, :1])) / 6.0


def shape_gradients(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(V (n,) [m^3] (``volumes``), d N_a / d x (n, 3, 4) [1/m]) of tetrahedra with corners
    (n, 4, 3) [m] (a zero volume gives non-finite gradients: the reader refuses such an
    element)."""
    jac = np.einsum("ia,eaj->eij", _REFERENCE_GRADIENT, corners)
    gradient = np.linalg.solve(jac, np.broadcast_to(_REFERENCE_GRADIENT, (len(jac), 3, 4)))
    return volumes(corners), gradient


def mass_matrix(mass: np.ndarray, lumped: np.ndarray) -> np.ndarray:
    """(n, 12, 12) mass matrices of elements of total mass (n,) [kg]: lumped (n,) bool, a
    quarter on each corner's translations, else consistent m / 20 (1 + delta_ab) I_3."""
    consistent = np.kron((np.ones((4, 4)) + np.eye(4)) / 20.0, np.eye(3))
    weights = np.where(lumped[:, None, None], np.eye(12) / 4.0, consistent)
    return mass[:, None, None] * weights
