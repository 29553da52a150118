"""Bending of the 4-node shell quadrilateral without transverse shear flexibility: the Discrete
Kirchhoff Quadrilateral (DKQ), vectorized.

Batoz & Ben Tahar, "Evaluation of a new quadrilateral thin plate bending element", IJNME 18
(1982) 1655-1677.  The section rotations beta = (beta_x, beta_y) are the 8-node serendipity
field over the quadrilateral (its corners and edge mid-points, the geometry bilinear); the
mid-point rotations are eliminated by the discrete Kirchhoff conditions of the triangle
(``shell_tria.rotation_nodes`` with four corners): beta = -grad w at the corners, the tangential
rotation at an edge's mid-point from the cubic Hermite w along the edge, the normal rotation
linear along it.  The curvatures kappa = [beta_x,x, beta_y,y, beta_x,y + beta_y,x] are
integrated with 2 x 2 Gauss points, as the paper does.

The element is shear rigid (Kirchhoff): a PSHELL whose MID3 is blank has no transverse shear
flexibility (MSC Nastran QRG PSHELL), and the deck's quadrilaterals are these (``ShellMesh``
``shear_ratio`` inf); its stiffness is t^3 times a thickness-free matrix, so the exact thickness
powers of ``shell.power_matrices`` hold.  Local DOFs per node as in ``bayesupdate.fe.elements.
shell``: [u v w rx ry rz], beta_x = ry, beta_y = -rx.
"""

import numpy as np

from bayesupdate.fe.elements.shell_tria import rotation_nodes

#: natural coordinates of the corners, then of the mid-points of edges 1-2, 2-3, 3-4, 4-1
_XI = np.array([-1.0, 1.0, 1.0, -1.0, 0.0, 1.0, 0.0, -1.0])
_ETA = np.array([-1.0, -1.0, 1.0, 1.0, -1.0, 0.0, 1.0, 0.0])


def serendipity_derivatives(pts: np.ndarray) -> np.ndarray:
    """(q, 2, 8) derivatives d/dxi, d/deta of the 8-node serendipity shape functions at the
    natural points pts (q, 2) in [-1, 1]^2 (nodes as ``_XI``, ``_ETA``)."""
    xi, eta = pts[:, 0:1], pts[:, 1:2]
    xc, ec = _XI[None, :4], _ETA[None, :4]
    out = np.empty((len(pts), 2, 8))
    # corners: (1 + xi xi_i)(1 + eta eta_i)(xi xi_i + eta eta_i - 1) / 4
    out[:, 0, :4] = 0.25 * xc * (1 + eta * ec) * (2 * xi * xc + eta * ec)
    out[:, 1, :4] = 0.25 * ec * (1 + xi * xc) * (xi * xc + 2 * eta * ec)
    # mid-points on eta = +-1: (1 - xi^2)(1 + eta eta_i) / 2;
    # on xi = +-1: (1 + xi xi_i)(1 - eta^2) / 2
    em, xm = _ETA[None, [4, 6]], _XI[None, [5, 7]]
    out[:, 0, [4, 6]] = -xi * (1 + eta * em)
    out[:, 1, [4, 6]] = 0.5 * (1 - xi**2) * em
    out[:, 0, [5, 7]] = 0.5 * xm * (1 - eta**2)
    out[:, 1, [5, 7]] = -eta * (1 + xi * xm)
    return out


def dkq_curvature(xy: np.ndarray, Jinv: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """(n, q, 3, 24) DKQ curvature operators [kappa_x, kappa_y, kappa_xy] [1/m per DOF] at the
    natural points pts (q, 2) of quadrilaterals xy (n, 4, 2) [m], with the inverse Jacobians
    Jinv (n, q, 2, 2) of their bilinear geometry (rows d/dx, d/dy in terms of d/dxi, d/deta)."""
    dnat = serendipity_derivatives(pts)  # (q, 2, 8)
    dN = np.einsum("nqab,qbm->nqam", Jinv, dnat)  # (n, q, 2 [x, y], 8)
    grad = np.einsum("nqam,nmcj->nqacj", dN, rotation_nodes(xy))  # d beta_c / d x_a
    return np.stack(
        [grad[:, :, 0, 0], grad[:, :, 1, 1], grad[:, :, 1, 0] + grad[:, :, 0, 1]], axis=2
    )
