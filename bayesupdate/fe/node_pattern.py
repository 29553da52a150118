"""CSR pattern of element matrices whose DOFs come in whole 6-DOF node blocks (shells).

The DOF-level pattern of such elements is the node-pair pattern with every pair expanded to a
6 x 6 block, so the sort and the search that make the (row, col) keys unique run on the
n_e k^2 node pairs instead of the 36 times more DOF pairs (the set-up of a 1e5-1e6 DOF shell
model spent most of its pattern time there).  The result is the same CSR (rows, cols, indptr)
and the same element positions as the DOF-level construction in ``sparse_modal.SparsePattern``:
the union of the element entries plus the diagonal of every DOF (unused nodes get only that).
"""

import numpy as np

NODE_DOF = 6


def node_blocks(dofs: np.ndarray) -> np.ndarray | None:
    """(n_e, k) node numbers of a DOF map (n_e, 6k) made of whole node blocks
    [6a, 6a+1, ..., 6a+5]; None if it is not."""
    n_e, d = dofs.shape
    if d % NODE_DOF:
        return None
    blocks = dofs.reshape(n_e, d // NODE_DOF, NODE_DOF)
    nodes = blocks[:, :, 0] // NODE_DOF
    if not np.array_equal(blocks, NODE_DOF * nodes[:, :, None] + np.arange(NODE_DOF)):
        return None
    return nodes


def node_pattern(n_dof: int, node_maps: list[np.ndarray], index_dtype):
    """(rows, cols, indptr, positions) of the DOF-level CSR pattern of elements with node maps
    (n_e, k) each; positions[b] (n_e d^2,) are the CSR positions of block b's element entries
    in row-major order (d = 6k).  Indices are ``index_dtype`` (int32 where nnz allows)."""
    n_node = n_dof // NODE_DOF
    keys = np.concatenate([_pair_keys(c, n_node) for c in node_maps])
    pairs = np.unique(keys)  # sorted; a few million node pairs at most
    a, b = pairs // n_node, pairs % n_node
    deg = np.bincount(a, minlength=n_node)
    node_ptr = np.concatenate([[0], np.cumsum(deg)])
    # DOF row lengths: 6 deg(a) for each of the six rows of a used node, 1 (the diagonal) else
    row_len = np.repeat(np.where(deg > 0, NODE_DOF * deg, 1), NODE_DOF)
    indptr = np.concatenate([[0], np.cumsum(row_len)]).astype(index_dtype)
    nnz = int(indptr[-1])
    rank = np.arange(pairs.size) - node_ptr[a]
    pos = _entry_positions(indptr, a, rank)  # (n_pairs, 6, 6)
    cols = np.empty(nnz, index_dtype)
    cols[pos] = (NODE_DOF * b)[:, None, None] + np.arange(NODE_DOF)
    rows = np.repeat(np.arange(n_dof, dtype=index_dtype), row_len)
    unused = np.repeat(deg == 0, NODE_DOF)
    cols[indptr[:-1][unused]] = np.flatnonzero(unused)
    positions = []
    for c in node_maps:
        r = np.searchsorted(pairs, _pair_keys(c, n_node)).reshape(c.shape + (c.shape[1],))
        first = c[:, :, None]
        p = _entry_positions(indptr, first, r - node_ptr[first])
        positions.append(p.transpose(0, 1, 3, 2, 4).astype(index_dtype).ravel())
    return rows, cols, indptr, positions


def _pair_keys(nodes: np.ndarray, n_node: int) -> np.ndarray:
    """(n_e k^2,) keys a n_node + b of every node pair (a, b) of elements (n_e, k), row-major."""
    c = nodes.astype(np.int64)
    return (c[:, :, None] * n_node + c[:, None, :]).reshape(-1)


def _entry_positions(indptr, a, rank):
    """CSR positions (..., 6, 6) [p, q] of the DOF entries (6a + p, 6b + q) of node pairs whose
    second node b is the ``rank``-th neighbour of node a (a, rank broadcast together): row
    6a + p starts at indptr[6a + p] and holds the neighbours' 6-column blocks in node order."""
    p = np.arange(NODE_DOF)
    row = NODE_DOF * a[..., None] + p  # (..., 6)
    start = indptr[row].astype(np.int64) + (NODE_DOF * rank)[..., None]
    return start[..., :, None] + p
