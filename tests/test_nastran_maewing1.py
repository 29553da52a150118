"""The mAEWing1 aircraft's own MSC decks as published (``../shared/data/gvt_maewing1/fem``, README
there), read unmodified: INCLUDEd files, CBEAM offsets with one reused continuation marker
(``+cb1``), MAT1 with E and G and NU blank (NU = E / 2G - 1 = 1.66), CBUSH hinges with a CID and
ends 0.02 in apart, a grounded CBUSH, CMASS2 rotary inertias, SUPORT, EIGR MGIV, PARAM WTMASS
and PARAMs with no effect on modes (POST, PRTMAXIM, GRDPNT, VREF).

Each deck's 20 lowest elastic frequencies must be MSC Nastran's (its ``.f06`` eigenvalue table,
parsed here) within 0.01 %, with 6 rigid-body modes, and its mass / WTMASS must be the weight of
the ``.f06``'s grid point weight generator (lbf).  Skipped without the shared data.
"""

import json
import re
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.cli import main

FEM = Path(__file__).resolve().parents[2] / "shared" / "data" / "gvt_maewing1" / "fem"
if not FEM.is_dir():
    pytest.skip(f"shared data not found: {FEM}", allow_module_level=True)

DECKS = {
    "v3.3": ("v3.3_hati/sol103_mAEWing1_Hati_FEMv3p3.bdf", "sol103_maewing1_hati_femv3p3.f06"),
    "v4.2": ("v4.2_updated/sol103_mAEWing1_FEMv4p2.bdf", "sol103_maewing1_femv4p2.f06"),
    "v4.2.1": ("v4.2.1_updated/sol103_mAEWing1_FEMv4p2p1.bdf", "sol103_maewing1_femv4p2p1.f06"),
}


def f06_table(path: Path) -> tuple[np.ndarray, float]:
    """(cycles [Hz] of every mode in the real eigenvalue tables, in mode order; the weight of
    the grid point weight generator's MASS AXIS SYSTEM X row)."""
    modes, weight, in_table = {}, None, False
    lines = path.read_text(errors="replace").splitlines()
    for k, line in enumerate(lines):
        if "R E A L   E I G E N V A L U E S" in line:
            in_table = True
            continue
        if "MASS AXIS SYSTEM (S)" in line and weight is None:
            weight = float(lines[k + 1].split()[1])
        parts = line.split()
        if in_table and len(parts) >= 5 and parts[0].isdigit() and parts[1].isdigit():
            modes[int(parts[0])] = float(parts[4])
        elif in_table and parts and not parts[0].isdigit() and "MODE" not in line:
            in_table = re.match(r"^\s*(NO\.|EXTRACTION)", line) is not None
    return np.array([modes[m] for m in sorted(modes)]), weight


@pytest.mark.parametrize("name", list(DECKS))
def test_published_deck_matches_msc_f06_within_0_01_percent(name):
    from bayesupdate.nastran import load_nastran_model

    deck, f06 = DECKS[name]
    msc, weight = f06_table(FEM / Path(deck).parent / f06)
    assert np.all(msc[:6] == 0.0) and msc[6] > 5.0  # the f06: six rigid modes (SUPORT)
    model = load_nastran_model(str(FEM / deck))
    r = model.solve(n_modes=20)
    rel = r.frequencies_hz / msc[6:26] - 1
    assert np.abs(rel).max() < 1e-4, rel
    # closer still: the f06 prints 7 digits; with Cowper's shear factor on the PBARL BARs
    # (NU = E / 2G - 1 = 1.66 there) instead of MSC's 5/6 this was 8.5e-6 (v3.3, mode 14)
    assert np.abs(rel).max() < 2e-6, rel
    assert r.modes.n_rigid == 6
    info = model.structure.metadata["nastran"]
    assert info["units"]["system"] == "in, lbf, s"
    assert r.mass_kg / info["wtmass"] == pytest.approx(weight, rel=1e-6)  # lbf


def test_modes_json_on_the_unmodified_deck_names_the_ignored_params_and_mat1_note(capsys):
    deck = FEM / DECKS["v4.2"][0]
    assert main(["modes", "--model", str(deck), "--modes", "20", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["rigid_modes"] == 6 and len(out["frequencies_hz"]) == 20
    assert out["units"]["length"] == "in" and out["units"]["mass"] == "lbf s^2/in"
    notes = " ".join(out["notes"])
    assert "PARAM GRDPNT, POST, PRTMAXIM, VREF ignored" in notes
    # MAT1 943: E 6.66e6, G 1.252e6, NU blank -> NU = E / 2G - 1
    assert f"NU = {6.66e6 / (2 * 1.252e6) - 1:.4g}" in notes


def test_sol200_deck_design_variables_become_parameters():
    """The authors' SOL 200 deck (v4.2's structure, 34 DESVARs): all 34 are parameters with the
    DESVAR bounds: relations on PBEAM A/I1/J/NSM, MAT1 E/RHO/G, CONM2 M, and the element cards'
    own fields (CBEAM offsets, CONM2 X1/I11/I22, CMASS2 M: ``tests/test_nastran_sol200_desvars``
    checks them against the written deck); no DESVAR is left in a note; at the cards' values
    the model is v4.2's."""
    from bayesupdate.nastran import load_nastran_model

    model = load_nastran_model(str(FEM / "sol200_full_model/sol200_mAEWing1_FEMv4p2.bdf"))
    assert len(model.parameter_names) == 34
    bounds = model.default_bounds()
    assert bounds["DEN2"] == (0.001, 0.01) and bounds["FLICOMP"] == (0.5, 2.0)
    assert bounds["W2A1_9002"] == (-1.35, 1.35) and bounds["P2IXX"] == (0.0, 5.0)
    assert model.bindings["DEN2"].target == "MAT1 903,913 RHO"  # one DESVAR, two DVMREL1
    assert model.bindings["MAT_GO"].target == "MAT1 903 G"  # the beams' shear modulus
    assert model.default_parameters()["FLICOMP"] == pytest.approx(0.950993)  # CONM2 301 M
    assert len(model.bindings["W2A2"].relations) == 68  # W2A and W2B of 34 CBEAMs, COEF +-1
    notes = model.structure.metadata["nastran"]["notes"]
    assert not any("DESVAR(s) not made parameters" in n for n in notes), notes
    v42 = load_nastran_model(str(FEM / DECKS["v4.2"][0]))
    np.testing.assert_allclose(
        model.solve(n_modes=10).frequencies_hz, v42.solve(n_modes=10).frequencies_hz, rtol=1e-8
    )


def test_a_wing_property_bound_on_both_wings_solves_as_the_deck_written_with_it(tmp_path):
    """``PBEAM 1003 I1`` of v3.3 is used on both wings (two pieces of bound elements): the bound
    model at the deck's value equals the unbound deck, and at twice that value equals the deck
    the writer writes with it (read again, unbound).  The bound model adds the rebuilt elements'
    change to the deck's assembled matrices, so its entries carry round-off of the deck's
    stiffest entries (MAT1 906, E = 6.66e10, beside foam-covered wing beams): measured 1.9e-8 on
    mode 1 (the written value itself is exact), asserted at 5e-8."""
    from bayesupdate.nastran import load_nastran_model
    from bayesupdate.nastran.writer import write_updated_deck

    deck = FEM / "v3.3_hati" / "sol103_mAEWing1_Hati_FEMv3p3.bdf"
    if not deck.exists():
        pytest.skip(f"shared data not found: {deck}")
    plain = load_nastran_model(str(deck)).solve(None, 8).frequencies_hz
    bound = load_nastran_model(str(deck), {"i1": {"binds": "PBEAM 1003 I1"}})
    i1 = bound.default_parameters()["i1"]
    assert i1 == pytest.approx(0.00994078256)
    np.testing.assert_allclose(bound.solve(None, 8).frequencies_hz, plain, rtol=1e-12)
    stiffer = bound.solve({"i1": 2 * i1}, 8).frequencies_hz
    assert stiffer[0] > plain[0] * 1.05  # the wing's first bending rises
    written = write_updated_deck(bound, {"i1": 2 * i1}, tmp_path / "v33_i1.bdf")
    again = load_nastran_model(str(written)).solve(None, 8).frequencies_hz
    np.testing.assert_allclose(stiffer, again, rtol=5e-8)
