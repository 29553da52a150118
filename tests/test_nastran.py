"""Nastran bulk data in (``bayesupdate.nastran``), through ``bayesupdate modes --model deck``.

Verification on decks nobody here wrote (``shared/data/nastran``, README there): the MSC beam
deck against MSC's eigenvalues (0.1 %), the NX FEMAP exhaust (4,466 shells) against NX's modes
2-10 (3 %); conversions against closed forms on small decks written here; bad input exits 2
with one line.  Skipped when pyNastran (``pip install bayesupdate[nastran]``) or the shared data
are missing.
"""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.cli import main

pytest.importorskip("pyNastran", reason="pip install bayesupdate[nastran] (pyNastran)")

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "nastran"
needs_data = pytest.mark.skipif(not DATA.is_dir(), reason=f"shared data missing: {DATA}")

#: MSC Nastran, beam_modes.f06 real eigenvalue table [Hz]
MSC_BEAM_HZ = [456.660, 456.660, 2674.588, 2674.588, 3554.923, 4507.487, 6626.104, 6626.104,
               11111.585, 11111.585]  # fmt: skip
#: NX Nastran, modal_example.op2 eigenvalue table [Hz] (shared/data/nastran/README.md)
NX_EXHAUST_HZ = [3.5025, 71.958, 93.666, 101.436, 103.942, 115.813, 135.579, 141.304, 143.281,
                 166.839]  # fmt: skip


def modes_json(capsys, *argv):
    code = main(["modes", *map(str, argv), "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    return json.loads(out)


def rejected(capsys, *argv):
    code = main(["modes", *map(str, argv)])
    out, err = capsys.readouterr()
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@needs_data
def test_msc_beam_deck_matches_msc_within_0_1_percent(capsys):
    out = modes_json(capsys, "--model", DATA / "beam_modes" / "beam_modes.dat", "--modes", 10)
    f = np.array(out["frequencies_hz"])
    assert np.all(np.abs(f / MSC_BEAM_HZ - 1) < 1e-3), f / MSC_BEAM_HZ - 1
    assert out["rigid_modes"] == 0
    assert out["n_dof"] == 66  # 11 GRIDs in use (GRID 12 has no element: AUTOSPC)
    # CONM2 0.00259 + rod rho pi r^2 L = 7.4851e-4 x pi x 10 (lbf s^2/in, no WTMASS)
    assert out["mass_kg"] == pytest.approx(0.00259 + 7.4851e-4 * np.pi * 10, rel=1e-9)
    assert out["units"]["system"] == "in, lbf, s"


@needs_data
def test_femap_exhaust_modes_2_to_10_within_3_percent_of_nx(capsys):
    out = modes_json(capsys, "--model", DATA / "femap_exhaust" / "exhaust.bdf")
    f = np.array(out["frequencies_hz"])
    assert f.size == 10  # EIGRL ND = 10 through the case control's METHOD
    assert np.all(np.abs(f[1:] / NX_EXHAUST_HZ[1:] - 1) < 0.03), f / NX_EXHAUST_HZ - 1
    # mode 1 (rotation about the hanger line) is formulation-sensitive: NX 3.50, OpenSees
    # ASDShellQ4 3.65, MYSTRAN 5.0-8.2 Hz (README); a flat quad without its warp link gave 20.8
    assert 3.0 < f[0] < 4.0
    assert out["rigid_modes"] == 0 and out["n_dof"] == 6 * 4472
    assert out["units"]["wtmass"] == pytest.approx(0.00259)


SPRING_DECK = """SOL 103
CEND
SPC = 1
METHOD = 1
BEGIN BULK
EIGRL   1                       3
PARAM   WTMASS  0.5
CORD2R  7               0.      0.      0.      1.      1.      0.
        0.      1.      1.
GRID    1               0.      0.      0.      7
GRID    2               0.      0.      0.      7
CONM2   10      1               2.0
CELAS2  11      100.    1       1       2       1
CELAS2  12      400.    1       2
CELAS2  13      900.    1       3
SPC1    1       123456  2
ENDDATA
"""


def test_spring_mass_deck_applies_wtmass_and_cd_frames(tmp_path):
    """1 kg-equivalent CONM2 (2 x WTMASS 0.5) on springs 100, 400, 900 along the axes of a
    rotated CD frame: f = sqrt(k / m) / 2 pi, each mode along its CD axis."""
    from bayesupdate.nastran import load_nastran_model

    deck = tmp_path / "springs.bdf"
    deck.write_text(SPRING_DECK)
    model = load_nastran_model(deck)
    r = model.solve(n_modes=3)
    assert r.frequencies_hz == pytest.approx(np.sqrt([100.0, 400.0, 900.0]) / (2 * np.pi))
    assert r.mass_kg == pytest.approx(1.0)
    # CORD2R 7: z along basic (1, 1, 0)/sqrt 2, x in the plane of z and (0, 1, 1)
    ez = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
    grid1 = list(model.structure.metadata["nastran"]["grid_ids"]).index(1)
    u = r.modes.shapes[6 * grid1 : 6 * grid1 + 3, 2]
    assert abs(u @ ez) / np.linalg.norm(u) == pytest.approx(1.0, abs=1e-9)


MIXED_DECK = """SOL 103
CEND
SPC = 1
METHOD = 1
BEGIN BULK
EIGRL,1,,,6
GRID,1,,0.,0.,0.
GRID,2,,10.,0.,0.
GRID,3,,10.,0.,0.
GRID,4,,10.,0.,0.
CROD,1,5,1,2
PROD,5,7,0.5
MAT1,7,1.e7,,.3
RBAR,2,2,3,123456,,,123456
CBUSH,3,8,3,4,,,,0
PBUSH,8,K,1.e4,1.e4,1.e4,1.e6,1.e6,1.e6
CONM1,10,4,0,2.,0.,2.,0.,0.
,2.,0.,0.,0.,1.,0.,0.,0.
,0.,1.,0.,0.,0.,0.,0.,1.
SPC1,1,123456,1
SPC1,1,23456,2
ENDDATA
"""


def test_rod_rbar_bush_conm1_deck_matches_closed_form(capsys, tmp_path):
    """Rod EA/L = 5e5 to a rigid bar, a 6-DOF bush (1e4 translations, 1e6 rotations) to a
    CONM1 (mass 2, inertia 1): x in series, y and z on the bush, rotations on the bush."""
    deck = tmp_path / "mixed.bdf"
    deck.write_text(MIXED_DECK)
    out = modes_json(capsys, "--model", deck)
    k_x = 1 / (1 / 5e5 + 1 / 1e4)
    expected = np.sqrt([k_x / 2, 1e4 / 2, 1e4 / 2, 1e6, 1e6, 1e6]) / (2 * np.pi)
    assert out["frequencies_hz"] == pytest.approx(expected, rel=1e-6)
    assert out["mass_kg"] == pytest.approx(2.0)
    apart = tmp_path / "apart.bdf"
    apart.write_text(MIXED_DECK.replace("GRID,4,,10.", "GRID,4,,20."))
    assert "apart.bdf:15: CBUSH 3" in rejected(capsys, "--model", apart)


def test_missing_pynastran_is_one_line(capsys, tmp_path, monkeypatch):
    deck = tmp_path / "springs.bdf"
    deck.write_text(SPRING_DECK)
    monkeypatch.setitem(sys.modules, "pyNastran.bdf.bdf", None)
    line = rejected(capsys, "--model", deck)
    assert "pip install bayesupdate[nastran]" in line


def test_unsupported_card_named_with_its_line(capsys, tmp_path):
    deck = tmp_path / "damper.bdf"
    deck.write_text(SPRING_DECK.replace("ENDDATA", "CDAMP2  20      1.      1       1\nENDDATA"))
    line = rejected(capsys, "--model", deck)
    assert "CDAMP2" in line and "damper.bdf:17" in line


def test_unreadable_deck_and_massless_deck(capsys, tmp_path):
    bad = tmp_path / "bad.dat"
    bad.write_text("BEGIN BULK\nGRID    1       x       y\nENDDATA\n")
    assert "pyNastran cannot read" in rejected(capsys, "--model", bad)
    massless = tmp_path / "massless.bdf"
    massless.write_text(SPRING_DECK.replace("2.0\n", "0.0\n"))
    assert "no mass" in rejected(capsys, "--model", massless)
