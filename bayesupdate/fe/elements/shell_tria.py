"""Bending of the 3-node shell triangle: the Discrete Kirchhoff Triangle (DKT), vectorized.

Batoz, Bathe & Ho, "A study of three-node triangular plate bending elements", IJNME 15 (1980)
1771-1812, sec. 3 (the DKT element); Batoz, IJNME 18 (1982) 1077 gives the explicit form.  The
section rotations beta = (beta_x, beta_y) are quadratic over the triangle (6 nodes: the corners
and the edge mid-points); the mid-point rotations are eliminated by the discrete Kirchhoff
conditions, so only the corner DOFs w, beta_x, beta_y remain:

* beta = -grad w at the corners (the corner rotations are the nodal rotations);
* along each edge i -> j (length L, tangent s, normal n) w is the cubic Hermite interpolant of
  w_i, w_j and the corner slopes w,s = -beta_s, and beta_s = -w,s at the mid-point k:
  beta_s,k = -3 (w_j - w_i) / (2 L) - (beta_s,i + beta_s,j) / 4;
* beta_n varies linearly along the edge: beta_n,k = (beta_n,i + beta_n,j) / 2.

The curvatures kappa = [beta_x,x, beta_y,y, beta_x,y + beta_y,x] are then linear, so the
3-point mid-edge rule integrates int kappa^T D kappa dA exactly.  The element is Kirchhoff
(transverse shear rigid): the Kirchhoff constraints are met exactly in each element, so it does
not lock at any thickness and its stiffness is t^3 times a thickness-free matrix, which keeps the
exact thickness powers of ``shell.power_matrices``.  Without shear flexibility a thick plate is
as stiff as Kirchhoff's with rotary inertia: on the simply supported square plate (32 x 32 x 2,
``studies/ctria3_plate.py``) modes 1-8 are 0.2-1.7 % above the Mindlin solution at a/t = 50,
0.8-5.3 % at a/t = 20 and 2.8-15 % at a/t = 10 (MITC4 quads: within 1 % at each).

The MITC3 triangle used before (Lee & Bathe, Comput. Struct. 82 (2004) 945) ties one shear
strain per edge: with linear rotations these ask for a curl-free rotation in every element, more
constraints than a mesh of triangles has rotational freedom, so it locks as t / h falls (same
plate, one diagonal: modes 1-8 up to 2.1 % high at a/t = 100 and 32 % at a/t = 1000; DKT 0.93
and 0.98 %).  A locking-free Mindlin triangle with corner DOFs only needs internal bubbles
condensed with the shear stiffness (MITC3+, Lee & Bathe 2014) or a mesh-dependent shear factor
t^2 / (t^2 + alpha h^2) (stabilized DSG3 and CS-DSG3, Nguyen-Thoi et al. 2012;
MIN3, Tessler & Hughes 1985; DKMT, Katili 1993): either makes the stiffness
a rational function of t, which the exact thickness powers cannot hold.

Local DOFs per node as in ``bayesupdate.fe.elements.shell``: [u v w rx ry rz], beta_x = ry, beta_y
= -rx.
"""

import numpy as np

U, V, W, RX, RY, RZ = range(6)

#: the edges as corner pairs (i, j) in the order of their mid-point nodes 3, 4, 5
_EDGES = ((0, 1), (1, 2), (2, 0))


def _quadratic_derivatives(pts: np.ndarray) -> np.ndarray:
    """(q, 2, 6) derivatives d/dr, d/ds of the 6-node quadratic shape functions at the natural
    points pts (q, 2): corners L_i (2 L_i - 1), then 4 L_i L_j on the edges of ``_EDGES``."""
    r, s = pts[:, 0], pts[:, 1]
    L = np.stack([1 - r - s, r, s], axis=1)  # (q, 3) area coordinates
    dL = np.array([[-1.0, 1.0, 0.0], [-1.0, 0.0, 1.0]])  # (2, 3): d L_i / d(r, s)
    out = np.empty((len(pts), 2, 6))
    out[:, :, :3] = (4 * L - 1)[:, None, :] * dL[None]
    for k, (i, j) in enumerate(_EDGES):
        out[:, :, 3 + k] = 4 * (L[:, None, i] * dL[None, :, j] + L[:, None, j] * dL[None, :, i])
    return out


def rotation_nodes(xy: np.ndarray) -> np.ndarray:
    """(n, 2c, 2, 6c) the rotations (beta_x, beta_y) at the 2c nodes (the c corners, then the
    mid-points of edges 1-2, 2-3, ..., c-1) in terms of the 6c element DOFs, from the discrete
    Kirchhoff conditions above; xy (n, c, 2) corner coordinates in the element plane [m], c = 3
    (DKT) or 4 (the discrete Kirchhoff quadrilateral, ``shell_dkq``: the same edge conditions,
    Batoz & Ben Tahar, IJNME 18 (1982) 1655)."""
    n, c = xy.shape[:2]
    A = np.zeros((n, 2 * c, 2, 6 * c))
    corner = np.arange(c)
    A[:, corner, 0, 6 * corner + RY] = 1.0
    A[:, corner, 1, 6 * corner + RX] = -1.0
    edges = _EDGES if c == 3 else tuple((i, (i + 1) % c) for i in range(c))
    for k, (i, j) in enumerate(edges):
        e = xy[:, j] - xy[:, i]
        length = np.linalg.norm(e, axis=1)
        s = e / length[:, None]
        nrm = np.stack([s[:, 1], -s[:, 0]], axis=1)
        # beta_k = s beta_s,k + n beta_n,k with the Hermite mid-point slope and linear beta_n
        P = -0.25 * np.einsum("na,nb->nab", s, s) + 0.5 * np.einsum("na,nb->nab", nrm, nrm)
        Ak = np.einsum("nab,nbj->naj", P, A[:, i] + A[:, j])
        grad_w = -1.5 * s / length[:, None]
        Ak[:, :, 6 * j + W] += grad_w
        Ak[:, :, 6 * i + W] -= grad_w
        A[:, c + k] = Ak
    return A


def dkt_curvature(xy: np.ndarray, Jinv: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """(n, q, 3, 18) DKT curvature operators [kappa_x, kappa_y, kappa_xy] [1/m per DOF] at the
    natural points pts (q, 2) of triangles xy (n, 3, 2) [m] with inverse Jacobians Jinv (n, 2, 2)
    (rows d/dx, d/dy in terms of d/dr, d/ds)."""
    dnat = _quadratic_derivatives(pts)  # (q, 2, 6)
    dN = np.einsum("nab,qbm->nqam", Jinv, dnat)  # (n, q, 2 [x, y], 6)
    grad = np.einsum("nqam,nmcj->nqacj", dN, rotation_nodes(xy))  # d beta_c / d x_a
    return np.stack(
        [grad[:, :, 0, 0], grad[:, :, 1, 1], grad[:, :, 1, 0] + grad[:, :, 0, 1]], axis=2
    )
