"""Shells inside ``Structure`` / ``FEModel``: mixed beams + shells + supports, parameters bound to
shell thickness (exact powers), modulus and density, shell energies, bad shell input.

References that could be wrong: a fresh structure built at the parameter values (direct element
matrices, not the power sums), the exact scalings f ~ sqrt(E) and f ~ 1/sqrt(rho) of a
one-material model, and the energy balance sum_e U_e = lambda / 2.
"""

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import Binding, FEModel, Material, StructureBuilder, circular_tube
from bayesupdate.fe import shell_mesh as sm

AL = Material(70e9, 0.33, 2700.0, "aluminium")
SEC = circular_tube(0.03, 2e-3)


def _stiffened_plate(t_skin=2e-3, t_web=3e-3, rho_web=2700.0):
    """A 0.6 x 0.4 m skin clamped on x = 0, a web along y = 0.2 (shells), a tube along the free
    edge (beams) and a point mass on an RBE2."""
    b = StructureBuilder()
    nodes, q, _ = sm.plate(0.6, 0.4, 12, 8)
    ids = b.add_shells(nodes, q, thickness=t_skin, material=AL, part="skin")
    web_nodes, wq, _ = sm.plate(0.6, 0.05, 12, 2)
    web = np.column_stack([web_nodes[:, 0], np.full(len(web_nodes), 0.2), web_nodes[:, 1]])
    web_mat = Material(70e9, 0.33, rho_web)
    b.add_shells(web, wq, thickness=t_web, material=web_mat, part="web")
    edge = ids[np.isclose(nodes[:, 0], 0.6)]
    for a, c in zip(edge[:-1], edge[1:], strict=True):
        b.add_beam(a, c, SEC, AL, "tube")
    for n in ids[np.isclose(nodes[:, 0], 0.0)]:
        b.add_support(n)
    m = b.add_node((0.6, 0.2, 0.05))
    b.add_point_mass(m, 0.3, "mass")
    b.add_rbe2(ids[np.argmin(np.linalg.norm(nodes - [0.6, 0.2, 0], axis=1))], [m])
    return b.build()


BINDINGS = {
    "t_skin": Binding("skin", "thickness"),
    "t_web": Binding("web", "thickness"),
    "rho_web": Binding("web", "density"),
}
DEFAULTS = {"t_skin": 2e-3, "t_web": 3e-3, "rho_web": 2700.0}
BOUNDS = {"t_skin": (1e-3, 4e-3), "t_web": (1e-3, 6e-3), "rho_web": (1000.0, 8000.0)}


def test_thickness_and_density_parameters_equal_a_structure_built_at_those_values():
    s = _stiffened_plate()
    model = FEModel(s, BINDINGS, DEFAULTS, BOUNDS)
    rng = np.random.default_rng(7)
    for _ in range(2):
        p = {k: rng.uniform(*BOUNDS[k]) for k in BINDINGS}
        r = model.solve(p, n_modes=8)
        fresh = _stiffened_plate(p["t_skin"], p["t_web"], p["rho_web"])
        f_ref = FEModel(fresh, {}, {}, {}).solve(n_modes=8)
        np.testing.assert_allclose(r.frequencies_hz, f_ref.frequencies_hz, rtol=1e-9)
        assert r.mass_kg == pytest.approx(f_ref.mass_kg, rel=1e-12)
    assert r.modes.n_rigid == 0


def test_modulus_and_density_of_a_one_material_shell_model_scale_exactly():
    b = StructureBuilder()
    nodes, quads = sm.box(0.5, 0.3, 0.2, 5, 3, 2)
    b.add_shells(nodes, quads, thickness=1.5e-3, material=AL, part="box")
    s = b.build()
    names = {"E": Binding("box", "modulus_factor"), "rho": Binding("box", "density")}
    model = FEModel(s, names, {"E": 1.0, "rho": 2700.0}, {"E": (0.5, 2), "rho": (1e3, 1e4)})
    r0 = model.solve(n_modes=6)
    r1 = model.solve({"E": 1.3, "rho": 2000.0}, n_modes=6)
    assert r0.modes.n_rigid == 6
    np.testing.assert_allclose(
        r1.frequencies_hz, r0.frequencies_hz * np.sqrt(1.3 * 2700.0 / 2000.0), rtol=1e-9
    )
    area = 2 * (0.5 * 0.3 + 0.5 * 0.2 + 0.3 * 0.2)
    assert r0.mass_kg == pytest.approx(2700.0 * 1.5e-3 * area, rel=1e-12)
    np.testing.assert_allclose(r0.centre_of_gravity, [0.25, 0.15, 0.1], atol=1e-12)


def test_shell_energies_sum_to_the_eigenvalue_and_densities_integrate_to_the_shares():
    s = _stiffened_plate()
    model = FEModel(s, BINDINGS, DEFAULTS, BOUNDS)
    r = model.solve(n_modes=5, energies=True)
    en = r.energies
    np.testing.assert_allclose(en.strain_by_part.sum(axis=0), 1.0, rtol=1e-12)
    skin = s.shells.part == s.part_index("skin")
    np.testing.assert_allclose(
        en.shell_strain[skin].sum(axis=0), en.strain_by_part[s.part_index("skin")], rtol=1e-12
    )
    area = en.shell_strain[:1] / en.shell_strain_density[:1]
    np.testing.assert_allclose(area, (0.6 / 12) * (0.4 / 8), rtol=1e-12)
    # energy balance: the elements' strain energy is lambda / 2 for each mass-normalized mode
    g = model._general  # noqa: SLF001 - the model's own matrices
    K, M, _ = g.assemble(model.element_properties(), model.shell_properties())
    phi = r.modes.shapes
    np.testing.assert_allclose(np.einsum("im,im->m", phi, K @ phi), r.modes.eigenvalues, rtol=1e-8)
    np.testing.assert_allclose(np.einsum("im,im->m", phi, M @ phi), 1.0, rtol=1e-8)


def test_bad_shell_input_names_the_part_and_element():
    b = StructureBuilder()
    nodes, q, _ = sm.plate(1.0, 1.0, 2, 2)
    with pytest.raises(BayesUpdateError, match=r"part 'skin'.*quad 1 has thickness = -0.001"):
        b.add_shells(nodes, q, thickness=[1e-3, -1e-3, 1e-3, 1e-3], material=AL, part="skin")
    bad = q.copy()
    bad[2, 1] = bad[2, 0]
    with pytest.raises(BayesUpdateError, match=r"part 'skin'.*quad 2 repeats a node"):
        b.add_shells(nodes, bad, thickness=1e-3, material=AL, part="skin")
    b.add_shells(nodes, q, thickness=1e-3, material=AL, part="skin")
    model = FEModel(b.build(), {"t": Binding("skin", "thickness")}, {"t": 1e-3}, {"t": (0, 1)})
    with pytest.raises(BayesUpdateError, match=r"parameter t = 0.0: thickness must be"):
        model.solve({"t": 0.0})
    with pytest.raises(BayesUpdateError, match=r"has shells, supports or rigid elements"):
        _ = model.assembler  # the banded beam-only assembler does not apply


# -- springs to ground: suspension modes apart, stiff springs converged ---------------------------
def _plate_on_springs(k, n=16):
    """A 1.0 x 0.8 m, 4 mm aluminium plate (n x n quads, 6 (n + 1)^2 DOFs: above the dense
    limit, so the Lanczos path runs) on translational springs k [N/m] at its four corners."""
    nodes, quads, _ = sm.plate(1.0, 0.8, n, n)
    b = StructureBuilder()
    ids = b.add_shells(nodes, quads, thickness=4e-3, material=AL, part="plate")
    for corner in ids[[0, n, (n + 1) * n, (n + 1) ** 2 - 1]]:
        b.add_spring(corner, None, [k, k, k, 0, 0, 0], "ground")
    return FEModel(b.build(), {"k": Binding("ground", "stiffness_factor")}, {"k": 1.0},
                   {"k": (0.1, 10.0)})  # fmt: skip


def test_suspension_modes_on_soft_ground_springs_are_elastic_modes():
    """Soft springs (k = 100 N/m) in three translations at the four corners: no rigid mode is left
    and the six suspension modes, rigid-shaped with their energy in the springs, are elastic
    modes 1-6.  In-plane the plate is nearly rigid against the springs, so two translations sit at
    sqrt(4 k / m) and the in-plane turn at sqrt(12 k / m) (J = m (a^2 + b^2) / 12,
    k_theta = k (a^2 + b^2)), up to the in-plane compliance k / (E t) ~ 4e-7 (measured 1.2e-6 on
    the translations).  Out of plane the plate bends under its bounce and tilts (0.8 % lower),
    which is why those are not compared."""
    model = _plate_on_springs(100.0)
    r = model.solve(n_modes=8)
    dense = model.solve(n_modes=8, method="dense")
    m = 2700.0 * 4e-3 * 0.8
    assert r.modes.n_rigid == 0 and dense.modes.n_rigid == 0
    f_susp = r.frequencies_hz[:6]
    f_trans, f_turn = np.sqrt(4 * 100.0 / m) / (2 * np.pi), np.sqrt(12 * 100.0 / m) / (2 * np.pi)
    assert np.sum(np.isclose(f_susp, f_trans, rtol=1e-5)) == 2
    assert np.sum(np.isclose(f_susp, f_turn, rtol=1e-5)) == 1
    assert r.frequencies_hz[6] > 8 * f_susp.max()  # the plate's own modes start at 16.6 Hz
    np.testing.assert_allclose(r.frequencies_hz[6:], dense.frequencies_hz[6:], rtol=1e-9)
    np.testing.assert_allclose(f_susp, dense.frequencies_hz[:6], rtol=1e-6)
    stiffer = model.solve({"k": 4.0}, n_modes=8)  # the springs' parameter scales them: f ~ sqrt(k)
    assert np.sum(np.isclose(stiffer.frequencies_hz[:6], 2 * f_trans, rtol=1e-5)) == 2


def test_sparse_path_finds_suspension_modes_like_the_beam_path():
    """A beam portal on soft ground springs: the beam path (fe.eigensolve, checked against
    OpenSees in test_fe_peer_opensees) and the sparse path agree that no mode is rigid and on
    every frequency, the six suspension modes included (to 1e-9 against the beam path's dense
    LAPACK; its banded Krylov stops at a 1e-4 residual, measured 7e-7 off on the suspension
    modes here)."""
    b = StructureBuilder()
    tube = circular_tube(0.06, 3e-3)
    feet = [b.add_node((0, 0, 0)), b.add_node((2, 0, 0))]
    tops = [b.add_node((0, 0, 1.5)), b.add_node((2, 0, 1.5))]
    for foot, top in zip(feet, tops, strict=True):
        b.add_line(foot, top, tube, AL, "columns")
        b.add_spring(foot, None, [1e3, 1e3, 1e3, 1e2, 1e2, 1e2], "ground")
    b.add_line(tops[0], tops[1], tube, AL, "beam")
    model = FEModel(b.build(), {}, {}, {})
    banded, sparse = model.solve(n_modes=12), model.solve(n_modes=12, method="sparse")
    dense = model.solve(n_modes=12, method="dense")
    assert banded.modes.n_rigid == sparse.modes.n_rigid == dense.modes.n_rigid == 0
    np.testing.assert_allclose(sparse.frequencies_hz, dense.frequencies_hz, rtol=1e-9)
    np.testing.assert_allclose(sparse.frequencies_hz[:6], banded.frequencies_hz[:6], rtol=1e-5)
    np.testing.assert_allclose(sparse.frequencies_hz[6:], banded.frequencies_hz[6:], rtol=1e-7)


def test_very_stiff_ground_springs_converge_as_tightly_as_dense_and_equal_pins():
    """k = 1e13 N/m (K spans ~1e13 / 1e2 in its diagonal): the Lanczos path matches dense LAPACK
    to 1e-9 (measured 3e-11) and pinned corners (exact elimination) to 1e-6; no mode is
    taken for a suspension mode."""
    model = _plate_on_springs(1e13)
    r = model.solve(n_modes=8)
    dense = model.solve(n_modes=8, method="dense")
    assert r.modes.n_rigid == 0
    np.testing.assert_allclose(r.frequencies_hz, dense.frequencies_hz, rtol=1e-9)
    nodes, quads, _ = sm.plate(1.0, 0.8, 16, 16)
    b = StructureBuilder()
    ids = b.add_shells(nodes, quads, thickness=4e-3, material=AL, part="plate")
    for corner in ids[[0, 16, 17 * 16, 17**2 - 1]]:
        b.add_support(corner, "123")
    pinned = FEModel(b.build(), {}, {}, {}).solve(n_modes=8)
    np.testing.assert_allclose(r.frequencies_hz, pinned.frequencies_hz, rtol=1e-6)


def test_a_rigid_body_on_springs_keeps_its_modes_on_the_sparse_path():
    """A point mass on springs to ground has only rigid-shaped modes: they are its modes
    (f = sqrt(k / m) / 2 pi), not suspension modes to drop (the banded beam path refuses it)."""
    b = StructureBuilder()
    n = b.add_node((0.3, 0.2, 0.1))
    b.add_point_mass(n, 2.0, "m", inertia=np.diag([0.01, 0.02, 0.03]))
    b.add_spring(n, None, [100.0, 400.0, 900.0, 1.0, 4.0, 9.0], "k")
    r = FEModel(b.build(), {}, {}, {}).solve(n_modes=6, method="sparse")
    k_over_m = [1.0 / 0.01, 4.0 / 0.02, 9.0 / 0.03, 100.0 / 2, 400.0 / 2, 900.0 / 2]
    np.testing.assert_allclose(
        r.frequencies_hz, np.sqrt(sorted(k_over_m)) / (2 * np.pi), rtol=1e-12
    )
    assert r.modes.n_rigid == 0
