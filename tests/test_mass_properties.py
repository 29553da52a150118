"""Rigid-body mass properties (``fe.mass_properties``) against closed forms and MSC Nastran's grid
point weight generator, and measured values with units (``units.compound_unit``).

Closed forms: point masses (m = sum m_i, c = sum m_i x_i / m, J = sum m_i (|r_i|^2 I - r_i r_i^T)
+ their own rotary inertia about the CG); a uniform tube of length L along a rotated axis
(J = R diag(rho J_p L, m L^2/12 + rho I L, m L^2/12 + rho I L) R^T).  The mAEWing1 decks: the
``.f06`` GPWG block (MO about PARAM GRDPNT, C.G. relative to it, I(S) about the C.G. in
weight units lbf in^2 = inertia / WTMASS).
"""

import re
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from test_fe_analytic import LENGTH, tube_model

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import STEEL, circular_tube
from bayesupdate.fe.mass_properties import from_rigid_mass, rigid_body_mass_matrix
from bayesupdate.inference.mass_properties import model_units, parse_tables
from bayesupdate.units import compound_unit, mass_property_value

FEM = Path(__file__).resolve().parents[2] / "shared" / "data" / "gvt_maewing1" / "fem"


def test_point_masses_and_a_rotary_inertia_give_the_closed_form():
    rng = np.random.default_rng(3)
    x = rng.uniform(-2.0, 3.0, (5, 3))
    m = rng.uniform(0.5, 4.0, 5)
    own = np.array([[0.3, 0.02, -0.01], [0.02, 0.5, 0.04], [-0.01, 0.04, 0.7]])  # at node 2
    M = np.zeros((30, 30))
    for i in range(5):
        M[6 * i : 6 * i + 3, 6 * i : 6 * i + 3] = m[i] * np.eye(3)
    M[15:18, 15:18] = own
    props = from_rigid_mass(rigid_body_mass_matrix(M, x))
    c = m @ x / m.sum()
    r = x - c
    J = (
        sum(mi * (ri @ ri * np.eye(3) - np.outer(ri, ri)) for mi, ri in zip(m, r, strict=True))
        + own
    )
    assert props.mass == pytest.approx(m.sum(), rel=1e-12)
    np.testing.assert_allclose(props.cg, c, rtol=0, atol=1e-12)
    np.testing.assert_allclose(props.inertia, J, rtol=0, atol=1e-10 * np.abs(J).max())
    # Nastran's product sign (CONM2 I21, GPWG I(S)): Ixy = sum m x y about the CG
    assert props.products[0] == pytest.approx(sum(m * r[:, 0] * r[:, 1]) - own[0, 1], rel=1e-10)
    # about another point: the parallel-axis theorem against the direct sum
    p = np.array([1.0, -0.5, 2.0])
    d = x - p
    Jp = (
        sum(mi * (di @ di * np.eye(3) - np.outer(di, di)) for mi, di in zip(m, d, strict=True))
        + own
    )
    np.testing.assert_allclose(props.inertia_about(p), Jp, rtol=0, atol=1e-10 * np.abs(Jp).max())


@pytest.mark.parametrize("shear_rotary", [(False, False), (True, True)])
def test_uniform_tube_on_a_rotated_axis_gives_the_closed_form(shear_rotary):
    R = Rotation.from_euler("zyx", [30, -20, 50], degrees=True).as_matrix()
    shear, rotary = shear_rotary
    props = tube_model(n_el=7, shear=shear, rotary=rotary, rotation=R).mass_properties()
    p = circular_tube(0.045, 1.5e-3).properties()
    rho = STEEL.density
    m = rho * p["A"] * LENGTH
    bend = m * LENGTH**2 / 12 + rotary * rho * p["Iy"] * LENGTH
    J = R @ np.diag([rho * (p["Iy"] + p["Iz"]) * LENGTH, bend, bend]) @ R.T
    assert props.mass == pytest.approx(m, rel=1e-12)
    np.testing.assert_allclose(props.cg, R @ [LENGTH / 2, 0, 0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(props.inertia, J, rtol=0, atol=1e-10 * np.abs(J).max())


def gpwg(path: Path) -> dict:
    """The grid point weight generator block of an MSC ``.f06``: reference point, MO (6, 6),
    mass and C.G. (relative to the reference point) of the MASS AXIS SYSTEM rows, I(S) (3, 3)."""
    lines = path.read_text(errors="replace").splitlines()
    k = next(i for i, s in enumerate(lines) if "W E I G H T   G E N E R A T O R" in s)

    def row(line):
        return [float(v) for v in re.findall(r"-?\d\.\d+E[-+]\d+", line)]

    ref = int(lines[k + 1].split("=")[1])
    mo = np.array([row(s) for s in lines[k + 3 : k + 9]])
    axes = next(i for i in range(k, k + 40) if "MASS AXIS SYSTEM (S)" in lines[i])
    x, y, z = (row(lines[axes + j]) for j in (1, 2, 3))
    inertia = np.array([row(s) for s in lines[axes + 5 : axes + 8]])
    # the C.G. coordinate along each axis is read off the rows of the two other directions
    cg = np.array([y[1], x[2], x[3]])
    return dict(ref=ref, mo=mo, weight=x[0], cg=cg, inertia=inertia)


DECKS = {
    "v3.3": "v3.3_hati/sol103_mAEWing1_Hati_FEMv3p3.bdf",
    "v4.2": "v4.2_updated/sol103_mAEWing1_FEMv4p2.bdf",
}


@pytest.mark.skipif(not FEM.is_dir(), reason=f"shared data not found: {FEM}")
@pytest.mark.parametrize("name", list(DECKS))
def test_maewing1_mass_properties_match_msc_grid_point_weight_generator(name):
    from bayesupdate.nastran import load_nastran_model

    deck = FEM / DECKS[name]
    msc = gpwg(next(deck.parent.glob("*.f06")))
    model = load_nastran_model(str(deck))
    wtmass = model.structure.metadata["nastran"]["units"]["wtmass"]
    props = model.mass_properties()
    grids = list(model.structure.metadata["nastran"]["grid_ids"])
    ref = model.structure.nodes[grids.index(msc["ref"])]
    # the f06 prints 7 significant digits
    assert props.mass / wtmass == pytest.approx(msc["weight"], rel=1e-6)
    np.testing.assert_allclose(props.cg - ref, msc["cg"], rtol=0, atol=1e-8)
    # I(S): moments on the diagonal, products of inertia (+ integral of x y dm) off it
    weight_inertia = props.inertia / wtmass
    I_s = np.diag(np.diag(weight_inertia)) - (weight_inertia - np.diag(np.diag(weight_inertia)))
    np.testing.assert_allclose(I_s, msc["inertia"], rtol=0, atol=2e-6 * msc["inertia"].max())
    # MO: the inertia about the reference point (the SOL 200 DRESP1 WEIGHT rows 4-6)
    np.testing.assert_allclose(
        np.diag(props.inertia_about(ref)) / wtmass, np.diag(msc["mo"])[3:], rtol=1e-6
    )


@pytest.mark.parametrize(
    "text, kind, si",
    [
        ("13.76 lb", "mass", 13.76 * 0.45359237),
        ("1 lbf s^2/in", "mass", 0.45359237 * 9.80665 / 0.0254),
        ("2 slug", "mass", 2 * 0.45359237 * 9.80665 / 0.3048),
        ("0.5 t", "mass", 500.0),
        ("9560 lb in^2", "inertia", 9560 * 0.45359237 * 0.0254**2),
        ("3 lbf*s^2*in", "inertia", 3 * 0.45359237 * 9.80665 * 0.0254),
        ("8.18 in", "length", 8.18 * 0.0254),
    ],
)
def test_a_value_with_a_unit_is_its_si_value(text, kind, si):
    value, is_si = mass_property_value(text, kind, "data")
    assert is_si and value == pytest.approx(si, rel=1e-14)


def test_the_deck_units_convert_a_weight_in_lb_to_wtmass_times_weight():
    # an inch-lbf-s deck's mass unit is lbf s^2/in: 13.76 lb of mass is 13.76 / g(in/s^2) of it,
    # WTMASS x weight with WTMASS = 1/386.088 (the deck's 0.00259 is that, rounded)
    units = model_units({"mass": "lbf s^2/in", "length": "in"})
    value = mass_property_value("13.76 lb", "mass", "data.mass")[0] / units.factor("mass")
    assert value == pytest.approx(13.76 / (9.80665 / 0.0254), rel=1e-14)
    assert units.inertia == "lbf s^2 in"
    assert model_units({"mass": "t (1000 kg)", "length": "mm"}).factor("inertia") == 1e-3


@pytest.mark.parametrize(
    "value, kind, words",
    [
        ("13.76 furlong", "mass", "unknown unit 'furlong'"),
        ("13.76 lbf", "mass", "a weight; give the mass"),
        ("2 kg m", "inertia", "not a inertia unit"),
        ("kg", "mass", "cannot read"),
        ([1, 2], "length", "give a number or a string"),
    ],
)
def test_a_bad_unit_is_one_line_naming_the_known_ones(value, kind, words):
    with pytest.raises(BayesUpdateError) as info:
        mass_property_value(value, kind, "data.mass")
    message = str(info.value)
    assert words in message and "\n" not in message and message.startswith("data.mass")
    if "unit" in words:
        assert "known units: kg, g, t, lb" in message
    assert compound_unit("lb in^2", "inertia", "x") > 0


@pytest.mark.parametrize(
    "cg, inertia, words",
    [
        ({"x": "8 in"}, None, "data.cg.sd: give the sd of x"),
        ({"w": "8 in", "sd": 0.1}, None, "data.cg.w: unknown key"),
        ({"sd": 0.1}, None, "data.cg: give at least one of"),
        (None, {"ixx": 3.0, "sd": {"iyy": 1.0}}, "data.inertia.sd.iyy: no measured value"),
        (None, {"ixx": 3.0, "sd": "1 %", "about": [1, 2]}, "data.inertia.about: give"),
        ({"y": 0.0, "sd": "1 %"}, None, "y is 0; give its sd as a value"),
        (None, {"ixx": "3 kg", "sd": 0.1}, "'kg' is not a inertia unit"),
        ("8 in", None, "data.cg: must be a table"),
    ],
)
def test_bad_cg_or_inertia_tables_are_one_line(cg, inertia, words):
    with pytest.raises(BayesUpdateError) as info:
        parse_tables(cg, inertia, "data")
    assert words in str(info.value) and "\n" not in str(info.value)
