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
Kirchhoff with the same D: 1 % on each mode, as ``test_fe_shell_tria``'s deck.  A sandwich
whose faces (MID2, 1.6 E, the same NU) and core (MID3, G3 = G1 / 10) are other MAT1s: the
bending ratio times E2 / E1, the shear ratio times G3 / G1 (QRG PSHELL), against Mindlin
likewise (measured 32 x 32: 0.05-0.36 %, extrapolated within 0.002 %; faces and core each move
modes 1-8 by 1.2-5.8 % and 85-171 %); faces of another NU than MID1 bend with their own
(D = E2 t^3 / 12 (1 - nu2^2)).  The plate,
its deck and the closed forms are ``studies/pshell_ratios.py``'s (which also runs MYSTRAN).
"""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.cli import main
from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran import load_nastran_model

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
from pshell_ratios import MODES_1_TO_8, STEEL, plate_deck  # noqa: E402

A = 1.0
BENDING, SHEAR = 2.5, 0.5
#: a sandwich: faces MAT1 2 (1.6 E, the same NU) carry the bending, a core MAT1 3 (E / 10, NU
#: 0.3: G3 / G1 = 0.1) the transverse shear
FACES, CORE = "MAT1,2,3.2E+11,,0.30,7800.0", "MAT1,3,2.0E+10,,0.30,100.0"


def _modes(path, capsys) -> np.ndarray:
    assert main(["modes", "--model", str(path), "--modes", "8", "--json"]) == 0
    return np.array(json.loads(capsys.readouterr().out)["frequencies_hz"])


def test_sandwich_quads_converge_to_mindlin_with_the_decks_ratios(tmp_path, capsys):
    t = A / 10
    pshell = f"PSHELL,1,1,{t},1,{BENDING},1,{SHEAR}"
    decks = (plate_deck(tmp_path / f"q{n}.bdf", n, t, pshell) for n in (16, 32))
    coarse, fine = (_modes(deck, capsys) for deck in decks)
    ref = np.array([STEEL.mindlin_hz(t, m, n, BENDING, SHEAR) for m, n in MODES_1_TO_8])
    # each ratio counts: the deck's modes are far from the plate with either one left out
    solid_bending = np.array([STEEL.mindlin_hz(t, m, n, 1.0, SHEAR) for m, n in MODES_1_TO_8])
    solid_shear = np.array([STEEL.mindlin_hz(t, m, n, BENDING) for m, n in MODES_1_TO_8])
    np.testing.assert_allclose(fine, ref, rtol=0.01)
    assert np.all(fine / solid_bending > 1.2) and np.all(fine / solid_shear < 0.98)
    np.testing.assert_allclose(fine + (fine - coarse) / 3, ref, rtol=5e-4)
    rate = np.log2((coarse - ref) / (fine - ref))
    assert np.all((rate > 1.8) & (rate < 2.3)), rate


def test_sandwich_triangles_against_kirchhoff_and_ts_t_or_mid3_has_no_effect(tmp_path, capsys):
    t = A / 100
    ref = np.array([STEEL.kirchhoff_hz(t, m, n, BENDING) for m, n in MODES_1_TO_8])
    decks = (f"PSHELL,1,1,{t},1,{BENDING},1,{SHEAR}", f"PSHELL,1,1,{t},1,{BENDING},1",
             f"PSHELL,1,1,{t},1,{BENDING}")  # fmt: skip
    f, f_default, f_rigid = (_modes(plate_deck(tmp_path / f"t{i}.bdf", 32, t, p, True), capsys)
                             for i, p in enumerate(decks))  # fmt: skip
    np.testing.assert_allclose(f, ref, rtol=0.01)
    np.testing.assert_array_equal(f, f_default)
    np.testing.assert_array_equal(f, f_rigid)  # MID3 blank: the DKT is shear rigid anyway


@pytest.mark.parametrize("field", ["12I/T**3", "TS/T"])
def test_a_ratio_that_is_not_positive_is_refused_with_its_line(tmp_path, capsys, field):
    ratios = f"{BENDING},1,0." if field == "TS/T" else "-1.,1,0.5"
    deck = plate_deck(tmp_path / "bad.bdf", 2, 0.01, f"PSHELL,1,1,0.01,1,{ratios}")
    assert main(["modes", "--model", str(deck), "--modes", "8", "--json"]) == 2
    line = 1 + deck.read_text().splitlines().index(f"PSHELL,1,1,0.01,1,{ratios}")
    err = capsys.readouterr().err
    assert f"bad.bdf:{line}" in err and f"{field} = " in err and "must be > 0" in err


def _coarse_and_fine(tmp_path, capsys, t, pshell: str, mats: str) -> list[np.ndarray]:
    """Modes 1-8 of the plate in 16 x 16 and 32 x 32 quads with ``pshell`` and the MAT1 lines
    ``mats`` beside the steel's."""
    out = []
    for n in (16, 32):
        deck = plate_deck(tmp_path / f"p{n}.bdf", n, t, pshell)
        deck.write_text(deck.read_text().replace("ENDDATA", f"{mats}\nENDDATA"))
        out.append(_modes(deck, capsys))
    return out


def test_sandwich_faces_and_core_materials_against_mindlin(tmp_path, capsys):
    t = A / 10
    pshell = f"PSHELL,1,1,{t},2,{BENDING},3,{SHEAR}"
    coarse, fine = _coarse_and_fine(tmp_path, capsys, t, pshell, f"{FACES}\n{CORE}")
    bending, kappa = BENDING * 1.6, SHEAR * 0.1
    ref = np.array([STEEL.mindlin_hz(t, m, n, bending, kappa) for m, n in MODES_1_TO_8])
    faces_only = np.array([STEEL.mindlin_hz(t, m, n, BENDING, kappa) for m, n in MODES_1_TO_8])
    core_only = np.array([STEEL.mindlin_hz(t, m, n, bending, SHEAR) for m, n in MODES_1_TO_8])
    np.testing.assert_allclose(fine, ref, rtol=0.01)
    assert np.all(fine / faces_only > 1.01) and np.all(fine / core_only < 0.9)
    np.testing.assert_allclose(fine + (fine - coarse) / 3, ref, rtol=5e-4)


def test_sandwich_faces_of_another_nu_against_mindlin(tmp_path, capsys):
    """Faces (MID2) of another NU than MID1 (0.2 against 0.3; TS/T on MID1's G): the bending
    matrix is the faces' own, D = 12I/T**3 E2 t^3 / 12 (1 - nu2^2) (QRG PSHELL), which on the
    simply supported plate is Mindlin's D; with MID1's NU, D would be 5.5 % larger and modes
    1-8 0.8-2.0 % higher.  Measured: 32 x 32 within 0.09-0.56 %, extrapolated within 7e-5;
    asserted as the sandwich above, and 0.2 % away from the plate with MID1's NU."""
    t = A / 10
    pshell = f"PSHELL,1,1,{t},2,{BENDING},1,{SHEAR}"
    coarse, fine = _coarse_and_fine(tmp_path, capsys, t, pshell, "MAT1,2,3.2E+11,,0.20,7800.0")
    nu, nu2 = STEEL.nu, 0.2
    bending, kappa = BENDING * 1.6 * (1 - nu**2) / (1 - nu2**2), SHEAR
    ref = np.array([STEEL.mindlin_hz(t, m, n, bending, kappa) for m, n in MODES_1_TO_8])
    mid1_nu = np.array([STEEL.mindlin_hz(t, m, n, BENDING * 1.6, kappa) for m, n in MODES_1_TO_8])
    np.testing.assert_allclose(fine, ref, rtol=0.01)
    np.testing.assert_allclose(fine + (fine - coarse) / 3, ref, rtol=5e-4)
    assert np.all(np.abs(fine + (fine - coarse) / 3 - mid1_nu) > 2e-3 * mid1_nu)


def _sandwich(tmp_path, pshell: str, mats: str = f"{FACES}\n{CORE}"):
    deck = plate_deck(tmp_path / "sandwich.bdf", 2, 0.01, pshell)
    deck.write_text(deck.read_text().replace("ENDDATA", f"{mats}\nENDDATA"))
    return deck


@pytest.mark.parametrize(
    "pshell, mats, words",
    [
        (
            "PSHELL,1,1,0.01,2,,3",
            "MAT1,2,3.2E+11,1.0E+11,,7800.0\n" + CORE,
            "MID2 2: NU = 0.6 (from E and G) is outside (-1, 0.5)",
        ),
        ("PSHELL,1,1,0.01,,,,,,\n,,,3", FACES, "MID4 (membrane-bending coupling) needs both"),
        ("PSHELL,1,1,0.01,-1", FACES, "MID2 = -1 (plane strain) is not supported"),
    ],
)
def test_sandwich_cards_it_cannot_hold_are_refused_with_their_line(
    tmp_path, capsys, pshell, mats, words
):
    deck = _sandwich(tmp_path, pshell, mats)
    assert main(["modes", "--model", str(deck), "--modes", "4", "--json"]) == 2
    err = capsys.readouterr().err
    line = 1 + deck.read_text().splitlines().index(pshell.split("\n")[0])
    assert f"sandwich.bdf:{line}" in err and words in err, err


@pytest.mark.parametrize("mid", [1, 3])
def test_one_e_cannot_bind_a_sandwich(tmp_path, mid):
    deck = _sandwich(tmp_path, f"PSHELL,1,1,0.01,2,{BENDING},3,{SHEAR}")
    with pytest.raises(BayesUpdateError, match=r"PSHELL 1 take\(s\) bending or transverse shear"):
        load_nastran_model(deck, {"E": {"binds": f"MAT1 {mid} E", "bounds": [1e9, 1e12]}})


def test_a_sandwichs_thickness_binding_is_the_deck_written_with_it(tmp_path):
    """PSHELL T bound on the sandwich: its bending and shear ratios are factors of the element's
    pieces, so K and M stay exact powers of t and the bound model at T = 0.13 m is the deck
    written with T = 0.13 m (measured: identical frequencies; asserted to 1e-12, round-off)."""

    def deck(t, name):
        path = plate_deck(tmp_path / name, 8, t, f"PSHELL,1,1,{t},2,{BENDING},3,{SHEAR}")
        path.write_text(path.read_text().replace("ENDDATA", f"{FACES}\n{CORE}\nENDDATA"))
        return path

    bound = load_nastran_model(deck(0.1, "a.bdf"), {"t": {"binds": "PSHELL 1 T",
                                                           "bounds": [0.05, 0.2]}})  # fmt: skip
    written = load_nastran_model(deck(0.13, "b.bdf"))
    np.testing.assert_allclose(bound.solve({"t": 0.13}, n_modes=6).frequencies_hz,
                               written.solve(n_modes=6).frequencies_hz, rtol=1e-12)  # fmt: skip
