"""The built-in exhaust model against the seed paper (Lupea 2013): mass, Table 1, mode characters,
envelope, vocabulary (parts, joints, sensors, design variables) and bad input."""

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import STEEL, StructureBuilder
from bayesupdate.models import get_model
from bayesupdate.models.exhaust import (
    DESIGN_BOUNDS,
    DESIGN_DEFAULTS,
    JOINTS,
    PARTS,
    build_exhaust_model,
    envelope,
    load_geometries,
    mode_character,
)
from bayesupdate.models.exhaust_paper import (
    DESIGN_VARIABLES,
    MEASURED_MASS_KG,
    TABLE1_FEA_HZ,
    TABLE3_INITIAL_SI,
    TABLE3_OPTIMUM_SI,
)

#: what the stored best fit reaches (studies/reproduce_paper_fe.py --check); the issue's floor is
#: RMS 5 % and every mode within 10 %
BEST_RMS = 0.024
BEST_MAX = 0.041
#: runner-up geometries: what the worst stored runner-up reaches (RMS 3.19 %, max 5.30 %)
RUNNER_RMS = 0.032
RUNNER_MAX = 0.054


@pytest.fixture(scope="module")
def model():
    return build_exhaust_model()


@pytest.fixture(scope="module")
def result(model):
    return model.solve(n_modes=12, energies=True)


def test_registered_and_design_variables(model):
    assert get_model("exhaust").parameter_names == model.parameter_names
    assert model.parameter_names == DESIGN_VARIABLES
    assert model.default_parameters() == pytest.approx(TABLE3_INITIAL_SI)
    for name, (lo, hi) in DESIGN_BOUNDS.items():
        assert lo < DESIGN_DEFAULTS[name] < hi
        assert lo < TABLE3_OPTIMUM_SI[name] < hi  # the paper's optimum is admissible


def test_mass_is_measured_mass(result):
    assert result.mass_kg == pytest.approx(MEASURED_MASS_KG, rel=0.005)


def test_table1_agreement(result):
    err = result.frequencies_hz / TABLE1_FEA_HZ - 1.0
    assert np.sqrt(np.mean(err**2)) <= BEST_RMS
    assert np.max(np.abs(err)) <= BEST_MAX


def test_first_three_mode_characters(model, result):
    chars = mode_character(model.structure, result.modes.shapes)
    # seed section 3.2: 1 horizontal two nodes, 2 vertical two nodes, 3 horizontal three nodes
    assert [c["plane"] for c in chars[:3]] == ["H", "V", "H"]
    assert [c["nodes"] for c in chars[:3]] == [2, 2, 3]


def test_envelope_of_a_small_car(model):
    env = envelope(model.structure)
    assert 3.0 <= env["length"] <= 4.2
    assert env["width"] <= 0.9


def test_model_is_small(model):
    assert model.structure.n_dof <= 360


def test_sensors_labels_and_order(model, result):
    s = model.structure
    labels = s.sensor_labels
    assert len(labels) == 40
    assert labels[:4] == ("1V", "1H", "2V", "2H")
    assert set(labels) == {f"{k}{d}" for k in range(1, 21) for d in "VH"}
    nodes_v = s.sensor_node[0::2]
    # numbered from the manifold end (x = 0) to the tail: the arc length along the path grows
    path = list(s.metadata["path_nodes"])
    position = [path.index(n) for n in nodes_v]
    assert position == sorted(position) and len(set(position)) == 20
    np.testing.assert_allclose(s.sensor_direction[0::2], np.tile([0, 0, 1.0], (20, 1)))
    np.testing.assert_allclose(s.sensor_direction[1::2], np.tile([0, 1.0, 0], (20, 1)))
    # sensor shapes are the modal translations at those DOFs
    np.testing.assert_allclose(
        result.sensor_shapes[0], result.modes.shapes[6 * s.sensor_node[0] + 2]
    )


def test_parts_joints_and_elbow(model, result):
    s = model.structure
    assert set(PARTS) | set(JOINTS) == set(s.parts)
    assert "elbow" in s.bends
    # joints are zero-length springs between coincident nodes
    for j in JOINTS:
        idx = np.flatnonzero(s.spring_part == s.parts.index(j))
        assert idx.size == 1
        a, b = s.spring_nodes[idx[0]]
        np.testing.assert_allclose(s.nodes[a], s.nodes[b])
    # the first two modes work the cold pipe between the mufflers (seed section 3.2)
    share = result.energies.strain_by_part[s.parts.index("cold_pipe"), :2]
    assert np.all(share > 0.2)


@pytest.mark.parametrize("k", range(1, 1 + len(load_geometries()["runners_up"])))
def test_runner_up_geometries(k):
    m = build_exhaust_model(k)
    r = m.solve(n_modes=12)
    err = r.frequencies_hz / TABLE1_FEA_HZ - 1.0
    assert r.mass_kg == pytest.approx(MEASURED_MASS_KG, rel=0.005)
    assert np.sqrt(np.mean(err**2)) <= RUNNER_RMS
    assert np.max(np.abs(err)) <= RUNNER_MAX
    chars = mode_character(m.structure, r.modes.shapes)
    assert [c["plane"] for c in chars[:3]] == ["H", "V", "H"]
    env = envelope(m.structure)
    assert 3.0 <= env["length"] <= 4.2 and env["width"] <= 0.9


def test_runner_ups_differ_from_best():
    data = load_geometries()
    best = data["best"]["values"]
    for r in data["runners_up"]:
        assert any(abs(r["values"][k] - best[k]) > 1e-3 * abs(best[k]) for k in best)


@pytest.mark.parametrize(
    "name, value", [("t_hot_pipe", -1e-3), ("t_cold_pipe", 0.0), ("rho_catalyst", -5.0)]
)
def test_bad_values_raise_naming_the_item(model, name, value):
    with pytest.raises(BayesUpdateError, match=name):
        model.solve({name: value})


def test_unknown_parameter_raises(model):
    with pytest.raises(BayesUpdateError, match="t_tail_pipe"):
        model.solve({"t_tail_pipe": 1e-3})


def test_unknown_geometry_choice_raises():
    with pytest.raises(BayesUpdateError, match="exhaust geometry"):
        build_exhaust_model(99)


def test_design_variables_act_on_their_parts(model):
    """Doubling the intermediate muffler's density adds its shell mass at 10,000 kg/m^3
    (A L rho from the section); a thicker main muffler adds mass; both change the modes."""
    from bayesupdate.fe.sections import section_properties

    s = model.structure
    base = model.solve(n_modes=12)
    heavier = model.solve({"rho_intermediate_muffler": 20e3}, n_modes=12)
    thicker = model.solve({"t_main_muffler": 2e-3}, n_modes=12)
    im = s.beam_part == s.part_index("intermediate_muffler")
    sec = section_properties(
        s.beam_shape[im], s.beam_width[im], s.beam_height[im], s.beam_thickness[im], s.beam_nu[im]
    )
    shell_volume = float(np.sum(sec["A"] * model.assembler.parametric["beam"].lengths[im]))
    assert heavier.mass_kg - base.mass_kg == pytest.approx(10e3 * shell_volume, rel=1e-9)
    assert thicker.mass_kg > base.mass_kg + 0.5
    assert np.all(heavier.frequencies_hz[:2] < base.frequencies_hz[:2])
    assert not np.allclose(thicker.frequencies_hz, base.frequencies_hz, rtol=1e-3)


def test_mode_character_on_a_straight_oval_tube():
    """Free-free oval tube along x, wider along y (stiffer in the horizontal plane): the modes
    alternate V, H with two, two, three, three nodes (Euler-Bernoulli free-free beam)."""
    from bayesupdate.fe import FEModel, oval_tube

    b = StructureBuilder()
    a = b.add_node((0, 0, 0))
    e = b.add_node((2.0, 0, 0))
    ids = b.add_line(a, e, oval_tube(0.06, 0.04, 1.5e-3), STEEL, "pipe", element_length=0.05)
    b.metadata["path_nodes"] = np.array(ids)
    s = b.build()
    r = FEModel(s, {}, {}, {}, name="tube").solve(n_modes=4)
    chars = mode_character(s, r.modes.shapes)
    assert [c["plane"] for c in chars] == ["V", "H", "V", "H"]
    assert [c["nodes"] for c in chars] == [2, 2, 3, 3]
    for c in chars:
        assert min(c["h_share"], 1 - c["h_share"]) < 1e-8
