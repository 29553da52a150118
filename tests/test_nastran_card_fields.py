"""Element cards' own fields as parameters (``nastran.bindings.CARD_FIELDS``: written into the
cards and converted again, ``lines.LineRebuild``, whose records ``nastran.card_records`` fits
once) against closed forms, one per kind.

* CONM2 X1 and I33 (MSC QRG CONM2: inertia about the centre of gravity, offset from the grid): a
  mass m at arm x on a grid that only turns about z, held by a torsion spring k:
  omega^2 = k / (I33 + m x^2), a rigid offset link (m x^2 is not linear in x).
* CONM2 M bound beside its X1: the mass is written into the card too (a factor on the read
  mass would keep m x^2 at the deck's x).
* CMASS2 M (MSC QRG CMASS2) on a spring CELAS2 k, one DOF: omega^2 = k / m.
* CBEAM W1A (MSC QRG CBEAM, offsets in the grids' frames, OFFT GGG): a massless beam along x
  from a clamped grid to a grid that moves only along x with a CONM2 M; an offset w of end A
  along x shortens the flexible part to L - w: omega^2 = E A / ((L - w) M).
"""

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran import load_nastran_model

ARM = """GRID,1,,0.,0.,0.,,12345
CELAS2,7,1000.,1,6
CONM2,31,1,,2.,0.5,0.,0.
,0.,,0.,,,0.3
"""
SPRING = """GRID,1,,0.,0.,0.,,12456
CELAS2,7,1000.,1,3
CMASS2,21,2.5,1,3
"""
ROD = """GRID,1,,0.,0.,0.,,123456
GRID,2,,10.,0.,0.,,23456
CBEAM,1,5,1,2,0.,1.,0.
,,,0.,0.,0.,0.,0.,0.
PBEAM,5,1,0.5,0.02,0.01,,0.015
MAT1,1,1.e7,4.e6
CONM2,31,2,,3.
"""


def _deck(tmp_path, bulk: str) -> str:
    path = tmp_path / "deck.bdf"
    path.write_text(f"SOL 103\nCEND\nMETHOD = 1\nBEGIN BULK\nEIGRL,1,,,1\n{bulk}ENDDATA\n")
    return str(path)


def _hz(omega2) -> float:
    return float(np.sqrt(omega2) / (2 * np.pi))


@pytest.mark.parametrize("x, j", [(0.5, 0.3), (-0.8, 0.3), (0.1, 0.05)])
def test_conm2_offset_and_inertia_on_a_rigid_arm(tmp_path, x, j):
    model = load_nastran_model(_deck(tmp_path, ARM), {"x": {"binds": "CONM2 31 X1",
                                                            "bounds": [-1.0, 1.0]},
                                                      "j": {"binds": "CONM2 31 I33"}})  # fmt: skip
    assert model.default_parameters() == {"x": 0.5, "j": 0.3}
    f = model.solve({"x": x, "j": j}, n_modes=1).frequencies_hz[0]
    assert model.general.card_notes == [""]  # from fitted records (``nastran.card_records``)
    assert f == pytest.approx(_hz(1000.0 / (j + 2.0 * x * x)), rel=1e-12)


def test_conm2_mass_beside_its_offset_is_written_into_the_card(tmp_path):
    model = load_nastran_model(_deck(tmp_path, ARM), {"m": {"binds": "CONM2 31 M"},
                                                      "x": {"binds": "CONM2 31 X1",
                                                            "bounds": [-1.0, 1.0]}})  # fmt: skip
    assert model.bindings["m"].relations == (("CONM2", 31, "M", 0.0, 1.0),)
    f = model.solve({"m": 3.0, "x": -0.7}, n_modes=1).frequencies_hz[0]
    assert f == pytest.approx(_hz(1000.0 / (0.3 + 3.0 * 0.49)), rel=1e-12)


@pytest.mark.parametrize("m", [2.5, 1.5, 4.0])
def test_cmass2_on_a_spring(tmp_path, m):
    model = load_nastran_model(_deck(tmp_path, SPRING), {"m": {"binds": "CMASS2 21 M"}})
    assert model.default_bounds()["m"] == (1.25, 5.0)  # 0.5-2 x the card's M
    f = model.solve({"m": m}, n_modes=1).frequencies_hz[0]
    assert model.general.card_notes == [""]
    assert f == pytest.approx(_hz(1000.0 / m), rel=1e-12)


@pytest.mark.parametrize("w", [0.0, 3.0, -1.5])
def test_cbeam_end_offset_along_the_axis(tmp_path, w):
    model = load_nastran_model(_deck(tmp_path, ROD), {"w": {"binds": "CBEAM 1 W1A",
                                                            "bounds": [-2.0, 4.0]}})  # fmt: skip
    f = model.solve({"w": w}, n_modes=1).frequencies_hz[0]
    assert model.general.card_notes == [""]
    assert f == pytest.approx(_hz(1.0e7 * 0.5 / ((10.0 - w) * 3.0)), rel=1e-9)


def test_an_offset_needs_bounds_and_an_inertia_a_low_bound_of_0(tmp_path):
    deck = _deck(tmp_path, ARM)
    with pytest.raises(BayesUpdateError, match=r"CONM2 31 X1.*give bounds = \[low, high\]"):
        load_nastran_model(deck, {"x": {"binds": "CONM2 31 X1"}})
    with pytest.raises(BayesUpdateError, match="the low bound must be >= 0"):
        load_nastran_model(deck, {"j": {"binds": "CONM2 31 I33", "bounds": [-0.1, 1.0]}})
    model = load_nastran_model(deck, {"j": {"binds": "CONM2 31 I33", "bounds": [0.0, 1.0]}})
    assert model.solve({"j": 0.0}, n_modes=1).frequencies_hz[0] == pytest.approx(
        _hz(1000.0 / 0.5), rel=1e-12
    )


def test_an_inertia_is_an_exact_affine_term_and_an_offset_is_named_non_linear(tmp_path):
    """For the reduced basis (``NastranModel.line_terms``): CONM2 I33 and CMASS2 M enter M
    linearly (exact affine terms, checked at seeded points to 1e-9); CONM2 X1 does not (m x^2)
    and is named."""
    linear = load_nastran_model(_deck(tmp_path, ARM), {"j": {"binds": "CONM2 31 I33"}})
    assert [t.name for t in linear.line_terms()] == ["j"]
    spring = load_nastran_model(_deck(tmp_path, SPRING), {"m": {"binds": "CMASS2 21 M"}})
    (term,) = spring.line_terms()
    assert np.abs(term.dM).sum() == pytest.approx(1.0, rel=1e-12)  # d(m)/dm on one DOF
    offset = load_nastran_model(_deck(tmp_path, ARM), {"x": {"binds": "CONM2 31 X1",
                                                             "bounds": [-1.0, 1.0]}})  # fmt: skip
    assert offset.line_terms() == ()
    assert "parameter x ('CONM2 31 X1') does not enter" in offset.line_nonlinear
