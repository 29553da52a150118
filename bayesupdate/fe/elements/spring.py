"""Six-component springs (and dashpots) between two nodes or to ground, acting at a location
that need not be at the nodes: the element of Nastran's CBUSH (MSC Nastran Quick Reference
Guide, CBUSH: the spring-damper sits at a point on the line GA-GB at the fraction S, or at an
offset given in OCID, and is rigidly connected to both grids).

With p the element's location and o_A = p - x_A, o_B = p - x_B its rigid offsets from the nodes
[m], the six springs see the relative motion at p (small rotations),

    d = [u_B + theta_B x o_B - (u_A + theta_A x o_A);  theta_B - theta_A]
      = T_B q_B - T_A q_A,     T_X = [[I, -skew(o_X)], [0, I]]   (``constraints.rigid_link``),

in the element frame R (3x3, rows = the element axes in global coordinates): f = k R6 d with
k = diag(k1..k6) [N/m, N m/rad] and R6 = blockdiag(R, R).  The element stiffness on the node DOFs
q = (q_A, q_B) is therefore

    K_e = B^T (R6^T k R6) B,   B = [-T_A, T_B]   (6 x 12),

a congruence of a positive semi-definite matrix: symmetric, and zero on every rigid motion of the
two nodes (d = 0 for u_X = u_0 + theta_0 x x_X, theta_X = theta_0, whatever p), so the forces it
transmits are in moment equilibrium about any point.  A grounded element (no node B) has d =
-T_A q_A and keeps only the [A, A] block.  With p at coincident nodes (o_A = o_B = 0) T_X = I and
K_e is the zero-length spring [[kg, -kg], [-kg, kg]], kg = R6^T k R6, computed by the very same
operations.  Units: SI in, SI out; arrays (n, 12, 12) on [node A DOFs, node B DOFs] in global axes.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.fe.constraints import rigid_link
from bayesupdate.fe.elements.base import (
    Bindable,
    ElementSettings,
    check_fields,
    grounded_line_dofs,
    register_parametric,
)


@register_parametric
@dataclass(frozen=True)
class Springs:
    """Six-component springs (S): nodes (S, 2) (second -1: grounded), part (S,), k (S, 6)
    [N/m, N m/rad] along the rows of frame (S, 3, 3), offsets (S, 2, 3) [m] from each node to
    the spring's location.  An ``elements.base.ParametricFamily``: K is linear in the factor
    ``spring_scale`` (the parameter ``stiffness_factor``), M is none."""

    #: registry name; the ``ElementProperties`` field; the linear matrix
    family = "spring"
    fields = ("spring_scale",)
    linear = "K"
    #: the property a parameter binds (``fe.model.Binding``) on a part's springs
    properties = (
        Bindable("stiffness_factor", "spring_scale", "K", rule="factor", positive=False,
                 acts_on="factor on the part's springs"),
    )  # fmt: skip

    nodes: np.ndarray
    part: np.ndarray
    k: np.ndarray
    frame: np.ndarray
    offsets: np.ndarray

    @classmethod
    def of(cls, structure) -> "Springs":
        s = structure
        return cls(s.spring_nodes, s.spring_part, s.spring_k, s.spring_frame, s.spring_offsets())

    @property
    def n_elements(self) -> int:
        return int(self.nodes.shape[0])

    @property
    def grounded(self) -> np.ndarray:
        return self.nodes[:, 1] < 0

    def nominal(self) -> dict[str, np.ndarray]:
        """Factor 1 on every spring."""
        return {"spring_scale": np.ones(self.n_elements)}

    def check(self, props, parts: tuple[str, ...]) -> None:
        """Factors finite and >= 0."""
        check_fields((("spring factor", props.spring_scale, None, False),), self.part, parts)

    def dofs(self) -> np.ndarray:
        """(S, 12) global DOF numbers [node A, node B] (``base.grounded_line_dofs``: a grounded
        spring repeats node A, its B blocks are zero)."""
        return grounded_line_dofs(self.nodes)

    def matrices(self, props, settings: ElementSettings, elements=None):
        """(K (n_e, 12, 12), None) at the factors ``props.spring_scale`` (S,)
        (``two_node_matrices``)."""
        e = slice(None) if elements is None else elements
        k = self.k[e] * props.spring_scale[e, None]
        return two_node_matrices(k, self.frame[e], self.grounded[e], self.offsets[e]), None

    def masses(self, props, xyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """No mass: (0,) and (0, 3)."""
        return np.zeros(0), np.zeros((0, 3))


def frame_values(values: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """(n, 6, 6) R6^T diag(values) R6 in global axes: values (n, 6) along the rows of frame
    (n, 3, 3) (translations [N/m] then rotations [N m/rad], or dashpot rates)."""
    R6 = np.zeros((len(values), 6, 6))
    R6[:, :3, :3] = frame
    R6[:, 3:, 3:] = frame
    return np.einsum("sji,sj,sjl->sil", R6, values, R6)


def two_node_matrices(values, frame, grounded, offsets=None) -> np.ndarray:
    """(n, 12, 12) element matrices B^T (R6^T diag(values) R6) B of the module docstring.

    values : (n, 6) stiffness [N/m, N m/rad] (or damping rates) along the rows of ``frame``
    (n, 3, 3); grounded : (n,) bool, no node B (its blocks stay zero); offsets : (n, 2, 3) or None,
    o_A = p - x_A and o_B = p - x_B [m] from each node to the element's location p (None or 0:
    the nodes' own DOFs, the zero-length spring).
    """
    n = len(values)
    kg = frame_values(values, frame)
    out = np.zeros((n, 12, 12))
    out[:, :6, :6] = kg
    free = ~np.asarray(grounded, bool)
    out[free, 6:, 6:] = kg[free]
    out[free, :6, 6:] = -kg[free]
    out[free, 6:, :6] = -kg[free]
    if offsets is None:
        return out
    moved = np.flatnonzero(np.any(np.asarray(offsets) != 0, axis=(1, 2)))
    if moved.size:
        # B = [-T_A, T_B]: K_e = B^T kg B; a grounded element has B = [-T_A, 0]
        T = rigid_link(np.asarray(offsets, float)[moved])  # (m, 2, 6, 6)
        B = np.concatenate([-T[:, 0], T[:, 1] * free[moved, None, None]], axis=2)
        out[moved] = np.einsum("mji,mjk,mkl->mil", B, kg[moved], B)
    return out


def location_offsets(xyz_a, xyz_b, location) -> np.ndarray:
    """(2, 3) o_A = p - x_A, o_B = p - x_B [m] of one element at ``location`` p (3,) [m]; node B
    None (grounded) gives o_B = 0."""
    p = np.asarray(location, float)
    o_b = np.zeros(3) if xyz_b is None else p - np.asarray(xyz_b, float)
    return np.stack([p - np.asarray(xyz_a, float), o_b])
