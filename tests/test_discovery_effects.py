"""The effect library: spec parsing, where effects may sit, and what each does to the physics."""

import numpy as np
import pytest

from bayesupdate.discovery.effects import (
    EFFECT_KINDS,
    effect_locations,
    extend_model,
    parse_effect_spec,
)
from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import STEEL, Binding, FEModel, StructureBuilder, circular_tube

SEC = circular_tube(0.045, 1.5e-3)


@pytest.fixture(scope="module")
def small_model():
    """Two pipes joined by a joint spring, an elbow, and four sensor points."""
    b = StructureBuilder()
    a = b.add_pipe_run(
        [(0, 0, 0), (1.0, 0, 0), (1.4, 0.6, 0)],
        SEC,
        STEEL,
        "pipe_a",
        bend_radii=[0.15],
        bend_names=["elbow"],
        element_length=0.1,
    )
    j = b.add_node(b.node_xyz(a[-1]))
    d = np.array([0.4, 0.6, 0.0]) / np.linalg.norm([0.4, 0.6, 0.0])
    b.add_spring(
        a[-1],
        j,
        [1e8, 1e8, 1e8, 1e5, 2e4, 2e4],
        "pipe_a/pipe_b",
        frame=np.array([d, np.cross([0, 0, 1.0], d), [0, 0, 1.0]]),
    )
    c = b.add_pipe_run(
        [b.node_xyz(j), b.node_xyz(j) + (1.0, 0.2, 0.0)],
        SEC,
        STEEL,
        "pipe_b",
        start_node=j,
        element_length=0.1,
    )
    for k, node in enumerate([a[0], a[5], c[3], c[-1]], start=1):
        b.add_sensor(f"{k}V", node, "V")
        b.add_sensor(f"{k}H", node, "H")
    return FEModel(
        b.build(),
        {"t_a": Binding("pipe_a", "thickness")},
        {"t_a": 1.5e-3},
        {"t_a": (0.5e-3, 3e-3)},
        name="small",
    )


def test_parse_specs_of_the_design_vocabulary():
    e = parse_effect_spec("joint_flexibility@cold_pipe/main_muffler:k_rot=2e3")
    assert (e.kind, e.location, e.parameters) == (
        "joint_flexibility",
        "cold_pipe/main_muffler",
        {"k_rot": 2000.0},
    )
    assert parse_effect_spec("added_mass@14:m=400g").parameters == {"m": pytest.approx(0.4)}
    assert (
        parse_effect_spec("bend_flexibility@elbow:factor=2").spec()
        == "bend_flexibility@elbow:factor=2"
    )
    assert parse_effect_spec("stiffness_change@cold_pipe").parameters == {}


@pytest.mark.parametrize(
    "spec, message",
    [
        ("added_mas@14:m=0.4", "unknown kind"),
        ("added_mass:m=0.4", "expected KIND@LOCATION"),
        ("added_mass@14:mass=0.4", "no parameter"),
        ("added_mass@14:m=5", "outside the bounds"),
        ("added_mass@14:m", "name=value"),
        ("added_mass@14:m=abc", "cannot read"),
    ],
)
def test_bad_specs_are_clear_errors(spec, message):
    with pytest.raises(BayesUpdateError, match=message):
        parse_effect_spec(spec)


def test_locations(small_model):
    assert effect_locations(small_model, "added_mass") == ["1", "2", "3", "4"]
    assert effect_locations(small_model, "joint_flexibility") == ["pipe_a/pipe_b"]
    assert effect_locations(small_model, "bend_flexibility") == ["elbow"]
    assert effect_locations(small_model, "stiffness_change") == ["pipe_a", "pipe_b"]
    with pytest.raises(BayesUpdateError, match="unknown location"):
        extend_model(small_model, parse_effect_spec("added_mass@9:m=0.1"))


def test_added_mass_adds_exactly_its_mass_and_lowers_frequencies(small_model):
    base = small_model.solve(n_modes=6)
    ext = extend_model(small_model, parse_effect_spec("added_mass@4:m=0.5"))
    assert "added_mass@4:m" in ext.parameter_names and "t_a" in ext.parameter_names
    r = ext.solve(n_modes=6)
    assert r.mass_kg == pytest.approx(base.mass_kg + 0.5, rel=1e-12)
    assert np.all(r.frequencies_hz < base.frequencies_hz)
    zero = ext.solve({"added_mass@4:m": 0.0}, n_modes=6)
    np.testing.assert_allclose(zero.frequencies_hz, base.frequencies_hz, rtol=1e-10)


def test_joint_flexibility_parameter_is_the_bending_stiffness(small_model):
    base = small_model.solve(n_modes=6)
    ext = extend_model(small_model, parse_effect_spec("joint_flexibility@pipe_a/pipe_b"))
    # the modelled joint had 2e4 N m/rad in both bending planes: same value, same model
    same = ext.solve({"joint_flexibility@pipe_a/pipe_b:k_rot": 2e4}, n_modes=6)
    np.testing.assert_allclose(same.frequencies_hz, base.frequencies_hz, rtol=1e-9)
    soft = ext.solve({"joint_flexibility@pipe_a/pipe_b:k_rot": 2e2}, n_modes=6)
    assert soft.frequencies_hz[0] < 0.9 * base.frequencies_hz[0]


def test_bend_and_stiffness_factors(small_model):
    base = small_model.solve(n_modes=6).frequencies_hz
    bend = extend_model(small_model, parse_effect_spec("bend_flexibility@elbow:factor=1"))
    np.testing.assert_allclose(bend.solve(n_modes=6).frequencies_hz, base, rtol=1e-10)
    assert np.all(
        bend.solve({"bend_flexibility@elbow:factor": 4.0}, n_modes=6).frequencies_hz
        <= base * (1 + 1e-12)
    )
    stiff = extend_model(small_model, parse_effect_spec("stiffness_change@pipe_b:factor=1"))
    np.testing.assert_allclose(stiff.solve(n_modes=6).frequencies_hz, base, rtol=1e-10)


def test_soft_boundary_spring_makes_suspension_modes_and_stiffens_slightly(small_model):
    # an elastic cord (500 N/m, three translations) at one end: the three rotations about that
    # point stay rigid, the three translations become low suspension modes (elastic modes 1-3);
    # adding stiffness can only raise the other elastic frequencies (interlacing)
    base = small_model.solve(n_modes=6).frequencies_hz
    ext = extend_model(small_model, parse_effect_spec("boundary_spring@1:k=500"))
    r = ext.solve(n_modes=9)
    assert r.modes.n_rigid == 3
    assert np.all(r.frequencies_hz[:3] < 0.3 * base[0])
    assert np.all(r.frequencies_hz[3:] >= base * (1 - 1e-9))
    assert np.all(r.frequencies_hz[3:] < base * 1.05)


def test_every_kind_has_parameters_with_bounds_and_priors():
    for kind in EFFECT_KINDS.values():
        for p in kind.parameters:
            assert p.bounds[0] <= p.default <= p.bounds[1]
            assert p.prior["kind"] in ("uniform", "lognormal", "normal")
