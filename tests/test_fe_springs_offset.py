"""Springs whose ends are apart, acting at a location (``fe.elements.spring``, Nastran CBUSH with
GA, GB
apart): equilibrium, rigid-body invariance, closed forms, RBE2 equivalence, the coincident case."""

import numpy as np
import pytest
import scipy.linalg as sla

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.assembly import Assembler
from bayesupdate.fe.model import FEModel
from bayesupdate.fe.modify import with_spring
from bayesupdate.fe.rotations import rigid_body_basis
from bayesupdate.fe.structure import StructureBuilder


def _rotation(seed):
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


def _two_bodies(xa, xb, k, frame, location, grounded=False):
    """Point masses with inertia at two nodes joined (or node A grounded) by one spring."""
    b = StructureBuilder()
    a = b.add_node(xa)
    b.add_point_mass(a, 2.0, "body a", inertia=[0.3, 0.4, 0.5])
    nb = None
    if not grounded:
        nb = b.add_node(xb)
        b.add_point_mass(nb, 3.0, "body b", inertia=[0.6, 0.2, 0.7])
    b.add_spring(a, nb, k, "bush", frame=frame, location=location)
    return b.build()


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rigid_motion_gives_no_force_and_forces_balance(seed):
    rng = np.random.default_rng(seed)
    xa, xb = rng.normal(size=3), rng.normal(size=3)
    k = rng.uniform(1e3, 1e5, 6)
    for location in (rng.normal(size=3) * 3, 0.3 * xa + 0.7 * xb, xa):
        s = _two_bodies(xa, xb, k, _rotation(seed), location)
        a = Assembler(s)
        Ke = a.matrices("spring", a.default_properties())[0][0]
        # every rigid motion of the two nodes: zero force, whatever the location
        R = rigid_body_basis(s.nodes)
        assert np.abs(Ke @ R).max() < 1e-10 * np.abs(Ke).max()
        # a deformation: the node forces sum to zero and their moments about the origin too
        f = (Ke @ rng.normal(size=12)).reshape(2, 6)
        force = f[:, :3].sum(axis=0)
        moment = (np.cross(s.nodes, f[:, :3]) + f[:, 3:]).sum(axis=0)
        scale = np.abs(f).max() * (1 + np.abs(s.nodes).max())
        assert np.abs(force).max() < 1e-11 * scale
        assert np.abs(moment).max() < 1e-11 * scale
        assert np.allclose(Ke, Ke.T, rtol=0, atol=1e-12 * np.abs(Ke).max())


def test_springs_see_the_relative_motion_at_the_location():
    # node B turns by 1e-3 rad about z; at p = x_B + (0.4, 0, 0) that is 4e-4 m along y, which
    # the spring along y (k = 2e4 N/m) resists with 8 N; node A does not move
    xa, xb, p = np.zeros(3), np.array([1.0, 0, 0]), np.array([1.4, 0, 0])
    s = _two_bodies(xa, xb, [0, 2e4, 0, 0, 0, 0], None, p)
    a = Assembler(s)
    Ke = a.matrices("spring", a.default_properties())[0][0]
    q = np.zeros(12)
    q[6 + 5] = 1e-3
    f = Ke @ q  # the node loads that hold this deformation
    assert f[6 + 1] == pytest.approx(8.0, rel=1e-12)
    assert f[1] == pytest.approx(-8.0, rel=1e-12)  # the reaction on A
    assert f[6 + 5] == pytest.approx(8.0 * 0.4, rel=1e-12)  # about z: lever 0.4 m from B
    assert f[5] == pytest.approx(-8.0 * 1.4, rel=1e-12)  # and 1.4 m from A
    assert np.count_nonzero(np.abs(f) > 1e-9) == 4


def test_body_on_lateral_spring_at_lever_arm_closed_form():
    # a body (m, Jz) at node A on a grounded spring k along y acting at lever a along x:
    # rotation alone (uy held): omega^2 = k a^2 / Jz; uy and rz coupled:
    # omega^2 = k (1/m + a^2 / Jz), the other root 0
    m, Jz, k, a = 2.0, 0.5, 3.0e4, 0.25
    node = np.array([0.3, -0.2, 1.0])
    s = _two_bodies(node, None, [0, k, 0, 0, 0, 0], None, node + [a, 0, 0], grounded=True)
    K, M, _ = Assembler(s).assemble()
    K, M = K.toarray(), M.toarray()
    rz = [5]
    assert np.sqrt(K[np.ix_(rz, rz)][0, 0] / M[5, 5]) == pytest.approx(
        np.sqrt(k * a**2 / Jz), rel=1e-13
    )
    dofs = [1, 5]
    lam = sla.eigh(K[np.ix_(dofs, dofs)], M[np.ix_(dofs, dofs)], eigvals_only=True)
    assert lam[0] == pytest.approx(0.0, abs=1e-9 * lam[1])
    assert lam[1] == pytest.approx(k * (1 / m + a**2 / Jz), rel=1e-13)
    # two springs at +-a decouple uy and rz: omega^2 = 2k/m and 2 k a^2 / Jz
    b = StructureBuilder()
    n = b.add_node(node)
    b.add_point_mass(n, m, "body", inertia=[0.3, 0.4, Jz])
    for side in (1, -1):
        b.add_spring(n, None, [0, k, 0, 0, 0, 0], "bush", location=node + [side * a, 0, 0])
    K, M, _ = Assembler(b.build()).assemble()
    lam = sla.eigh(K.toarray()[np.ix_(dofs, dofs)], M.toarray()[np.ix_(dofs, dofs)])[0]
    assert lam == pytest.approx(sorted([2 * k / m, 2 * k * a**2 / Jz]), rel=1e-13)


def test_offset_spring_equals_rbe2_links_to_coincident_spring():
    # the same physics built another way: two new nodes at the location p, each rigidly tied
    # (RBE2) to one body, joined by a zero-length spring; the constraints are eliminated
    # exactly (``fe.constraints``), so the modes agree to round-off
    rng = np.random.default_rng(4)
    xa, xb = np.zeros(3), np.array([0.8, 0.1, -0.2])
    p = np.array([0.5, 0.3, 0.2])
    k, R = rng.uniform(1e3, 1e4, 6), _rotation(4)

    def bodies(b):
        ids = [b.add_node(xa), b.add_node(xb)]
        b.add_point_mass(ids[0], 2.0, "a", inertia=[0.3, 0.4, 0.5])
        b.add_point_mass(ids[1], 3.0, "b", inertia=[0.6, 0.2, 0.7])
        return ids

    b1 = StructureBuilder()
    na, nb = bodies(b1)
    b1.add_spring(na, nb, k, "bush", frame=R, location=p)
    b1.add_support(na, "1")  # the sparse path for both (a support that leaves the rest free)
    b2 = StructureBuilder()
    na, nb = bodies(b2)
    pa, pb = b2.add_node(p), b2.add_node(p)
    b2.add_spring(pa, pb, k, "bush", frame=R)
    b2.add_rbe2(na, [pa])
    b2.add_rbe2(nb, [pb])
    b2.add_support(na, "1")
    f1 = FEModel(b1.build(), {}, {}, {}).solve(n_modes=6, method="dense").frequencies_hz
    f2 = FEModel(b2.build(), {}, {}, {}).solve(n_modes=6, method="dense").frequencies_hz
    assert f1 == pytest.approx(f2, rel=1e-9)
    assert f1.min() > 1.0  # six elastic modes, none lost to the rigid set


def test_free_bodies_keep_six_exact_rigid_modes():
    rng = np.random.default_rng(5)
    s = _two_bodies(np.zeros(3), np.array([1.0, 0.5, 0]), rng.uniform(1e3, 1e4, 6),
                    _rotation(5), location=[0.2, 0.9, 0.4])  # fmt: skip
    r = FEModel(s, {}, {}, {}).solve(n_modes=6, method="dense")
    assert r.modes.n_rigid == 6
    assert r.frequencies_hz.min() > 1.0


def _old_spring_matrices(s, scale):
    """The zero-length spring as it was assembled before the location existed."""
    Rb = np.zeros((len(s.spring_part), 6, 6))
    Rb[:, :3, :3] = s.spring_frame
    Rb[:, 3:, 3:] = s.spring_frame
    kg = np.einsum("sji,sj,sjl->sil", Rb, s.spring_k * scale[:, None], Rb)
    out = np.zeros((len(s.spring_part), 12, 12))
    out[:, :6, :6] = kg
    free = s.spring_nodes[:, 1] >= 0
    out[free, 6:, 6:] = kg[free]
    out[free, :6, 6:] = -kg[free]
    out[free, 6:, :6] = -kg[free]
    return out


def test_coincident_location_is_bit_for_bit_the_zero_length_spring():
    rng = np.random.default_rng(6)
    x = rng.normal(size=3)
    built = []
    for location in (None, x):
        b = StructureBuilder()
        a, c = b.add_node(x), b.add_node(x)
        b.add_point_mass(a, 1.0, "m", inertia=[1, 1, 1])
        b.add_point_mass(c, 1.0, "m", inertia=[1, 1, 1])
        b.add_spring(a, c, rng.uniform(1, 1e6, 6), "bush", frame=_rotation(6), location=location)
        b.add_spring(a, None, rng.uniform(1, 1e6, 6), "ground", location=location)
        built.append(b.build())
    assert built[0].spring_offset is None and built[1].spring_offset is None
    s = built[0]
    a = Assembler(s)
    props = a.default_properties()
    K = a.matrices("spring", props)[0]
    assert np.array_equal(K, _old_spring_matrices(s, props.spring_scale))


def test_modify_keeps_offsets_in_step_and_bad_location_is_named():
    s = _two_bodies(np.zeros(3), np.array([1.0, 0, 0]), [1e3] * 6, None, [0.5, 0.2, 0])
    t = with_spring(s, 0, 1, [1.0] * 6, "extra")
    assert t.spring_offsets().shape == (2, 2, 3)
    assert np.array_equal(t.spring_offsets()[0], [[0.5, 0.2, 0], [-0.5, 0.2, 0]])
    b = StructureBuilder()
    n = b.add_node([0, 0, 0])
    with pytest.raises(BayesUpdateError, match="location must be 3 finite"):
        b.add_spring(n, None, [1.0] * 6, "bush", location=[0, np.nan, 0])
