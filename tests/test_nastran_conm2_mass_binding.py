"""A parameter bound to CONM2 M scales the mass (and the m d^2 terms of its offset) but not the
card's own inertia I11-I33, which are separate fields (MSC Nastran QRG CONM2): the model at the
parameter and the deck written with it (``--write-bdf``) solve to the same closed form."""

import numpy as np
import pytest
import scipy.linalg

from bayesupdate.nastran import load_nastran_model
from bayesupdate.nastran.writer import write_updated_deck

KZ, KR = 400.0, 900.0
M, X1, I22 = 2.0, 0.5, 3.0
BULK = (
    "SOL 103\nCEND\nSPC = 1\nMETHOD = 1\nBEGIN BULK\nEIGRL,1,,,2\nGRID,1,,0.,0.,0.\n"
    f"CONM2,9,1,,{M},{X1},0.,0.\n,0.,0.,{I22},0.,0.,0.\n"
    f"CELAS2,1,{KZ},1,3\nCELAS2,2,{KR},1,5\nSPC1,1,1246,1\nENDDATA\n"
)


def _closed_form_hz(scale: float) -> np.ndarray:
    """(z, ry) at the grid: the mass at x = X1 moves z - X1 ry, so M = s m [[1, -X1], [-X1,
    X1^2]] + [[0, 0], [0, I22]] (I22 unscaled) against K = diag(kz, kry)."""
    mass = scale * M * np.array([[1.0, -X1], [-X1, X1**2]]) + np.diag([0.0, I22])
    lam = scipy.linalg.eigh(np.diag([KZ, KR]), mass, eigvals_only=True)
    return np.sqrt(lam) / (2 * np.pi)


def test_conm2_m_binding_leaves_the_cards_inertia_and_matches_the_written_deck(tmp_path):
    deck = tmp_path / "deck.bdf"
    deck.write_text(BULK)
    model = load_nastran_model(deck, {"m": {"binds": "CONM2 9 M scale", "bounds": [0.1, 2.0]}})
    at_deck = model.solve({"m": 1.0}, n_modes=2).frequencies_hz
    assert at_deck == pytest.approx(_closed_form_hz(1.0), rel=1e-9)
    scaled = model.solve({"m": 0.3}, n_modes=2).frequencies_hz
    # 2.65 and 4.28 Hz; I22 scaled with M as well would give 3.69 and 5.60 Hz
    assert scaled == pytest.approx(_closed_form_hz(0.3), rel=1e-9)
    written = write_updated_deck(model, {"m": 0.3}, tmp_path / "updated.bdf")
    again = load_nastran_model(written).solve(n_modes=2).frequencies_hz
    assert again == pytest.approx(scaled, rel=1e-9)
