"""The FE modal solver against analytic solutions of beams, bars and mass-spring systems."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from bayesupdate.fe import STEEL, FEModel, StructureBuilder, circular_tube, solve_modes
from bayesupdate.fe.assembly import Assembler
from bayesupdate.fe.rotations import rigid_body_basis

D, T, LENGTH = 0.045, 1.5e-3, 2.0
BETA_L = np.array([4.7300408, 7.8532046, 10.9956078])  # free-free beam roots


def tube_model(n_el=40, shear=True, rotary=True, rotation=None, parts=1):
    b = StructureBuilder(shear=shear, rotary_inertia=rotary)
    sec = circular_tube(D, T)
    R = np.eye(3) if rotation is None else rotation
    pts = [R @ np.array([LENGTH * k / parts, 0.0, 0.0]) for k in range(parts + 1)]
    nodes = [b.add_node(p) for p in pts]
    for k in range(parts):
        b.add_line(
            nodes[k],
            nodes[k + 1],
            sec,
            STEEL,
            f"part{k}",
            element_length=LENGTH / n_el * 1.0000001,
            up=R @ np.array([0, 0, 1.0]),
        )
    return FEModel(b.build(), {}, {}, {})


def euler_bernoulli_hz():
    p = circular_tube(D, T).properties()
    return (
        BETA_L**2
        / (2 * np.pi * LENGTH**2)
        * np.sqrt(STEEL.youngs_modulus * p["Iy"] / (STEEL.density * p["A"]))
    )


def test_free_free_bending_matches_euler_bernoulli():
    r = tube_model(n_el=40, shear=False, rotary=False).solve(n_modes=8)
    assert r.modes.n_rigid == 6
    bending = r.frequencies_hz[[0, 2, 4]]  # each bending mode appears in y and z
    np.testing.assert_allclose(r.frequencies_hz[[1, 3, 5]], bending, rtol=1e-8)
    np.testing.assert_allclose(bending, euler_bernoulli_hz(), rtol=1e-3)


def test_mesh_convergence_is_monotone_and_fast():
    exact = euler_bernoulli_hz()[2]
    errors = [
        tube_model(n_el=n, shear=False, rotary=False).solve(n_modes=6).frequencies_hz[4] / exact - 1
        for n in (5, 10, 20)
    ]
    assert errors[0] > errors[1] > errors[2] > 0  # consistent mass: upper bounds, converging
    # cubic elements: error falls ~h^4, so halving h cuts it by > 8
    assert errors[0] / errors[1] > 8 and errors[1] / errors[2] > 8


def _free_free_shape_derivatives(beta_l, x_over_l):
    """phi and its first three derivatives for the free-free beam mode (unit length)."""
    b = beta_l
    sigma = (np.cosh(b) - np.cos(b)) / (np.sinh(b) - np.sin(b))
    bx = b * x_over_l
    d0 = np.cosh(bx) + np.cos(bx) - sigma * (np.sinh(bx) + np.sin(bx))
    d1 = b * (np.sinh(bx) - np.sin(bx) - sigma * (np.cosh(bx) + np.cos(bx)))
    d2 = b**2 * (np.cosh(bx) - np.cos(bx) - sigma * (np.sinh(bx) - np.sin(bx)))
    d3 = b**3 * (np.sinh(bx) + np.sin(bx) - sigma * (np.cosh(bx) - np.cos(bx)))
    return d0, d1, d2, d3


def test_timoshenko_lies_below_euler_bernoulli_by_the_perturbation_amount():
    # First-order perturbation of the Rayleigh quotient of each free-free mode (shapes exact):
    # rotary inertia: dlambda/lambda = -(I/A) int phi'^2 / int phi^2;
    # shear:          dlambda/lambda = -(E I / kGA) int phi'''^2 / int phi''^2.
    eb = tube_model(shear=False, rotary=False).solve(n_modes=6).frequencies_hz[[0, 2, 4]]
    ti = tube_model(shear=True, rotary=True).solve(n_modes=6).frequencies_hz[[0, 2, 4]]
    p = circular_tube(D, T).properties()
    G = STEEL.youngs_modulus / (2 * (1 + STEEL.poisson))
    x = np.linspace(0.0, 1.0, 200001)
    expected = []
    for bl in BETA_L:
        d0, d1, d2, d3 = _free_free_shape_derivatives(bl, x)
        rot = p["Iy"] / p["A"] * np.trapezoid(d1**2, x) / np.trapezoid(d0**2, x) / LENGTH**2
        shr = (
            STEEL.youngs_modulus
            * p["Iy"]
            / (G * p["Asy"])
            * np.trapezoid(d3**2, x)
            / np.trapezoid(d2**2, x)
            / LENGTH**2
        )
        expected.append(0.5 * (rot + shr))  # frequency drop = half the eigenvalue drop
    drop = 1 - ti / eb
    assert np.all(drop > 0)
    # the neglected terms are second order: relative to the drop they are of the size of the drop
    # itself (measured ~2x the drop: 0.6 %, 2 %, 4 % for drops of 0.3 %, 1 %, 1.9 %)
    rel = np.abs(drop / np.array(expected) - 1)
    assert np.all(rel < 2.5 * drop), (rel, drop)


@pytest.mark.parametrize("mode", [1, 2, 3])
def test_simply_supported_timoshenko_exact(mode):
    # thick short tube so that shear and rotary inertia matter (~5-15 %)
    Ds, ts, L = 0.1, 5e-3, 0.5
    b = StructureBuilder(shear=True, rotary_inertia=True)
    n0, n1 = b.add_node((0, 0, 0)), b.add_node((L, 0, 0))
    b.add_line(n0, n1, circular_tube(Ds, ts), STEEL, "beam", element_length=L / 80 * 1.0000001)
    big = 1e15
    b.add_spring(n0, None, [big, big, big, big, 0, 0], "support")  # pinned, axial + torsion held
    b.add_spring(n1, None, [0, big, big, 0, 0, 0], "support")
    m = FEModel(b.build(), {}, {}, {})
    r = m.solve(n_modes=12, method="dense")
    p = circular_tube(Ds, ts).properties()
    E, rho = STEEL.youngs_modulus, STEEL.density
    G = E / (2 * (1 + STEEL.poisson))
    kGA = G * p["Asy"]
    I, A = p["Iy"], p["A"]
    alpha = mode * np.pi / L
    a = rho**2 * I * A / kGA
    bb = -(rho * A + rho * I * (1 + E * A / kGA) * alpha**2)
    c = E * I * alpha**4
    omega2 = (-bb - np.sqrt(bb**2 - 4 * a * c)) / (2 * a)
    exact_hz = np.sqrt(omega2) / (2 * np.pi)
    eb_hz = alpha**2 * np.sqrt(E * I / (rho * A)) / (2 * np.pi)
    assert exact_hz < 0.97 * eb_hz  # the case really tests shear
    # the bending mode appears twice (y and z); torsion/axial modes lie in between
    rel = np.abs(r.frequencies_hz / exact_hz - 1)
    assert np.sort(rel)[1] < 5e-4


def test_torsion_and_axial_analytic():
    r = tube_model(n_el=60).solve(n_modes=40)
    G = STEEL.youngs_modulus / (2 * (1 + STEEL.poisson))
    f_torsion = np.sqrt(G / STEEL.density) / (2 * LENGTH)  # J = Ip for a round tube
    f_axial = np.sqrt(STEEL.youngs_modulus / STEEL.density) / (2 * LENGTH)
    for f in (f_torsion, f_axial):
        assert np.min(np.abs(r.frequencies_hz / f - 1)) < 5e-4


def test_total_mass_and_centre():
    m = tube_model()
    r = m.solve(n_modes=2)
    p = circular_tube(D, T).properties()
    assert r.mass_kg == pytest.approx(STEEL.density * p["A"] * LENGTH, rel=1e-12)
    np.testing.assert_allclose(r.centre_of_gravity, [LENGTH / 2, 0, 0], atol=1e-12)


def test_frequencies_invariant_under_rigid_rotation():
    rot = Rotation.from_euler("xyz", [0.3, -1.1, 0.7]).as_matrix()
    f0 = tube_model(n_el=20).solve(n_modes=10).frequencies_hz
    f1 = tube_model(n_el=20, rotation=rot).solve(n_modes=10).frequencies_hz
    np.testing.assert_allclose(f1, f0, rtol=1e-9)


def test_krylov_matches_dense_lapack():
    b = StructureBuilder()
    ids = b.add_pipe_run(
        [(0, 0, 0), (1.2, 0, 0), (1.6, 0.8, 0.2), (3.0, 0.9, 0.2)],
        circular_tube(D, 1e-3),
        STEEL,
        "pipe",
        bend_radii=[0.2, 0.3],
        element_length=0.1,
    )
    b.add_point_mass(ids[12], 3.0, "lump", inertia=[0.02, 0.03, 0.04], offset=(0.0, 0.05, 0.1))
    m = FEModel(b.build(), {}, {}, {})
    fk = m.solve(n_modes=12).frequencies_hz
    fd = m.solve(n_modes=12, method="dense").frequencies_hz
    np.testing.assert_allclose(fk, fd, rtol=1e-7)


def test_modes_are_mass_normalized_and_energy_shares_sum_to_one():
    m = tube_model(n_el=20, parts=2)
    r = m.solve(n_modes=6, energies=True)
    K, M, _ = m.assembler.assemble()
    phi = r.modes.shapes
    np.testing.assert_allclose(phi.T @ (M @ phi), np.eye(6), atol=1e-9)
    np.testing.assert_allclose(np.diag(phi.T @ (K @ phi)), r.modes.eigenvalues, rtol=1e-9)
    np.testing.assert_allclose(r.energies.strain_by_part.sum(axis=0), 1.0, rtol=1e-12)
    # symmetric beam in two equal halves: the first bending mode strains both halves equally
    np.testing.assert_allclose(r.energies.strain_by_part[:, 0], [0.5, 0.5], atol=1e-6)


def test_point_mass_with_offset_and_inertia_on_springs():
    # one node on a 6-DOF spring to ground carrying a mass m (inertia J) at offset e along y:
    # ux couples with rz through the offset: M = [[m, -m e], [-m e, m e^2 + Jz]], K = diag(kx, krz)
    m_, e, Jz = 2.0, 0.15, 0.01
    kx, krz = 4.0e4, 900.0
    b = StructureBuilder()
    n = b.add_node((0, 0, 0))
    b.add_point_mass(n, m_, "mass", inertia=[0.02, 0.03, Jz], offset=(0, e, 0))
    b.add_spring(n, None, [kx, 5e4, 6e4, 700.0, 800.0, krz], "spring")
    s = b.build()
    a = Assembler(s)
    K, M, _ = a.assemble()
    sol = solve_modes(K, M, 6, rigid_basis_of(s), method="dense", remove_rigid=False)
    Mxz = np.array([[m_, -m_ * e], [-m_ * e, m_ * e**2 + Jz]])
    lam = np.linalg.eigvals(np.linalg.solve(Mxz, np.diag([kx, krz])))
    expected = np.sqrt(np.sort(lam.real)) / (2 * np.pi)
    for f in expected:
        assert np.min(np.abs(sol.frequencies_hz / f - 1)) < 1e-10
    # the decoupled y translation: sqrt(ky / m)
    assert np.min(np.abs(sol.frequencies_hz / (np.sqrt(5e4 / m_) / (2 * np.pi)) - 1)) < 1e-10


def rigid_basis_of(structure):
    return rigid_body_basis(structure.nodes)
