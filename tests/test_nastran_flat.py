"""The flat deck (``nastran.flat.write_flat_deck``: one file of large-field cards, one-section
PBEAM/CBEAM as PBAR/CBAR with the CBEAM's twist inertia, for MYSTRAN) reads as the deck it was
written from: a small deck with tabs, an INCLUDE, a one-line PBEAM and offsets, and the
mAEWing1 v3.3 deck as published."""

from pathlib import Path

import numpy as np
import pytest

from bayesupdate.nastran import load_nastran_model
from bayesupdate.nastran.flat import write_flat_deck

FEM = Path(__file__).resolve().parents[2] / "shared" / "data" / "gvt_maewing1" / "fem"

#: a free frame of three CBEAMs (one-line PBEAM: end B = end A; tabs in fields; offsets), a
#: CONM2, a grounded CBUSH on soft springs and SUPORT
BEAMS = """GRID\t1\t\t0.\t0.\t0.
GRID\t2\t\t10.\t0.\t0.
GRID\t3\t\t10.\t8.\t0.
GRID\t4\t\t20.\t8.\t1.
CBEAM,1,5,1,2,0.,0.,1.
CBEAM,2,5,2,3,0.,0.,1.
,,,0.,0.2,0.,0.,0.2,0.
CBEAM,3,6,3,4,0.,0.,1.
PBEAM\t5\t1\t0.5\t0.02\t0.01\t\t0.015
PBEAM,6,1,0.3,0.01,0.02,,0.01,0.001
,0.,0.,0.,0.,0.,0.,0.,0.
,0.8,0.9
MAT1,1,1.e7,4.e6,,0.1
CONM2,9,4,,2.,0.,0.,0.1
CBUSH,7,8,1,,,,,0
PBUSH,8,K,0.1,0.1,0.1,0.1,0.1,0.1
SUPORT,1,123456
"""


def _deck(tmp_path) -> Path:
    (tmp_path / "Beams.dat").write_text(BEAMS)
    path = tmp_path / "frame.bdf"
    path.write_text("SOL 103\nCEND\nMETHOD = 1\nBEGIN BULK\nEIGRL,1,,,8\nPARAM,WTMASS,0.5\n"
                    "INCLUDE 'beams.dat'\nENDDATA\n")  # fmt: skip
    return path


def test_flat_deck_reads_as_the_deck(tmp_path):
    """The flat deck of a deck with tabs, an INCLUDE in another letter case, a one-line PBEAM, a
    PBEAM with K1, K2 and NSM, and offsets: no tab, no CBEAM/PBEAM left (CBAR, PBAR and two
    massless CONM2 per beam), and the same 8 modes to 1e-12."""
    path = _deck(tmp_path)
    flat = write_flat_deck(path, tmp_path / "flat.bdf")
    text = flat.read_text()
    assert "\t" not in text and "INCLUDE" not in text and text.endswith("ENDDATA\n")
    assert "CBEAM" not in text and "PBEAM" not in text and text.count("CBAR*") == 3
    assert text.count("CONM2*") == 1 + 2 * 3  # the deck's and each beam's twist inertia
    # dense LAPACK on both: the iterative default stops at its own tolerance (~1e-10)
    a = load_nastran_model(str(path)).solve(n_modes=8, method="dense")
    b = load_nastran_model(str(flat)).solve(n_modes=8, method="dense")
    assert b.modes.n_rigid == a.modes.n_rigid == 6
    np.testing.assert_allclose(b.frequencies_hz, a.frequencies_hz, rtol=1e-12)
    assert b.mass_kg == pytest.approx(a.mass_kg, rel=1e-14)


def test_flat_deck_for_mystran_grounds_the_bush_on_a_held_grid(tmp_path):
    """``mystran=True``: the grounded CBUSH's GB is a new GRID (id 5, after the largest) at
    GA's place held by PS 123456, and SUPORT is gone."""
    flat = write_flat_deck(_deck(tmp_path), tmp_path / "flat.bdf", mystran=True).read_text()
    assert "SUPORT" not in flat
    grid = next(ln for ln in flat.splitlines() if ln.startswith("GRID*   5 "))
    assert grid.split()[1:] == ["5", "0.0", "0.0"]  # X1 X2 (X3 on the continuation)
    assert "123456" in flat.split(grid)[1].splitlines()[1]
    bush = next(ln for ln in flat.splitlines() if ln.startswith("CBUSH*"))
    assert bush.split()[1:5] == ["7", "8", "1", "5"]


def test_flat_v3p3_deck_reads_as_published(tmp_path):
    """mAEWing1 v3.3 as published (INCLUDEs, tabs, 20 PBEAM* of one section, 40 CBEAMs, a
    grounded CBUSH, SUPORT): its flat deck has the same 20 elastic modes to 1e-12."""
    deck = FEM / "v3.3_hati" / "sol103_mAEWing1_Hati_FEMv3p3.bdf"
    if not deck.exists():
        pytest.skip(f"shared data not found: {deck}")
    a = load_nastran_model(str(deck)).solve(n_modes=20).frequencies_hz
    flat = write_flat_deck(deck, tmp_path / "flat.bdf")
    b = load_nastran_model(str(flat)).solve(n_modes=20).frequencies_hz
    np.testing.assert_allclose(b, a, rtol=1e-12)
