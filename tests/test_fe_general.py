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
    # energy balance: the elements' strain energy is lambda / 2 for each mass-normalised mode
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
        _ = model.assembler  # the beam-only reduced model does not apply
