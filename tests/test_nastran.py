"""Nastran bulk data in (``bayesupdate.nastran``), through ``bayesupdate modes --model deck``.

Verification on decks nobody here wrote (``shared/data/nastran``, README there): the MSC beam
deck against MSC's eigenvalues (4e-4 %), the NX FEMAP exhaust (4,466 shells) against NX's modes
2-10 (3 %); conversions against closed forms on small decks written here (PBAR/PBEAM sections,
shear factors, PBARL shapes, CBAR offsets and pin flags, CD frames); bad input exits 2 with one
line.  The decks are read by the package's own reader (``nastran.deck``): no pyNastran.  The
shared-data tests are skipped when the shared data are missing.
"""

import json
import pickle
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

from bayesupdate.cli import main

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
def test_msc_beam_deck_matches_msc_within_4e_4_percent(capsys):
    out = modes_json(capsys, "--model", DATA / "beam_modes" / "beam_modes.dat", "--modes", 10)
    f = np.array(out["frequencies_hz"])
    # CBAR/CBEAM as general beams with MAT1's own G: within 7.5e-5 % of the f06 (measured;
    # with G = E / 2(1 + nu) the torsion mode was 4.0e-4 % low), asserted at 4e-4 %
    assert np.all(np.abs(f / MSC_BEAM_HZ - 1) < 4e-6), f / MSC_BEAM_HZ - 1
    assert out["rigid_modes"] == 0
    assert out["n_dof"] == 66  # 11 GRIDs in use (GRID 12 has no element: AUTOSPC)
    # CONM2 0.00259 + rod rho pi r^2 L = 7.4851e-4 x pi x 10 (lbf s^2/in, no WTMASS)
    assert out["mass"] == pytest.approx(0.00259 + 7.4851e-4 * np.pi * 10, rel=1e-9)
    assert out["units"]["system"] == "in, lbf, s"
    # the deck's own mass unit, never called kg
    assert out["mass_unit"] == "lbf s^2/in" and "mass_kg" not in out


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
    assert out["mass"] == pytest.approx(2.0)


@pytest.mark.parametrize("rbar", ["RBAR,2,2,3,123456", "RBAR,2,3,2,,123456,123456"])
def test_rbar_forms_with_six_independent_components_at_one_end(capsys, tmp_path, rbar):
    """MSC QRG RBAR: CMA and CMB blank make every component not in CNA, CNB dependent (MSC's
    BAH plane writes its tail's RBARs so); the six independent ones may be at either end (GA
    and GB swapped, CNB and CMA): the mixed deck's closed form either way."""
    deck = tmp_path / "rbar.bdf"
    deck.write_text(MIXED_DECK.replace("RBAR,2,2,3,123456,,,123456", rbar))
    out = modes_json(capsys, "--model", deck)
    k_x = 1 / (1 / 5e5 + 1 / 1e4)
    expected = np.sqrt([k_x / 2, 1e4 / 2, 1e4 / 2, 1e6, 1e6, 1e6]) / (2 * np.pi)
    assert out["frequencies_hz"] == pytest.approx(expected, rel=1e-6)


def test_rbar_with_independent_components_split_over_both_ends_is_refused(capsys, tmp_path):
    deck = tmp_path / "split.bdf"
    deck.write_text(MIXED_DECK.replace("RBAR,2,2,3,123456,,,123456", "RBAR,2,2,3,123,456"))
    line = rejected(capsys, "--model", deck)
    assert "RBAR 2: only all six independent components at one end" in line, line
    assert "split.bdf:" in line, line


def test_cbush_with_ends_apart_acts_at_its_midpoint_through_rigid_arms(capsys, tmp_path):
    """The mixed deck with GRID 4 at x = 20: the bush (CID 0, S = 0.5) acts at x = 15, 5 from
    the mass.  Lateral v and rotation t of GRID 4 (the bar end holds GRID 3): the spring point
    moves v - 5 t, so K = [[ky, -5 ky], [-5 ky, kr + 25 ky]] on M = diag(2, 1) (MSC QRG CBUSH:
    the element's offsets are rigid); x in series and the twist as before."""
    apart = tmp_path / "apart.bdf"
    apart.write_text(MIXED_DECK.replace("GRID,4,,10.", "GRID,4,,20."))
    out = modes_json(capsys, "--model", apart)
    ky, kr = 1e4, 1e6
    K = np.array([[ky, -5 * ky], [-5 * ky, kr + 25 * ky]])
    bend = np.sqrt(scipy.linalg.eigh(K, np.diag([2.0, 1.0]), eigvals_only=True))
    k_x = 1 / (1 / 5e5 + 1 / 1e4)
    expected = np.sort(np.r_[np.sqrt(k_x / 2), bend, bend, np.sqrt(kr)]) / (2 * np.pi)
    assert out["frequencies_hz"] == pytest.approx(expected, rel=1e-6)


def test_the_reader_needs_no_pynastran(capsys, tmp_path, monkeypatch):
    deck = tmp_path / "springs.bdf"
    deck.write_text(SPRING_DECK)
    monkeypatch.setitem(sys.modules, "pyNastran", None)
    out = modes_json(capsys, "--model", deck)
    assert out["frequencies_hz"] == pytest.approx(np.sqrt([100.0, 400.0, 900.0]) / (2 * np.pi))


def test_unsupported_card_named_with_its_line(capsys, tmp_path):
    deck = tmp_path / "shear.bdf"
    panel = "CSHEAR  20      1       1       2       1       2"
    deck.write_text(SPRING_DECK.replace("ENDDATA", f"{panel}\nENDDATA"))
    line = rejected(capsys, "--model", deck)
    assert "CSHEAR 20" in line and "shear.bdf:17" in line


def test_cards_of_other_analyses_are_ignored_and_listed(capsys, tmp_path):
    """A damper, a load, an aerodynamic panel, MDLPRM's HDF5 output and an aeroelastic DMI
    (W2GJ) leave the real modes as they are (the spring deck's closed form), each group listed
    once; a preload (STATSUB), another MDLPRM (OFFDEF: offsets) and another DMI are refused."""
    deck = tmp_path / "other.bdf"
    dmi = "DMI     W2GJ    0       2       1       0               1       1"
    extra = ("CDAMP2  20      1.      1       1\nFORCE   30      1               1.      1.\n"
             f"AERO    0       1.      1.      1.\nMDLPRM  HDF5    1\n{dmi}\nENDDATA")  # fmt: skip
    deck.write_text(SPRING_DECK.replace("ENDDATA", extra))
    out = modes_json(capsys, "--model", deck)
    assert out["frequencies_hz"] == pytest.approx(np.sqrt([100.0, 400.0, 900.0]) / (2 * np.pi))
    notes = " ".join(out["notes"])
    for what in ("of damping elements ignored", "of static and dynamic loads ignored",
                 "of the aeroelastic model ignored"):  # fmt: skip
        assert what in notes, notes
    assert "MDLPRM HDF5 output settings ignored" in notes, notes
    assert "DMI W2GJ (aeroelastic corrections) ignored" in notes, notes
    text = deck.read_text().replace("CEND", "CEND\nSTATSUB = 1").replace("W2GJ", "STIFF")
    deck.write_text(text.replace("MDLPRM  HDF5    1", "MDLPRM  HDF5    1       OFFDEF  1"))
    line = rejected(capsys, "--model", deck)
    assert "other.bdf:3 case control STATSUB" in line, line
    assert "MDLPRM OFFDEF is not supported" in line, line
    assert "DMI STIFF is not supported" in line, line


#: a DMIG's header (symmetric, real) and one column: 50 at GRID 1 component 1
DMIG = ("DMIG    KAX     0       6       1       0\n"
        "DMIG    KAX     1       1               1       1       50.")  # fmt: skip


def test_a_dmig_counts_only_where_k2gg_or_m2gg_selects_it(capsys, tmp_path):
    """A DMIG that the case control adds to the dynamic stiffness of extra points (K2PP) or
    selects nowhere leaves the real modes as they are (the spring deck's closed form), with a
    note; one that K2GG (here with a scale factor and a second matrix) or M2GG adds to K or M
    is refused, named with its line."""
    deck = tmp_path / "dmig.bdf"

    def write(command: str) -> None:
        text = SPRING_DECK.replace("ENDDATA", f"{DMIG}\nENDDATA")
        deck.write_text(text.replace("CEND", f"CEND\n{command}"))

    for command in ("K2PP = KAX", "$ no selection"):
        write(command)
        out = modes_json(capsys, "--model", deck)
        freq = np.sqrt([100.0, 400.0, 900.0]) / (2 * np.pi)
        assert out["frequencies_hz"] == pytest.approx(freq)
        assert any("DMIG KAX ignored: no K2GG or M2GG selects it" in n for n in out["notes"])
    for command in ("K2GG = 1.5*KAX, KBX", "M2GG = KAX"):
        write(command)
        line = rejected(capsys, "--model", deck)
        assert "dmig.bdf:18 DMIG KAX: DMIG KAX is not supported: the case control's K2GG" in line


def test_unreadable_deck_and_massless_deck(capsys, tmp_path):
    bad = tmp_path / "bad.dat"
    bad.write_text("BEGIN BULK\nGRID    1       x       y\nENDDATA\n")
    assert "bad.dat:2 GRID 1: CP = 'X': give an integer" in rejected(capsys, "--model", bad)
    massless = tmp_path / "massless.bdf"
    massless.write_text(SPRING_DECK.replace("2.0\n", "0.0\n"))
    assert "no mass" in rejected(capsys, "--model", massless)


# -- CBAR/CBEAM general sections, offsets, pin flags and CD frames --------------------------------
def _num(value) -> str:
    """A float for a free-field card at full precision (repr: '0.0015', '1e-06')."""
    return repr(float(value))


def _deck(bulk: str, extra_case: str = "") -> str:
    return (
        f"SOL 103\nCEND\nSPC = 1\nMETHOD = 1\n{extra_case}BEGIN BULK\nEIGRL,1,,,4\n{bulk}ENDDATA\n"
    )


CANTILEVER = """GRID,1,,0.,0.,0.
GRID,2,,2.,0.,0.
MAT1,1,2.e11,,0.3,0.
CONM2,9,2,,10.
SPC1,1,123456,1
"""


def test_pbar_and_pbeam_cantilever_match_closed_forms(tmp_path):
    """A massless cantilever (one element, exact for a tip load) with a 10 kg tip mass:
    k = 1 / (L^3 / 3 E I + L / (K G A)), f = sqrt(k / m) / 2 pi.  The orientation vector is
    basic z, so plane 1 (I1, K1) bends along basic z and plane 2 (I2, K2) along basic y."""
    from bayesupdate.nastran import load_nastran_model

    A, I1, I2, L, E, m = 2e-3, 4e-6, 1e-6, 2.0, 2e11, 10.0
    G = E / 2.6
    cases = {
        "PBAR,5,1,2.e-3,4.e-6,1.e-6,2.e-6\n": (np.inf, np.inf),  # K1, K2 blank: rigid
        "PBEAM,5,1,2.e-3,4.e-6,1.e-6,,2.e-6\n,,,,,,,,\n,0.6,0.8\n": (0.6, 0.8),
    }
    for card, (k1, k2) in cases.items():
        elem = "CBAR" if card.startswith("PBAR") else "CBEAM"
        deck = tmp_path / f"{elem}.bdf"
        deck.write_text(_deck(CANTILEVER + card + f"{elem},7,5,1,2,0.,0.,1.\n"))
        r = load_nastran_model(deck).solve(n_modes=2)
        k = [1 / (L**3 / (3 * E * i) + L / (kk * G * A)) for i, kk in ((I2, k2), (I1, k1))]
        assert r.frequencies_hz == pytest.approx(np.sqrt(np.array(k) / m) / (2 * np.pi), rel=1e-12)
        u = r.modes.shapes[6:9]  # grid 2: the lower mode along basic y (I2), then z (I1)
        assert abs(u[1, 0]) / np.linalg.norm(u[:, 0]) == pytest.approx(1.0, abs=1e-9)
        assert abs(u[2, 1]) / np.linalg.norm(u[:, 1]) == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize(
    "pbarl, pbar",
    [
        # MSC BAR: DIM1 along z_elem, DIM2 along y_elem: I1 = d1 d2^3 / 12
        ("BAR,,,,\n,0.03,0.05", (0.03 * 0.05, 0.03 * 0.05**3 / 12, 0.05 * 0.03**3 / 12)),
        # MSC BOX: DIM3 the walls across DIM2, DIM4 across DIM1
        ("BOX,,,,\n,0.06,0.1,4.e-3,5.e-3",
         (0.06 * 0.1 - 0.05 * 0.092, (0.06 * 0.1**3 - 0.05 * 0.092**3) / 12,
          (0.1 * 0.06**3 - 0.092 * 0.05**3) / 12)),
        # MSC I: DIM1 the height along y_elem
        ("I,,,,\n,0.2,0.1,0.1,6.e-3,9.e-3,9.e-3",
         (2 * 0.1 * 9e-3 + 0.182 * 6e-3, (0.1 * 0.2**3 - 0.094 * 0.182**3) / 12,
          (2 * 9e-3 * 0.1**3 + 0.182 * 6e-3**3) / 12)),
    ],
)  # fmt: skip
def test_pbarl_shapes_follow_msc_axes(tmp_path, pbarl, pbar):
    """A PBARL shape reads as the PBAR with MSC's A, I1, I2 (MSC QRG PBARL figures; the shear
    factors and J of the shape are passed on to the PBAR so that only the axes are compared)."""
    from bayesupdate.nastran import load_nastran_model

    kind = pbarl.split(",")[0]
    first = tmp_path / "pbarl.bdf"
    first.write_text(_deck(CANTILEVER + f"PBARL,5,1,,{pbarl}\nCBAR,7,5,1,2,0.,1.,1.\n"))
    m1 = load_nastran_model(first)
    sec = m1.structure.general_beams
    assert (sec.area[0], sec.iz[0], sec.iy[0]) == pytest.approx(pbar, rel=1e-12)  # I1 = iz
    J, K1, K2 = sec.torsion[0], sec.shear_y[0], sec.shear_z[0]
    second = tmp_path / "pbar.bdf"
    fields = ",".join(_num(v) for v in (*pbar, J))
    card = f"PBAR,5,1,{fields}\n,,,,,,,,\n,{_num(K1)},{_num(K2)}\n"
    second.write_text(_deck(CANTILEVER + card + "CBAR,7,5,1,2,0.,1.,1.\n"))
    f1 = m1.solve(n_modes=3).frequencies_hz  # the tip's 3 translations carry all the mass
    f2 = load_nastran_model(second).solve(n_modes=3).frequencies_hz
    np.testing.assert_allclose(f1, f2, rtol=1e-12, err_msg=kind)


OFFSET_COMMON = """MAT1,1,2.e11,,0.3,7800.
PBARL,5,1,,BOX,,,,
,0.06,0.1,4.e-3,5.e-3
CORD2R,7,,0.,0.,0.,0.3,0.4,0.866
,1.,0.2,0.
CONM2,9,2,,10.,,,,
,1.,,2.,,,3.
SPC1,1,123456,1
"""


@pytest.mark.parametrize("elem, prop", [("CBAR", "PBARL"), ("CBEAM", "PBEAML")])
def test_cbar_offsets_equal_rigid_bars_to_the_offset_points(tmp_path, elem, prop):
    """WA in GA's CD frame (OFFT G), WB in basic (OFFT B), v in GA's CD frame: the same as the
    bar between the offset points (basic coordinates written here) joined by RBARs; a CBEAM's
    W1A..W3B likewise (its lumped torsional inertia sits at the offset ends in both)."""
    from bayesupdate.nastran import load_nastran_model
    from bayesupdate.nastran.deck import Refusals, read_deck
    from bayesupdate.nastran.frames import read_grids

    common = OFFSET_COMMON.replace("PBARL", prop)
    wa_cd, wb = np.array([0.05, 0.1, -0.02]), np.array([0.0, -0.08, 0.06])
    offset = tmp_path / "offset.bdf"
    offset.write_text(_deck(common + "GRID,1,,0.,0.,0.,7\nGRID,2,,2.,0.5,0.\n"
                            f"{elem},3,5,1,2,0.,0.,1.,GGB\n,,,{','.join(map(str, wa_cd))},"
                            f"{','.join(map(str, wb))}\n"))  # fmt: skip
    model = load_nastran_model(offset)
    beta = read_grids(read_deck(offset), Refusals("")).coords[7].axes  # rows: CD 7 axes in basic
    wa = beta.T @ wa_cd
    ends = tmp_path / "ends.bdf"
    ends.write_text(_deck(common + "GRID,1,,0.,0.,0.,7\nGRID,2,,2.,0.5,0.\n"
                          f"GRID,3,,{','.join(map(_num, wa))},7\n"
                          f"GRID,4,,{','.join(map(_num, np.array([2.0, 0.5, 0]) + wb))}\n"
                          f"{elem},3,5,3,4,0.,0.,1.\nRBAR,4,1,3,123456,,,123456\n"
                          "RBAR,5,2,4,123456,,,123456\n"))  # fmt: skip
    f1 = model.solve(n_modes=4).frequencies_hz
    f2 = load_nastran_model(ends).solve(n_modes=4).frequencies_hz
    np.testing.assert_allclose(f1, f2, rtol=1e-10)


def _offset_frequencies(tmp_path, elem: str, grids: str, card: str) -> np.ndarray:
    """The first 4 frequencies of OFFSET_COMMON's BOX bar with an isotropic tip mass (so that
    turning the bar turns the whole model) on ``grids``, the element card ``card``."""
    from bayesupdate.nastran import load_nastran_model

    common = OFFSET_COMMON.replace(",1.,,2.,,,3.", ",2.,,2.,,,2.")
    deck = tmp_path / f"deck{len(list(tmp_path.iterdir()))}.bdf"
    prop = "PBARL" if elem == "CBAR" else "PBEAML"
    deck.write_text(_deck(common.replace("PBARL", prop) + grids + card))
    return load_nastran_model(deck).solve(n_modes=4).frequencies_hz


@pytest.mark.parametrize("elem", ["CBAR", "CBEAM"])
def test_offt_o_offsets_are_in_the_element_axes(tmp_path, elem):
    """OFFT O (MSC QRG CBAR/CBEAM): an offset in the element's axes, the frame of the grids
    GA -> GB (not the offset ends) and v.  A bar along basic x with v = basic z has element
    axes x, y = z, z = -y (z = x cross v), so WA = (0, 0.1, 0.05) in element axes is
    (0, -0.05, 0.1) in basic, by hand.  The same bar turned along CD frame 7's skew x axis (v
    along its z, in GA's CD 7) is the first model turned, so it has the same frequencies with
    the same element-axis offsets, where the same numbers as basic offsets do not."""
    from bayesupdate.nastran.deck import Refusals, read_deck
    from bayesupdate.nastran.frames import read_grids

    card = f"{elem},3,5,1,2,0.,0.,1.,{{offt}}\n,,,{{wa}},{{wb}}\n"
    wa, wb = "0.,0.1,0.05", "0.,-0.02,0.03"
    straight = "GRID,1,,0.,0.,0.\nGRID,2,,2.,0.,0.\n"
    f_o = _offset_frequencies(tmp_path, elem, straight, card.format(offt="GOO", wa=wa, wb=wb))
    by_hand = card.format(offt="GBB", wa="0.,-0.05,0.1", wb="0.,-0.03,-0.02")
    np.testing.assert_allclose(f_o, _offset_frequencies(tmp_path, elem, straight, by_hand),
                               rtol=1e-10)  # fmt: skip
    probe = tmp_path / "probe.bdf"
    probe.write_text(_deck(OFFSET_COMMON + "GRID,1,,0.,0.,0.,7\n"))
    x7 = read_grids(read_deck(probe), Refusals("")).coords[7].axes[0]
    turned = f"GRID,1,,0.,0.,0.,7\nGRID,2,,{','.join(map(_num, 2.0 * x7))}\n"
    f_turned = _offset_frequencies(tmp_path, elem, turned, card.format(offt="GOO", wa=wa, wb=wb))
    np.testing.assert_allclose(f_turned, f_o, rtol=1e-9)
    f_basic = _offset_frequencies(tmp_path, elem, turned, card.format(offt="GBB", wa=wa, wb=wb))
    assert np.max(np.abs(f_basic / f_o - 1)) > 1e-3


def test_cbeam_bit_is_ignored_as_msc_ignores_it_on_an_ordinary_cbeam(tmp_path):
    """CBEAM field 9 as BIT (a real): the built-in twist of a beam p-element only (MSC QRG
    CBEAM), so the offsets keep OFFT's default GGG (WA in GA's CD frame 7 here) and the model is
    the one with OFFT blank, with a note for a BIT other than 0."""
    from bayesupdate.nastran import load_nastran_model

    models = {}
    for name, field in (("bit", "0.3"), ("blank", "")):
        deck = tmp_path / f"{name}.bdf"
        deck.write_text(_deck(OFFSET_COMMON.replace("PBARL", "PBEAML")
                              + "GRID,1,,0.,0.,0.,7\nGRID,2,,2.,0.5,0.\n"
                              f"CBEAM,3,5,1,2,0.,0.,1.,{field}\n,,,0.05,0.1,-0.02\n"))  # fmt: skip
        models[name] = load_nastran_model(deck)
    f = {k: m.solve(n_modes=4).frequencies_hz for k, m in models.items()}
    np.testing.assert_array_equal(f["bit"], f["blank"])
    notes = models["bit"].structure.metadata["nastran"]["notes"]
    assert any("BIT" in n and "p-elements only" in n for n in notes), notes
    assert not any("BIT" in n for n in models["blank"].structure.metadata["nastran"]["notes"])


@pytest.mark.parametrize(
    "elem, prop",
    [("CBAR", "PBAR,5,1,2.e-3,4.e-6,1.e-6,2.e-6"), ("CBEAM", "PBEAM,5,1,2.e-3,4.e-6,1.e-6,,2.e-6")],
)
def test_cbar_pin_flag_equals_a_hinge_grid_in_a_cd_frame(tmp_path, elem, prop):
    """PB = 6 at a clamped end = the bar ending on a coincident grid tied by an RBE2 in all
    but 6 of that grid's CD frame 7.  The bar's v is basic z, so its local z (the released
    axis) is x cross v = -basic y; frame 7 has its z along basic y and its x, y turned about it
    (so '12345' there is a rotated component set: the grid gets its frame).  Lumped mass: no
    inertia on the released rotation, so the two are the same model; a CBEAM's PB likewise."""
    from bayesupdate.nastran import load_nastran_model

    common = ("GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,2.,0.,0.\nMAT1,1,2.e11,,0.3,7800.\n"
              f"{prop}\n{elem},1,5,1,2,0.,0.,1.\nSPC1,1,123456,1,3\n"
              "CORD2R,7,,0.,0.,0.,0.,1.,0.\n,0.6,0.,0.8\n")  # fmt: skip
    pinned = tmp_path / "pinned.bdf"
    pinned.write_text(_deck(common + f"{elem},2,5,2,3,0.,0.,1.\n,,6\n"))
    hinge = tmp_path / "hinge.bdf"
    hinge.write_text(_deck(common + f"GRID,4,,2.,0.,0.,7\n{elem},2,5,2,4,0.,0.,1.\n"
                           "RBE2,8,3,12345,4\n"))  # fmt: skip
    m = load_nastran_model(hinge)
    assert m.structure.constraints.frame_node.size == 1  # grid 4 has its CD frame
    f1 = load_nastran_model(pinned).solve(n_modes=3).frequencies_hz  # grid 2 has the mass
    np.testing.assert_allclose(f1, m.solve(n_modes=3).frequencies_hz, rtol=1e-10)


def _sliding_foot(rotation: np.ndarray, framed: bool) -> str:
    """An L-shaped bar frame clamped at grid 1; grid 3 slides: SPC '2' in CD frame 7 (axes =
    rows of ``rotation``) if ``framed``, else every point turned by ``rotation`` and SPC '2' in
    basic."""
    pts = np.array([(0, 0, 0), (1.5, 0, 0), (1.5, 1.0, -0.8)], float)
    turn = np.eye(3) if framed else rotation
    x = pts @ turn.T
    v = turn @ np.array([0.0, 0.0, 1.0])
    cd = 7 if framed else 0
    z, xz = rotation[2], rotation[0]
    lines = [f"GRID,{k + 1},,{','.join(map(_num, p))}" + (f",{cd}" if k == 2 else "")
             for k, p in enumerate(x)]  # fmt: skip
    lines += [
        f"CORD2R,7,,0.,0.,0.,{','.join(map(_num, z))}",
        f",{','.join(map(_num, xz))}",
        "MAT1,1,7.e10,,0.33,2700.",
        "PBARL,5,1,,I,,,,",
        ",0.12,0.08,0.08,5.e-3,7.e-3,7.e-3",
        f"CBAR,1,5,1,2,{','.join(map(_num, v))}",
        f"CBAR,2,5,2,3,{','.join(map(_num, v))}",
        "CONM2,9,2,,4.",
        "SPC1,1,123456,1",
        "SPC1,1,2,3",
    ]
    return _deck("\n".join(lines) + "\n")


def test_partial_spc_in_a_rotated_cd_frame_equals_the_rotated_deck(tmp_path):
    from scipy.spatial.transform import Rotation

    from bayesupdate.nastran import load_nastran_model

    A = Rotation.from_euler("zyx", [35, -20, 50], degrees=True).as_matrix().T
    f = []
    for framed in (True, False):
        deck = tmp_path / f"foot{framed}.bdf"
        deck.write_text(_sliding_foot(A, framed))
        f.append(load_nastran_model(deck).solve(n_modes=4).frequencies_hz)
    np.testing.assert_allclose(f[0], f[1], rtol=1e-10)


@pytest.mark.parametrize(
    "card, words",
    [
        ("PBARL,5,1,,HAT,,,,\n,0.1,0.05,0.005,0.02\nCBAR,7,5,1,2,0.,0.,1.\n",
         "CBAR 7: PBARL 5 type HAT"),
        ("PBAR,5,1,2.e-3,4.e-6,1.e-6,2.e-6\nCBAR,7,5,1,2,0.,0.,1.,GXO\n,,,0.,0.,0.1\n",
         "CBAR 7: OFFT GXO: give three letters"),
        ("PBAR,5,1,2.e-3,4.e-6,1.e-6,2.e-6\nCBAR,7,5,1,2,0.,0.,1.,0.5\n",
         "CBAR 7: OFFT = 0.5: give a code"),
        ("PBAR,5,1,2.e-3,4.e-6,1.e-6,2.e-6\nCBAR,7,5,1,2,1.,0.,0.\n",
         "CBAR 7: the orientation vector is parallel to the axis"),
        ("PBAR,5,1,2.e-3,4.e-6,1.e-6,2.e-6\nCBAR,7,5,1,2,0.,0.,1.\n,1,1\n",
         "CBAR 7: its pin flags let it move without strain"),
        ("PBAR,5,1,-2.e-3,4.e-6,1.e-6,2.e-6\nCBAR,7,5,1,2,0.,0.,1.\n",
         "CBAR 7: section 'PBAR 5': area"),
    ],
)  # fmt: skip
def test_bad_beam_cards_are_one_line_errors(capsys, tmp_path, card, words):
    deck = tmp_path / "bad.bdf"
    deck.write_text(_deck(CANTILEVER + card))
    line = rejected(capsys, "--model", deck)
    assert words in line and "bad.bdf:" in line, line


def test_coupled_cbar_mass_is_translational_as_msc_forms_it(capsys, tmp_path):
    """PARAM COUPMASS 1: a CBAR's mass is the consistent mass of its translations alone, no
    rotary inertia of bending and no torsional inertia (as MSC's: pyNastran's pt145 deck then
    gives its f06 to the printed digits).  A steel cantilever (1 m, 40 CBARs, shear rigid, I1
    1e-6 and I2 2e-6 m^4 on A 1e-3 m^2) with a
    massless tip carrying 1 kg m^2 about its axis: Euler-Bernoulli's bending roots in both
    planes (Blevins, *Formulas for natural frequency and mode shape*, table 8-1: 1.87510,
    4.69409), and a twist of the massless shaft, f = sqrt(G J / L I_tip) / 2 pi (the shaft's
    own torsional inertia rho (I1 + I2) L / 3 would lower it by 0.39 %)."""
    E, G, rho, A, I1, I2, J, L = 2.0e11, 7.7e10, 7800.0, 1.0e-3, 1.0e-6, 2.0e-6, 2.0e-6, 1.0
    n = 40
    lines = ["SOL 103", "CEND", "SPC = 1", "METHOD = 1", "BEGIN BULK", "EIGRL,1,,,5",
             "PARAM,COUPMASS,1", f"PBAR,1,1,{A!r},{I1!r},{I2!r},{J!r}",
             f"MAT1,1,{E!r},{G!r},,{rho!r}", "SPC1,1,123456,1",
             f"CONM2,99,{n + 1},,0.\n,1.,,0.,,,0."]  # fmt: skip
    lines += [f"GRID,{i + 1},,{L * i / n!r},0.,0." for i in range(n + 1)]
    lines += [f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,1.,0." for i in range(n)]
    deck = tmp_path / "cantilever.bdf"
    deck.write_text("\n".join([*lines, "ENDDATA", ""]))
    f = np.array(modes_json(capsys, "--model", deck)["frequencies_hz"])
    bending = [b**2 / (2 * np.pi * L**2) * np.sqrt(E * i / (rho * A))
               for b in (1.875104069, 4.694091133) for i in (I1, I2)]  # fmt: skip
    twist = np.sqrt(G * J / L / 1.0) / (2 * np.pi)
    np.testing.assert_allclose(f, np.sort([*bending, twist]), rtol=3e-7)


def test_grdset_fills_the_grids_blank_fields(capsys, tmp_path):
    """GRDSET (MSC QRG): its CD, PS fill every GRID's blank ones; a GRID's own field stays.  A
    cantilever of 10 CBARs held in z and its rotations about x, y (PS 345) by GRDSET gives the
    modes of the same deck with PS 345 written on each GRID, and not those of the free deck."""

    def deck(name, grdset: bool, each: str, mid: str = ""):
        lines = ["SOL 103", "CEND", "SPC = 1", "METHOD = 1", "BEGIN BULK", "EIGRL,1,,,4",
                 "PBAR,1,1,1.0E-3,1.0E-6,2.0E-6,2.0E-6", "MAT1,1,2.0E11,7.7E10,,7800.",
                 "SPC1,1,123456,1"]  # fmt: skip
        lines += ["GRDSET,,,,,,,345"] if grdset else []
        lines += [f"GRID,{i + 1},,{i / 10!r},0.,0.,,{mid if i == 5 and mid else each}"
                  for i in range(11)]  # fmt: skip
        lines += [f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,1.,0." for i in range(10)]
        path = tmp_path / name
        path.write_text("\n".join([*lines, "ENDDATA", ""]))
        return modes_json(capsys, "--model", path)["frequencies_hz"]

    held = deck("each.bdf", False, "345")
    assert deck("grdset.bdf", True, "") == held
    assert deck("free.bdf", False, "") != held
    own = deck("own.bdf", False, "345", mid="3456")  # GRID 6's own PS also holds its rz
    assert deck("grdset_own.bdf", True, "", mid="3456") == own != held


MPC_DECK = """SOL 103
CEND
SPC = 1
{mpc}METHOD = 1
BEGIN BULK
EIGRL,1,,,2
GRID,2,,0.,0.,0.
GRID,3,,1.,0.,0.
CONM2,20,2,,2.
CONM2,30,3,,3.
CELAS2,21,100.,2,1
CELAS2,31,400.,3,1
CELAS2,40,50.,2,1,3,1
SPC1,1,23456,2,3
MPC,7,2,1,1.,3,1,-0.5
ENDDATA
"""


def test_mpc_ties_dofs_as_its_equation_says(capsys, tmp_path):
    """MSC QRG MPC: 1.0 u2 - 0.5 u3 = 0 makes GRID 2's x half of GRID 3's (a lever): one mode,
    f = sqrt((k3 + k2 / 4 + k23 / 4) / (m3 + m2 / 4)) / 2 pi (k23 the spring between them);
    without MPC = 7 in the case control the set is left out (a note says so): two modes."""
    deck = tmp_path / "mpc.bdf"
    deck.write_text(MPC_DECK.format(mpc="MPC = 7\n"))
    out = modes_json(capsys, "--model", deck, "--modes", "1")
    lever = np.sqrt((400.0 + 100.0 / 4 + 50.0 / 4) / (3.0 + 2.0 / 4)) / (2 * np.pi)
    assert out["frequencies_hz"] == pytest.approx([lever], rel=0, abs=5e-7)  # printed digits
    deck.write_text(MPC_DECK.format(mpc=""))
    out = modes_json(capsys, "--model", deck)
    K = np.array([[150.0, -50.0], [-50.0, 450.0]])
    apart = np.sqrt(scipy.linalg.eigh(K, np.diag([2.0, 3.0]), eigvals_only=True)) / (2 * np.pi)
    assert out["frequencies_hz"] == pytest.approx(apart, rel=0, abs=5e-7)
    assert any("MPC set(s) [7] not selected" in n for n in out["notes"]), out["notes"]
    # a dependent DOF that a support also holds: the MPC is named with its file:line, the DOF
    # by its GRID (the solver's node 0)
    held = MPC_DECK.format(mpc="MPC = 7\n").replace("23456,2,3", "123456,2\nSPC1,1,23456,3")
    deck.write_text(held)
    line = rejected(capsys, "--model", deck, "--modes", "1")
    assert "mpc.bdf:17 MPC 7" in line and "also fixed by a support" in line, line
    assert "its dependent DOF GRID 2 ux" in line, line


TIP_MASS_DECK = """SOL 103
CEND
SPC = 1
BEGIN BULK
GRID,1,,0.,0.,0.
GRID,2,,10.,0.,0.
GRID,3,,20.,0.,0.
CBAR,1,5,1,2,0.,1.,0.
CBAR,2,5,2,3,0.,1.,0.
PBAR,5,7,1.,1.,1.,1.
MAT1,7,1.e7,,.3
CONM2,10,3,,1.
SPC1,1,123456,1
ENDDATA
"""


def test_more_modes_than_dofs_with_mass_is_refused_by_count_not_as_a_mechanism(tmp_path):
    """A massless cantilever of two CBARs with a point mass (no inertia) at its tip: 12 free
    DOFs, 3 with mass, so 3 modes.  Asking for 4 used to return a mode of zero mass, whose
    rounded infinite eigenvalue was reported as a mechanism naming the beam's rotations (as on
    MSC's single-CQUAD4 laminate deck v10112 with lumped mass); it is refused by count now."""
    from bayesupdate.errors import BayesUpdateError
    from bayesupdate.nastran import load_nastran_model

    deck = tmp_path / "tip_mass.bdf"
    deck.write_text(TIP_MASS_DECK)
    model = load_nastran_model(deck)
    with pytest.raises(BayesUpdateError, match=r"only 3 elastic modes \(9 of its 12 DOFs carry no"):
        model.solve(n_modes=4)
    # the three: bending in y and z (k = 3 EI / L^3 of the 20-long cantilever), and axial EA / L
    f = model.solve(n_modes=3).frequencies_hz
    k = np.array([3e7 / 20.0**3, 3e7 / 20.0**3, 1e7 / 20.0])
    assert np.sort(f) == pytest.approx(np.sqrt(k) / (2 * np.pi), rel=1e-12)  # cubic: exact


HINGE_DECK = """SOL 103
CEND
SPC = 1
BEGIN BULK
GRID,101,,0.,0.,0.
GRID,102,,10.,0.,0.
GRID,103,,20.,0.,0.
CBAR,1,5,101,102,0.,1.,0.
CBAR,2,5,102,103,0.,1.,0.,,
,56
PBAR,5,7,1.,1.,1.,1.
MAT1,7,1.e7,,.3
CONM2,10,103,,1.
CONM2,11,102,,1.
SPC1,1,123456,101
ENDDATA
"""


def test_a_mechanism_in_a_deck_is_named_by_its_grid_ids(tmp_path):
    """A cantilever of two CBARs whose second is pinned to the first in both bending moments
    (PA 56): the tip swings freely about GRID 102, in y and in z.  The message names the deck's
    GRIDs (101-103), not the solver's node numbers (0-2)."""
    from bayesupdate.errors import BayesUpdateError
    from bayesupdate.nastran import load_nastran_model

    deck = tmp_path / "hinge.bdf"
    deck.write_text(HINGE_DECK)
    with pytest.raises(BayesUpdateError, match=r"mechanism: 2 zero-energy mode\(s\)") as err:
        load_nastran_model(deck).solve(n_modes=3)
    moving = str(err.value).split("moves")[1]
    assert "GRID 103" in moving and "node" not in moving
    # raised in a worker process, it crosses back pickled with its wording and its DOFs
    back = pickle.loads(pickle.dumps(err.value))
    assert type(back) is type(err.value) and str(back) == str(err.value)
    assert back.count == 2 and back.dofs.tolist() == err.value.dofs.tolist()
