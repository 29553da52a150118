"""Nastran cards against closed forms (MSC Nastran Quick Reference Guide semantics): tapered PBEAM
stations, CBUSH CID / OCID / PBUSH M, CONM1 6x6, CELAS1 + PELAS, CMASS1 + PMASS, RBE3 weight
groups with their own components and a UM set; bad input in one message with file:line."""

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

from bayesupdate.cli import main
from bayesupdate.fe import standard_sections as ss
from bayesupdate.nastran import load_nastran_model


def _deck(bulk: str, n_modes: int = 4, case: str = "") -> str:
    return (f"SOL 103\nCEND\nSPC = 1\nMETHOD = 1\n{case}BEGIN BULK\nEIGRL,1,,,{n_modes}\n{bulk}"
            "ENDDATA\n")  # fmt: skip


def _write(tmp_path, text: str, name: str = "deck.bdf"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _hz(omega2) -> np.ndarray:
    return np.sqrt(np.asarray(omega2, float)) / (2 * np.pi)


def rejected(capsys, *argv) -> str:
    code = main(["modes", *map(str, argv)])
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


# -- PBEAM tapered stations -----------------------------------------------------------------------
def _pbeam_area(tmp_path, pbeam: str) -> float:
    bulk = (f"GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nMAT1,1,2.e11,,0.3,7800.\n{pbeam}"
            "CBEAM,1,5,1,2,0.,0.,1.\nSPC1,1,123456,1\n")  # fmt: skip
    return float(load_nastran_model(_write(tmp_path, _deck(bulk))).structure.general_beams.area[0])


@pytest.mark.parametrize(
    "stations, area",
    [
        (",NO,1.,4.e-3\n", 3e-3),  # ends A 2, B 4: the mean 3
        (",NO,0.5\n,NO,1.,4.e-3\n", 3e-3),  # blank station: linear between A and B
        (",NO,0.5,5.e-3\n,NO,1.,4.e-3\n", 4e-3),  # (2 + 5) / 4 + (5 + 4) / 4
        (",NO,1.\n", 2e-3),  # end B blank: end A's (a constant beam)
        (",,,,,,,,\n,YESA,0.25,6.e-3\n", 4e-3),  # with C1(A)..F2(A); no end B: end A's
    ],
)  # fmt: skip
def test_pbeam_stations_follow_the_qrg_blank_rules(tmp_path, stations, area):
    """QRG PBEAM: blank fields at end B are end A's, at an intermediate station the linear
    interpolation between A and B; the element uses the mean over its length of the
    piecewise-linear variation (trapezoid rule over the stations)."""
    pbeam = f"PBEAM,5,1,2.e-3,4.e-6,1.e-6,,2.e-6\n{stations}"
    assert _pbeam_area(tmp_path, pbeam) == pytest.approx(area, rel=1e-12)


def _wedge(n: int) -> str:
    """A cantilever of depth h0 (1 - x/L) (a wedge: A ~ h, I1 ~ h^3), n tapered CBEAMs, each
    PBEAM with end A and end B from the exact law (no C/D/E/F line), shear-rigid (K1 = K2 = 0),
    consistent mass."""
    L, b, h0 = 1.0, 0.02, 0.01

    def sec(s):
        h = h0 * (1 - s)
        return ",".join(repr(v) for v in (b * h, b * h**3 / 12, h * b**3 / 12, 0.0, h * b**3 / 3))

    lines = ["PARAM,COUPMASS,1", "MAT1,1,2.e11,,0.3,7800.", "SPC1,1,123456,1"]
    lines += [f"GRID,{k + 1},,{k * L / n!r},0.,0." for k in range(n + 1)]
    for k in range(n):
        lines += [f"PBEAM,{k + 1},1,{sec(k / n)}", f",NO,1.,{sec((k + 1) / n)}", ",0.,0.",
                  f"CBEAM,{k + 1},{k + 1},{k + 1},{k + 2},0.,0.,1."]  # fmt: skip
    return _deck("\n".join(lines) + "\n", n_modes=1)


def test_tapered_pbeams_converge_to_kirchhoffs_wedge(tmp_path):
    """Kirchhoff's wedge cantilever (depth tapering linearly to 0 at the free end, constant
    width): omega_1 = 5.315 sqrt(E I0 / (m0 L^4)) (Timoshenko, Young & Weaver, *Vibration
    Problems in Engineering*, 4th ed., 1974, sec. 5.11).  Each element is a linearly tapered
    CBEAM (its A, I, J linear between its ends: I is cubic in the wedge) but the last, whose end
    B has no section and which uses its mean section, with a note; they converge at second
    order: 20 elements -0.22 %, 40 -0.054 % (the mean sections alone were within 0.5 % and
    0.15 %), the error / 4 or so."""
    E, rho, b, h0 = 2e11, 7800.0, 0.02, 0.01
    exact = 5.315 * np.sqrt(E * b * h0**3 / 12 / (rho * b * h0)) / (2 * np.pi)
    err = {}
    for n in (20, 40):
        model = load_nastran_model(_write(tmp_path, _wedge(n), f"wedge{n}.bdf"))
        err[n] = model.solve(n_modes=1).frequencies_hz[0] / exact - 1
        taper = model.structure.general_beams.taper
        assert np.all(taper[:-1, 0] != taper[:-1, 1]) and np.all(taper[-1, 0] == taper[-1, 1])
        notes = model.structure.metadata["nastran"]["notes"]
        assert any(f"PBEAM {n} is tapered" in s for s in notes), notes
    assert -2.5e-3 < err[20] < 0 and -6e-4 < err[40] < 0, err
    assert 3.5 < err[20] / err[40] < 4.5, err


def test_a_tapered_cbeam_is_nxs_on_its_own_static_solution():
    """NX Nastran 8.5's static solution of a strongly tapered cantilever of four CBEAMs under
    gravity (pyNastran's ``sol200/model_200`` at its initial design, ``tests/data/
    nx_tapered_cbeam.*``, written by ``studies/nx_tapered_cbeam.py``): with the section linear
    along each element and its flexibility integrated by 3 Gauss points, and the NSM lumped by
    its first moments, every displacement and rotation is NX's to its float32 output (largest
    relative difference per component 1.2e-8..7.0e-8; the mean section read before: 5.2e-3 and
    2.2e-2), and the mass and its first moments are NX's weight generator's (2.4e-8)."""
    import json

    import scipy.sparse.linalg as spla

    data_dir = Path(__file__).parent / "data"
    nx = json.loads((data_dir / "nx_tapered_cbeam.json").read_text())
    model = load_nastran_model(str(data_dir / "nx_tapered_cbeam.bdf"))
    K, M = model.matrices()
    tr = model.general.transform
    down = np.zeros(K.shape[0])
    down[2::6] = -nx["gravity"]
    u = tr.T @ spla.spsolve(tr.reduce(K).tocsc(), tr.T.T @ (M @ down))
    expected = np.array(nx["displacements"])
    err = np.abs(u.reshape(-1, 6) - expected).max(axis=0) / np.abs(expected).max(axis=0)
    assert np.all(err < 2e-7), err
    mass, cg = model.total_mass()
    assert mass == pytest.approx(nx["mass"], rel=1e-7)
    assert mass * cg == pytest.approx(np.array(nx["first_moments"]), rel=1e-7)


def test_a_tapered_cbeams_material_as_a_parameter(tmp_path):
    """MAT1 1 E of the tapered cantilever (``tests/data/nx_tapered_cbeam.bdf``) as a scale: at
    1.5 its modes are those of the deck with E = 1.5 typed in (1e-10; the bound elements are
    re-computed with their taper)."""
    deck = Path(__file__).parent / "data" / "nx_tapered_cbeam.bdf"
    model = load_nastran_model(str(deck), {"e": {"binds": "MAT1 1 E scale"}})
    typed = tmp_path / "typed.bdf"
    typed.write_text(deck.read_text().replace("MAT1,1,1.,1.", "MAT1,1,1.5,1."))
    expected = load_nastran_model(str(typed)).predict(n_modes=6).frequencies_hz
    assert model.predict({"e": 1.5}, n_modes=6).frequencies_hz == pytest.approx(expected, rel=1e-10)


# -- PBEAML tapered stations ----------------------------------------------------------------------
def _tapered_bar(tmp_path, stations: str):
    """The model of one CBEAM, PBEAML BAR b = 0.03, h 0.02 and NSM 0.5 at end A, then
    ``stations``."""
    bulk = ("GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nMAT1,1,2.e11,,0.3,7800.\n"
            f"PBEAML,5,1,,BAR\n,0.03,0.02,0.5{stations}CBEAM,1,5,1,2,0.,0.,1.\n"
            "SPC1,1,123456,1\n")  # fmt: skip
    return load_nastran_model(_write(tmp_path, _deck(bulk)))


def test_a_tapered_pbeaml_is_the_pbeam_of_its_end_sections(tmp_path):
    """A PBEAML BAR, DIM1 b = 0.03 and DIM2 h from 0.02 (end A) to 0.01 (end B), NSM 0.5 to
    1.5, is read as MSC reads it: the PBEAM of the sections at its ends (MSC's f06 prints that
    replacement), A, I1, I2 and J linear along the element, so its mean A = b (hA + hB) / 2,
    I1 = b (hA^3 + hB^3) / 24 (not the mean of the exact section, b (hA^3 + hA^2 hB + hA hB^2
    + hB^3) / 48), I2 = b^3 (hA + hB) / 24, NSM 1; both ends' sections kept (a tapered
    element), no note."""
    model = _tapered_bar(tmp_path, ",NO,1.,0.03,0.01,1.5\n")
    g = model.structure.general_beams
    b, ha, hb = 0.03, 0.02, 0.01
    assert g.area[0] == pytest.approx(b * (ha + hb) / 2, rel=1e-12)
    assert g.iz[0] == pytest.approx(b * (ha**3 + hb**3) / 24, rel=1e-12)
    assert g.iy[0] == pytest.approx(b**3 * (ha + hb) / 24, rel=1e-12)
    assert g.nsm[0] == pytest.approx(1.0, rel=1e-12)
    ends = g.taper[0] * np.array([g.area[0], g.iy[0], g.iz[0], g.torsion[0]])
    assert ends[:, 2] == pytest.approx([b * ha**3 / 12, b * hb**3 / 12], rel=1e-12)
    notes = model.structure.metadata["nastran"]["notes"]
    assert not any("PBEAML 5 is tapered" in n for n in notes), notes


@pytest.mark.parametrize(
    "stations",
    [
        ",NO,0.5,,,\n,NO,1.,0.03,0.01,1.5\n",  # a blank station: linear between A and B
        ",NO,0.5,0.03,0.015,1.\n,NO,1.,0.03,0.01,1.5\n",  # a station on the linear law
    ],
)  # fmt: skip
def test_a_pbeaml_station_between_its_ends_is_a_pbeam_station(tmp_path, stations):
    """With a station at x / L = 0.5 (given, or blank: the QRG's linear interpolation of the
    dimensions, h = 0.015), the PBEAM of the three stations' sections: I1 at the middle is
    b 0.015^3 / 12, off the line between the ends' (I1 is cubic in h), so the element uses the
    mean of the piecewise-linear variation, (I_A + 2 I_M + I_B) / 4, with a note, as a PBEAM
    with such a station (``test_pbeam_stations_follow_the_qrg_blank_rules``)."""
    model = _tapered_bar(tmp_path, stations)
    g = model.structure.general_beams
    b = 0.03
    i_a, i_m, i_b = (b * h**3 / 12 for h in (0.02, 0.015, 0.01))
    assert g.iz[0] == pytest.approx((i_a + 2 * i_m + i_b) / 4, rel=1e-12)
    assert g.area[0] == pytest.approx(b * 0.015, rel=1e-12)
    notes = model.structure.metadata["nastran"]["notes"]
    assert any("PBEAML 5 is tapered with stations off the line" in n for n in notes), notes


def _pbeaml_wedge(n: int) -> str:
    """Kirchhoff's wedge (``_wedge``) with each element a PBEAML BAR from its end depths but the
    last, whose end B has no section (depth 0: a PBEAML there is refused, as MSC's BAR needs
    DIM2 > 0), a PBEAM as in ``_wedge``."""
    L, b, h0 = 1.0, 0.02, 0.01
    lines = ["PARAM,COUPMASS,1", "MAT1,1,2.e11,,0.3,7800.", "SPC1,1,123456,1"]
    lines += [f"GRID,{k + 1},,{k * L / n!r},0.,0." for k in range(n + 1)]
    for k in range(n - 1):
        ha, hb = h0 * (1 - k / n), h0 * (1 - (k + 1) / n)
        lines += [f"PBEAML,{k + 1},1,,BAR", f",{b!r},{ha!r},0.,NO,1.,{b!r},{hb!r},0.",
                  f"CBEAM,{k + 1},{k + 1},{k + 1},{k + 2},0.,0.,1."]  # fmt: skip
    h = h0 / n
    end_a = ",".join(repr(v) for v in (b * h, b * h**3 / 12, h * b**3 / 12, 0.0, h * b**3 / 3))
    lines += [f"PBEAM,{n},1,{end_a}", ",NO,1.,0.,0.,0.,0.,0.", ",0.,0.",
              f"CBEAM,{n},{n},{n},{n + 1},0.,0.,1."]  # fmt: skip
    return _deck("\n".join(lines) + "\n", n_modes=1)


def test_tapered_pbeamls_converge_to_kirchhoffs_wedge(tmp_path):
    """The wedge of ``test_tapered_pbeams_converge_to_kirchhoffs_wedge`` in tapered PBEAML BARs
    (shear factor 5/6: shear flexibility is (h / L)^2 ~ 1e-4 here), each the linearly tapered
    PBEAM of its end sections: second-order convergence to omega_1 = 5.315 sqrt(E I0 / (m0
    L^4)), 20 elements -0.226 %, 40 -0.059 % (the shear-rigid PBEAMs -0.221 %, -0.054 %)."""
    E, rho, b, h0 = 2e11, 7800.0, 0.02, 0.01
    exact = 5.315 * np.sqrt(E * b * h0**3 / 12 / (rho * b * h0)) / (2 * np.pi)
    err = {}
    for n in (20, 40):
        model = load_nastran_model(_write(tmp_path, _pbeaml_wedge(n), f"wedge{n}.bdf"))
        err[n] = model.solve(n_modes=1).frequencies_hz[0] / exact - 1
        taper = model.structure.general_beams.taper
        assert np.all(taper[:-1, 0] != taper[:-1, 1])  # every PBEAML a tapered element
    assert -2.5e-3 < err[20] < 0 and -7e-4 < err[40] < 0, err
    assert 3.5 < err[20] / err[40] < 4.5, err


# -- PBARL open shapes ---------------------------------------------------------------------------
def _cantilever(prop: str) -> str:
    """Ten CBARs along x on ``prop`` (PID 7, MID 1), v along y: plane 1 is x-y."""
    lines = ["MAT1,1,7.e10,,0.33,2700.", "SPC1,1,123456,1", prop]
    lines += [f"GRID,{k + 1},,{0.5 * k!r},0.,0." for k in range(11)]
    lines += [f"CBAR,{k + 1},7,{k + 1},{k + 2},0.,1.,0." for k in range(10)]
    return _deck("\n".join(lines) + "\n", n_modes=6)


@pytest.mark.parametrize(
    "kind, dims, section",
    [
        ("T", (0.1, 0.2, 0.012, 0.008), lambda: ss.tee_section(0.2, 0.1, 0.008, 0.012)),
        ("T2", (0.1, 0.2, 0.012, 0.008), lambda: ss.tee_section(0.2, 0.1, 0.008, 0.012)),
        ("CHAN", (0.08, 0.2, 0.008, 0.012), lambda: ss.channel_section(0.2, 0.08, 0.008, 0.012)),
    ],
)  # fmt: skip
def test_a_pbarl_open_shape_is_the_pbar_of_its_section(tmp_path, kind, dims, section):
    """PBARL T, T2 (DIM1 flange width, DIM2 height, DIM3 flange, DIM4 web) and CHAN (DIM1
    flange width, DIM2 height, DIM3 web, DIM4 flanges), height along y_elem: the cantilever's
    six modes are those of the PBAR with the section's A, I1 = its moment about the height,
    I2, J, K1 = the web's share of A and K2 the flanges' (rel 1e-10), with a note that J and
    the shear factors are the thin walls', not a vendor's."""
    s = section()
    pbarl = f"PBARL,7,1,,{kind}\n,{','.join(repr(d) for d in dims)}"
    pbar = (f"PBAR,7,1,{s.area!r},{s.iy!r},{s.iz!r},{s.torsion!r}\n,,,,,,,,\n"
            f",{s.shear_z!r},{s.shear_y!r}")  # fmt: skip
    model = load_nastran_model(_write(tmp_path, _cantilever(pbarl), "pbarl.bdf"))
    ours = model.solve(n_modes=6).frequencies_hz
    theirs = load_nastran_model(_write(tmp_path, _cantilever(pbar), "pbar.bdf"))
    assert ours == pytest.approx(theirs.solve(n_modes=6).frequencies_hz, rel=1e-10)
    notes = model.structure.metadata["nastran"]["notes"]
    assert any(f"PBARL 7 {kind}: J and the shear factors of thin walls" in n for n in notes)


# -- CBUSH CID, OCID and PBUSH M -----------------------------------------------------------------
CORD7 = "CORD2R,7,,0.,0.,0.,0.3,0.4,0.866\n,1.,0.2,0.\n"


def test_grounded_cbush_springs_act_along_its_cid_axes(tmp_path):
    """A 2 (x WTMASS 0.5 = 1) CONM2 on a grounded CBUSH with CID 7 (a rotated CORD2R), K1-K3 =
    100, 400, 900, rotations held: f_i = sqrt(K_i / 1) / 2 pi, mode i along axis i of CID 7."""
    from bayesupdate.nastran.deck import Refusals, read_deck
    from bayesupdate.nastran.frames import read_grids

    bulk = (f"PARAM,WTMASS,0.5\n{CORD7}GRID,1,,0.,0.,0.\nCONM2,9,1,,2.\n"
            "CBUSH,3,8,1,,,,,7\nPBUSH,8,K,100.,400.,900.\nSPC1,1,456,1\n")  # fmt: skip
    path = _write(tmp_path, _deck(bulk, 3))
    r = load_nastran_model(path).solve(n_modes=3)
    assert r.frequencies_hz == pytest.approx(_hz([100.0, 400.0, 900.0]), rel=1e-10)
    axes = read_grids(read_deck(path), Refusals("")).coords[7].axes  # rows: CID 7 axes
    for i in range(3):
        u = r.modes.shapes[:3, i]
        assert abs(axes[i] @ u) / np.linalg.norm(u) == pytest.approx(1.0, abs=1e-9)


MIXED = """GRID,1,,0.,0.,0.
GRID,2,,10.,0.,0.
GRID,3,,10.,0.,0.
GRID,4,,20.,0.,0.
CROD,1,5,1,2
PROD,5,7,0.5
MAT1,7,1.e7,,.3
RBAR,2,2,3,123456,,,123456
CONM1,10,4,0,2.,0.,2.,0.,0.
,2.,0.,0.,0.,1.,0.,0.,0.
,0.,1.,0.,0.,0.,0.,0.,1.
SPC1,1,123456,1
SPC1,1,23456,2
PBUSH,8,K,1.e4,1.e4,1.e4,1.e6,1.e6,1.e6
"""


def _bush_apart_hz() -> np.ndarray:
    """The MIXED deck's closed form with the bush acting at x = 15, 5 from the mass (as
    ``test_nastran.test_cbush_with_ends_apart_acts_at_its_midpoint_through_rigid_arms``)."""
    ky, kr = 1e4, 1e6
    K = np.array([[ky, -5 * ky], [-5 * ky, kr + 25 * ky]])
    bend = scipy.linalg.eigh(K, np.diag([2.0, 1.0]), eigvals_only=True)
    k_x = 1 / (1 / 5e5 + 1 / 1e4)
    return np.sort(_hz(np.r_[k_x / 2, bend, bend, kr]))


@pytest.mark.parametrize(
    "cbush",
    [
        "CBUSH,3,8,3,4,,,,0\n,,0,5.,0.,0.\n",  # OCID 0 (basic): S1-S3 from GA
        # OCID 9: x' = basic y, y' = -basic x, so S2 = -5 is basic +5 x
        "CBUSH,3,8,3,4,,,,0\n,,9,0.,-5.,0.\nCORD2R,9,,0.,0.,0.,0.,0.,1.\n,0.,1.,0.\n",
        "CBUSH,3,8,3,4,,,,0\n,0.5\n",  # S = 0.5 on GA-GB, OCID -1 (blank)
    ],
)  # fmt: skip
def test_cbush_offset_in_ocid_equals_the_same_point_by_s(tmp_path, cbush):
    """The bush point GA + (5, 0, 0) given by OCID 0 and S1-S3, by a rotated OCID or by S on
    GA-GB: the same closed form (rigid arms from both grids, MSC QRG CBUSH)."""
    path = _write(tmp_path, _deck(MIXED + cbush, 6))
    f = load_nastran_model(path).solve(n_modes=6).frequencies_hz
    assert f == pytest.approx(_bush_apart_hz(), rel=1e-6)


def test_pbush_mass_is_split_by_s_and_damping_is_noted(tmp_path):
    """PBUSH M = 2 on a CBUSH at S = 0.25 (MSC QRG PBUSH remark 13): 1.5 at GA (clamped), 0.5 at
    GB, which carries a 1 CONM2 with inertia 1: translations sqrt(k / 1.5), rotations
    sqrt(kr / 1); the total mass counts all 3; B and GE are noted as ignored."""
    bulk = ("GRID,1,,0.,0.,0.\nGRID,2,,0.,0.,0.\nCONM2,9,2,,1.,,,,\n,1.,,1.,,,1.\n"
            "CBUSH,3,8,1,2,,,,0\n,0.25\nPBUSH,8,K,1.e4,1.e4,1.e4,1.e6,1.e6,1.e6\n"
            ",,M,2.\n,,GE,0.02\n,,B,3.\nSPC1,1,123456,1\n")  # fmt: skip
    model = load_nastran_model(_write(tmp_path, _deck(bulk, 6)))
    f = model.solve(n_modes=6).frequencies_hz
    assert f == pytest.approx(_hz([1e4 / 1.5] * 3 + [1e6] * 3), rel=1e-9)
    assert model.solve(n_modes=1).mass_kg == pytest.approx(3.0, rel=1e-12)
    notes = model.structure.metadata["nastran"]["notes"]
    assert any("PBUSH 8: B and GE (damping) ignored" in n for n in notes), notes


@pytest.mark.parametrize("s, share", [("", 0.5), ("0.", 1.0), ("0.8", 0.2)])
def test_pbush_mass_on_a_grounded_cbush(tmp_path, s, share):
    """PBUSH M = 4 (x WTMASS 0.5) on a grounded CBUSH (CID 7) at S blank (0.5), 0 and 0.8: GB is a
    grounded terminal (QRG CBUSH remark 6), so (1 - S) x 2 moves at GA (PBUSH remark 13),
    the same in the three CID directions; K1-K3 = 100, 400, 900 and the rotations held give
    f_i = sqrt(K_i / ((1 - S) 2)) / 2 pi, the model's mass (1 - S) 2, and a note."""
    bulk = (f"PARAM,WTMASS,0.5\n{CORD7}GRID,1,,0.,0.,0.\nCBUSH,3,8,1,,,,,7\n,{s}\n"
            "PBUSH,8,K,100.,400.,900.\n,,M,4.\nSPC1,1,456,1\n")  # fmt: skip
    model = load_nastran_model(_write(tmp_path, _deck(bulk, 3)))
    r = model.solve(n_modes=3)
    m = 2.0 * share
    assert r.frequencies_hz == pytest.approx(_hz(np.array([100.0, 400.0, 900.0]) / m), rel=1e-10)
    assert r.mass_kg == pytest.approx(m, rel=1e-12)
    notes = model.structure.metadata["nastran"]["notes"]
    assert any(f"CBUSH 3 is grounded: (1 - S) = {share:g} of its PBUSH MASS" in n
               for n in notes), notes  # fmt: skip


# -- CONM1, CELAS1 + PELAS, CMASS1 + PMASS ------------------------------------------------------
def test_conm1_general_6x6_mass_matrix(tmp_path):
    """CONM1 with M11 = 2, M22 = 3, M33 = 5 (no rigid body has that) and M51 = 0.5 coupling x
    with the rotation about y (inertia M55 = 1): on grounded springs kx, ky, kz, kry (CELAS2)
    and rx, rz held, the frequencies are sqrt(ky / 3), sqrt(kz / 5) and those of the 2x2
    problem (x, ry): K = diag(kx, kry), M = [[2, 0.5], [0.5, 1]]."""
    kx, ky, kz, kr = 100.0, 600.0, 2000.0, 50.0
    bulk = ("GRID,1,,0.,0.,0.\nCONM1,10,1,,2.,0.,3.,0.,0.\n,5.,0.,0.,0.,0.,0.5,0.,0.\n"
            ",0.,1.,0.,0.,0.,0.,0.,0.\n"
            f"CELAS2,1,{kx},1,1\nCELAS2,2,{ky},1,2\nCELAS2,3,{kz},1,3\nCELAS2,5,{kr},1,5\n"
            "SPC1,1,46,1\n")  # fmt: skip
    model = load_nastran_model(_write(tmp_path, _deck(bulk, 4)))
    f = model.solve(n_modes=4).frequencies_hz
    pair = scipy.linalg.eigh(np.diag([kx, kr]), np.array([[2.0, 0.5], [0.5, 1.0]]),
                             eigvals_only=True)  # fmt: skip
    assert f == pytest.approx(np.sort(_hz([ky / 3, kz / 5, *pair])), rel=1e-9)


def test_celas1_pelas_and_cmass1_pmass(tmp_path):
    """CELAS1 -> PELAS K = 400 and CMASS1 -> PMASS M = 4 on component 2 of a grid, the rest
    held: f = sqrt(400 / 4) / 2 pi; between two grids (C1 of 1, C1 of 2, grid 2 held) the
    same (grid 2 held, with a CONM2 so that the model has rigid-body mass)."""
    one = ("GRID,1,,0.,0.,0.\nCELAS1,1,5,1,2\nPELAS,5,400.\nCMASS1,2,6,1,2\nPMASS,6,4.\n"
           "SPC1,1,13456,1\n")  # fmt: skip
    r = load_nastran_model(_write(tmp_path, _deck(one, 1))).solve(n_modes=1)
    assert r.frequencies_hz[0] == pytest.approx(_hz(100.0), rel=1e-12)
    two = ("GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nCELAS1,1,5,1,1,2,1\nPELAS,5,400.\n"
           "CMASS1,2,6,1,1,2,1\nPMASS,6,4.\nCONM2,7,2,,1.\nSPC1,1,23456,1\n"
           "SPC1,1,123456,2\n")  # fmt: skip
    r = load_nastran_model(_write(tmp_path, _deck(two, 1), "two.bdf")).solve(n_modes=1)
    assert r.frequencies_hz[0] == pytest.approx(_hz(100.0), rel=1e-12)


# -- RBE3 weight groups and UM -------------------------------------------------------------------
def _rbe3_deck(um: str = "") -> str:
    """Reference grid 9 at the origin with a 2 CONM2 (its rotations held); four grids, each on
    grounded 6-DOF springs k = 1e4: group 1 (WT 1, C 123) at (+-1, 0, 0), group 2 (WT 3, C 1) at
    (0, +-1, 0)."""
    return _deck(
        "GRID,9,,0.,0.,0.\nGRID,1,,1.,0.,0.\nGRID,2,,-1.,0.,0.\nGRID,3,,0.,1.,0.\n"
        "GRID,4,,0.,-1.,0.\nCONM2,20,9,,2.\nPBUSH,8,K,1.e4,1.e4,1.e4,1.e4,1.e4,1.e4\n"
        + "".join(f"CBUSH,{g},8,{g},,,,,0\n" for g in (1, 2, 3, 4))
        + f"RBE3,30,,9,123,1.,123,1,2\n,3.,1,3,4{um}\nSPC1,1,456,9\n",
        n_modes=3,
    )


def test_rbe3_weight_groups_with_their_own_components(tmp_path):
    """With the nodes symmetric about the reference, the reference translation along i is the
    weighted mean of the nodes that use component i: u_x = (u1 + u2 + 3 u3 + 3 u4) / 8,
    u_y = (u1 + u2) / 2, u_z likewise (a hand computation of the QRG RBE3 mean).  The nodes' own
    springs k and the mass m on the reference give omega^2 = k / (m |a|^2) for u_r = a . u:
    |a|^2 = 20 / 64 along x and 1 / 2 along y and z.  A UM set (the node DOFs made dependent
    instead, MSC QRG RBE3) is the same constraint: the same frequencies."""
    k, m = 1e4, 2.0
    expected = np.sort(_hz([k / (m * 20 / 64), k / (m * 0.5), k / (m * 0.5)]))
    for um, name in (
        ("", "plain.bdf"),
        ("\n,UM,1,123", "um.bdf"),
        ("\n,UM,1,2,3,1,2,3", "um2.bdf"),
    ):
        f = load_nastran_model(_write(tmp_path, _rbe3_deck(um), name)).solve(n_modes=3)
        assert f.frequencies_hz == pytest.approx(expected, rel=1e-10)


def test_rbe3_um_lets_the_reference_be_fixed(tmp_path):
    """The RBE3 of ``_rbe3_deck`` with its reference grid clamped and UM = grid 1's 123: the
    constraint is a . u = 0 along each axis (a = (1, 1, 3, 3) along x over grids 1-4, (1, 1) along
    y and z over grids 1, 2).  Grids 1-4 carry CONM2 masses 1, 2, 3, 4 on springs k: the modes
    are those of K = k I, M = diag(m) on the null space of a, computed here by projection."""
    k, m = 1e4, np.array([1.0, 2.0, 3.0, 4.0])
    deck = _rbe3_deck("\n,UM,1,123").replace(
        "CONM2,20,9,,2.",
        "".join(f"CONM2,{20 + g},{g},,{m[g - 1]}\n" for g in (1, 2, 3, 4)).rstrip("\n"),
    )
    deck = deck.replace("SPC1,1,456,9", "SPC1,1,123456,9").replace("EIGRL,1,,,3", "EIGRL,1,,,9")
    f = load_nastran_model(_write(tmp_path, deck)).solve(n_modes=9).frequencies_hz
    expected = []
    for a in (np.array([1.0, 1, 3, 3]), np.array([1.0, 1, 0, 0]), np.array([1.0, 1, 0, 0])):
        Z = scipy.linalg.null_space(a[None])
        expected += list(scipy.linalg.eigh(k * Z.T @ Z, Z.T @ np.diag(m) @ Z, eigvals_only=True))
    assert f == pytest.approx(np.sort(_hz(expected)), rel=1e-9)


def test_rbe3_um_with_the_wrong_dofs_is_refused(capsys, tmp_path):
    """Two UM DOFs for three REFC components, and three whose coefficients are dependent (grid
    3 is in a group with C = 1 only, so its z is in no equation): one line each, naming the
    card and its file:line."""
    path = _write(tmp_path, _rbe3_deck("\n,UM,1,12"), "bad.bdf")
    line = rejected(capsys, "--model", path)
    assert "bad.bdf:18 RBE3 30: UM has 2 DOFs; REFC 123 has 3" in line, line
    path = _write(tmp_path, _rbe3_deck("\n,UM,1,12,3,3"), "bad.bdf")
    line = rejected(capsys, "--model", path)
    assert "bad.bdf:18 RBE3 30: its UM DOFs do not determine" in line, line


# -- bad input: one message, exit 2, every card's file:line ---------------------------------------
UNBINDABLE = ("GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nMAT1,1,2.e11,,0.3,7800.\n"
              "PBAR,5,1,2.e-3,4.e-6,1.e-6,2.e-6\nCBAR,6,5,1,2,0.,0.,1.\nSPC1,1,123456,1\n"
              "INCLUDE 'Missing.dat'\nDESVAR,1,AREA,2.e-3,1.e-3,4.e-3\n"
              "DVPREL1,10,PBAR,5,I12\n,1,1.\nCSHEAR,20,1,1,2,1,2\n")  # fmt: skip


def test_bad_include_unbindable_dvprel1_and_unsupported_card_in_one_message(tmp_path):
    """A missing INCLUDE (in any letter case), a DVPREL1 on a field that cannot be bound (PBAR
    I12) where the DESVARs are to be the parameters, and an unsupported card: one message, each
    with its file:line."""
    from bayesupdate.errors import BayesUpdateError

    with pytest.raises(BayesUpdateError) as err:
        load_nastran_model(_write(tmp_path, _deck(UNBINDABLE), "main.bdf"))
    line = str(err.value)
    for where in ("main.bdf:13 INCLUDE 'Missing.dat': no such file", "main.bdf:15 DVPREL1 10",
                  "main.bdf:17 CSHEAR 20"):  # fmt: skip
        assert where in line, line
    assert "3 card(s) refused" in line, line


def test_modes_leaves_an_unbindable_desvar_out_with_a_note(capsys, tmp_path):
    """``modes`` needs no parameters: the deck's DESVAR whose DVPREL1 sets a field no binding
    acts on (PBAR I12) stays at the card's value, named in the note, and the deck's modes are
    those of the same deck without it (before, the whole deck was refused)."""
    bulk = UNBINDABLE.replace("INCLUDE 'Missing.dat'\n", "").replace("CSHEAR,20,1,1,2,1,2\n", "")
    path = _write(tmp_path, _deck(bulk), "main.bdf")
    code = main(["modes", "--model", str(path), "--modes", "3", "--json"])
    out, err = capsys.readouterr()
    assert code == 0, err
    notes = " ".join(json.loads(out)["notes"])
    assert "AREA (1: 0.002 in [0.001, 0.004]): main.bdf:14 DVPREL1 10: PBAR I12 is a field" in notes
    plain = _write(tmp_path, _deck(bulk.split("DESVAR")[0]), "plain.bdf")
    expected = load_nastran_model(plain).solve(n_modes=3).frequencies_hz
    assert json.loads(out)["frequencies_hz"] == pytest.approx(expected, rel=1e-6)


def test_a_binding_on_a_tapered_pbeam_is_refused(tmp_path):
    """A binding writes one value at every PBEAM station, which would make the taper constant:
    refused, naming the parameter and the card's file:line."""
    from bayesupdate.errors import BayesUpdateError

    bulk = ("GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nMAT1,1,2.e11,,0.3,7800.\n"
            "PBEAM,5,1,2.e-3,4.e-6,1.e-6,,2.e-6\n,NO,1.,4.e-3\nCBEAM,1,5,1,2,0.,0.,1.\n"
            "SPC1,1,123456,1\n")  # fmt: skip
    deck = _write(tmp_path, _deck(bulk), "tapered.bdf")
    with pytest.raises(BayesUpdateError, match=r"parameter a: binds 'PBEAM 5 A': PBEAM 5 "
                       r"\(tapered.bdf:10\) is tapered"):  # fmt: skip
        load_nastran_model(deck, parameters={"a": {"binds": "PBEAM 5 A"}})


def test_a_binding_on_a_tapered_pbeaml_is_refused(tmp_path):
    """As for PBEAM: a binding would write one DIM2 at every PBEAML station."""
    from bayesupdate.errors import BayesUpdateError

    bulk = ("GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nMAT1,1,2.e11,,0.3,7800.\n"
            "PBEAML,5,1,,BAR\n,0.03,0.02,0.5,NO,1.,0.03,0.01,1.5\nCBEAM,1,5,1,2,0.,0.,1.\n"
            "SPC1,1,123456,1\n")  # fmt: skip
    deck = _write(tmp_path, _deck(bulk), "taperedl.bdf")
    with pytest.raises(BayesUpdateError, match=r"parameter d: binds 'PBEAML 5 DIM2': PBEAML 5 "
                       r"\(taperedl.bdf:10\) is tapered"):  # fmt: skip
        load_nastran_model(deck, parameters={"d": {"binds": "PBEAML 5 DIM2"}})


_CORD1_GRIDS = ("GRID,1,,0.,0.,0.\nGRID,2,,0.,0.,1.\nGRID,3,,1.,1.,0.\n"
                "GRID,4,,2.,0.,0.\nGRID,5,,2.,1.,0.\nGRID,6,,3.,0.,0.\n"
                "GRID,10,5,1.,0.,0.\nGRID,11,6,1.,2.,3.\n")  # fmt: skip


def test_a_cord1r_card_defines_two_systems(tmp_path):
    """CORD1R's fields 6-9 (CIDB, G1B-G3B) are a second system (MSC QRG CORD1R): system 5 on
    GRIDs 1-3 (origin 0, z basic z, x along (1, 1, 0)) and 6 on GRIDs 4-6 (origin (2, 0, 0), z
    basic y, x basic x, so y = -basic z) on one card place GRID 10 (1, 0, 0 in 5) at
    (1, 1, 0) / sqrt 2 and GRID 11 (1, 2, 3 in 6) at (3, 3, -2), as two cards do."""
    from bayesupdate.nastran.deck import Refusals, read_deck
    from bayesupdate.nastran.frames import read_grids

    one = _write(tmp_path, "BEGIN BULK\nCORD1R,5,1,2,3,6,4,5,6\n" + _CORD1_GRIDS + "ENDDATA\n")
    two = _write(tmp_path, "BEGIN BULK\nCORD1R,5,1,2,3\nCORD1R,6,4,5,6\n" + _CORD1_GRIDS
                 + "ENDDATA\n", "two.bdf")  # fmt: skip
    a, b = (read_grids(read_deck(p), Refusals("")) for p in (one, two))
    xyz = {int(g): a.xyz[k] for k, g in enumerate(a.ids)}
    np.testing.assert_allclose(xyz[10], [0.5**0.5, 0.5**0.5, 0.0], atol=1e-15)
    np.testing.assert_allclose(xyz[11], [3.0, 3.0, -2.0], atol=1e-15)
    np.testing.assert_allclose(a.coords[6].axes, [[1, 0, 0], [0, 0, -1], [0, 1, 0]], atol=1e-15)
    np.testing.assert_array_equal(a.xyz, b.xyz)


def test_a_cord1r_second_system_with_a_taken_id_is_refused(tmp_path):
    from bayesupdate.errors import BayesUpdateError

    bulk = "CORD2R,6,,0.,0.,0.,0.,0.,1.\n,1.,0.,0.\nCORD1R,5,1,2,3,6,4,5,6\n" + _CORD1_GRIDS
    path = _write(tmp_path, _deck(bulk))
    with pytest.raises(BayesUpdateError, match=r"deck.bdf:\d+ CORD1R 6: coordinate system 6 is"):
        load_nastran_model(path)
