"""Supports and rigid elements by exact elimination of the dependent DOFs (no penalties).

Every DOF is either *fixed* (a single-point constraint, u = 0), *dependent* (a linear function of
other DOFs, written by a rigid element) or *independent*.  ``constraint_transform`` returns the
sparse T (n_dof, n_ind) with u = T u_ind, so the constrained problem is
(T^T K T) x = lambda (T^T M T) x (Cook et al., *Concepts and Applications of FEA*, 4th ed.,
sec. 9.2, transformation method).  T is built for all rigid elements at once (no element loop).

Rigid elements (6 DOFs per node: ux uy uz rx ry rz, small rotations):

* ``rbe2``: the chosen components of each dependent node d follow the independent node i
  rigidly, u_d = u_i + theta_i x (x_d - x_i), theta_d = theta_i (Nastran RBE2).
* ``rbe3``: the reference node's chosen components are the weighted least-squares rigid motion
  of a set of nodes: (u_r, theta_r) = argmin sum_k |W_k^1/2 (u_k - G_k (u_r, theta_r))|^2 with
  G_k = [[I, -skew(x_k - x_r)], [0, I]], so (u_r, theta_r) = A^-1 sum_k G_k^T W_k u_k,
  A = sum_k G_k^T W_k G_k.  W_k = w_k on the node's chosen translations and w_k L^2 on its chosen
  rotations, L the mean distance of the nodes from the reference (Nastran RBE3 with its
  characteristic length).  It reproduces rigid motions exactly and adds no stiffness.  A UM
  set (Nastran RBE3 UM) makes other DOFs of the element dependent instead: the same equations
  C u = 0 (C = [I, -B] on the reference's components and the nodes' DOFs) solved for the UM
  DOFs D, u_D = -C_D^-1 C_I u_I, so the reference's components may be fixed or dependent in
  another element.

A rigid element may depend on DOFs that another rigid element makes dependent (chains); the
substitution is repeated until T refers to independent DOFs only, and a loop is an error.

Node-local frames (``fe.frames``, Nastran's GRID CD): a node with a frame has its six DOFs in
that frame's axes A (3, 3) (rows, global) at the node: u_node = L w_node, L = diag(A^T, A^T)
(orthogonal).  Supports and the components of rigid elements are then read in w: an RBE2 leg
is w_d = L_d^T G L_i w_i, an RBE3 fits the reference's global motion q to the nodes' w_k
through L_k^T G_k and gives w_r = L_r^T q.  The transformation is T = Lambda T_w with Lambda the
block diagonal of the L's (exact, no penalties); without frames Lambda = I and T is unchanged.
"""

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.rotations import skew

COMPONENTS = ("ux", "uy", "uz", "rx", "ry", "rz")


def parse_components(components, what: str) -> np.ndarray:
    """(6,) bool mask from Nastran-style digits ("123456", "123", 135) or names ("ux", "rz")."""
    if isinstance(components, str) and components and set(components) <= set("123456"):
        idx = [int(c) - 1 for c in components]
    elif isinstance(components, int | np.integer):
        idx = [int(c) - 1 for c in str(int(components))]
    else:
        names = [components] if isinstance(components, str) else list(components)
        bad = [c for c in names if c not in COMPONENTS]
        if bad or not names:
            raise BayesUpdateError(
                f"{what}: components must be digits 1-6 (e.g. '123456') or names {COMPONENTS}, "
                f"got {components!r}"
            )
        idx = [COMPONENTS.index(c) for c in names]
    if not idx or min(idx) < 0 or max(idx) > 5:
        raise BayesUpdateError(f"{what}: components must be digits 1-6, got {components!r}")
    mask = np.zeros(6, bool)
    mask[idx] = True
    return mask


def _empty(shape, dtype=float):
    return field(default_factory=lambda: np.zeros(shape, dtype=dtype))


@dataclass(frozen=True)
class Constraints:
    """Supports and rigid elements as flat arrays (one row per support, RBE2 leg, RBE3 leg).

    fixed_node (F,), fixed_components (F, 6) bool.
    RBE2 legs: rbe2_element (L2,), rbe2_independent (L2,) node, rbe2_dependent (L2,) node,
    rbe2_components (L2, 6) bool (dependent components).
    RBE3: rbe3_reference (R3,) node, rbe3_ref_components (R3, 6) bool (dependent components);
    legs rbe3_element (L3,) index into rbe3_reference, rbe3_node (L3,), rbe3_weight (L3,),
    rbe3_components (L3, 6) bool (the node's components used in the average).
    RBE3 UM sets: rbe3_um_element (U,) index into rbe3_reference, rbe3_um_node (U,),
    rbe3_um_components (U, 6) bool: the DOFs made dependent instead of the reference's.
    Node frames: frame_node (Fn,) distinct nodes, frame_axes (Fn, 3, 3) rows = the node's local
    DOF axes in global coordinates; components of supports and rigid elements on these nodes
    are in those axes.
    Multipoint constraints (Nastran MPC): terms mpc_equation (E,) equation index, mpc_node (E,),
    mpc_component (E,) 0-5 (in the node's axes), mpc_coef (E,): sum of coef u = 0, the first
    term of each equation its dependent DOF.
    """

    fixed_node: np.ndarray = _empty(0, int)
    fixed_components: np.ndarray = _empty((0, 6), bool)
    rbe2_element: np.ndarray = _empty(0, int)
    rbe2_independent: np.ndarray = _empty(0, int)
    rbe2_dependent: np.ndarray = _empty(0, int)
    rbe2_components: np.ndarray = _empty((0, 6), bool)
    rbe3_reference: np.ndarray = _empty(0, int)
    rbe3_ref_components: np.ndarray = _empty((0, 6), bool)
    rbe3_element: np.ndarray = _empty(0, int)
    rbe3_node: np.ndarray = _empty(0, int)
    rbe3_weight: np.ndarray = _empty(0)
    rbe3_components: np.ndarray = _empty((0, 6), bool)
    rbe3_um_element: np.ndarray = _empty(0, int)
    rbe3_um_node: np.ndarray = _empty(0, int)
    rbe3_um_components: np.ndarray = _empty((0, 6), bool)
    frame_node: np.ndarray = _empty(0, int)
    frame_axes: np.ndarray = _empty((0, 3, 3))
    mpc_equation: np.ndarray = _empty(0, int)
    mpc_node: np.ndarray = _empty(0, int)
    mpc_component: np.ndarray = _empty(0, int)
    mpc_coef: np.ndarray = _empty(0)

    @property
    def n_mpc(self) -> int:
        return int(self.mpc_equation.max()) + 1 if self.mpc_equation.size else 0

    @property
    def n_rbe2(self) -> int:
        return int(self.rbe2_element.max()) + 1 if self.rbe2_element.size else 0

    @property
    def is_empty(self) -> bool:
        return not (
            self.fixed_node.size
            or self.rbe2_element.size
            or self.rbe3_reference.size
            or self.frame_node.size
            or self.mpc_equation.size
        )

    def fixed_dofs(self) -> np.ndarray:
        """Sorted unique global DOF numbers held at zero."""
        node, comp = np.nonzero(self.fixed_components)
        return np.unique(6 * self.fixed_node[node] + comp)

    def edges(self) -> np.ndarray:
        """(n, 2) node pairs that the rigid elements connect (for connectivity checks)."""
        a = np.stack([self.rbe2_independent, self.rbe2_dependent], axis=1)
        b = np.stack([self.rbe3_reference[self.rbe3_element], self.rbe3_node], axis=1)
        first = np.unique(self.mpc_equation, return_index=True)[1]
        m = np.stack([self.mpc_node[first][self.mpc_equation], self.mpc_node], axis=1)
        return np.concatenate([a, b, m]).reshape(-1, 2).astype(int)


@dataclass(frozen=True)
class ConstraintTransform:
    """u = T @ u_ind.  T : (n_dof, n_ind) CSR; independent : (n_ind,) DOF numbers (6 node + i,
    in the node's own frame where it has one) of the retained DOFs; fixed, dependent : DOF
    numbers likewise.  rotation : Lambda (n_dof, n_dof) CSR with u = Lambda w (None: no node
    frames, then T is the identity on the independent DOFs)."""

    T: sp.csr_matrix
    independent: np.ndarray
    fixed: np.ndarray
    dependent: np.ndarray
    rotation: sp.csr_matrix | None = None

    def reduce(self, A):
        """T^T A T for a sparse (n_dof, n_dof) matrix, as CSR."""
        return (self.T.T @ (A @ self.T)).tocsr()

    def expand(self, x: np.ndarray) -> np.ndarray:
        """Full DOF vectors (n_dof, ...) from independent ones (n_ind, ...)."""
        return self.T @ x


def rigid_link(r: np.ndarray) -> np.ndarray:
    """(n, 6, 6) G with (u, theta) at x + r = G (u, theta) at x for small rotations."""
    G = np.zeros(r.shape[:-1] + (6, 6))
    G[..., :3, :3] = np.eye(3)
    G[..., 3:, 3:] = np.eye(3)
    G[..., :3, 3:] = -skew(r)
    return G


def _rbe2_rows(nodes, c: Constraints, L=None):
    """(rows, cols, vals) of the RBE2 dependencies, then each dependent DOF and its element.
    L : None or (N, 6, 6) node rotations (u = L w): the coefficients act between frames."""
    G = rigid_link(nodes[c.rbe2_dependent] - nodes[c.rbe2_independent])  # (L2, 6, 6)
    if L is not None:
        G = L[c.rbe2_dependent].transpose(0, 2, 1) @ G @ L[c.rbe2_independent]
    leg, comp = np.nonzero(c.rbe2_components)
    rows = np.repeat(6 * c.rbe2_dependent[leg] + comp, 6)
    cols = (6 * c.rbe2_independent[leg][:, None] + np.arange(6)).ravel()
    vals = G[leg, comp].ravel()
    return (
        rows,
        cols,
        vals,
        6 * c.rbe2_dependent[leg] + comp,
        [f"rbe2 {i}" for i in c.rbe2_element[leg]],
    )


def _rbe3_rows(nodes, c: Constraints, L=None):
    """(rows, cols, vals) of the RBE3 reference dependencies (weighted LSQ fit), then each
    dependent DOF and its element.  L : None or (N, 6, 6) node rotations (module docstring)."""
    n_el = c.rbe3_reference.size
    e = c.rbe3_element
    r = nodes[c.rbe3_node] - nodes[c.rbe3_reference[e]]  # (L3, 3)
    dist = np.linalg.norm(r, axis=1)
    length = np.bincount(e, dist, n_el) / np.maximum(np.bincount(e, minlength=n_el), 1)
    scale = np.where(np.arange(6) < 3, 1.0, length[e][:, None] ** 2)
    W = c.rbe3_weight[:, None] * scale * c.rbe3_components  # (L3, 6) diagonal weights
    G = rigid_link(r)
    if L is not None:
        G = L[c.rbe3_node].transpose(0, 2, 1) @ G  # the fit works on the nodes' own components
    GtW = G.transpose(0, 2, 1) * W[:, None, :]  # G_k^T W_k
    A = np.zeros((n_el, 6, 6))
    np.add.at(A, e, GtW @ G)
    ref_mask = c.rbe3_ref_components
    Lr = None if L is None else L[c.rbe3_reference]
    B = _pinv_checked(A, ref_mask, Lr)[e] @ GtW  # (L3, 6, 6): (u_r, theta_r) += B_k u_k
    leg, comp = np.nonzero(ref_mask[e])
    rows = np.repeat(6 * c.rbe3_reference[e[leg]] + comp, 6)
    cols = (6 * c.rbe3_node[leg][:, None] + np.arange(6)).ravel()
    vals = B[leg, comp].ravel()
    el, comp = np.nonzero(ref_mask)
    out = rows, cols, vals, 6 * c.rbe3_reference[el] + comp, [f"rbe3 {i}" for i in el]
    row_element = np.repeat(e[leg], 6)
    for i in np.unique(c.rbe3_um_element):
        out, row_element = _um_rows(out, row_element, c, int(i))
    return out


def _um_rows(parts, row_element, c: Constraints, i: int):
    """(``parts`` (rows, cols, vals, dependent DOFs, owners), the element of each entry) with
    RBE3 ``i``'s equations u_r = B u_n solved for its UM DOFs instead (module docstring)."""
    rows, cols, vals, dep, owners = parts
    mine = row_element == i
    ref = np.unique(rows[mine])  # the reference's dependent DOFs
    k, comp = np.nonzero(c.rbe3_um_components[c.rbe3_um_element == i])
    um = 6 * c.rbe3_um_node[c.rbe3_um_element == i][k] + comp
    dofs = np.unique(np.concatenate([ref, cols[mine]]))
    if um.size != ref.size or not np.all(np.isin(um, dofs)):
        raise BayesUpdateError(
            f"rbe3 {i}: its UM set needs {ref.size} DOFs of the element's nodes or reference "
            f"(as many as its reference components), got {um.size}"
        )
    C = np.zeros((ref.size, dofs.size))  # C u = 0: u_r - B u_n
    C[np.arange(ref.size), np.searchsorted(dofs, ref)] = 1.0
    np.add.at(C, (np.searchsorted(ref, rows[mine]), np.searchsorted(dofs, cols[mine])), -vals[mine])
    d = np.searchsorted(dofs, um)
    rest = np.setdiff1d(np.arange(dofs.size), d)
    C_d = C[:, d]
    if np.linalg.cond(C_d) > 1e12:
        raise BayesUpdateError(
            f"rbe3 {i}: its UM DOFs do not determine the element's equations (their coefficients "
            "are dependent); choose other UM DOFs"
        )
    coef = -np.linalg.solve(C_d, C[:, rest])  # (n, n_rest): u_D = coef u_rest
    keep, other = ~mine, np.array([o != f"rbe3 {i}" for o in owners], bool)
    parts = (
        np.concatenate([rows[keep], np.repeat(um, rest.size)]),
        np.concatenate([cols[keep], np.tile(dofs[rest], um.size)]),
        np.concatenate([vals[keep], coef.ravel()]),
        np.concatenate([dep[other], um]),
        [o for o in owners if o != f"rbe3 {i}"] + [f"rbe3 {i}"] * um.size,
    )
    return parts, np.concatenate([row_element[keep], np.full(um.size * rest.size, i)])


def _pinv_checked(A, ref_mask, Lr=None):
    """Pseudo-inverses (n, 6, 6) of the normal matrices A; the dependent components
    ``ref_mask`` (n, 6) must be determined (orthogonal to the null space of A), e.g. the rotation
    about the line through collinear nodes is not, unless their rotations are used.  With the
    reference frames Lr (n, 6, 6) the result maps to the reference's own components."""
    U, s, Vt = np.linalg.svd(A)
    null = s < 1e-10 * s[:, :1]
    Vl = Vt if Lr is None else Vt @ Lr  # null directions in the reference's own components
    reach = np.einsum("nk,nki->ni", null.astype(float), np.abs(Vl))  # null-space weight per comp
    bad = np.any((reach > 1e-6) & ref_mask, axis=1)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        comp = [COMPONENTS[k] for k in np.flatnonzero((reach[i] > 1e-6) & ref_mask[i])]
        raise BayesUpdateError(
            f"rbe3 {i}: its nodes do not determine the reference's {', '.join(comp)} (e.g. "
            "collinear nodes with translations only); add nodes, use their rotations "
            "(node_components='123456') or make fewer reference components dependent"
        )
    inv_s = np.where(null, 0.0, 1.0 / np.where(null, 1.0, s))
    P = np.einsum("nji,nj,nkj->nik", Vt, inv_s, U)
    return P if Lr is None else Lr.transpose(0, 2, 1) @ P


def _mpc_rows(c: Constraints):
    """(rows, cols, vals) of the MPC equations solved for their first terms, u_d = -sum_i
    (a_i / a_d) u_i (the components in the nodes' own axes: no frame to apply), then each
    dependent DOF and its equation."""
    eq = c.mpc_equation
    first = np.unique(eq, return_index=True)[1]
    a0 = c.mpc_coef[first][eq]
    if np.any(c.mpc_coef[first] == 0):
        e = int(eq[first][np.flatnonzero(c.mpc_coef[first] == 0)[0]])
        raise BayesUpdateError(f"mpc {e}: its dependent term has coefficient 0")
    dof = 6 * c.mpc_node + c.mpc_component
    dep = dof[first][eq]
    other = np.ones(eq.size, bool)
    other[first] = False
    owners = [f"mpc {int(e)}" for e in eq[first]]
    return dep[other], dof[other], -c.mpc_coef[other] / a0[other], dof[first], owners


def _dependencies(nodes, c: Constraints, L=None):
    """Sparse G (n_dof, n_dof): dependent rows hold their rigid-element (or MPC) coefficients,
    every other row is the identity.  Checks that each DOF is dependent in at most one
    element."""
    n_dof = 6 * nodes.shape[0]
    r2 = _rbe2_rows(nodes, c, L)
    r3 = _rbe3_rows(nodes, c, L) if c.rbe3_reference.size else None
    parts = [r2] + ([r3] if r3 is not None else [])
    parts += [_mpc_rows(c)] if c.mpc_equation.size else []
    dep = np.concatenate([p[3] for p in parts])
    owners = [o for p in parts for o in p[4]]
    uniq, first, counts = np.unique(dep, return_index=True, return_counts=True)
    if np.any(counts > 1):
        d = int(uniq[np.flatnonzero(counts > 1)[0]])
        who = [owners[i] for i in np.flatnonzero(dep == d)]
        raise BayesUpdateError(
            f"node {d // 6} {COMPONENTS[d % 6]} is a dependent DOF of both {who[0]} and {who[1]}; "
            "a DOF can be dependent in one rigid element only"
        )
    rows = np.concatenate([p[0] for p in parts])
    cols = np.concatenate([p[1] for p in parts])
    vals = np.concatenate([p[2] for p in parts])
    keep = np.abs(vals) > 0
    eye = np.setdiff1d(np.arange(n_dof), uniq)
    G = sp.csr_matrix(
        (
            np.concatenate([vals[keep], np.ones(eye.size)]),
            (np.concatenate([rows[keep], eye]), np.concatenate([cols[keep], eye])),
        ),
        shape=(n_dof, n_dof),
    )
    return G, uniq, dict(zip(uniq.tolist(), (owners[i] for i in first), strict=True))


def constraint_transform(nodes: np.ndarray, c: Constraints) -> ConstraintTransform:
    """The transformation T (u = T u_ind) for nodes (N, 3) [m] and constraints ``c``.

    Raises BayesUpdateError naming the element for a dependent DOF that is also fixed or
    dependent in another element, and for rigid elements that depend on each other in a loop.
    """
    n_dof = 6 * nodes.shape[0]
    fixed = c.fixed_dofs()
    L, Lam = node_rotations(nodes.shape[0], c)
    if c.rbe2_element.size == 0 and c.rbe3_reference.size == 0 and c.mpc_equation.size == 0:
        keep = np.setdiff1d(np.arange(n_dof), fixed)
        T = sp.csr_matrix((np.ones(keep.size), (keep, np.arange(keep.size))), (n_dof, keep.size))
        return _with_frames(ConstraintTransform(T, keep, fixed, np.zeros(0, int)), Lam)
    G, dep, owner = _dependencies(nodes, c, L)
    clash = np.intersect1d(dep, fixed)
    if clash.size:
        d = int(clash[0])
        raise BayesUpdateError(
            f"{owner[d]}: its dependent DOF node {d // 6} {COMPONENTS[d % 6]} is also fixed by a "
            "support; support the independent node instead"
        )
    is_dep = np.zeros(n_dof, bool)
    is_dep[dep] = True
    T = G
    n_elements = c.n_rbe2 + c.rbe3_reference.size + c.n_mpc
    for _ in range(n_elements + 1):
        coo = T.tocoo()
        if not np.any(is_dep[coo.col[coo.data != 0]]):
            break
        T = (T @ G).tocsr()
    else:
        coo = T.tocoo()
        d = int(coo.row[is_dep[coo.col] & (coo.data != 0)][0])
        raise BayesUpdateError(
            f"{owner.get(d, 'a rigid element')}: rigid elements depend on each other in a loop "
            f"(through node {d // 6} {COMPONENTS[d % 6]}); make one of them independent"
        )
    keep = np.flatnonzero(~is_dep & ~np.isin(np.arange(n_dof), fixed))
    T = T.tocsc()[:, keep].tocsr()
    T.eliminate_zeros()
    return _with_frames(ConstraintTransform(T, keep, fixed, dep), Lam)


def node_rotations(n_nodes: int, c: Constraints):
    """(L (N, 6, 6), Lambda (6N, 6N) CSR) with u = L w per node, or (None, None) without
    node frames.  L = diag(A^T, A^T) for a node with axes A (rows), the identity otherwise."""
    if c.frame_node.size == 0:
        return None, None
    if np.unique(c.frame_node).size != c.frame_node.size:
        raise BayesUpdateError("a node has two coordinate frames; give each node one frame")
    A = np.broadcast_to(np.eye(3), (n_nodes, 3, 3)).copy()
    A[c.frame_node] = c.frame_axes
    L = np.zeros((n_nodes, 6, 6))
    L[:, :3, :3] = A.transpose(0, 2, 1)
    L[:, 3:, 3:] = L[:, :3, :3]
    rows = np.repeat(6 * np.arange(n_nodes)[:, None] + np.arange(6), 6, axis=1).ravel()
    cols = np.tile(6 * np.arange(n_nodes)[:, None] + np.arange(6), (1, 6)).ravel()
    Lam = sp.csr_matrix((L.ravel(), (rows, cols)), shape=(6 * n_nodes,) * 2)
    Lam.eliminate_zeros()
    return L, Lam


def _with_frames(tr: ConstraintTransform, Lam) -> ConstraintTransform:
    """The transform in global DOFs: T = Lambda T_w (unchanged without frames)."""
    if Lam is None:
        return tr
    T = (Lam @ tr.T).tocsr()
    T.eliminate_zeros()
    return ConstraintTransform(T, tr.independent, tr.fixed, tr.dependent, Lam)
