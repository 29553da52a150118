"""Rigid-body mass properties of a structure from its mass matrix: mass, centre of gravity and
inertia tensor about the centre of gravity.

With R (n_dof, 6) the rigid-body motions about the origin (3 translations, 3 small rotations
theta with u = theta x x: ``assembly.rigid_body_basis(nodes, centre=0)``), the rigid-body mass
matrix is M_r = R^T M R (6, 6), which MSC Nastran's grid point weight generator prints as [MO]
about its reference point (MSC Nastran Linear Static Analysis User's Guide, "Grid Point Weight
Generator"; PARAM GRDPNT):

    M_r = [[ m I,          -m skew(c) ],
           [ m skew(c),     J_o       ]],

so m = trace(M_r[:3, :3]) / 3, m c = (M_r[1, 5], M_r[2, 3], M_r[0, 4]) and the inertia tensor
about the centre of gravity follows from the one about the origin by the parallel-axis theorem,
J_cg = J_o - m (|c|^2 I - c c^T).  Products of inertia are reported as Nastran writes them on
CONM2 (I21, I31, I32) and in the weight generator's I(S): I_xy = integral of x y dm about the
centre of gravity, so J = [[Ixx, -Ixy, -Ixz], [-Ixy, Iyy, -Iyz], [-Ixz, -Iyz, Izz]].

Values are in the model's own consistent units (SI for built-in models; a Nastran deck's own,
e.g. lbf s^2/in, in and lbf s^2 in for an inch-lbf-s deck).
"""

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.assembly import rigid_body_basis

#: component names of a ``MassProperties``, in ``MassProperties.vector`` order
COMPONENTS = ("mass", "cg_x", "cg_y", "cg_z", "ixx", "iyy", "izz", "ixy", "ixz", "iyz")


@dataclass(frozen=True)
class MassProperties:
    """Rigid-body mass properties.

    mass : total mass [model mass unit].  cg : (3,) centre of gravity in the model's frame
    [model length unit].  inertia : (3, 3) inertia tensor about the centre of gravity, axes
    parallel to the model's [mass x length^2] (off-diagonals are minus the products of inertia).
    """

    mass: float
    cg: np.ndarray
    inertia: np.ndarray

    @property
    def products(self) -> np.ndarray:
        """(Ixy, Ixz, Iyz): integrals of x y, x z, y z dm about the centre of gravity."""
        J = self.inertia
        return -np.array([J[0, 1], J[0, 2], J[1, 2]])

    def inertia_about(self, point) -> np.ndarray:
        """(3, 3) inertia tensor about axes through ``point`` (3,) parallel to the model's,
        by the parallel-axis theorem J_p = J_cg + m (|d|^2 I - d d^T), d = cg - point."""
        d = np.asarray(self.cg, dtype=float) - np.asarray(point, dtype=float)
        return self.inertia + self.mass * (d @ d * np.eye(3) - np.outer(d, d))

    def vector(self) -> np.ndarray:
        """(10,) values in ``COMPONENTS`` order."""
        J = self.inertia
        return np.concatenate([[self.mass], self.cg, np.diag(J), self.products])

    def as_dict(self) -> dict[str, float]:
        """{component: value} in ``COMPONENTS`` order."""
        return dict(zip(COMPONENTS, map(float, self.vector()), strict=True))


def rigid_body_mass_matrix(M, nodes: np.ndarray) -> np.ndarray:
    """(6, 6) rigid-body mass matrix about the origin, R^T M R.

    M : (6N, 6N) mass matrix (dense or sparse) of N nodes with 6 DOFs each, in the global frame,
    before supports and rigid elements are applied.  nodes : (N, 3) node coordinates."""
    nodes = np.asarray(nodes, dtype=float)
    if M.shape != (6 * len(nodes), 6 * len(nodes)):
        raise BayesUpdateError(
            f"mass properties: a mass matrix {M.shape} for {len(nodes)} nodes (needs 6 per node)"
        )
    R = rigid_body_basis(nodes, centre=np.zeros(3))
    return np.asarray(R.T @ (M @ R))


def from_rigid_mass(Mr: np.ndarray) -> MassProperties:
    """``MassProperties`` of a (6, 6) rigid-body mass matrix about the origin (module
    docstring).  A mass that is not > 0 is an error (no centre of gravity)."""
    Mr = np.asarray(Mr, dtype=float)
    m = float(np.trace(Mr[:3, :3]) / 3.0)
    if not m > 0:
        raise BayesUpdateError(f"mass properties: the total mass is {m:g}; it must be > 0")
    c = np.array([Mr[1, 5], Mr[2, 3], Mr[0, 4]]) / m
    J_o = 0.5 * (Mr[3:, 3:] + Mr[3:, 3:].T)
    J = J_o - m * (c @ c * np.eye(3) - np.outer(c, c))
    return MassProperties(m, c, J)


def model_mass_properties(model, params: Mapping[str, float] | None = None) -> MassProperties:
    """``MassProperties`` of an FE model (anything with ``matrices(params)`` and a
    ``structure``) at ``params`` (name -> value; missing names take the defaults)."""
    M = model.matrices(params)[1]
    return from_rigid_mass(rigid_body_mass_matrix(M, model.structure.nodes))
