"""Scalar masses (``fe.elements.scalar_mass``, Nastran CMASS1/CMASS2): a 2-DOF closed form, a
grounded
rotary scalar mass against a point mass's inertia, the mass report, energies, reduced terms."""

import numpy as np
import pytest
import scipy.linalg as sla
from roundoff import frequency_roundoff, largest_eigenvalue

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import STEEL, Binding, FEModel, StructureBuilder, circular_tube
from bayesupdate.fe.assembly import Assembler
from bayesupdate.fe.reduced.affine import AffineDecomposition, decompose


def _rotation(seed):
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


@pytest.mark.parametrize("frame_seed", [None, 3])
def test_two_dof_scalar_system_closed_form(frame_seed):
    # x1 on a grounded spring k1, x2 tied to x1 by k2; masses m1, m2 grounded on x1, x2 and mc
    # between them: M = [[m1 + mc, -mc], [-mc, m2 + mc]], K = [[k1 + k2, -k2], [-k2, k2]];
    # det(K - lam M) = 0 is a quadratic a lam^2 + b lam + c
    m1, m2, mc, k1, k2 = 2.0, 1.5, 0.4, 3.0e4, 1.0e4
    R = np.eye(3) if frame_seed is None else _rotation(frame_seed)
    b = StructureBuilder()
    n1, n2 = b.add_node([0, 0, 0]), b.add_node([1.0, 0, 0])
    kx = [k1, 0, 0, 0, 0, 0]
    b.add_spring(n1, None, kx, "k1", frame=R)
    b.add_spring(n1, n2, [k2, 0, 0, 0, 0, 0], "k2", frame=R)
    b.add_scalar_mass(n1, 1, m1, "m1", frame_a=R)
    b.add_scalar_mass(n2, "ux", m2, "m2", frame_a=R)
    b.add_scalar_mass(n1, 1, mc, "mc", node_b=n2, component_b=1, frame_a=R, frame_b=R)
    K, M, _ = Assembler(b.build()).assemble()
    # the two scalar coordinates w = R[0] . u at each node
    W = np.zeros((12, 2))
    W[0:3, 0] = R[0]
    W[6:9, 1] = R[0]
    Kw, Mw = W.T @ K.toarray() @ W, W.T @ M.toarray() @ W
    assert Mw == pytest.approx(np.array([[m1 + mc, -mc], [-mc, m2 + mc]]), rel=1e-14)
    a = (m1 + mc) * (m2 + mc) - mc**2
    bq = -((k1 + k2) * (m2 + mc) + k2 * (m1 + mc) - 2 * k2 * mc)
    c = (k1 + k2) * k2 - k2**2
    closed = np.sort(np.roots([a, bq, c]).real)
    assert sla.eigh(Kw, Mw, eigvals_only=True) == pytest.approx(closed, rel=1e-12)
    # the mass lies on that direction only: M W spans the same two columns
    assert np.abs(M.toarray() - M.toarray() @ W @ W.T).max() < 1e-14


def _beam(rotary):
    """A free tube beam; ``rotary`` adds a rotary inertia at its tip (scalar or point mass)."""
    b = StructureBuilder()
    x0, x1 = b.add_node([0, 0, 0]), b.add_node([1.2, 0.3, 0.1])
    ids = b.add_line(x0, x1, circular_tube(0.05, 2e-3), STEEL, "tube", element_length=0.1)
    rotary(b, ids[-1])
    return b.build()


def test_grounded_rotary_scalar_mass_equals_point_inertia_about_its_axis():
    J, R = 0.02, _rotation(8)
    n = R[1]  # the scalar mass turns about the second axis of its node's frame (component 5)
    scalar = _beam(lambda b, node: b.add_scalar_mass(node, 5, J, "tip", frame_a=R))
    point = _beam(lambda b, node: b.add_point_mass(node, 0.0, "tip", inertia=J * np.outer(n, n)))
    Ms, Mp = Assembler(scalar).assemble()[1], Assembler(point).assemble()[1]
    assert np.abs((Ms - Mp).toarray()).max() < 1e-16
    rs = FEModel(scalar, {}, {}, {}).solve(n_modes=6, energies=True)
    rp = FEModel(point, {}, {}, {}).solve(n_modes=6, energies=True)
    # the same pencil to 1e-16: the same frequencies to round-off (tests/roundoff.py, a dense
    # solve; 6.4e-12 on the first mode, measured 1.5e-12 with OpenBLAS's SkylakeX kernels)
    K, M = Assembler(scalar).assemble()[:2]
    scale = frequency_roundoff(K, M, rs.modes.shapes, largest_eigenvalue(K, M))
    assert np.all(np.abs(rs.frequencies_hz / rp.frequencies_hz - 1.0) <= scale)
    assert rs.energies.kinetic_by_part == pytest.approx(rp.energies.kinetic_by_part, abs=1e-12)
    assert rs.energies.kinetic_by_part[scalar.part_index("tip")].max() > 1e-3
    # a rotary inertia carries no translational mass
    assert rs.mass_kg == pytest.approx(rp.mass_kg, rel=1e-14)


def test_mass_report_counts_translational_scalar_masses():
    # three grounded scalar masses on T1, T2, T3 of a node are a point mass there; one between
    # two nodes on the same axis carries no rigid-body mass
    def tube(extra):
        b = StructureBuilder()
        x0, x1 = b.add_node([0, 0, 0]), b.add_node([1.0, 0.2, 0])
        ids = b.add_line(x0, x1, circular_tube(0.05, 2e-3), STEEL, "tube", element_length=0.25)
        extra(b, ids)
        return FEModel(b.build(), {}, {}, {})

    def scalars(b, ids):
        for c in (1, 2, 3):
            b.add_scalar_mass(ids[-1], c, 0.7, "tip")
        b.add_scalar_mass(ids[0], 2, 5.0, "relative", node_b=ids[1], component_b=2)

    fs = tube(scalars)
    fp = tube(lambda b, ids: b.add_point_mass(ids[-1], 0.7, "tip"))
    banded = (fs.total_mass(), fp.total_mass())
    general = [
        (r.mass_kg, r.centre_of_gravity) for r in (fe.solve(method="sparse") for fe in (fs, fp))
    ]
    for (ms, cs), (mp, cp) in (banded, general):
        assert ms == pytest.approx(mp, rel=1e-13)
        assert cs == pytest.approx(cp, rel=1e-12)
    assert banded[0][0] == pytest.approx(general[0][0], rel=1e-12)


def test_reduced_terms_carry_the_scalar_masses():
    b = StructureBuilder()
    x0, x1 = b.add_node([0, 0, 0]), b.add_node([0.8, 0, 0])
    ids = b.add_line(x0, x1, circular_tube(0.05, 2e-3), STEEL, "tube", element_length=0.2)
    b.add_scalar_mass(ids[2], 3, 0.5, "cmass", node_b=ids[3], component_b=1)
    b.add_scalar_mass(ids[-1], 6, 1e-3, "cmass")
    fe = FEModel(b.build(), {"rho": Binding("tube", "density")}, {"rho": 7850.0},
                 {"rho": (7000.0, 9000.0)})  # fmt: skip
    dec = decompose(fe, fe.default_bounds(), 1e-10)
    theta = np.array([[8200.0]])
    V = np.eye(fe.structure.n_dof)
    M = np.einsum(
        "bt,tij->ij", dec.coefficients(theta)[1], AffineDecomposition.project(V, dec.m_stacks)
    )
    assert np.abs(M - fe.matrices({"rho": 8200.0})[1].toarray()).max() < 1e-14


def test_bad_scalar_masses_are_named():
    b = StructureBuilder()
    n = b.add_node([0, 0, 0])
    with pytest.raises(BayesUpdateError, match="exactly one component"):
        b.add_scalar_mass(n, 12, 1.0, "m")
    with pytest.raises(BayesUpdateError, match="mass must be finite and >= 0"):
        b.add_scalar_mass(n, 1, -1.0, "m")
    with pytest.raises(BayesUpdateError, match="node_b and component_b together"):
        b.add_scalar_mass(n, 1, 1.0, "m", component_b=2)
