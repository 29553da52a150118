"""The point of a model nearest to a test point: a node, a point on a line element, or a point
on a shell face, with the weights that interpolate the element's nodes there.

Line elements (beams, rods) and shell edges: the foot of the perpendicular on the segment,
weights (1 - s, s) (linear shape functions).  Triangles: the foot on the plane where it falls
inside, weights = barycentric coordinates (the linear shape functions).  Quads: the foot on the
nearer of its two triangles, then the bilinear natural coordinates (xi, eta) of that foot by
Gauss-Newton on x(xi, eta) = sum N_i(xi, eta) x_i and weights N_i = (1 +- xi)(1 +- eta) / 4
(the shape functions of the 4-node element; Zienkiewicz & Taylor, The Finite Element Method,
vol. 1, sec. 6.2).  Pairing on elements, the candidates are the line elements and shell faces
with their nodes (a node as near as every element point wins, weights 1); a node on no element
(a point mass's, a spring's grounded end) is none.  Pairing on nodes, every node is one.
"""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from bayesupdate.testgeom.mesh import ModelMesh

_XI = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])


@dataclass(frozen=True)
class Location:
    """Where a test point sits on the model: kind ('node', 'line', 'tria', 'quad', or 'edge'
    of a shell), element row in its family (``ModelMesh.lines``, ``trias``, ``quads``; -1 for a
    node or an edge), nodes (k,) node rows, weights (k,), foot (3,) the model
    point [model unit], distance [model unit], nearest (the nearest node's row; of coincident
    nodes, one on an element)."""

    kind: str
    element: int
    nodes: np.ndarray
    weights: np.ndarray
    foot: np.ndarray
    distance: float
    nearest: int


def _segments(p, A, B):
    """(distance (E,), s (E,)) of point p to the segments A-B (E, 3)."""
    AB = B - A
    L2 = np.einsum("ij,ij->i", AB, AB)
    s = np.clip(np.einsum("ij,ij->i", p - A, AB) / np.where(L2 > 0, L2, 1.0), 0.0, 1.0)
    return np.linalg.norm(A + s[:, None] * AB - p, axis=1), s


def _triangles(p, A, B, C):
    """(distance (E,), barycentric (E, 3)) of p's foot on each triangle's plane; inf where the
    foot falls outside the triangle (an edge then is nearer)."""
    e0, e1, v = B - A, C - A, p - A
    d00, d01, d11 = (np.einsum("ij,ij->i", x, y) for x, y in ((e0, e0), (e0, e1), (e1, e1)))
    d20, d21 = np.einsum("ij,ij->i", v, e0), np.einsum("ij,ij->i", v, e1)
    det = d00 * d11 - d01**2
    ok = det > 1e-300
    det = np.where(ok, det, 1.0)
    b1, b2 = (d11 * d20 - d01 * d21) / det, (d00 * d21 - d01 * d20) / det
    bary = np.column_stack([1 - b1 - b2, b1, b2])
    inside = ok & (bary >= -1e-12).all(axis=1)
    foot = A + b1[:, None] * e0 + b2[:, None] * e1
    return np.where(inside, np.linalg.norm(foot - p, axis=1), np.inf), bary


def bilinear_weights(corners, point, iterations: int = 20) -> np.ndarray:
    """(4,) shape functions of a 4-node quad (corners (4, 3)) at the natural coordinates of
    ``point`` (on or near its surface), by Gauss-Newton (module docstring)."""
    xi = np.zeros(2)
    for _ in range(iterations):
        a, b = 1 + _XI[:, 0] * xi[0], 1 + _XI[:, 1] * xi[1]
        J = corners.T @ (0.25 * np.column_stack([_XI[:, 0] * b, _XI[:, 1] * a]))  # (3, 2)
        r = point - (0.25 * a * b) @ corners
        step = np.linalg.solve(J.T @ J, J.T @ r)
        xi = np.clip(xi + step, -1.0, 1.0)
        if np.abs(step).max() < 1e-12:
            break
    return 0.25 * (1 + _XI[:, 0] * xi[0]) * (1 + _XI[:, 1] * xi[1])


def _best_line(p, X, lines, rows):
    """(distance, kind, element, nodes (2,), weights (2,)) of the nearest point on the
    segments ``lines[rows]``."""
    if not len(rows):
        return np.inf, None, -1, None, None
    d, s = _segments(p, X[lines[rows, 0]], X[lines[rows, 1]])
    i = int(np.argmin(d))
    return float(d[i]), "line", int(rows[i]), lines[rows[i]], np.array([1 - s[i], s[i]])


def _best_face(p, X, trias, quads, t_rows, q_rows):
    """Nearest interior point of the shell faces ``trias[t_rows]``, ``quads[q_rows]`` (quads
    by their two halves)."""
    best = (np.inf, None, -1, None, None)
    if len(t_rows):
        t = trias[t_rows]
        d, bary = _triangles(p, X[t[:, 0]], X[t[:, 1]], X[t[:, 2]])
        i = int(np.argmin(d))
        best = min(best, (float(d[i]), "tria", int(t_rows[i]), t[i], bary[i]), key=lambda b: b[0])
    for half in ((0, 1, 2), (0, 2, 3)) if len(q_rows) else ():
        q = quads[q_rows]
        tri = q[:, half]
        d, bary = _triangles(p, X[tri[:, 0]], X[tri[:, 1]], X[tri[:, 2]])
        i = int(np.argmin(d))
        if d[i] < best[0]:
            # the quad's bilinear weights at this foot are worked out for the winner only
            best = (float(d[i]), "quad", int(q_rows[i]), tri[i], bary[i])
    return best


def _shell_edges(mesh) -> np.ndarray:
    """(E, 2) node rows of every shell edge, each once."""
    q, t = mesh.quads, mesh.trias
    edges = [q[:, [k, (k + 1) % 4]] for k in range(4)] + [t[:, [k, (k + 1) % 3]] for k in range(3)]
    edges = np.sort(np.concatenate(edges), axis=1)
    return np.unique(edges, axis=0) if len(edges) else np.zeros((0, 2), int)


def _incidence(elements, n_nodes: int) -> sp.csr_matrix:
    """(n_nodes, n_elements) node-element incidence of (E, k) node rows."""
    E, k = elements.shape
    data = np.ones(E * k, bool)
    cols = np.repeat(np.arange(E), k)
    return sp.csr_matrix((data, (elements.ravel(), cols)), shape=(n_nodes, E))


def _gather(csr: sp.csr_matrix, rows: np.ndarray) -> np.ndarray:
    """The column indices of ``rows`` of a CSR matrix, concatenated (no scipy indexing)."""
    start, stop = csr.indptr[rows], csr.indptr[rows + 1]
    counts = stop - start
    offsets = np.repeat(start - np.cumsum(counts) + counts, counts)
    return csr.indices[offsets + np.arange(counts.sum())]


class Locator:
    """``locate`` on one mesh, its search structures built once: a k-d tree of the nodes, the
    shell edges, and the longest element edge h.  A point's nearest element point is no
    farther than its nearest node (distance d), so only elements with a node within d + h of
    the point are searched."""

    def __init__(self, mesh: ModelMesh):
        self.mesh, self.tree = mesh, cKDTree(mesh.nodes)
        self.edges = _shell_edges(mesh)
        X = mesh.nodes
        self.size = max(float(np.ptp(X)), 1e-300)
        every = np.concatenate([mesh.lines, self.edges]) if len(self.edges) else mesh.lines
        self.h = float(np.linalg.norm(X[every[:, 0]] - X[every[:, 1]], axis=1).max()) if len(
            every) else 0.0  # fmt: skip

        n = len(X)
        on_element = np.zeros(n, bool)
        for family in (mesh.lines, mesh.quads, mesh.trias):
            on_element[family.ravel()] = True
        self.element_rows = np.flatnonzero(on_element)
        self.element_tree = cKDTree(X[self.element_rows]) if on_element.any() else None
        # node -> element incidence of each family (lines, edges, trias, quads)
        self.incidence = [_incidence(e, n) for e in (mesh.lines, self.edges, mesh.trias,
                                                     mesh.quads)]  # fmt: skip

    def _nearest_nodes(self, points, on_elements: bool) -> tuple[np.ndarray, np.ndarray]:
        """(distances, rows) of each point's nearest node (``on_elements``: of the nodes on a
        line element or shell, where the model has any); of coincident nodes the lowest row
        (``coincident`` lists the others)."""
        rows = self.element_rows if on_elements and len(self.element_rows) else None
        tree = self.tree if rows is None else self.element_tree
        k = min(8, tree.n)
        d, i = tree.query(points, k=k)
        d, i = d.reshape(len(points), k), i.reshape(len(points), k)
        i = i if rows is None else rows[i]
        tie = d <= d[:, :1] + 1e-9 * self.size
        col = np.where(tie, i, np.iinfo(np.int64).max).argmin(axis=1)
        at = np.arange(len(points))
        return d[at, col], i[at, col]

    def coincident(self, row: int) -> np.ndarray:
        """Rows of the other nodes at node ``row``'s position (to 1e-9 of the model's size):
        the two sides of a joint, a spring's grounded end."""
        near = self.tree.query_ball_point(self.mesh.nodes[row], 1e-9 * self.size)
        return np.array(sorted(set(near) - {row}), dtype=np.int64)

    def _candidates(self, p, dn) -> list[np.ndarray]:
        """Element rows of each family with a node within dn + h of ``p``."""
        near = np.asarray(self.tree.query_ball_point(p, dn * (1 + 1e-9) + self.h), np.int64)
        return [np.unique(_gather(inc, near)) for inc in self.incidence]

    def __call__(self, points, on_elements: bool = True, weights: bool = True):
        """``Location`` of each point (n, 3) [model unit]: the nearest node, or with
        ``on_elements`` the nearest point of a line element or shell face (nodes on none, such
        as a point mass's or a spring's, are then no candidates).
        weights : False skips a quad's bilinear weights (its nodes and weights are then those
        of the triangle half the foot is on: enough for the foot point alone)."""
        m, X = self.mesh, self.mesh.nodes
        points = np.atleast_2d(np.asarray(points, dtype=float))
        d_node, nearest = self._nearest_nodes(points, on_elements)
        out = []
        for p, dn, n in zip(points, d_node, nearest, strict=True):
            node = Location("node", -1, np.array([n]), np.ones(1), X[n], float(dn), int(n))
            if on_elements:
                rows = self._candidates(p, dn)
                edge = _best_line(p, X, self.edges, rows[1])
                edge = (edge[0], "edge", -1, *edge[3:])
                best = min(_best_line(p, X, m.lines, rows[0]), edge,
                           _best_face(p, X, m.trias, m.quads, rows[2], rows[3]),
                           key=lambda b: b[0])  # fmt: skip
                d, kind, element, nodes, w = best
                if d < dn - 1e-9 * self.size:
                    foot = w @ X[nodes]
                    if kind == "quad" and weights:
                        nodes = m.quads[element]
                        w = bilinear_weights(X[nodes], foot)
                        foot = w @ X[nodes]
                    node = Location(kind, element, np.asarray(nodes), w, foot, float(d), int(n))
            out.append(node)
        return tuple(out)


def locate(points, mesh: ModelMesh, on_elements: bool = True) -> tuple[Location, ...]:
    """``Location`` of each point (n, 3) [model unit] on ``mesh`` (``Locator``, built for this
    call; keep a ``Locator`` to locate many times on one mesh)."""
    return Locator(mesh)(points, on_elements)
