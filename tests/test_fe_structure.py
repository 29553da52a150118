"""Pipe runs, bends, the B31.3 elbow factor, parameter bindings and bad input of the FE layer."""

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import STEEL, Binding, FEModel, StructureBuilder, circular_tube
from bayesupdate.fe.elements.beam import bend_flexibility_factor

SEC = circular_tube(0.045, 1.5e-3)


def l_pipe(elbow=True, radius=0.2):
    b = StructureBuilder()
    b.add_pipe_run(
        [(0, 0, 0), (1.0, 0, 0), (1.0, 1.0, 0)],
        SEC,
        STEEL,
        "pipe",
        bend_radii=[radius],
        bend_names=["elbow"],
        element_length=0.1,
        elbow_flexibility=elbow,
    )
    return b.build()


def test_bend_is_an_arc_of_the_given_radius():
    s = l_pipe()
    bend_nodes = np.unique(s.beam_nodes[s.beam_bend == s.bends.index("elbow")])
    centre = np.array([0.8, 0.2, 0.0])
    np.testing.assert_allclose(
        np.linalg.norm(s.nodes[bend_nodes] - centre, axis=1), 0.2, rtol=1e-12
    )
    # 90 degrees in <= 15 degree pieces
    assert np.sum(s.beam_bend == 0) == 6


def test_b31_3_flexibility_factor():
    t, R, D = 1.5e-3, 0.2, 0.045
    r = (D - t) / 2
    h = t * R / r**2
    assert bend_flexibility_factor(np.array([t]), np.array([R]), np.array([D]))[0] == pytest.approx(
        1.65 / h, rel=1e-12
    )
    # a stiff (thick, large-radius) bend is not made stiffer than a straight pipe: k >= 1
    assert bend_flexibility_factor(np.array([8e-3]), np.array([5.0]), np.array([0.045]))[0] == 1


def test_elbow_flexibility_softens_in_plane_bending_only_through_the_bend():
    f_rigid = FEModel(l_pipe(elbow=False), {}, {}, {}).solve(n_modes=4).frequencies_hz
    f_flex = FEModel(l_pipe(elbow=True), {}, {}, {}).solve(n_modes=4).frequencies_hz
    assert np.all(f_flex < f_rigid)
    assert np.all(f_flex > 0.5 * f_rigid)


def test_bindings_change_what_they_should():
    s = l_pipe()
    m = FEModel(
        s,
        {
            "t": Binding("pipe", "thickness"),
            "rho": Binding("pipe", "density"),
            "k": Binding("elbow", "bend_factor"),
        },
        {"t": 1.5e-3, "rho": 7850.0, "k": 1.0},
        {"t": (0.5e-3, 3e-3), "rho": (2e3, 2e4), "k": (0.5, 5.0)},
    )
    base = m.solve(n_modes=4)
    heavy = m.solve({"rho": 2 * 7850.0}, n_modes=4)
    # density scales M only: frequencies by 1/sqrt(2), mass by 2
    np.testing.assert_allclose(heavy.frequencies_hz, base.frequencies_hz / np.sqrt(2), rtol=1e-8)
    assert heavy.mass_kg == pytest.approx(2 * base.mass_kg, rel=1e-12)
    soft = m.solve({"k": 3.0}, n_modes=4)
    assert np.all(soft.frequencies_hz <= base.frequencies_hz * (1 + 1e-12))
    assert soft.mass_kg == pytest.approx(base.mass_kg, rel=1e-14)


def test_sensors_read_translations_along_their_direction():
    b = StructureBuilder()
    ids = b.add_pipe_run([(0, 0, 0), (2.0, 0, 0)], SEC, STEEL, "pipe", element_length=0.1)
    b.add_sensor("1V", ids[0], "V")
    b.add_sensor("1H", ids[0], "H")
    m = FEModel(b.build(), {}, {}, {})
    r = m.solve(n_modes=4)
    phi = r.modes.shapes
    np.testing.assert_allclose(r.sensor_shapes[0], phi[6 * ids[0] + 2], rtol=1e-14)
    np.testing.assert_allclose(r.sensor_shapes[1], phi[6 * ids[0] + 1], rtol=1e-14)
    assert r.sensor_labels == ("1V", "1H")


@pytest.mark.parametrize(
    "params, message",
    [
        ({"t": -1e-3}, "thickness"),
        ({"t": 0.0}, "thickness"),
        ({"rho": 0.0}, "density"),
        ({"rho": float("nan")}, "density"),
        ({"t": 0.03}, "thickness"),
        ({"typo": 1.0}, "typo"),
    ],
)
def test_bad_parameter_values_name_the_item(params, message):
    s = l_pipe()
    m = FEModel(
        s,
        {"t": Binding("pipe", "thickness"), "rho": Binding("pipe", "density")},
        {"t": 1.5e-3, "rho": 7850.0},
        {"t": (0.5e-3, 3e-3), "rho": (2e3, 2e4)},
    )
    with pytest.raises(BayesUpdateError, match=message):
        m.solve(params)


def test_bend_radius_smaller_than_pipe_radius_is_rejected():
    with pytest.raises(BayesUpdateError, match="bend radius"):
        l_pipe(radius=0.01)


def test_disconnected_structure_is_rejected():
    b = StructureBuilder()
    b.add_pipe_run([(0, 0, 0), (1.0, 0, 0)], SEC, STEEL, "a")
    b.add_pipe_run([(0, 1, 0), (1.0, 1, 0)], SEC, STEEL, "b")
    with pytest.raises(BayesUpdateError, match="disconnected"):
        b.build()


def test_unknown_part_or_property_is_rejected():
    s = l_pipe()
    with pytest.raises(BayesUpdateError, match="unknown part"):
        FEModel(s, {"t": Binding("muffler", "thickness")}, {"t": 1e-3}, {"t": (1e-4, 1e-2)})
    with pytest.raises(BayesUpdateError, match="unknown property"):
        FEModel(s, {"t": Binding("pipe", "colour")}, {"t": 1e-3}, {"t": (1e-4, 1e-2)})


def test_reassembly_reusing_unchanged_beams_equals_a_fresh_assembly():
    s = l_pipe()
    bindings = {"t": Binding("pipe", "thickness"), "rho": Binding("pipe", "density")}
    defaults, bounds = {"t": 1.5e-3, "rho": 7850.0}, {"t": (5e-4, 3e-3), "rho": (2e3, 2e4)}
    m = FEModel(s, bindings, defaults, bounds)
    for point in ({"t": 2e-3}, {"t": 2e-3, "rho": 9e3}, {"t": 1e-3}):
        fresh = FEModel(s, bindings, defaults, bounds).solve(point, n_modes=6)
        np.testing.assert_array_equal(
            m.solve(point, n_modes=6).frequencies_hz, fresh.frequencies_hz
        )
