"""``bayesupdate discover`` on a Nastran deck: the user's path, through the CLI.

A free-free steel plate deck (two PSHELLs of different thickness, so no mirror symmetry) with
six test points.  The "true" structure is the same deck with a CONM2 typed in at one test
point's GRID; its test is simulated (``simulate --model true.bdf --test-points``) and
identified.  ``discover`` on the study (the deck without that CONM2, one bound thickness) must
name an added mass at that point, with the CONM2's mass.  With PSHELL 2 given its own MAT1 at
0.8 x E instead, it must name a stiffness change of PSHELL 2 by 0.8.  On a test of the deck
itself it must name nothing.
"""

import json

import pytest

from bayesupdate.cli import main

NX, NY = 6, 3
#: test point -> GRID (id = 1 + i + 7 j): the corners and two inner GRIDs
POINTS = {1: 1, 2: 7, 3: 22, 4: 28, 5: 10, 6: 19}
HIDDEN_POINT, HIDDEN_KG = 6, 0.02


def _plate(path, extra=()):
    """0.3 m x 0.15 m, PSHELL 1 (0.4 mm) on the left half, PSHELL 2 (0.6 mm) on the right."""
    lines = ["SOL 103", "CEND", "METHOD = 1", "BEGIN BULK", "EIGRL,1,,,10"]
    for j in range(NY + 1):
        for i in range(NX + 1):
            lines.append(f"GRID,{1 + i + 7 * j},,{0.05 * i:.6f},{0.05 * j:.6f},0.")
    for j in range(NY):
        for i in range(NX):
            g = 1 + i + 7 * j
            lines.append(f"CQUAD4,{1 + i + NX * j},{1 if i < NX // 2 else 2},{g},{g + 1},"
                         f"{g + 8},{g + 7}")  # fmt: skip
    lines += ["PSHELL,1,7,0.0004,7,,7", "PSHELL,2,7,0.0006,7,,7", "MAT1,7,2.1e11,,0.3,7850.",
              *extra, "ENDDATA"]  # fmt: skip
    path.write_text("\n".join(lines) + "\n")
    return path


def _cli_json(capsys, argv) -> dict:
    code = main(argv)
    captured = capsys.readouterr()
    assert code == 0, captured.err
    return json.loads(captured.out.strip().splitlines()[-1])


def _discover(tmp_path, capsys, truth_deck) -> dict:
    points = tmp_path / "points.csv"
    points.write_text("point,grid\n" + "".join(f"{k},{g}\n" for k, g in POINTS.items()))
    uff, modes = tmp_path / "test.uff", tmp_path / "modes.h5"
    _cli_json(capsys, ["simulate", "--model", str(truth_deck), "--test-points", str(points),
                       "--noise", "0.01", "--seed", "0", "--out", str(uff), "--json"])  # fmt: skip
    identified = _cli_json(capsys, ["identify", str(uff), "--out", str(modes), "--json"])
    assert len(identified["modes"]) >= 5
    rows = "\n".join(f'"{k}" = {g}' for k, g in POINTS.items())
    study = tmp_path / "study.toml"
    study.write_text(
        f'[model]\nsource = "{_plate(tmp_path / "plate.bdf")}"\n[model.test_points]\n{rows}\n'
        f'[data]\nsource = "{modes}"\n'
        '[parameters.t1]\nbinds = "PSHELL 1 T"\nbounds = [0.00025, 0.0006]\n'
    )
    return _cli_json(capsys, ["discover", str(study), "--json"])


def test_discover_names_a_hidden_mass_at_its_test_point(tmp_path, capsys):
    grid = POINTS[HIDDEN_POINT]
    truth = _plate(tmp_path / "true.bdf", [f"CONM2,900,{grid},,{HIDDEN_KG}"])
    out = _discover(tmp_path, capsys, truth)
    assert out["verdict"] == "explained"
    named = out["named_effect"]
    assert (named["kind"], named["location"]) == ("added_mass", str(HIDDEN_POINT))
    assert named["parameters"]["m"] == pytest.approx(HIDDEN_KG, rel=0.05)
    assert out["design_after"]["t1"] == pytest.approx(0.0004, rel=0.01)
    # added masses and boundary springs at every test point, stiffness changes on both PSHELLs
    scanned = {(c["kind"], c["location"]) for c in out["candidates"]}
    assert {("added_mass", str(k)) for k in POINTS} <= scanned
    assert {("boundary_spring", str(k)) for k in POINTS} <= scanned
    assert {("stiffness_change", "PSHELL 1"), ("stiffness_change", "PSHELL 2")} <= scanned
    assert out["gap_after"] < 0.1 * out["gap_before"]


def test_discover_names_a_softer_pshell(tmp_path, capsys):
    # the true deck gives PSHELL 2 its own MAT1 with 0.8 x E
    truth = _plate(tmp_path / "true.bdf", ["MAT1,8,1.68e11,,0.3,7850."])
    truth.write_text(truth.read_text().replace("PSHELL,2,7,0.0006,7,,7", "PSHELL,2,8,0.0006,8,,8"))
    out = _discover(tmp_path, capsys, truth)
    assert out["verdict"] == "explained"
    named = out["named_effect"]
    assert (named["kind"], named["location"]) == ("stiffness_change", "PSHELL 2")
    assert named["parameters"]["factor"] == pytest.approx(0.8, rel=0.01)


def test_discover_names_nothing_on_a_test_of_the_deck_itself(tmp_path, capsys):
    out = _discover(tmp_path, capsys, _plate(tmp_path / "true.bdf"))
    assert out["verdict"] == "no discrepancy"
    assert out["named_effect"] is None and out["effects"] == []
