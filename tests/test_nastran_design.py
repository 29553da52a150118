"""A deck's design model (MSC QRG DESVAR, DVPREL1, DVMREL1, DVCREL1) against the same deck with the
related fields edited by hand: every relation evaluated (``writer.write_design_deck``: CBEAM
offsets with COEF +1 and -1, MAT1 G, CMASS2 M with COEF 0.5 and 1, CONM2 X1 with C0, CONM2 I11),
every DESVAR as a parameter (the element cards' own fields re-built), and the note naming a
DESVAR that cannot be one (two DESVARs in one relation) with its file:line."""

from pathlib import Path

import numpy as np
import pytest

from bayesupdate.nastran import load_nastran_model
from bayesupdate.nastran.writer import write_design_deck

#: a free frame: two CBEAMs (PBEAM 5, MAT1 1 with E and G), a CONM2 with offset and inertia at
#: GRID 3, two CMASS2 rotary inertias; fields marked {name} are the design model's
BULK = """EIGRL,1,,,8
GRID,1,,0.,0.,0.
GRID,2,,10.,0.,0.
GRID,3,,20.,0.,0.
CBEAM,11,5,1,2,0.,0.,1.
,,,0.,{w11},0.,0.,{w11},0.
CBEAM,12,5,2,3,0.,0.,1.
,,,0.,{w12},0.,0.,{w12},0.
PBEAM,5,1,0.5,0.02,0.01,,0.015
MAT1,1,1.e7,{g},,0.1
CONM2,31,3,,2.,{x1},0.,0.
,{i11},,0.3,,,0.4
CMASS2,21,{m21},1,4
CMASS2,22,{m22},2,4
"""
DESIGN = """DESVAR,1,OFF,0.05,-1.,1.
DESVAR,2,GMOD,4.e6,1.e6,1.e7
DESVAR,3,ROT,0.2,0.01,1.
DESVAR,4,XCG,0.,-1.,1.
DESVAR,5,IXX,0.25,0.01,1.
DVCREL1,101,CBEAM,11,W2A
,1,1.
DVCREL1,102,CBEAM,11,W2B
,1,1.
DVCREL1,103,CBEAM,12,W2A
,1,-1.
DVCREL1,104,CBEAM,12,W2B
,1,-1.
DVMREL1,201,MAT1,1,G
,2,1.
DVCREL1,301,CMASS2,21,M
,3,0.5
DVCREL1,302,CMASS2,22,M
,3,1.
DVCREL1,401,CONM2,31,X1,,,0.1
,4,1.
DVCREL1,501,CONM2,31,I11
,5,2.
"""
#: the cards' own values (not the relations' at XINIT: SOL 200 replaces them)
CARDS = dict(w11=0.0, w12=0.0, g=4.0e6, x1=0.1, i11=0.5, m21=0.1, m22=0.2)


def _deck(tmp_path, name: str, fields: dict, design: bool) -> str:
    text = BULK.format(**fields) + (DESIGN if design else "")
    path = tmp_path / name
    path.write_text(f"SOL 103\nCEND\nMETHOD = 1\nBEGIN BULK\n{text}ENDDATA\n")
    return str(path)


def _by_hand(x: dict) -> dict:
    """The related fields at DESVAR values x, typed as a user edits the cards."""
    return dict(w11=x["OFF"], w12=-x["OFF"], g=x["GMOD"], x1=0.1 + x["XCG"], i11=2 * x["IXX"],
                m21=0.5 * x["ROT"], m22=x["ROT"])  # fmt: skip


@pytest.mark.parametrize(
    "x", [None, dict(OFF=0.3, GMOD=2.5e6, ROT=0.6, XCG=-0.4, IXX=0.05)], ids=["xinit", "moved"]
)
def test_the_design_deck_is_the_deck_edited_by_hand(tmp_path, x):
    """At XINIT and at other DESVAR values: the deck ``write_design_deck`` writes (all nine
    relations evaluated) has the modes of the deck edited by hand, and differs from the cards'
    own values (the relations change the model)."""
    values = x or dict(OFF=0.05, GMOD=4.0e6, ROT=0.2, XCG=0.0, IXX=0.25)
    design = _deck(tmp_path, "design.bdf", CARDS, design=True)
    written = write_design_deck(design, tmp_path / "written.bdf", x)
    hand = _deck(tmp_path, "hand.bdf", _by_hand(values), design=False)
    f_written = load_nastran_model(str(written), parameters={}).solve(n_modes=8).frequencies_hz
    f_hand = load_nastran_model(hand).solve(n_modes=8).frequencies_hz
    np.testing.assert_allclose(f_written, f_hand, rtol=1e-12)
    f_cards = load_nastran_model(_deck(tmp_path, "cards.bdf", CARDS, False)).solve(n_modes=8)
    assert np.max(np.abs(f_cards.frequencies_hz / f_hand - 1)) > 1e-3


def test_every_desvar_is_a_parameter_and_solves_as_the_deck_edited_by_hand(tmp_path):
    """All five DESVARs are parameters: GMOD (DVMREL1 on MAT1 G), and the element cards' own
    fields written into the cards (CBEAM W2A/W2B with COEF +1 and -1, CMASS2 M with COEF 0.5
    and 1, CONM2 X1 with C0 = 0.1, CONM2 I11 with COEF 2), with the DESVAR bounds (XLB < 0
    kept for the offsets); away from XINIT the bound model, and the deck ``--write-bdf``
    writes from it, have the modes of the deck edited by hand."""
    from bayesupdate.nastran.writer import write_updated_deck

    model = load_nastran_model(_deck(tmp_path, "design.bdf", CARDS, design=True))
    assert sorted(model.parameter_names) == ["GMOD", "IXX", "OFF", "ROT", "XCG"]
    assert model.bindings["GMOD"].target == "MAT1 1 G"
    bounds = model.default_bounds()
    assert tuple(bounds["GMOD"]) == (1.0e6, 1.0e7) and tuple(bounds["OFF"]) == (-1.0, 1.0)
    assert model.bindings["OFF"].relations == (
        ("CBEAM", 11, "W2A", 0.0, 1.0), ("CBEAM", 11, "W2B", 0.0, 1.0),
        ("CBEAM", 12, "W2A", 0.0, -1.0), ("CBEAM", 12, "W2B", 0.0, -1.0))  # fmt: skip
    # the cards' values: W2 = 0, CONM2 X1 = 0.1 (C0 0.1), I11 0.5 / 2, CMASS2 0.1 / 0.5, 0.2 / 1
    assert model.default_parameters() == pytest.approx(
        dict(OFF=0.0, GMOD=4.0e6, ROT=0.2, XCG=0.0, IXX=0.25), rel=1e-12
    )
    x = dict(OFF=0.3, GMOD=2.5e6, ROT=0.6, XCG=-0.4, IXX=0.05)
    hand = load_nastran_model(_deck(tmp_path, "hand.bdf", _by_hand(x), design=False))
    f_hand = hand.solve(n_modes=8).frequencies_hz
    f = model.solve(x, n_modes=8).frequencies_hz
    np.testing.assert_allclose(f, f_hand, rtol=1e-9)
    written = write_updated_deck(model, x, tmp_path / "w.bdf")
    again = load_nastran_model(str(written), parameters={}).solve(n_modes=8).frequencies_hz
    np.testing.assert_allclose(again, f_hand, rtol=1e-12)


def test_a_desvar_that_is_not_one_binding_is_named(tmp_path):
    """A DVCREL1 that sums two DESVARs (CONM2 X1 = 0.1 + XCG + IXX) keeps both out (one
    parameter is one DESVAR); the note names each with the file:line of that relation."""
    summed = DESIGN.replace("DVCREL1,401,CONM2,31,X1,,,0.1\n,4,1.\n",
                            "DVCREL1,401,CONM2,31,X1,,,0.1\n,4,1.,5,1.\n")  # fmt: skip
    path = tmp_path / "summed.bdf"
    path.write_text(f"SOL 103\nCEND\nMETHOD = 1\nBEGIN BULK\n{BULK.format(**CARDS)}{summed}"
                    "ENDDATA\n")  # fmt: skip
    model = load_nastran_model(str(path))
    assert sorted(model.parameter_names) == ["GMOD", "OFF", "ROT"]
    note = next(n for n in model.structure.metadata["nastran"]["notes"] if "DESVAR(s)" in n)
    assert note.startswith("2 DESVAR(s) not made parameters"), note
    for part in ("XCG (4: 0 in [-1, 1]): ", "IXX (5: 0.25 in [0.01, 1]): "):
        assert part + "summed.bdf:38 DVCREL1 401: 2 DESVARs in one relation" in note, note


def test_a_shape_variable_is_named_and_the_deck_solves_at_its_grids(tmp_path):
    """A DESVAR that a DVGRID moves GRIDs with (a shape variable, MSC QRG DVGRID) is no
    parameter, even where a DVPREL also uses it; the deck solves as written (its GRIDs are at
    the DESVARs' initial values), the note names the DVGRID with its file:line."""
    plain = load_nastran_model(_deck(tmp_path, "plain.bdf", CARDS, True))
    shaped = DESIGN + "DVGRID,2,3,,1.,0.,1.,0.\n"
    path = tmp_path / "shape.bdf"
    path.write_text(f"SOL 103\nCEND\nMETHOD = 1\nBEGIN BULK\n{BULK.format(**CARDS)}{shaped}"
                    "ENDDATA\n")  # fmt: skip
    model = load_nastran_model(str(path))
    assert sorted(model.parameter_names) == ["IXX", "OFF", "ROT", "XCG"]
    note = next(n for n in model.structure.metadata["nastran"]["notes"] if "DESVAR(s)" in n)
    line = 1 + path.read_text().splitlines().index("DVGRID,2,3,,1.,0.,1.,0.")
    assert f"GMOD (2: 4e+06 in [1e+06, 1e+07]): shape.bdf:{line} DVGRID 2: it moves GRID 3" in note
    np.testing.assert_array_equal(model.predict(n_modes=6).frequencies_hz,
                                  plain.predict(n_modes=6).frequencies_hz)  # fmt: skip


def test_a_relation_to_a_missing_card_is_named(tmp_path):
    """A DVCREL1 on a CBEAM the deck does not have and a DVMREL1 naming a DESVAR it does not
    have: one message, each relation's file:line."""
    from bayesupdate.errors import BayesUpdateError

    bad = DESIGN + "DVCREL1,601,CBEAM,99,W1A\n,1,1.\nDVMREL1,602,MAT1,1,E\n,77,1.\n"
    path = tmp_path / "bad.bdf"
    path.write_text(f"SOL 103\nCEND\nBEGIN BULK\n{BULK.format(**CARDS)}{bad}ENDDATA\n")
    with pytest.raises(BayesUpdateError) as err:
        write_design_deck(path, tmp_path / "out.bdf")
    text = str(err.value)
    assert "2 design relation(s) refused" in text, text
    assert "bad.bdf:41 DVCREL1 601: no CBEAM 99" in text, text
    assert "bad.bdf:43 DVMREL1 602: no DESVAR [77]" in text, text


def test_a_desvar_on_line_fields_with_c0_and_different_coefs(tmp_path):
    """DESVAR AREA sets PBEAM 5 A = 0.1 + 2 x and PBEAM 6 A = 0.2 + 0.5 x (DVPREL1 C0 and COEF
    differ): one parameter over both (re-built line fields), default x = 0.2 where the cards
    agree (A = 0.5 and 0.3); at x = 0.3 the model, and the deck ``--write-bdf`` writes, equal
    the cards edited by hand (A = 0.7, 0.35)."""
    from bayesupdate.nastran.writer import write_updated_deck

    bulk = BULK.format(**CARDS).replace("CBEAM,12,5,", "CBEAM,12,6,")
    bulk += "PBEAM,6,1,{a6},0.02,0.01,,0.015\n"
    design = ("DESVAR,7,AREA,0.2,0.05,1.\nDVPREL1,71,PBEAM,5,A,,,0.1\n,7,2.\n"
              "DVPREL1,72,PBEAM,6,A,,,0.2\n,7,0.5\n")  # fmt: skip

    def deck(name, a5, a6, with_design):
        text = bulk.replace("PBEAM,5,1,0.5,", f"PBEAM,5,1,{a5},").format(a6=a6)
        path = tmp_path / name
        path.write_text(f"SOL 103\nCEND\nMETHOD = 1\nBEGIN BULK\n{text}"
                        f"{design if with_design else ''}ENDDATA\n")  # fmt: skip
        return str(path)

    model = load_nastran_model(deck("d.bdf", 0.5, 0.3, True))
    assert list(model.parameter_names) == ["AREA"]
    b = model.bindings["AREA"]
    assert b.target == "PBEAM 5,6 A" and (b.coefficients, b.offsets) == ((2.0, 0.5), (0.1, 0.2))
    assert model.default_parameters()["AREA"] == pytest.approx(0.2, rel=1e-12)
    hand = load_nastran_model(deck("h.bdf", 0.7, 0.35, False)).solve(n_modes=8)
    f = model.solve({"AREA": 0.3}, n_modes=8).frequencies_hz
    np.testing.assert_allclose(f, hand.frequencies_hz, rtol=1e-9)
    written = write_updated_deck(model, {"AREA": 0.3}, tmp_path / "w.bdf")
    again = load_nastran_model(str(written), parameters={}).solve(n_modes=8).frequencies_hz
    np.testing.assert_allclose(again, hand.frequencies_hz, rtol=1e-12)


#: a free frame of two CBEAMs on a tapered PBEAM 5 (end B given on its station line: A, I1, I2,
#: J differ from end A's); fields marked {name} are the design model's
TAPERED = """EIGRL,1,,,8
PARAM,COUPMASS,1
GRID,1,,0.,0.,0.
GRID,2,,10.,0.,0.
GRID,3,,20.,0.,5.
CBEAM,11,5,1,2,0.,0.,1.
CBEAM,12,5,2,3,0.,1.,0.
PBEAM,5,1,{a_a},0.02,0.01,,0.015
,NO,1.0,0.3,{i1_b},0.008,,0.01
MAT1,1,1.e7,4.e6,,0.1
"""
TAPERED_DESIGN = """DESVAR,1,AREA,0.25,0.1,1.
DESVAR,2,IB,0.006,0.001,0.1
DVPREL1,11,PBEAM,5,A
,1,2.
DVPREL1,12,PBEAM,5,I1(B)
,2,1.
"""


def test_a_tapered_pbeam_design_deck_sets_each_station(tmp_path):
    """DVPREL1 PNAME "A" sets end A alone and "I1(B)" end B alone (MSC QRG DVPREL1): the deck
    ``write_design_deck`` writes at AREA = 0.4, IB = 0.03 has the modes of the tapered deck
    edited by hand at those two stations (end B's A and end A's I1 stay), and differs from
    the deck made uniform.  Neither DESVAR is a parameter (a binding sets every station):
    the note names both relations."""

    def deck(name, a_a, i1_b, design):
        text = TAPERED.format(a_a=a_a, i1_b=i1_b) + (TAPERED_DESIGN if design else "")
        path = tmp_path / name
        path.write_text(f"SOL 103\nCEND\nMETHOD = 1\nBEGIN BULK\n{text}ENDDATA\n")
        return str(path)

    def modes(path):
        return load_nastran_model(path, parameters={}).solve(n_modes=8).frequencies_hz

    written = write_design_deck(deck("d.bdf", 0.5, 0.012, True), tmp_path / "w.bdf",
                                {"AREA": 0.4, "IB": 0.03})  # fmt: skip
    hand = modes(deck("h.bdf", 0.8, 0.03, False))
    np.testing.assert_allclose(modes(str(written)), hand, rtol=1e-12)
    uniform = tmp_path / "u.bdf"  # both stations written: what a binding would do
    uniform.write_text(Path(deck("u0.bdf", 0.8, 0.03, False)).read_text()
                       .replace(",NO,1.0,0.3,", ",NO,1.0,0.8,"))  # fmt: skip
    assert np.abs(modes(str(uniform)) / hand - 1).max() > 1e-3
    model = load_nastran_model(deck("d2.bdf", 0.5, 0.012, True))
    assert model.parameter_names == ()
    note = next(n for n in model.structure.metadata["nastran"]["notes"] if "DESVAR(s)" in n)
    assert "AREA (1: 0.25 in [0.1, 1]): d2.bdf:17 DVPREL1 11: sets one station of PBEAM 5" in note
    assert "IB (2: 0.006 in [0.001, 0.1]): d2.bdf:19 DVPREL1 12: sets one station" in note
