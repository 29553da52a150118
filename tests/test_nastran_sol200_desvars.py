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


def quotient_hz(matrices, shapes) -> np.ndarray:
    """Frequencies [Hz] of the Rayleigh quotients x^T K x / x^T M x of ``shapes`` (n, m) in
    extended precision (numpy longdouble): free of the solve's own round-off."""
    K, M = (X.toarray().astype(np.longdouble) for X in matrices)
    x = shapes.astype(np.longdouble)
    lam = np.einsum("ij,ij->j", x, K @ x) / np.einsum("ij,ij->j", x, M @ x)
    return np.sqrt(lam).astype(float) / (2 * np.pi)


@pytest.mark.parametrize("kind", list(KINDS))
def test_a_bound_element_card_field_solves_as_the_written_design_deck(model, kind, tmp_path):
    """Bound model at the moved values (the other DESVARs at the cards' values) against the
    deck written with every relation at those DESVAR values and read again: K and M to 1e-12
    of their largest entry (measured 1.9e-16), modes 7-16 to 1e-11 as the extended-precision
    Rayleigh quotients of each model's own shapes (measured 8.6e-13 to 1.1e-12) and to 5e-9
    as the solves report them: the round-off of this deck (each solve is ~1.2e-9 off its own
    quotients; dense LAPACK's frequencies of the two models differ by 1.0e-9 to 4.4e-9 over
    the four kinds, the block Krylov's by 1.8e-12 to 1.4e-9), the mass to 1e-12; the move
    changes the frequencies by more than 1e-4 (the parameter acts)."""
    x0, bounds = model.default_parameters(), model.default_bounds()
    moved = {}
    for k, name in enumerate(KINDS[kind]):
        low, high = bounds[name]
        moved[name] = low + (0.3 + 0.4 * k) * (high - low)
    r = model.solve(moved, n_modes=10)
    values = {model.bindings[n].desvar: v for n, v in {**x0, **moved}.items()}
    written = write_design_deck(DECK, tmp_path / "design.bdf", values)
    deck = load_nastran_model(str(written), parameters={})
    again = deck.solve(n_modes=10)
    mine, theirs = model.matrices(moved), deck.matrices()
    for X, Y in zip(mine, theirs, strict=True):
        assert abs(X - Y).max() <= 1e-12 * abs(Y).max()
    np.testing.assert_allclose(
        quotient_hz(mine, r.modes.shapes), quotient_hz(theirs, again.modes.shapes), rtol=1e-11
    )
    np.testing.assert_allclose(r.frequencies_hz, again.frequencies_hz, rtol=5e-9)
    assert r.mass_kg == pytest.approx(again.mass_kg, rel=1e-12)
    base = model.solve(n_modes=10).frequencies_hz
    assert np.abs(r.frequencies_hz / base - 1).max() > 1e-4


def test_a_study_of_its_desvars_runs_with_the_default_sampler_settings(tmp_path):
    """A study of the deck with no ``[parameters]`` and no ``[sampler]`` table: its 34 DESVARs
    are the parameters, and the walkers follow them (two per parameter, 68: the ensemble's
    least), where the 32 of before refused even ``calibrate`` ("32 is too few for 34")."""
    from bayesupdate.config import parse_study
    from bayesupdate.ema.modal_h5 import write_modal_h5
    from bayesupdate.modal_data import ModalData
    from bayesupdate.pipelines.study import prepare

    write_modal_h5(tmp_path / "m.h5", ModalData(np.array([7.81, 19.07, 31.71])))
    study = parse_study(
        {"model": {"source": str(DECK)}, "data": {"source": str(tmp_path / "m.h5")}}
    )
    assert study.sampler.walkers is None
    prepared = prepare(study)
    assert len(prepared.problem.parameters) == 34
    assert prepared.study.sampler.walkers == 68
