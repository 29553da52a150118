"""Point masses rigidly offset from their node (Nastran CONM2: mass, inertia tensor and offset),
vectorized over the masses.

A mass m [kg] with inertia tensor J (3, 3) [kg m^2] about its centre, which sits at the offset
o [m] from its node, moves rigidly with the node: its centre's DOFs are u_c = T q with
T = [[I, -skew(o)], [0, I]] (small rotations), so on the node DOFs

    M_e = T^T D T,   D = blockdiag(m I_3, J)

(MSC Nastran Quick Reference Guide, CONM2).  The parameters ``mass`` and ``mass_factor`` scale
m and J together (``fe.model``), so M_e is linear in the factor: the affine split of
``fe.reduced.affine`` takes the matrices at factor 1.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.fe.elements.base import (
    Bindable,
    ElementSettings,
    check_fields,
    register_parametric,
)
from bayesupdate.fe.rotations import skew


@register_parametric
@dataclass(frozen=True)
class PointMasses:
    """Point masses (P): nodes (P, 1), part (P,), mass (P,) [kg], inertia (P, 3, 3) [kg m^2]
    about each centre, offset (P, 3) [m] from the node to the centre, link (P, 6, 6) its
    ``offset_link``.  An ``elements.base.ParametricFamily``: M is linear in the factor
    ``mass_scale`` (the parameters ``mass`` and ``mass_factor``), K is none."""

    #: registry name; the ``ElementProperties`` field; the linear matrix
    family = "mass"
    fields = ("mass_scale",)
    linear = "M"
    #: the properties a parameter binds (``fe.model.Binding``) on a part's point masses
    properties = (
        Bindable("mass", "mass_scale", "M", rule="total", total_of="mass", positive=False,
                 unit="kg", acts_on="total of the part's point masses (scaled)"),
        Bindable("mass_factor", "mass_scale", "M", rule="factor", positive=False,
                 acts_on="factor on the part's point masses"),
    )  # fmt: skip

    nodes: np.ndarray
    part: np.ndarray
    mass: np.ndarray
    inertia: np.ndarray
    offset: np.ndarray
    link: np.ndarray

    @classmethod
    def of(cls, structure) -> "PointMasses":
        s = structure
        return cls(
            s.mass_node[:, None], s.mass_part, s.mass_value, s.mass_inertia, s.mass_offset,
            offset_link(s.mass_offset),
        )  # fmt: skip

    @property
    def n_elements(self) -> int:
        return int(self.nodes.shape[0])

    def nominal(self) -> dict[str, np.ndarray]:
        """Factor 1 on every mass."""
        return {"mass_scale": np.ones(self.n_elements)}

    def check(self, props, parts: tuple[str, ...]) -> None:
        """Factors finite and >= 0."""
        check_fields((("point-mass factor", props.mass_scale, None, False),), self.part, parts)

    def dofs(self) -> np.ndarray:
        """(P, 6) global DOF numbers of each mass's node."""
        return 6 * self.nodes + np.arange(6)

    def matrices(self, props, settings: ElementSettings, elements=None):
        """(None, M (n_e, 6, 6)) at the factors ``props.mass_scale`` (P,)."""
        e = slice(None) if elements is None else elements
        scale = props.mass_scale[e]
        M = point_mass_matrices(
            self.link[e], self.mass[e] * scale, self.inertia[e] * scale[:, None, None]
        )
        return None, M

    def masses(self, props, xyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(P,) masses m x factor [kg] and (P, 3) their centres [m] on nodes xyz (N, 3)."""
        return self.mass * props.mass_scale, xyz[self.nodes[:, 0]] + self.offset


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
