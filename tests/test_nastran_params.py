"""Parameters bound to a Nastran deck's fields (``bayesupdate.nastran.bindings``), test points on
GRIDs, and ``--write-bdf``, on a free-free steel plate deck written here (8 x 4 CQUAD4, left half
PSHELL 1, right half PSHELL 2, one CONM2).  A bound thickness must give the frequencies of the
deck with that thickness written in (the direct assembly); calibrate must recover perturbed
thicknesses from their frequencies, and the written deck must give the calibrated frequencies.
"""

import json

import numpy as np
import pytest

from bayesupdate.cli import main

NX, NY = 8, 4


def _plate(path, t1=0.002, t2=0.003, mass=0.05):
    """A plate deck (SI) at ``path``; GRID id = 1 + i + 9 j on a 0.4 m x 0.2 m grid."""
    lines = ["SOL 103", "CEND", "METHOD = 1", "BEGIN BULK", "EIGRL,1,,,10"]

    def gid(i, j):
        return 1 + i + (NX + 1) * j

    for j in range(NY + 1):
        for i in range(NX + 1):
            lines.append(f"GRID,{gid(i, j)},,{0.4 * i / NX:.6f},{0.2 * j / NY:.6f},0.")
    eid = 1
    for j in range(NY):
        for i in range(NX):
            pid = 1 if i < NX // 2 else 2
            nodes = f"{gid(i, j)},{gid(i + 1, j)},{gid(i + 1, j + 1)},{gid(i, j + 1)}"
            lines.append(f"CQUAD4,{eid},{pid},{nodes}")
            eid += 1
    lines += [f"PSHELL,1,7,{t1},7,,7", f"PSHELL,2,7,{t2},7,,7", "MAT1,7,2.1e11,,0.3,7850.",
              f"CONM2,500,1,,{mass}", "ENDDATA"]  # fmt: skip
    path.write_text("\n".join(lines) + "\n")
    return path


def _model(deck, parameters, labels=(), points=None):
    from bayesupdate.nastran import load_nastran_model

    return load_nastran_model(str(deck), parameters, labels, points)


def _freqs(deck, n=5):
    return _model(deck, {}).solve(n_modes=n).frequencies_hz


def test_bound_thickness_modulus_and_mass_equal_the_deck_written_with_them(tmp_path):
    deck = _plate(tmp_path / "plate.bdf")
    params = {
        "t2": {"binds": "PSHELL 2 T"},
        "e": {"binds": "MAT1 7 E scale"},
        "m": {"binds": "CONM2 500 M"},
    }
    model = _model(deck, params)
    assert model.default_parameters() == {"t2": 0.003, "e": 1.0, "m": 0.05}
    np.testing.assert_allclose(model.solve(n_modes=5).frequencies_hz, _freqs(deck), rtol=1e-10)
    got = model.solve({"t2": 0.0021, "e": 1.1, "m": 0.2}, n_modes=5)
    direct = _plate(tmp_path / "direct.bdf", t2=0.0021, mass=0.2)
    text = direct.read_text().replace("MAT1,7,2.1e11", "MAT1,7,2.31e11")
    direct.write_text(text)
    np.testing.assert_allclose(got.frequencies_hz, _freqs(direct), rtol=1e-9)
    assert got.mass_kg == pytest.approx(0.4 * 0.1 * 0.002 * 7850 + 0.4 * 0.1 * 0.0021 * 7850 + 0.2)


def test_modes_set_on_a_deck_binds_the_field_as_the_deck_written_with_it(tmp_path, capsys):
    deck = _plate(tmp_path / "plate.bdf")
    argv = ["modes", "--model", str(deck), "--set", "PSHELL 2 T=0.0021", "--set"]
    assert main([*argv, "MAT1 7 E scale=1.1", "--modes", "5", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    direct = _plate(tmp_path / "direct.bdf", t2=0.0021)
    direct.write_text(direct.read_text().replace("MAT1,7,2.1e11", "MAT1,7,2.31e11"))
    np.testing.assert_allclose(got["frequencies_hz"], _freqs(direct), rtol=1e-6)
    assert got["mass_kg"] == pytest.approx(
        0.4 * 0.1 * 0.002 * 7850 + 0.4 * 0.1 * 0.0021 * 7850 + 0.05
    )
    assert main(["modes", "--model", str(deck), "--set", "PSHELL 2 T=2mm"]) == 2
    assert "a plain number in the deck's units" in capsys.readouterr().err


def test_several_ids_and_density_scale(tmp_path):
    deck = _plate(tmp_path / "plate.bdf", t1=0.002, t2=0.002)
    model = _model(deck, {"t": {"binds": "PSHELL 1,2 T"}, "rho": {"binds": "MAT1 7 RHO scale"}})
    r = model.solve({"t": 0.0025, "rho": 0.5}, n_modes=3)
    # all shells at 2.5 mm, density halved: shell mass 0.08 m^2 x 2.5 mm x 3925 kg/m^3 + CONM2
    assert r.mass_kg == pytest.approx(0.08 * 0.0025 * 3925 + 0.05)
    direct = _plate(tmp_path / "d.bdf", t1=0.0025, t2=0.0025)
    direct.write_text(direct.read_text().replace(",7850.", ",3925."))
    np.testing.assert_allclose(r.frequencies_hz, _freqs(direct, 3), rtol=1e-9)


def test_test_labels_map_to_grids_and_through_the_table(tmp_path):
    deck = _plate(tmp_path / "plate.bdf")
    model = _model(deck, {}, ("1V", "45+Z", "9H", "7-X"), {"7": 9})
    r = model.solve(n_modes=4)
    full = r.modes.shapes
    grid_ids = model.structure.metadata["nastran"]["grid_ids"]
    node = {int(g): i for i, g in enumerate(grid_ids)}
    expect = [full[6 * node[1] + 2], full[6 * node[45] + 2], full[6 * node[9] + 1],
              -full[6 * node[9] + 0]]  # fmt: skip
    np.testing.assert_allclose(r.sensor_shapes, np.array(expect), atol=1e-12)


def test_calibrate_recovers_thicknesses_and_write_bdf_round_trip(tmp_path, capsys):
    deck = _plate(tmp_path / "plate.bdf")
    truth = _model(deck, {"t1": {"binds": "PSHELL 1 T"}, "t2": {"binds": "PSHELL 2 T"}})
    target = truth.solve({"t1": 0.0024, "t2": 0.0027}, n_modes=5).frequencies_hz
    study = tmp_path / "study.toml"
    study.write_text(
        f'[model]\nsource = "{deck}"\n[data]\nfrequencies_hz = {list(map(float, target))}\n'
        '[parameters.t1]\nbinds = "PSHELL 1 T"\nbounds = [0.001, 0.004]\n'
        '[parameters.t2]\nbinds = "PSHELL 2 T"\nbounds = [0.001, 0.004]\n'
        "[optimizer]\nstarts = 2\n"
    )
    out = tmp_path / "updated.bdf"
    assert main(["calibrate", str(study), "--json", "--write-bdf", str(out)]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["parameters"]["t1"] == pytest.approx(0.0024, rel=1e-5)
    assert result["parameters"]["t2"] == pytest.approx(0.0027, rel=1e-5)
    np.testing.assert_allclose(_freqs(out), result["frequencies_hz"][:5], rtol=1e-8)
    np.testing.assert_allclose(_freqs(out), target, rtol=1e-5)
    # nothing else changed: every other line as it was, in its place; the PSHELLs' other fields
    from bayesupdate.nastran.deck import read_deck

    old, new = deck.read_text().splitlines(), out.read_text().splitlines()
    assert [x for x in new if not x.startswith(("PSHELL", "*"))] == [
        x for x in old if not x.startswith("PSHELL")
    ]
    assert new.index(next(x for x in new if x.startswith("PSHELL"))) == old.index(
        "PSHELL,1,7,0.002,7,,7"
    )
    after = read_deck(out)
    pshell = after.table("PSHELL")
    assert pshell[1]["MID1"] == 7 and pshell[2]["MID3"] == 7


@pytest.mark.parametrize(
    "binds, message",
    [
        ("PSHELL 9 T", "no PSHELL 9"),
        ("PSHELL 1 Q", "no bindable field PSHELL Q"),
        ("PBARL 1 DIM1", "the deck has no PBARL 1"),
        ("PSHELL T", "give 'CARD ids FIELD'"),
        ("MAT1 3 E", "no MAT1 3"),
    ],
)
def test_bad_binding_is_one_line_exit_2(tmp_path, capsys, binds, message):
    deck = _plate(tmp_path / "plate.bdf")
    study = tmp_path / "s.toml"
    study.write_text(
        f'[model]\nsource = "{deck}"\n[data]\nfrequencies_hz = [70.0, 90.0]\n'
        f'[parameters.p]\nbinds = "{binds}"\nbounds = [0.001, 0.004]\n'
    )
    assert main(["calibrate", str(study)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err


def test_negative_thickness_and_unknown_grid_are_errors(tmp_path, capsys):
    from bayesupdate.errors import BayesUpdateError

    deck = _plate(tmp_path / "plate.bdf")
    model = _model(deck, {"t1": {"binds": "PSHELL 1 T"}})
    with pytest.raises(BayesUpdateError, match="binds 'PSHELL 1 T'; a thickness must be > 0"):
        model.solve({"t1": -0.001})
    with pytest.raises(BayesUpdateError, match="low bound must be > 0"):
        _model(deck, {"t1": {"binds": "PSHELL 1 T", "bounds": [-0.001, 0.003]}})
    with pytest.raises(BayesUpdateError, match="no GRID 99"):
        _model(deck, {}, ("99V",))
    with pytest.raises(BayesUpdateError, match="no GRID 77 .*mapped by model.test_points"):
        _model(deck, {}, ("3V",), {"3": 77})


def test_desvar_dvprel1_give_the_parameters_and_are_written_back(tmp_path):
    from bayesupdate.nastran.deck import read_deck

    deck = _plate(tmp_path / "plate.bdf")
    text = deck.read_text().replace(
        "ENDDATA",
        "DESVAR,1,TLEFT,0.001,0.0005,0.004\nDVPREL1,10,PSHELL,1,T,,,0.,+A\n+A,1,2.0\nENDDATA",
    )
    deck.write_text(text)
    model = _model(deck, {})  # no study parameters: the deck's design variable
    assert model.parameter_names == ("TLEFT",)
    assert model.default_parameters() == {"TLEFT": pytest.approx(0.001)}
    assert model.default_bounds() == {"TLEFT": (0.0005, 0.004)}
    got = model.solve({"TLEFT": 0.0012}, n_modes=4).frequencies_hz  # PSHELL 1 T = 2 x 1.2 mm
    np.testing.assert_allclose(got, _freqs(_plate(tmp_path / "d.bdf", t1=0.0024), 4), rtol=1e-9)
    from bayesupdate.nastran.writer import write_updated_deck

    out = write_updated_deck(model, {"TLEFT": 0.0012}, tmp_path / "out.bdf")
    written = read_deck(out)
    assert written.table("PSHELL")[1]["T"] == pytest.approx(0.0024)
    assert written.table("DESVAR")[1]["XINIT"] == pytest.approx(0.0012)
    assert written.table("PSHELL")[2]["T"] == pytest.approx(0.003)
