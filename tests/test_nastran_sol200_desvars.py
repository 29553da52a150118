"""The authors' SOL 200 deck of the mAEWing1 (``../shared/data/gvt_maewing1/fem``, README there):
each kind of DESVAR that sets an element card's own field (MSC QRG DVCREL1 on CONM2 M, X1, I11,
I22; CMASS2 M; CBEAM W1A/W1B/W2A/W2B with COEF +1 and -1) is a parameter whose bound model, away
from XINIT, has the frequencies of the deck ``writer.write_design_deck`` writes at the same
DESVAR values and reads again (SOL 200's own model at those values)."""

from pathlib import Path

import numpy as np
import pytest

from bayesupdate.nastran import load_nastran_model
from bayesupdate.nastran.writer import write_design_deck

DECK = (Path(__file__).resolve().parents[2] / "shared" / "data" / "gvt_maewing1" / "fem"
        / "sol200_full_model" / "sol200_mAEWing1_FEMv4p2.bdf")  # fmt: skip
if not DECK.exists():
    pytest.skip(f"shared data not found: {DECK}", allow_module_level=True)

#: one DESVAR of each kind, moved to 30 % / 70 % of its [XLB, XUB] (DESVAR label or label_id)
KINDS = {
    "conm2_offset_and_mass": ("X2", "BATTERY"),  # CONM2 302 X1 and M: m x, m x^2 together
    "conm2_inertia": ("P2IYY", "BEAMIXX"),  # CONM2 I22; I11 of 32 CONM2s, COEF 0.5 / 1
    "cmass2": ("CONMIYY",),  # 6 CMASS2 M, COEF 0.5 / 1
    "cbeam_offsets": ("W2A1_9002", "W1A2"),  # W2A/W2B COEF +-1 on 4 CBEAMs; W1A/W1B on 34
}


@pytest.fixture(scope="module")
def model():
    return load_nastran_model(str(DECK))


@pytest.mark.parametrize("kind", list(KINDS))
def test_a_bound_element_card_field_solves_as_the_written_design_deck(model, kind, tmp_path):
    """Bound model at the moved values (the other DESVARs at the cards' values) against the
    deck written with every relation at those DESVAR values and read again: K and M to 1e-12
    of their largest entry (measured 4e-18 and 2e-16), modes 7-16 to 1e-8, the mass to 1e-12;
    the move changes the frequencies by more than 1e-4 (the parameter acts).  The matrices are
    the exact check: two solves of matrices equal to 1e-16 give this deck's lowest elastic mode
    only to about 1e-9 (1.4e-9 by the default block Krylov, whose residual tolerance is 1e-5,
    6.5e-9 by dense LAPACK: 1e6 lbf/in hinge springs beside an 8 Hz mode), so a 1e-9 tolerance
    on the frequencies measured the solver's reproducibility, not the binding."""
    x0, bounds = model.default_parameters(), model.default_bounds()
    moved = {}
    for k, name in enumerate(KINDS[kind]):
        low, high = bounds[name]
        moved[name] = low + (0.3 + 0.4 * k) * (high - low)
    r = model.solve(moved, n_modes=10)
    values = {model.bindings[n].desvar: v for n, v in {**x0, **moved}.items()}
    written = write_design_deck(DECK, tmp_path / "design.bdf", values)
    deck = load_nastran_model(str(written), parameters={})
    for bound, read in zip(model.matrices(moved)[:2], deck.matrices(None)[:2], strict=True):
        assert abs(bound - read).max() <= 1e-12 * abs(read).max()
    again = deck.solve(n_modes=10)
    np.testing.assert_allclose(r.frequencies_hz, again.frequencies_hz, rtol=1e-8)
    assert r.mass_kg == pytest.approx(again.mass_kg, rel=1e-12)
    base = model.solve(n_modes=10).frequencies_hz
    assert np.abs(r.frequencies_hz / base - 1).max() > 1e-4
