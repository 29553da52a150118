"""CTUBE + PTUBE read as the CROD of its tube (``nastran.cards.rods``), against closed forms.

The deck: one tube along x from GRID 1 (clamped) to GRID 2, which carries a CONM2 of mass m and
twist inertia I11 and moves only along and about x: an axial oscillator,
omega^2 = (EA / L) / (m + m_tube / 2) with the tube's mass lumped half at each end (Nastran's
default), and a torsional one, omega^2 = (GJ / L) / I11 (a rod's lumped mass has no twist
inertia), with A = pi (OD^2 - D_i^2) / 4, J = pi (OD^4 - D_i^4) / 32 and D_i = OD - 2T.
"""

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran import load_nastran_model

E, G, RHO = 7.0e10, 2.6e10, 2700.0
L, M, I11, NSM = 1.2, 3.5, 0.02, 0.4


def tube_deck(path, ptube, extra=()):
    lines = ["SOL 103", "CEND", "SPC = 1", "METHOD = 1", "BEGIN BULK", "EIGRL,1,,,2",
             f"MAT1,1,{E:.3E},{G:.3E},,{RHO}", ptube, "GRID,1,,0.,0.,0.", f"GRID,2,,{L},0.,0.",
             "CTUBE,7,5,1,2", f"CONM2,9,2,,{M}", f",{I11}", "SPC1,1,123456,1", "SPC1,1,2356,2",
             *extra, "ENDDATA"]  # fmt: skip
    path.write_text("\n".join(lines) + "\n")
    return str(path)


@pytest.mark.parametrize("od,t", [(0.05, 0.004), (0.03, 0.0)])
def test_tube_axial_and_torsion_against_closed_forms(tmp_path, od, t):
    """A thin tube and (T = 0) a solid rod: both frequencies to 1e-12."""
    deck = tube_deck(tmp_path / "tube.bdf", f"PTUBE,5,1,{od},{t},{NSM}")
    inner = od - 2 * t if t else 0.0
    A, J = np.pi * (od**2 - inner**2) / 4, np.pi * (od**4 - inner**4) / 32
    axial = E * A / L / (M + (RHO * A + NSM) * L / 2)
    twist = G * J / L / I11
    f = load_nastran_model(deck).predict(n_modes=2).frequencies_hz
    assert np.sort(f) == pytest.approx(np.sort(np.sqrt([axial, twist]) / (2 * np.pi)), rel=1e-12)


def test_tube_equals_the_crod_of_its_section(tmp_path):
    """With COUPMASS 1 (consistent rod mass): the CTUBE's modes are those of a CROD on a PROD
    with the tube's A and J typed in."""
    od, t = 0.05, 0.004
    A, J = np.pi * (od**2 - (od - 2 * t) ** 2) / 4, np.pi * (od**4 - (od - 2 * t) ** 4) / 32
    tube = tube_deck(tmp_path / "tube.bdf", f"PTUBE,5,1,{od},{t},{NSM}", ["PARAM,COUPMASS,1"])
    text = (tmp_path / "tube.bdf").read_text().replace("CTUBE,7,5,1,2", "CROD,7,5,1,2")
    rod = tmp_path / "rod.bdf"
    rod.write_text(text.replace(f"PTUBE,5,1,{od},{t},{NSM}", f"PROD,5,1,{A!r},{J!r},,{NSM}"))
    f_tube = load_nastran_model(tube).predict(n_modes=2).frequencies_hz
    f_rod = load_nastran_model(str(rod)).predict(n_modes=2).frequencies_hz
    assert f_tube == pytest.approx(f_rod, rel=1e-12)


def test_bad_tubes_are_refused_together(tmp_path):
    extra = ["PTUBE,6,1,0.05,0.03", "CTUBE,8,6,1,2", "PTUBE,4,1,0.05,0.004,,0.06",
             "CTUBE,10,4,1,2"]  # fmt: skip
    deck = tube_deck(tmp_path / "bad.bdf", "PTUBE,5,1,0.05,0.004", extra)
    with pytest.raises(BayesUpdateError) as err:
        load_nastran_model(deck)
    text = str(err.value)
    assert "PTUBE 6" in text and "T <= OD/2" in text
    assert "PTUBE 4" in text and "tapered" in text


def test_binding_a_tubes_material_is_refused(tmp_path):
    deck = tube_deck(tmp_path / "tube.bdf", "PTUBE,5,1,0.05,0.004")
    with pytest.raises(BayesUpdateError, match="PTUBE 5 use"):
        load_nastran_model(deck, {"e": {"binds": "MAT1 1 E scale"}})
