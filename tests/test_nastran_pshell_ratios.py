"""PSHELL 12I/T**3 and TS/T (MSC Nastran QRG PSHELL): a sandwich's bending inertia and its
transverse shear thickness, read from a deck and checked against Mindlin's closed form.

A simply supported square steel plate (a = 1 m) in n x n CQUAD4 through ``bayesupdate modes
--model`` with PSHELL 12I/T**3 = 2.5 and TS/T = 0.5 (MID2 = MID3 = MID1), at a/t = 10 where
both matter: against Mindlin's plate with D = 2.5 E t^3 / 12 (1 - nu^2), shear 0.5 G t and the
solid rotary inertia rho t^3 / 12 (the element keeps it; ``shell.local_pieces``), the ratios move
modes 1-8 by 22-33 % (12I/T**3 = 1) and 4-14 % (TS/T = 5/6).  Measured: 32 x 32 quads within
0.09-0.63 % (16 x 16: 0.38-2.5 %), convergence rate 2.00-2.02, the Richardson extrapolation
within 0.01 %; asserted: 1 % raw (the quads' level in ``test_fe_shell``), 0.05 % extrapolated,
rate in (1.8, 2.3).  CTRIA3 (DKT, shear rigid: TS/T has no effect) at a/t = 100 against
Kirchhoff with the same D: 1 % on each mode, as ``test_fe_shell_tria``'s deck.  The plate,
its deck and the closed forms are ``studies/pshell_ratios.py``'s (which also runs MYSTRAN).
"""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.cli import main

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
from pshell_ratios import MODES_1_TO_8, STEEL, plate_deck  # noqa: E402

A = 1.0
BENDING, SHEAR = 2.5, 0.5


def _modes(path, capsys) -> np.ndarray:
    assert main(["modes", "--model", str(path), "--modes", "8", "--json"]) == 0
    return np.array(json.loads(capsys.readouterr().out)["frequencies_hz"])


def test_sandwich_quads_converge_to_mindlin_with_the_decks_ratios(tmp_path, capsys):
    t = A / 10
    pshell = f"PSHELL,1,1,{t},1,{BENDING},1,{SHEAR}"
    decks = (plate_deck(tmp_path / f"q{n}.bdf", n, t, pshell) for n in (16, 32))
    coarse, fine = (_modes(deck, capsys) for deck in decks)
    ref = np.array([STEEL.mindlin_hz(t, m, n, BENDING, SHEAR) for m, n in MODES_1_TO_8])
    # each ratio alone moves every mode by more than the tolerance: a test that can fail
    solid_bending = np.array([STEEL.mindlin_hz(t, m, n, 1.0, SHEAR) for m, n in MODES_1_TO_8])
    solid_shear = np.array([STEEL.mindlin_hz(t, m, n, BENDING) for m, n in MODES_1_TO_8])
    assert np.all(solid_bending / ref < 0.8) and np.all(solid_shear / ref > 1.03)
    np.testing.assert_allclose(fine, ref, rtol=0.01)
    np.testing.assert_allclose(fine + (fine - coarse) / 3, ref, rtol=5e-4)
    rate = np.log2((coarse - ref) / (fine - ref))
    assert np.all((rate > 1.8) & (rate < 2.3)), rate


def test_sandwich_triangles_against_kirchhoff_and_ts_t_has_no_effect(tmp_path, capsys):
    t = A / 100
    ref = np.array([STEEL.kirchhoff_hz(t, m, n, BENDING) for m, n in MODES_1_TO_8])
    decks = (f"PSHELL,1,1,{t},1,{BENDING},1,{SHEAR}", f"PSHELL,1,1,{t},1,{BENDING},1")
    f, f_default = (_modes(plate_deck(tmp_path / f"t{i}.bdf", 32, t, p, True), capsys)
                    for i, p in enumerate(decks))  # fmt: skip
    np.testing.assert_allclose(f, ref, rtol=0.01)
    np.testing.assert_array_equal(f, f_default)


@pytest.mark.parametrize("field", ["12I/T**3", "TS/T"])
def test_a_ratio_that_is_not_positive_is_refused_with_its_line(tmp_path, capsys, field):
    ratios = f"{BENDING},1,0." if field == "TS/T" else "-1.,1,0.5"
    deck = plate_deck(tmp_path / "bad.bdf", 2, 0.01, f"PSHELL,1,1,0.01,1,{ratios}")
    assert main(["modes", "--model", str(deck), "--modes", "8", "--json"]) == 2
    line = 1 + deck.read_text().splitlines().index(f"PSHELL,1,1,0.01,1,{ratios}")
    err = capsys.readouterr().err
    assert f"bad.bdf:{line}" in err and f"{field} = " in err and "must be > 0" in err
