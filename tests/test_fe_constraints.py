"""Supports and rigid elements (exact elimination, ``fe.constraints``) through the public builder.

References that could be wrong: the parallel-axis theorem (rigid-body inertia of an RBE2 body),
the beam path's own point-mass offset (an RBE2 to an offset mass must give the same modes), the
unconstrained beam (an RBE3 must not stiffen it) and the banded Krylov path on the same beams.
"""

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import STEEL, FEModel, StructureBuilder, circular_tube
from bayesupdate.fe.assembly import Assembler

SEC = circular_tube(0.045, 1.5e-3)


def _skew(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def test_rbe2_body_has_exactly_the_rigid_body_inertia():
    rng = np.random.default_rng(4)
    b = StructureBuilder()
    x0 = np.array([0.1, -0.2, 0.3])
    master = b.add_node(x0)
    pts = x0 + rng.uniform(-0.5, 0.5, (5, 3))
    masses = rng.uniform(1.0, 3.0, 5)
    inertias = [np.diag(rng.uniform(0.01, 0.1, 3)) for _ in range(5)]
    slaves = [b.add_node(p) for p in pts]
    for n, m, J in zip(slaves, masses, inertias, strict=True):
        b.add_point_mass(n, m, "body", inertia=J)
    b.add_rbe2(master, slaves)
    g = Assembler(b.build())
    _, M, _ = g.assemble()
    Mr = g.transform.reduce(M).toarray()
    assert Mr.shape == (6, 6)  # everything else is dependent
    r = pts - x0
    m = masses.sum()
    c = masses @ r / m
    inertia = sum(J + mk * (rk @ rk * np.eye(3) - np.outer(rk, rk)) for rk, mk, J in
                  zip(r, masses, inertias, strict=True))  # fmt: skip
    np.testing.assert_allclose(Mr[:3, :3], m * np.eye(3), rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(Mr[:3, 3:], -m * _skew(c), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(Mr[3:, 3:], inertia, rtol=1e-12, atol=1e-12)
    total, cog = g.matrix_mass(M)
    np.testing.assert_allclose([total, *cog], [m, *(x0 + c)], rtol=1e-12)


def _cantilever(tip_mass):
    b = StructureBuilder()
    ids = b.add_line(b.add_node((0, 0, 0)), b.add_node((1.0, 0, 0)), SEC, STEEL, "beam")
    b.add_support(ids[0])
    tip_mass(b, ids[-1])
    return b.build()


def test_rbe2_to_an_offset_mass_equals_the_point_mass_offset_of_the_beam_path():
    J = np.diag([0.02, 0.03, 0.01])
    off = np.array([0.05, 0.1, -0.08])

    def via_rbe2(b, tip):
        n = b.add_node(b.node_xyz(tip) + off)
        b.add_point_mass(n, 2.0, "mass", inertia=J)
        b.add_rbe2(tip, [n])

    def via_offset(b, tip):
        b.add_point_mass(tip, 2.0, "mass", inertia=J, offset=off)

    f1 = FEModel(_cantilever(via_rbe2), {}, {}, {}).solve(n_modes=8).frequencies_hz
    f2 = FEModel(_cantilever(via_offset), {}, {}, {}).solve(n_modes=8).frequencies_hz
    np.testing.assert_allclose(f1, f2, rtol=1e-10)
    assert (
        f1[0]
        < 0.8
        * FEModel(_cantilever(lambda b, t: None), {}, {}, {}).solve(n_modes=1).frequencies_hz[0]
    )  # the mass matters


def _free_beam(spider=False, ref_mass=0.0):
    b = StructureBuilder()
    ids = b.add_line(b.add_node((0, 0, 0)), b.add_node((1.2, 0, 0)), SEC, STEEL, "beam")
    if spider:
        ref = b.add_node((0.55, 0.2, 0.1))
        b.add_rbe3(
            ref, [ids[2], ids[4], ids[7], ids[9]], [1.0, 2.0, 0.5, 1.0], node_components="123456"
        )
        if ref_mass:
            b.add_point_mass(ref, ref_mass, "sensor")
    return b.build()


def test_rbe3_adds_no_stiffness_and_the_sparse_path_matches_the_krylov_path():
    f_krylov = FEModel(_free_beam(), {}, {}, {}).solve(n_modes=8).frequencies_hz
    f_sparse = FEModel(_free_beam(), {}, {}, {}).solve(n_modes=8, method="sparse")
    f_spider = FEModel(_free_beam(spider=True), {}, {}, {}).solve(n_modes=8)
    np.testing.assert_allclose(f_sparse.frequencies_hz, f_krylov, rtol=1e-9)
    np.testing.assert_allclose(f_spider.frequencies_hz, f_krylov, rtol=1e-9)
    assert f_spider.modes.n_rigid == 6


def test_rbe3_reproduces_rigid_motion_so_a_mass_on_it_keeps_the_total_and_cog():
    beam = FEModel(_free_beam(), {}, {}, {}).solve(n_modes=2, method="sparse")
    r = FEModel(_free_beam(spider=True, ref_mass=0.7), {}, {}, {}).solve(n_modes=8)
    assert r.modes.n_rigid == 6  # the rigid motions stay exact zero modes
    assert r.mass_kg == pytest.approx(beam.mass_kg + 0.7, rel=1e-12)
    expect = (beam.mass_kg * beam.centre_of_gravity + 0.7 * np.array([0.55, 0.2, 0.1])) / (
        beam.mass_kg + 0.7
    )
    np.testing.assert_allclose(r.centre_of_gravity, expect, rtol=1e-12)
    assert np.all(r.frequencies_hz < beam.frequencies_hz[0] * 10)  # sanity: finite modes


def _builder_with_line():
    b = StructureBuilder()
    ids = b.add_line(b.add_node((0, 0, 0)), b.add_node((1.0, 0, 0)), SEC, STEEL, "beam")
    return b, ids


def test_dependent_dof_fixed_or_dependent_twice_or_in_a_loop_is_named():
    b, ids = _builder_with_line()
    b.add_rbe2(ids[0], [ids[3]])
    b.add_support(ids[3], "3")
    with pytest.raises(
        BayesUpdateError, match=r"rbe2 0: its dependent DOF node 4 uz is also fixed"
    ):
        FEModel(b.build(), {}, {}, {})
    b, ids = _builder_with_line()
    b.add_rbe2(ids[0], [ids[3]])
    b.add_rbe3(ids[3], [ids[5], ids[6], ids[8]], components="1")
    with pytest.raises(
        BayesUpdateError, match=r"node 4 ux is a dependent DOF of both rbe2 0 and rbe3 0"
    ):
        FEModel(b.build(), {}, {}, {})
    b, ids = _builder_with_line()
    b.add_rbe2(ids[1], [ids[2]], "12")
    b.add_rbe2(ids[2], [ids[5]], "2")
    b.add_rbe2(ids[5], [ids[1]], "2")  # uy: 1 -> 2 -> 5 -> 1
    with pytest.raises(BayesUpdateError, match=r"rbe2 \d: rigid elements depend on each other"):
        FEModel(b.build(), {}, {}, {})


def test_bad_rigid_elements_and_unused_nodes_are_named():
    b, ids = _builder_with_line()
    b.add_rbe3(b.add_node((0.5, 0.3, 0)), [ids[2], ids[4]])  # two nodes: rotation undetermined
    with pytest.raises(BayesUpdateError, match=r"rbe3 0: its nodes do not determine"):
        FEModel(b.build(), {}, {}, {})
    b, ids = _builder_with_line()
    with pytest.raises(BayesUpdateError, match=r"rbe2 0: needs dependent nodes"):
        b.add_rbe2(ids[1], [ids[1]])
    with pytest.raises(BayesUpdateError, match=r"support at node 3: components"):
        b.add_support(ids[2], "17")
    b.add_support(ids[0])
    b.add_node((5, 5, 5))
    with pytest.raises(BayesUpdateError, match=r"node 11 is used by no element"):
        b.build()


def test_mechanism_is_reported_with_the_dofs_involved():
    b = StructureBuilder()
    a = b.add_line(b.add_node((0, 0, 0)), b.add_node((1.0, 0, 0)), SEC, STEEL, "a")
    c = b.add_line(b.add_node((1.0, 0, 0)), b.add_node((2.0, 0, 0)), SEC, STEEL, "c")
    b.add_support(a[0])
    b.add_rbe2(a[-1], [c[0]], "123")  # a pin: the free member c swings about it
    with pytest.raises(
        BayesUpdateError, match=r"mechanism: 3 zero-energy mode.*moves node (1[1-9]|2[01]) "
    ):
        FEModel(b.build(), {}, {}, {}).solve(n_modes=4)
    b.add_rbe2(c[0], [a[-1]], "456")  # lock the pin's rotations: rx..rz of a's end from c
    f = FEModel(b.build(), {}, {}, {}).solve(n_modes=4).frequencies_hz
    single = StructureBuilder()
    single.add_line(single.add_node((0, 0, 0)), single.add_node((2.0, 0, 0)), SEC, STEEL, "a",
                    element_length=0.1)  # fmt: skip
    single.add_support(0)
    np.testing.assert_allclose(
        f, FEModel(single.build(), {}, {}, {}).solve(n_modes=4).frequencies_hz, rtol=1e-9
    )
