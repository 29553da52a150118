"""Point masses rigidly offset from their node (Nastran CONM2: mass, inertia tensor and offset),
vectorised over the masses.

A mass m [kg] with inertia tensor J (3, 3) [kg m^2] about its centre, which sits at the offset
o [m] from its node, moves rigidly with the node: its centre's DOFs are u_c = T q with
T = [[I, -skew(o)], [0, I]] (small rotations), so on the node DOFs

    M_e = T^T D T,   D = blockdiag(m I_3, J)

(MSC Nastran Quick Reference Guide, CONM2).  The parameters ``mass`` and ``mass_factor`` scale
m and J together (``fe.model``), so M_e is linear in the factor: the affine split of
``fe.reduced.affine`` takes the matrices at factor 1.
"""

import numpy as np

from bayesupdate.fe.rotations import skew


def offset_link(offset: np.ndarray) -> np.ndarray:
    """(P, 6, 6) T = [[I, -skew(o)], [0, I]] of masses at offsets ``offset`` (P, 3) [m]."""
    T = np.zeros((len(offset), 6, 6))
    T[:, :3, :3] = np.eye(3)
    T[:, 3:, 3:] = np.eye(3)
    T[:, :3, 3:] = -skew(offset)
    return T


def point_mass_matrices(T: np.ndarray, mass: np.ndarray, inertia: np.ndarray) -> np.ndarray:
    """(P, 6, 6) M_e = T^T D T on the node DOFs: T (P, 6, 6) from ``offset_link``, mass (P,) [kg],
    inertia (P, 3, 3) [kg m^2] about each mass's centre."""
    D = np.zeros((len(mass), 6, 6))
    D[:, :3, :3] = mass[:, None, None] * np.eye(3)
    D[:, 3:, 3:] = inertia
    return np.einsum("pji,pjk,pkl->pil", T, D, T)
