"""Test points on a Nastran deck (``bayesupdate.nastran.test_points``): ``simulate --model
deck.bdf`` with the points from ``--test-points`` or a study's ``[model.test_points]`` (a SET
too), and measured directions in a GRID's output (CD) frame, on the free-free steel plate deck
of ``test_nastran_params`` (two PSHELLs, one CONM2).  GRID 5 has a rectangular CD rotated 30 deg
about z, GRID 12 a cylindrical CD about the z axis through the origin: a direction given in
either maps to basic analytically.
"""

import json
import re

import numpy as np
import pytest
from test_nastran_params import _plate

from bayesupdate.cli import main

ANGLE = np.radians(30.0)


def _deck(path, t2=0.003):
    """The plate deck of ``test_nastran_params`` (0.4 m x 0.2 m, 8 x 4 CQUAD4, GRID id =
    1 + i + 9 j) at ``path`` with GRID 5 (0.2, 0) in a CORD2R turned 30 deg about z, GRID 12
    (0.1, 0.05) in a CORD2C about the z axis, case control SET 4 = the corners and edge middles
    1, 5, 9, 37, 41, 45 and bulk SET1 6 = 2, 3, 5."""
    c, s = np.cos(ANGLE), np.sin(ANGLE)
    text = _plate(path, t2=t2).read_text()
    extra = ["CORD2R,10,0,0.,0.,0.,0.,0.,1.,+C1", f"+C1,{c:.15f},{s:.15f},0.",
             "CORD2C,11,0,0.,0.,0.,0.,0.,1.,+C2", "+C2,1.,0.,0.", "SET1,6,2,3,5"]  # fmt: skip
    text = text.replace("METHOD = 1", "METHOD = 1\nSET 4 = 1,5,9,37,41,45")
    text = text.replace("EIGRL,1,,,10", "\n".join(["EIGRL,1,,,10", *extra]))
    text = re.sub(r"^(GRID,5,.*)$", r"\1,10", text, flags=re.M)
    text = re.sub(r"^(GRID,12,.*)$", r"\1,11", text, flags=re.M)
    path.write_text(text)
    return path


def _model(deck, labels=(), points=None):
    from bayesupdate.nastran import load_nastran_model

    return load_nastran_model(str(deck), {}, labels, points)


def _simulate(capsys, argv):
    code = main(["simulate", *argv, "--noise", "0", "--modes", "8", "--json", "--force"])
    captured = capsys.readouterr()
    return code, captured


def test_simulate_a_deck_at_csv_test_points_with_a_bound_set(tmp_path, capsys):
    deck = _deck(tmp_path / "plate.bdf")
    points = tmp_path / "points.csv"
    points.write_text("point,grid\n# hangers first\n1,1\n2,7\n3,16\n4,22\n5,28\n")
    out = tmp_path / "t.uff"
    code, cap = _simulate(capsys, ["--model", str(deck), "--test-points", str(points),
                                   "--set", "PSHELL 2 T=0.0024", "--out", str(out)])  # fmt: skip
    assert code == 0, cap.err
    got = json.loads(cap.out)
    # the true structure is the deck with that thickness written in
    direct = _model(_deck(tmp_path / "d.bdf", t2=0.0024)).solve(n_modes=8).frequencies_hz
    in_band = direct[direct <= 150.0]
    np.testing.assert_allclose(got["true_frequencies_hz"], np.round(in_band, 6), rtol=1e-9)
    assert got["parameters"] == {"PSHELL 2 T": 0.0024}
    # the seed's layout over 5 points: 4 V + 5 H + 1 cross FRF, accelerometers at test points
    assert got["n_frf"] == 10 and out.is_file()
    assert {got["reference_points"]["V"], got["reference_points"]["H"]} <= {1, 2, 3, 4, 5}
    assert got["units"]["length"] == "m"


def test_simulate_takes_a_studys_points_and_a_set_and_names_the_missing_layout(tmp_path, capsys):
    deck = _deck(tmp_path / "plate.bdf")
    study = tmp_path / "study.toml"
    study.write_text(
        f'[model]\nsource = "{deck}"\n[model.test_points]\nset = 4\n"50" = 10\n'
        '[data]\nsource = "modes.h5"\n[parameters.t2]\nbinds = "PSHELL 2 T"\n'
    )
    out = tmp_path / "t.uff"
    code, cap = _simulate(capsys, ["--study", str(study), "--set", "t2=0.0024", "--out", str(out)])
    assert code == 0, cap.err
    # SET 4's six GRIDs (test node = GRID id) and test node 50 = GRID 10: 7 points, 14 FRFs
    assert json.loads(cap.out)["n_frf"] == 14
    from bayesupdate.ema.uff_io import read_uff58

    frfs = read_uff58(out)
    hit = {int(label[:-1]) for label in frfs.reference_labels}  # the hammer roves over all
    assert hit == {1, 5, 9, 37, 41, 45, 50}
    assert {int(label[:-1]) for label in frfs.response_labels} <= hit
    code, cap = _simulate(capsys, ["--model", str(deck), "--out", str(out)])
    assert code == 2 and "--test-points" in cap.err and "\n" not in cap.err.strip()
    bad = tmp_path / "bad.csv"
    bad.write_text("1,1\n2,x\n")
    code, cap = _simulate(capsys, ["--model", str(deck), "--test-points", str(bad),
                                   "--out", str(out)])  # fmt: skip
    assert code == 2 and "bad.csv:2" in cap.err
    code, cap = _simulate(capsys, ["--model", str(deck), "--test-points", str(tmp_path / "p.toml"),
                                   "--out", str(out)])  # fmt: skip
    assert code == 2 and "cannot read" in cap.err


def test_directions_in_a_grids_output_frame_map_to_basic(tmp_path):
    deck = _deck(tmp_path / "plate.bdf")
    basic = ("5+X", "5+Y", "5+Z", "12+X", "12+Y")
    output = ("5+X", "5+Y", "12+X", "12+Y", "12+Z")
    table = {"frame": "output"}
    rb = _model(deck, basic).solve(n_modes=6).sensor_shapes
    ro = _model(deck, output, table).solve(n_modes=6).sensor_shapes
    c, s = np.cos(ANGLE), np.sin(ANGLE)
    # GRID 5: CD x = (c, s, 0), y = (-s, c, 0) in basic
    np.testing.assert_allclose(ro[0], c * rb[0] + s * rb[1], atol=1e-12)
    np.testing.assert_allclose(ro[1], -s * rb[0] + c * rb[1], atol=1e-12)
    # GRID 12 at (0.1, 0.05): cylindrical CD, radial and tangential axes there
    x, y = 0.1, 0.05
    er, et = np.array([x, y]) / np.hypot(x, y), np.array([-y, x]) / np.hypot(x, y)
    np.testing.assert_allclose(ro[2], er[0] * rb[3] + er[1] * rb[4], atol=1e-12)
    np.testing.assert_allclose(ro[3], et[0] * rb[3] + et[1] * rb[4], atol=1e-12)
    # a per-point frame: only point 5 in its output frame
    per = _model(deck, ("5+X", "12+X"), {"5": {"grid": 5, "frame": "output"}}).solve(n_modes=6)
    np.testing.assert_allclose(per.sensor_shapes[0], ro[0], atol=1e-12)
    np.testing.assert_allclose(per.sensor_shapes[1], rb[3], atol=1e-12)
    # a cylindrical CD's z is the basic z here; V is +Z
    np.testing.assert_allclose(ro[4], _z(deck, 12), atol=1e-12)
    np.testing.assert_allclose(rb[2], _z(deck, 5), atol=1e-12)


def _z(deck, grid):
    return _model(deck, (f"{grid}V",)).solve(n_modes=6).sensor_shapes[0]


@pytest.mark.parametrize(
    "table, message",
    [
        ({"frame": "local"}, "frame = 'local'"),
        ({"set": 9}, "no SET1 or case control SET 9 (it has [4, 6])"),
        ({"5": {"grid": 5, "frame": "cd"}}, "frame must be 'basic' or 'output'"),
        ({"5": {"node": 5}}, "give { grid"),
        ({"abc": 5}, "key 'abc'"),
    ],
)
def test_bad_test_point_tables_are_one_line_errors(tmp_path, table, message):
    from bayesupdate.errors import BayesUpdateError

    with pytest.raises(BayesUpdateError, match=None) as info:
        _model(_deck(tmp_path / "plate.bdf"), ("5+X",), table)
    assert message in str(info.value) and "\n" not in str(info.value)


def test_sets_name_test_points(tmp_path):
    from bayesupdate.nastran.test_points import table_points

    structure = _model(_deck(tmp_path / "plate.bdf")).structure
    assert table_points(structure, {"set": 6}) == [2, 3, 5]
    assert table_points(structure, {"set": 4, "40": 3}) == [1, 5, 9, 37, 40, 41, 45]


def test_a_test_point_given_twice_in_a_csv_is_refused_with_both_lines(tmp_path):
    """A CSV row repeating a point (a typo for another number) used to move the point silently
    to the later row's GRID; it is refused, naming both lines."""
    from bayesupdate.errors import BayesUpdateError
    from bayesupdate.nastran.test_points import read_test_points

    path = tmp_path / "points.csv"
    path.write_text("point,grid\n1,5\n2,6\n1,7\n")
    with pytest.raises(BayesUpdateError, match=r"points.csv:4: point 1 is given twice \(line 2"):
        read_test_points(path)
    path.write_text("point,grid\n1,5\n2,6\n")
    assert read_test_points(path) == {"1": 5, "2": 6}
