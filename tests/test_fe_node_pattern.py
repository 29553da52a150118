"""The node-block CSR pattern (``fe.node_pattern``) against the DOF-level construction, and the
chunked per-power shell data against the direct element assembly."""

import numpy as np

from bayesupdate.fe.elements import shell
from bayesupdate.fe.node_pattern import node_blocks, node_pattern
from bayesupdate.fe.shell_model import ShellAssembly, shell_mesh
from bayesupdate.fe.sparse_modal import SparsePattern, dof_pattern, element_dofs


def _random_connectivity(rng, n_node, n_el, k):
    return np.array([rng.choice(n_node, k, replace=False) for _ in range(n_el)]).reshape(-1, k)


def test_node_pattern_equals_dof_pattern_with_unused_nodes():
    rng = np.random.default_rng(3)
    for _ in range(10):
        n_node = int(rng.integers(8, 40))
        conn = [_random_connectivity(rng, n_node, int(rng.integers(1, 20)), k) for k in (4, 3)]
        blocks = [element_dofs(c) for c in conn]
        ref = dof_pattern(6 * n_node, blocks)
        got = node_pattern(6 * n_node, [node_blocks(b) for b in blocks], np.int32)
        for a, b in zip(got[:3], ref[:3], strict=True):
            np.testing.assert_array_equal(a, b)
        for a, b in zip(got[3], ref[3], strict=True):
            np.testing.assert_array_equal(a, b)


def test_node_blocks_rejects_partial_node_maps():
    dofs = element_dofs(np.array([[0, 2]]))
    assert node_blocks(dofs) is not None
    assert node_blocks(dofs[:, ::-1].copy()) is None
    assert node_blocks(dofs[:, :9]) is None
    # a non-node DOF map goes through the DOF-level path with the same result
    pat = SparsePattern(18, [dofs[:, :9]])
    ref = dof_pattern(18, [dofs[:, :9]])
    np.testing.assert_array_equal(pat.indptr, ref[2])


def test_chunked_power_data_matches_direct_assembly(monkeypatch):
    """More elements than one chunk, quads and triangles, offsets on some elements only."""
    monkeypatch.setattr(shell, "CHUNK", 7)
    n = 5
    x, y = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 0.8, n + 1), indexing="ij")
    nodes = np.column_stack([x.ravel(), y.ravel(), 0.02 * np.sin(3 * x.ravel())])
    ids = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    quads = np.stack([ids[:-1, :-1], ids[1:, :-1], ids[1:, 1:], ids[:-1, 1:]], -1).reshape(-1, 4)
    trias = np.concatenate([quads[:6, [0, 1, 2]], quads[:6, [0, 2, 3]]])
    quads = quads[6:]
    n_el = len(quads) + len(trias)
    rng = np.random.default_rng(4)
    mesh = shell_mesh(
        nodes, quads, trias, thickness=2e-3, E=70e9, nu=0.33, rho=2700.0,
        offset=np.where(np.arange(n_el) % 3 == 0, 1e-3, 0.0),
        offset_ratio=np.where(np.arange(n_el) % 4 == 0, 0.5, 0.0), nsm=0.4, warp_limit=1.0,
    )  # fmt: skip
    asm = ShellAssembly(mesh)
    t = 1e-3 * rng.uniform(1.0, 3.0)
    Kp, Mp = asm.power_data()
    K, M = asm.assemble(np.full(n_el, t))
    K_sum = sum(t**p * v for p, v in Kp.items())
    M_sum = sum(t**p * v for p, v in Mp.items())
    assert sorted(Kp) == [1, 2, 3] and sorted(Mp) == [0, 1, 2, 3]
    assert np.abs(K_sum - K.data).max() <= 1e-12 * np.abs(K.data).max()
    assert np.abs(M_sum - M.data).max() <= 1e-12 * np.abs(M.data).max()
