"""The shell exhaust (``exhaust_shell``): seed Table 1 at the default mesh, the 12.29 kg mass, the
beam exhaust's 20 sensor points, the five design variables bound to the real sheets, the inlet
collar, the per-element thickness factor, bad input.

Tolerances: the Table 1 targets (RMS <= 3 %, every mode within 5 %) at the default mesh
(density 32; measured RMS 1.46 %, max 2.84 %, with the main muffler's oval inlet collar fitted
by studies/exhaust_shell_fit.py); every mode pairs with the same-numbered mode of the beam
exhaust by MAC at the 40 sensor DOFs (measured diagonal 0.84-0.98).  The previous best (round
collar) keeps modes 9/10 within 3 Hz of each other (measured 1.6 Hz): the collar is what
separates them.  Mass to 1e-9 (the internals close the budget exactly); mass changes under a
design variable against the sheet areas times the change (exact, 1e-9).  Off-centre pipes and
the collar: hole rings on circles / ellipses of their size to 1e-12, sensor points to 1e-9
(construction).  Thickness factor: K, M against direct element assembly to 1e-12 of the largest
entry (round-off; the affine sum is exact).  Mesh convergence is study-only
(studies/exhaust_shell_table1.py --convergence: density 32 within 0.28 % of 64).
"""

import numpy as np
import pytest

from bayesupdate.correlation import mac_matrix
from bayesupdate.errors import BayesUpdateError
from bayesupdate.models import get_model
from bayesupdate.models.exhaust import mode_character
from bayesupdate.models.exhaust_paper import MEASURED_MASS_KG, TABLE1_FEA_HZ
from bayesupdate.models.exhaust_shell import _shell_areas
from bayesupdate.models.exhaust_shell_mesh import oval_body


@pytest.fixture(scope="module")
def shell():
    model = get_model("exhaust_shell")
    return model, model.solve(n_modes=12)


def test_table1_issue_target_at_the_default_mesh(shell):
    """RMS <= 3 %, every mode within 5 % of seed Table 1 (measured 1.46 %, 2.84 %)."""
    _, r = shell
    err = r.frequencies_hz / TABLE1_FEA_HZ - 1
    assert np.sqrt(np.mean(err**2)) <= 0.03
    assert np.abs(err).max() <= 0.05


def test_the_previous_round_collar_left_modes_9_and_10_together():
    """The runner-up with the round 40 mm collar (``geometry=3``, the previous best) puts H5 and
    V5 within 3 Hz of each other (measured 78.5/80.1 Hz at density 16); Table 1 has them 17.6 Hz
    apart, as the fitted oval collar does (measured 71.9/87.8 Hz at density 32)."""
    r = get_model("exhaust_shell", geometry=3, mesh_density=16).solve(n_modes=12)
    f = r.frequencies_hz
    assert TABLE1_FEA_HZ[8] < f[8] < f[9] < TABLE1_FEA_HZ[9] and f[9] - f[8] < 3.0


def test_modes_pair_with_the_beam_exhaust(shell):
    """Mode j of the shell model is mode j of the beam exhaust (largest MAC at the sensors)."""
    _, r = shell
    beam = get_model("exhaust").solve(n_modes=12)
    mac = mac_matrix(r.sensor_shapes, beam.sensor_shapes)
    np.testing.assert_array_equal(np.argmax(mac, axis=1), np.arange(12))


def test_first_modes_as_the_paper_describes(shell):
    """Seed section 3: mode 1 bends in the horizontal plane with two nodes, mode 2 in the
    vertical plane with two nodes, mode 3 horizontally with three nodes."""
    model, r = shell
    chars = mode_character(model.structure, r.modes.shapes)
    assert [(c["plane"], c["nodes"]) for c in chars[:3]] == [("H", 2), ("V", 2), ("H", 3)]


def test_mass_is_the_measured_one(shell):
    model, r = shell
    assert r.mass_kg == pytest.approx(MEASURED_MASS_KG, rel=1e-9)
    assert 0.0 < model.structure.metadata["mm_internal_mass_kg"] < 3.0


def test_same_twenty_sensor_points_as_the_beam_exhaust(shell):
    model, _ = shell
    beam = get_model("exhaust").structure
    s = model.structure
    assert s.sensor_labels == beam.sensor_labels and len(s.sensor_labels) == 40
    np.testing.assert_allclose(s.nodes[s.sensor_node], beam.nodes[beam.sensor_node], atol=1e-9)
    np.testing.assert_allclose(s.sensor_direction, beam.sensor_direction)


def _part_shells(model, part):
    s = model.structure
    return s.shells.part == s.part_index(part)


@pytest.mark.parametrize(
    ("name", "part", "column", "value"),
    [
        ("t_main_muffler", "main_muffler", 0, 0.577e-3),
        ("rho_catalyst", "catalyst", 2, 8.9e3),
        ("rho_intermediate_muffler", "intermediate_muffler", 2, 17.6e3),
    ],
)
def test_design_variables_act_on_every_sheet_of_their_body(shell, name, part, column, value):
    """t_main_muffler sets mantle, caps and baffles; the densities set mantle and caps; the mass
    then changes by area x (the change), exactly."""
    model, _ = shell
    mask = _part_shells(model, part)
    t0, _, rho0 = model.shell_properties()
    props = model.shell_properties({name: value})
    # a thickness is the variable times the sheet's factor (caps: the fitted gauge ratio)
    want = value * model.structure.shells.factor()[mask] if column == 0 else value
    np.testing.assert_array_equal(props[column][mask], want)
    others = ~mask
    np.testing.assert_array_equal(props[column][others], (t0, None, rho0)[column][others])
    area = _shell_areas(model.structure)[mask]
    if column == 0:
        dm = np.sum(area * rho0[mask] * (want - t0[mask]))
    else:
        dm = np.sum(area * t0[mask] * (value - rho0[mask]))
    m0 = np.sum(_shell_areas(model.structure) * (rho0 * t0))
    m1 = np.sum(_shell_areas(model.structure) * (props[2] * props[0]))
    assert m1 - m0 == pytest.approx(dm, rel=1e-9)
    assert abs(dm) > 0.1  # a real sheet: at least 100 g moves


def test_pipe_walls_bind_the_pipe_beams(shell):
    model, _ = shell
    s = model.structure
    props = model.element_properties({"t_hot_pipe": 2.08e-3, "t_cold_pipe": 1.29e-3})
    hot, cold = s.beam_part == s.part_index("hot_pipe"), s.beam_part == s.part_index("cold_pipe")
    assert hot.sum() > 5 and cold.sum() > 10
    np.testing.assert_array_equal(props.beam_thickness[hot], 2.08e-3)
    np.testing.assert_array_equal(props.beam_thickness[cold], 1.29e-3)


@pytest.mark.parametrize(
    ("options", "fragment"),
    [
        ({"mesh_density": 18}, "multiple of 4 in [16, 96]"),
        ({"mesh_density": 100}, "multiple of 4 in [16, 96]"),
        ({"mesh_density": "fine"}, "multiple of 4 in [16, 96]"),
        ({"geometry": {"mm_width": 1.0}}, "mm_width = 1.0 m is outside its plausible range"),
        ({"geometry": {"cat_cap_wall": 0.01}}, "range [0.001, 0.003] m"),
        ({"geometry": {"pipe_length": 1.0}}, "unknown quantities ['pipe_length']"),
        ({"geometry": {"mm_pipe_dy": 0.2}}, "mm_pipe_dy = 0.2 m is outside its plausible range"),
        ({"geometry": 99}, "use 'best', an index"),
        (
            {"geometry": {"mm_collar_height": 0.16, "mm_height": 0.14}},
            "inlet collar (40 x 160 mm at offset 0, 0 mm) reaches 115% of the way to the cap's rim",
        ),
    ],
)
def test_bad_input_is_one_line_with_the_range(options, fragment):
    with pytest.raises(BayesUpdateError) as exc:
        get_model("exhaust_shell", **options)
    assert fragment in str(exc.value)
    assert "\n" not in str(exc.value)


def test_off_centre_pipes_sit_on_the_caps_at_their_offset():
    """``offset``: both caps' hole rings are circles of the pipe's radius about (y, z) = offset
    from the body axis (the mantle rings' centre); the baffles' holes stay centred."""
    body = oval_body(0.39, 0.24, 0.3, 0.02, 16, baffles=(0.1, 0.2), offset=(0.06, -0.03))
    axis = body.nodes[body.rings].mean(axis=1)[:, 1:]
    np.testing.assert_allclose(axis, 0.0, atol=1e-12)
    for disc, centre in enumerate([(0.06, -0.03), (0.06, -0.03), (0.0, 0.0), (0.0, 0.0)]):
        ring = body.nodes[body.holes[disc]][:, 1:]
        np.testing.assert_allclose(np.linalg.norm(ring - centre, axis=1), 0.02, rtol=1e-12)


def test_the_inlet_collar_is_an_oval_ring_of_its_semi_axes():
    """``collar``: the inlet cap's hole ring is the ellipse of semi-axes (y, z) about the hole's
    offset; the outlet cap's stays the pipe's circle."""
    body = oval_body(0.33, 0.24, 0.3, 0.02, 16, offset=(0.01, -0.005), collar=(0.021, 0.04))
    yz = body.nodes[body.holes[0]][:, 1:] - (0.01, -0.005)
    np.testing.assert_allclose(np.sum((yz / (0.021, 0.04)) ** 2, axis=1), 1.0, rtol=1e-12)
    yz = body.nodes[body.holes[1]][:, 1:] - (0.01, -0.005)
    np.testing.assert_allclose(np.linalg.norm(yz, axis=1), 0.02, rtol=1e-12)


def test_an_offset_main_muffler_keeps_the_sensor_points_and_the_mass():
    """The body moves off the pipe line, the pipes (and the 20 sensor points on them and on
    the body's RBE3 reference line) stay where the beam exhaust has them."""
    model = get_model(
        "exhaust_shell", geometry={"mm_pipe_dy": -0.05, "mm_pipe_dz": 0.03}, mesh_density=16
    )
    s, beam = model.structure, get_model("exhaust").structure
    np.testing.assert_allclose(s.nodes[s.sensor_node], beam.nodes[beam.sensor_node], atol=1e-9)
    mm = np.unique(s.shells.quads[s.shells.part == s.part_index("main_muffler")])
    yz = s.nodes[mm][:, 1:]
    pipe_line = beam.nodes[beam.sensor_node][-1, 1:]  # the tail's line
    centre = 0.5 * (yz.max(axis=0) + yz.min(axis=0))
    np.testing.assert_allclose(centre - pipe_line, (0.05, -0.03), atol=1e-9)
    assert model.solve(n_modes=1).mass_kg == pytest.approx(MEASURED_MASS_KG, rel=1e-9)


# -- per-element thickness factor (fe.shell_model.ShellElements.thickness_factor) ---------------
def _factored_box():
    """A free steel box 0.5 x 0.4 x 0.3 m (4 x 3 x 2 quads a side): lids and walls, each lid
    quad at its own random thickness factor under the parameter t_lids (as the main muffler's
    caps under t_main_muffler), the walls' thickness and the lids' density parameters too."""
    from dataclasses import replace

    from bayesupdate.fe import Binding, FEModel, Material, StructureBuilder
    from bayesupdate.fe import shell_mesh as sm

    nodes, quads = sm.box(0.5, 0.4, 0.3, 4, 3, 2)
    lid = np.isin(np.round(nodes[quads].mean(axis=1)[:, 2], 9), (0.0, 0.3))
    b = StructureBuilder()
    steel = Material(210e9, 0.3, 7850.0, "steel")
    factor = np.random.default_rng(5).uniform(0.6, 2.0, int(lid.sum()))
    for part, sel, t in (("lids", lid, 2e-3 * factor), ("walls", ~lid, 1.5e-3)):
        used, local = np.unique(quads[sel], return_inverse=True)
        b.add_shells(nodes[used], local.reshape(-1, 4), thickness=t, material=steel, part=part,
                     offset=2e-4, nsm=0.3)  # fmt: skip
    s = b.build()
    full = np.concatenate([factor, np.ones(int((~lid).sum()))])  # lids added first
    s = replace(s, shells=replace(s.shells, thickness_factor=full))
    bindings = {
        "t_lids": Binding("lids", "thickness"),
        "t_walls": Binding("walls", "thickness"),
        "rho_lids": Binding("lids", "density"),
    }
    defaults = dict(t_lids=2e-3, t_walls=1.5e-3, rho_lids=7850.0)
    bounds = dict(t_lids=(1e-3, 3e-3), t_walls=(1e-3, 3e-3), rho_lids=(6000.0, 9000.0))
    return FEModel(s, bindings, defaults, bounds, name="box"), full


def test_thickness_factor_keeps_k_and_m_exact_sums_of_powers():
    """K, M of the model (groups' sums of theta^p factor^p K_p) and of the reduced basis's affine
    decomposition, at random parameter points, against the elements assembled directly at
    t_e = factor_e theta (1e-12 of the largest entry); the factor really changes K."""
    from bayesupdate.fe.reduced.affine import decompose
    from bayesupdate.fe.shell_model import ShellAssembly

    fe, factor = _factored_box()
    d = decompose(fe, fe.default_bounds(), 1e-9)
    eye = np.eye(fe.structure.n_dof)
    Kt, Mt = d.project(eye, d.k_stacks), d.project(eye, d.m_stacks)
    rng = np.random.default_rng(7)
    lo, hi = np.array([fe.default_bounds()[k] for k in fe.parameter_names]).T
    theta = lo + rng.random((4, lo.size)) * (hi - lo)
    cK, cM = d.coefficients(theta)
    for i, row in enumerate(theta):
        p = dict(zip(fe.parameter_names, row, strict=True))
        t, E, rho = fe.shell_properties(p)
        lids = fe.structure.shells.part == fe.structure.part_index("lids")
        np.testing.assert_allclose(t[lids], p["t_lids"] * factor[lids], rtol=1e-15)
        mesh = fe.structure.shells.mesh(fe.structure.nodes, thickness=t, E=E, rho=rho)
        K, M = (X.toarray() for X in ShellAssembly(mesh).assemble())
        Kf, Mf = (X.toarray() for X in fe.matrices(p))
        for X in (Kf, np.tensordot(cK[i], Kt, axes=1)):
            assert np.abs(X - K).max() <= 1e-12 * np.abs(K).max()
        for X in (Mf, np.tensordot(cM[i], Mt, axes=1)):
            assert np.abs(X - M).max() <= 1e-12 * np.abs(M).max()
    flat = fe.structure.shells.mesh(fe.structure.nodes, thickness=np.where(lids, p["t_lids"], t))
    assert np.abs(ShellAssembly(flat).assemble()[0].toarray() - K).max() > 0.1 * np.abs(K).max()
