"""Element cards' own fields solved from records fitted once (``nastran.card_records``) against
the cards written with the values and read again (``lines.LineRebuild``, the reference).

* A small deck with every kind the fit covers: a CBAR and a CBEAM with bound offsets (in a
  rotated CD frame, and OFFT 'GOO'), their PBAR/PBEAM A and the MAT1 RHO (the lumped end masses
  (rho A + NSM) L / 2 are bilinear in them and follow the offsets' length), a CONM2 in a rotated
  CID with its M, X1, X2 and I11 bound, a CMASS2 between two grids: lumped (COUPMASS blank, MSC's
  default) and consistent (COUPMASS 1) mass.
* The authors' SOL 200 deck with all 34 DESVARs moved (44 offset beams, 35 CONM2, 12 CMASS2).
* The fallback: a PBARL dimension on an offset CBAR is not affine (I = w h^3 / 12), so the
  cards are read again at every solve, and the reason is given.

Each at seeded points of the box (seed 146: chosen once, never tuned): the change of K and M
from the deck's values equals the reference's to 1e-12 of the largest entry (the reference
writes 16-character fields: ``bulk.real16`` keeps 13-14 digits).
"""

import re
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.nastran import load_nastran_model
from bayesupdate.nastran.bulk import parse_number, real16
from bayesupdate.nastran.lines import LineAssembler

SEED = 146
MIXED = """CORD2R,7,,0.,0.,0.,0.3,0.2,1.,
,1.,0.4,0.1
GRID,1,,0.,0.,0.
GRID,2,7,10.,1.,0.,7
GRID,3,,20.,0.5,1.
GRID,4,,20.,3.,1.
CBAR,11,21,1,2,0.,1.,0.
,,,0.2,0.1,0.,0.,-0.3,0.1
PBAR,21,1,0.6,0.03,0.02,0.04
CBEAM,12,22,2,3,0.,0.,1.,GOO
,,,0.,0.1,0.2,0.,0.,0.3
PBEAM,22,1,0.5,0.02,0.01,,0.015
CBEAM,13,22,3,4,1.,0.,0.
MAT1,1,1.e7,4.e6,,0.1
CONM2,31,4,7,3.,0.5,0.2,0.1
,0.3,,0.2,,,0.1
CMASS2,41,2.5,3,2,4,2
"""
BINDINGS = {
    "wa": {"binds": "CBAR 11 W1A", "bounds": [-0.5, 0.8]},
    "wb": {"binds": "CBAR 11 W2B", "bounds": [-1.0, 0.5]},
    "w2": {"binds": "CBEAM 12 W2A", "bounds": [-0.4, 0.6]},
    "w3": {"binds": "CBEAM 12 W3B", "bounds": [-0.2, 0.9]},
    "a_bar": {"binds": "PBAR 21 A"},
    "a_beam": {"binds": "PBEAM 22 A"},
    "rho": {"binds": "MAT1 1 RHO"},
    "m": {"binds": "CONM2 31 M"},
    "x1": {"binds": "CONM2 31 X1", "bounds": [-1.0, 1.0]},
    "x2": {"binds": "CONM2 31 X2", "bounds": [-1.0, 1.0]},
    "i11": {"binds": "CONM2 31 I11"},
    "cm": {"binds": "CMASS2 41 M"},
}
DECK = (Path(__file__).resolve().parents[2] / "shared" / "data" / "gvt_maewing1" / "fem"
        / "sol200_full_model" / "sol200_mAEWing1_FEMv4p2.bdf")  # fmt: skip


def _deck(tmp_path, bulk: str) -> str:
    path = tmp_path / "deck.bdf"
    path.write_text(f"SOL 103\nCEND\nMETHOD = 1\nBEGIN BULK\nEIGRL,1,,,6\n{bulk}ENDDATA\n")
    return str(path)


def _reference(model) -> LineAssembler:
    return LineAssembler(model.structure, model._shell_keys(), model.bdf, model.bindings,
                         model.deck, model._line_defaults, model._bounds, fast=False)  # fmt: skip


def _worst_miss(model, n_points: int) -> float:
    """The largest miss of the fitted path's (dK, dM) against the reference's at seeded
    points of the box, relative to the largest entry of the reference's K or M at the deck's
    values."""
    fast, ref = model.general, _reference(model)
    names = list(fast.bindings)
    low, high = (np.array([model._bounds[n][k] for n in names]) for k in (0, 1))
    scale = [np.abs(x).max() for x in ref.line_base()]
    worst = 0.0
    for u in np.random.default_rng(SEED).uniform(size=(n_points, len(names))):
        values = dict(model._line_defaults, **dict(zip(names, low + u * (high - low), strict=True)))
        for mine, exact, s in zip(fast.line_delta(values), ref.line_delta(values), scale,
                                  strict=True):  # fmt: skip
            worst = max(worst, float(np.abs(mine - exact).max()) / s)
    return worst


@pytest.mark.parametrize("coupmass", ["", "PARAM,COUPMASS,1\n"])
def test_every_kind_of_card_field_from_fitted_records(tmp_path, coupmass):
    model = load_nastran_model(_deck(tmp_path, MIXED + coupmass), BINDINGS)
    g = model.general
    assert len(g.cards) == 2 and g.card_notes == ["", ""]
    assert all(r is not None for r in g.card_records)
    offsets = g.card_records[0]
    assert offsets.cbeam.tolist() == [False, True]  # the CBAR lumps no twist inertia
    assert offsets.lumped.size == (2 if not coupmass else 0)
    assert _worst_miss(model, 4) < 1e-12


def test_the_fitted_records_solve_as_the_cards_read_again(tmp_path):
    """The frequencies of a solve at a moved point, fitted records against reference."""
    model = load_nastran_model(_deck(tmp_path, MIXED), BINDINGS)
    point = {"wa": 0.6, "wb": -0.7, "w2": 0.5, "w3": 0.8, "x1": -0.9, "x2": 0.6}
    fitted = model.solve(point, n_modes=10).frequencies_hz
    assert model.general.card_notes == ["", ""]
    reference = load_nastran_model(_deck(tmp_path, MIXED), BINDINGS)
    reference.general._card_records = [None, None]  # noqa: SLF001 - the cards read again
    reference.general._card_notes = ["reference", "reference"]  # noqa: SLF001
    again = reference.solve(point, n_modes=10).frequencies_hz
    np.testing.assert_allclose(fitted, again, rtol=1e-10)
    moved = model.solve({}, n_modes=10).frequencies_hz
    assert np.abs(fitted / moved - 1).max() > 1e-3  # the offsets and masses do move them


def test_a_dimension_on_an_offset_bar_keeps_the_cards_read_again(tmp_path):
    bulk = MIXED.replace("PBAR,21,1,0.6,0.03,0.02,0.04", "PBARL,21,1,,BAR\n,0.5,0.8")
    model = load_nastran_model(_deck(tmp_path, bulk), {
        "wa": BINDINGS["wa"], "h": {"binds": "PBARL 21 DIM2"}})  # fmt: skip
    g = model.general
    assert g.card_records == [None]
    # A = w h is affine in the height h; I = w h^3 / 12 is not
    assert re.fullmatch(r"the elements' i[yz] is not affine in wa, h", g.card_notes[0])
    f = model.solve({"wa": 0.3, "h": 1.1}, n_modes=3).frequencies_hz
    assert np.all(np.isfinite(f))


@pytest.mark.skipif(not DECK.exists(), reason=f"shared data not found: {DECK}")
def test_the_sol200_deck_every_desvar_moved():
    model = load_nastran_model(str(DECK))
    g = model.general
    assert g.card_notes == ["", ""]
    offsets, masses = g.card_records
    assert offsets.beams0.n_elements == 44 and offsets.cbeam.all()
    # the DVCREL1s act on 44 CBEAMs, 35 CONM2s and 12 CMASS2s (grep DVCREL1 in the deck)
    assert masses.lay.conm2.size == 35 and masses.lay.cmass.size == 12
    assert _worst_miss(model, 2) < 1e-12


@pytest.mark.parametrize("value, digits", [(-1.1746955442269744, 13), (1 / 3, 14),
                                           (1.2345678901234567e-5, 12)])  # fmt: skip
def test_a_written_real_keeps_the_digits_a_large_field_holds(value, digits):
    text = real16(value)
    assert len(text) <= 16
    assert abs(parse_number(text) / value - 1) < 10.0 ** (1 - digits)


def test_a_discovery_candidate_takes_the_fitted_records_over(tmp_path):
    """An effect appends a mass at a grid: the candidate's bound cards are the deck's, so their
    fitted records are taken over (only their places in the new pattern are found again), and
    it solves as a candidate that fits them afresh."""
    from bayesupdate.discovery.candidates import make_candidate
    from bayesupdate.discovery.effects import Effect

    model = load_nastran_model(_deck(tmp_path, MIXED), BINDINGS, test_labels=["3Y", "4Y"])
    point = {"wa": 0.6, "w3": 0.8, "x1": -0.9, "m": 3.5}
    model.solve(point, n_modes=6)
    candidate = make_candidate(model, Effect("added_mass", "3")).model
    moved = dict(point, **{"added_mass@3:m": 0.4})
    taken = candidate.solve(moved, n_modes=6).frequencies_hz
    mine, theirs = candidate.general.card_records, model.general.card_records
    # the same fit, placed on the candidate's own assembly
    assert all(a.fit is b.fit and a is not b for a, b in zip(mine, theirs, strict=True))
    fresh = make_candidate(model, Effect("added_mass", "3")).model
    fresh.general._known_cards = None  # noqa: SLF001 - fitted again from the cards
    again = fresh.solve(moved, n_modes=6).frequencies_hz
    assert fresh.general.card_records[0].fit is not theirs[0].fit
    np.testing.assert_allclose(taken, again, rtol=1e-12)
    assert np.abs(taken / model.solve(point, n_modes=6).frequencies_hz - 1).max() > 1e-3
