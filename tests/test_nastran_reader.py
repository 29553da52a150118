"""The package's own bulk-data reader (``bayesupdate.nastran.bulk`` and ``deck``) on small decks
written here: Nastran's number forms, small-, large- and free-field lines and tabs, continuation
lines (explicit markers, one marker reused by every card, blank first fields), INCLUDE (quoted,
continued over lines, relative to the including file, found in another letter case), the case
control's selections, MAT1 completed from any two of E, G, NU (MSC QRG MAT1), a CMASS2 rotary
inertia against its closed form, and every refusal of a deck in one message with its file:line.
"""

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran.bulk import parse_number
from bayesupdate.nastran.deck import Refusals, read_deck


@pytest.mark.parametrize(
    "text, value",
    [("1.0-3", 1.0e-3), (".5+2", 50.0), ("1.E4", 1.0e4), ("1.D4", 1.0e4), ("2.01e+9", 2.01e9),
     ("-7", -7), ("+5", 5), ("-.25E-1", -0.025), ("7.", 7.0), ("yes", "YES"), ("", None)],
)  # fmt: skip
def test_nastran_number_forms(text, value):
    got = parse_number(text)
    assert got == value and type(got) is type(value)


def test_bad_number_is_refused_with_its_field():
    with pytest.raises(ValueError, match="'1.0.3' is not a Nastran number"):
        parse_number("1.0.3")


def _values(path, name="CONM2"):
    deck = read_deck(path)
    return [c.values() for c in deck.of(name)]


def _small(*fields) -> str:
    """A small-field line: 8-character fields, right-aligned (as many decks write them)."""
    return "".join(f"{x:>8}" for x in fields).rstrip() + "\n"


def test_small_large_free_field_and_tabs_read_the_same_card(tmp_path):
    """One CONM2 (EID 7, G 3, M 1.5e-3, offset X1-X3, I11 and I33) written six ways."""
    small = _small("CONM2", 7, 3, "", "1.-3", ".1", "-.2", "3.+1", "", "+C1") + _small(
        "+C1", "2.+4", "", "0.0", "", "5.-2"
    )
    large = ("CONM2*  " + "".join(f"{x:>16}" for x in (7, 3, "", "1.0-3")) + "\n"
             "*       " + "".join(f"{x:>16}" for x in ("0.1", "-0.2", "3.0+1", "")) + "\n"
             "*       " + "".join(f"{x:>16}" for x in ("2.0+4", "", "0.0", "")) + "\n"
             "*       " + "".join(f"{x:>16}" for x in ("0.05",)) + "\n")  # fmt: skip
    free = "CONM2,7,3,,1.0E-3,0.1,-0.2,30.,\n,20000.,,0.,,0.05\n"
    tabs = "CONM2\t7\t3\t\t1.-3\t.1\t-.2\t3.+1\n\t2.+4\t\t0.\t\t5.-2\n"
    comment = ("$ a comment\n" + _small("CONM2", 7, 3, "", "1.-3", ".1", "-.2", "3.+1")[:-1]
               + "   $ here\n$ between\n" + _small("", "2.+4", "", "0.", "", "5.-2"))  # fmt: skip
    star8 = "CONM2  *" + large[8:]  # the name's star in column 8 (as some writers place it)
    expected = [7, 3, None, 1e-3, 0.1, -0.2, 30.0, None, 2e4, None, 0.0, None, 0.05]
    for k, text in enumerate((small, large, free, tabs, comment, star8)):
        deck = tmp_path / f"c{k}.bdf"
        deck.write_text("BEGIN BULK\n" + text + "ENDDATA\n")
        got = _values(deck)
        assert len(got) == 1 and got[0][: len(expected)] == expected, (k, got)


def test_named_large_field_continuation_and_a_small_one_after_it(tmp_path):
    """A large-field card whose continuation markers carry a name ('*     FM', as MSC's
    freedlm deck writes its CORD2R*), then a small-field continuation ('+     FN'): the '*'
    line holds four 16-character fields, the '+' line eight of 8 (QRG, bulk data format);
    the '*     FM' line was read as a small-field line."""
    text = ("CORD2R* " + "".join(f"{x:16}" for x in ("3", "", "25.", "0.")) + "*     FM\n"
            "*     FM " + "".join(f"{x:16}" for x in ("0.", "50.", "1.092785-6", "4.7-14"))
            + "*     FN\n" + "+     FN 24.9999 25.     1.092-6\n")  # fmt: skip
    deck = tmp_path / "cord.bdf"
    deck.write_text("BEGIN BULK\n" + text + "ENDDATA\n")
    (card,) = read_deck(deck).of("CORD2R")
    expected = [3, None, 25.0, 0.0, 0.0, 50.0, 1.092785e-6, 4.7e-14, 24.9999, 25.0, 1.092e-6]
    assert card.values()[:11] == expected


def test_continuations_with_one_reused_marker_and_implicit_ones(tmp_path):
    """Every CBEAM reuses '+cb1' (as the mAEWing1 decks do): each continuation belongs to the
    card right above it."""
    text = "".join(
        _small("CBEAM", e, 1, e, e + 1, "0.0", "0.0", "1.0", "", "+cb1")
        + _small("+cb1", "", "", w, "0.2", "0.0", w, "0.2", "0.0")
        for e, w in ((1, "0.1"), (2, "-0.3"), (3, "0.5"))
    )
    deck = tmp_path / "beams.bdf"
    deck.write_text("BEGIN BULK\n" + text + "ENDDATA\n")
    cards = read_deck(deck).of("CBEAM")
    assert [c.id() for c in cards] == [1, 2, 3]
    assert [c["W1A"] for c in cards] == [0.1, -0.3, 0.5]
    assert [c.line for c in cards] == [2, 4, 6] and [c.end for c in cards] == [3, 5, 7]


def test_include_quoted_continued_relative_and_in_another_case(tmp_path):
    sub = tmp_path / "parts"
    sub.mkdir()
    (sub / "Grids.DAT").write_text("GRID    1               0.      0.      0.\nINCLUDE more.dat\n")
    (sub / "more.dat").write_text("GRID    2               1.      0.      0.\n")
    (tmp_path / "mass.dat").write_text("CONM2   5       2               3.0\n")
    main = tmp_path / "main.bdf"
    main.write_text("SOL 103\nCEND\nBEGIN BULK\nINCLUDE 'parts/\n   grids.dat'\n"
                    "include mass.dat\nENDDATA\n")  # fmt: skip
    deck = read_deck(main)
    assert sorted(deck.table("GRID")) == [1, 2]  # more.dat: relative to Grids.DAT's folder
    assert deck.table("CONM2")[5].real("M") == 3.0
    assert any("read Grids.DAT" in n for n in deck.notes)
    assert deck.table("GRID")[2].where == "more.dat:1"
    main.write_text("BEGIN BULK\nINCLUDE 'nowhere.dat'\nGRID,1\nENDDATA\n")
    with pytest.raises(BayesUpdateError, match=r"main.bdf:2 INCLUDE 'nowhere.dat': no such file"):
        read_deck(main)


def test_case_control_takes_the_subcase_over_the_global_and_skips_comments(tmp_path):
    deck = tmp_path / "case.bdf"
    deck.write_text("SOL 103\nCEND\nMETHOD = 5\nSPC = 2\nSET 9 = 1, 3 THRU 5,\n 8\n"
                    "SUBCASE 1\n  METHOD = 101\n  $ SPC = 99\nBEGIN BULK\nENDDATA\n")  # fmt: skip
    d = read_deck(deck)
    assert d.sol == "103" and d.case == {"METHOD": 101, "SPC": 2}
    assert d.case_sets == {9: (1, 3, 4, 5, 8)}


ROTOR = """SOL 103
CEND
METHOD = 1
SPC = 1
BEGIN BULK
EIGRL,1,,,1
PARAM,WTMASS,0.5
GRID,1,,0.,0.,0.
CONM2,2,1,,1.
CMASS2,3,8.,1,5
CELAS2,4,400.,1,5
SPC1,1,12346,1
ENDDATA
"""


def test_cmass2_is_a_rotary_inertia_about_its_component(tmp_path):
    """Rotation 5 of GRID 1 on a 400 spring with CMASS2 8 x WTMASS 0.5: f = sqrt(400 / 4)/2 pi
    (the CONM2's translations are held; it has no inertia); on translation 3 instead, with the
    CONM2's 0.5: f = sqrt(400 / (4 + 0.5))/2 pi."""
    from bayesupdate.nastran import load_nastran_model

    deck = tmp_path / "rotor.bdf"
    deck.write_text(ROTOR)
    r = load_nastran_model(deck).solve(n_modes=1)
    assert r.frequencies_hz[0] == pytest.approx(np.sqrt(400.0 / 4.0) / (2 * np.pi), rel=1e-10)
    deck.write_text(ROTOR.replace("CMASS2,3,8.,1,5", "CMASS2,3,8.,1,3")
                    .replace("CELAS2,4,400.,1,5", "CELAS2,4,400.,1,3")
                    .replace("SPC1,1,12346,1", "SPC1,1,12456,1"))  # fmt: skip
    r = load_nastran_model(deck).solve(n_modes=1)
    assert r.frequencies_hz[0] == pytest.approx(np.sqrt(400.0 / 4.5) / (2 * np.pi), rel=1e-10)


@pytest.mark.parametrize(
    "fields, E, G, NU",
    [(("2.e+6", "5.e+5", ""), 2e6, 5e5, 1.0),  # NU = E / 2G - 1 (outside (-1, 0.5): a note)
     (("2.e+6", "", ".25"), 2e6, 8e5, 0.25),  # G = E / 2(1 + NU)
     (("", "8.e+5", ".25"), 2e6, 8e5, 0.25)],  # E = 2(1 + NU) G
)  # fmt: skip
def test_mat1_is_completed_from_any_two_of_e_g_nu(tmp_path, fields, E, G, NU):
    from bayesupdate.nastran import cards
    from bayesupdate.nastran.reader import context

    deck = tmp_path / "mat.bdf"
    deck.write_text("BEGIN BULK\nMAT1,3," + ",".join(fields) + ",0.1\nENDDATA\n")
    d = read_deck(deck)
    ctx = context(d, None, None, dict(wtmass=1.0, coupmass=-1), None, Refusals(""))
    m = cards.mat1(ctx, 3, d.table("MAT1")[3])
    assert (m.E, m.G, m.NU, m.RHO) == pytest.approx((E, G, NU, 0.1), rel=1e-12)
    assert any("NU = 1 from E and G" in n for n in ctx.notes) == (NU >= 0.5)


def test_every_refusal_of_a_deck_in_one_message(tmp_path, capsys):
    """Three bad cards in two files (an unsupported card, a PARAM that changes the modes, a
    CBAR to a missing GRID) and an ignored PARAM: one message names all three, each with its
    file:line, and nothing about the ignored one."""
    from bayesupdate.cli import main

    (tmp_path / "more.dat").write_text("$ bars\nCBAR,7,5,1,99,0.,0.,1.\n")
    deck = tmp_path / "bad.bdf"
    deck.write_text("SOL 103\nCEND\nBEGIN BULK\nPARAM,POST,-1\nPARAM,G,0.02\n"
                    "GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nMAT1,1,2.e11,,0.3,7800.\n"
                    "PBAR,5,1,2.e-3,4.e-6,1.e-6,2.e-6\nCBAR,6,5,1,2,0.,0.,1.\n"
                    "CSHEAR,20,1,1,2,1,2\nINCLUDE more.dat\nENDDATA\n")  # fmt: skip
    assert main(["modes", "--model", str(deck)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "3 card(s) refused" in err, err
    for where in ("bad.bdf:11 CSHEAR 20", "bad.bdf:5 PARAM G", "more.dat:2 CBAR 7: GRID 99"):
        assert where in err, err
    assert "POST" not in err


def test_units_from_wtmass_or_named(tmp_path):
    """WTMASS 1/386.09 is inch-lbf-s whatever the moduli; a study may name the system."""
    from bayesupdate.nastran import load_nastran_model

    deck = tmp_path / "rotor.bdf"
    deck.write_text(ROTOR.replace("PARAM,WTMASS,0.5", "PARAM,WTMASS,.00259"))
    units = load_nastran_model(deck).structure.metadata["nastran"]["units"]
    assert (units["length"], units["mass"]) == ("in", "lbf s^2/in")
    named = load_nastran_model(deck, units="SI").structure.metadata["nastran"]["units"]
    assert (named["length"], named["mass"]) == ("m", "kg")
    with pytest.raises(BayesUpdateError, match="units = 'furlong'"):
        load_nastran_model(deck, units="furlong")


def test_a_study_names_the_decks_units_in_its_model_table(tmp_path):
    """``[model] units = "si"`` reaches the deck through the study path (``study_model``); a
    built-in model refuses it in one line."""
    from bayesupdate.config import parse_study
    from bayesupdate.pipelines.model_source import study_model

    deck = tmp_path / "rotor.bdf"
    deck.write_text(ROTOR.replace("PARAM,WTMASS,0.5", "PARAM,WTMASS,.00259"))
    table = {"model": {"source": str(deck), "units": "si"},
             "parameters": {"k": {"binds": "CELAS2 4 K", "bounds": [1.0, 1e9]}}}  # fmt: skip
    model = study_model(parse_study(table))
    assert model.structure.metadata["nastran"]["units"]["length"] == "m"
    with pytest.raises(BayesUpdateError, match="model.units: only a Nastran deck"):
        study_model(parse_study({"model": {"source": "exhaust", "units": "si"}}))
