"""``correlate`` and ``sensitivity`` on the NX FEMAP exhaust (``studies/correlate_femap.py``):
the deck against its own virtual test at the worked example's 20 points, and the sensitivities of
its 10 modes to the four PSHELL thicknesses, the two MAT1 densities and the modulus of MAT1 2.

Checked: the MAC diagonal is 1 and the pairs are the identity, the cross-orthogonality through
the SEREP TAM is the identity; every mass in the deck is a MAT1 density, so the two densities'
sensitivities sum to -1/2 for every mode (lambda is homogeneous of degree -1 in M); the
thicknesses the worked example calibrates (PSHELL 3 and 9) are among the suggested parameters;
E and RHO of MAT1 2 are not one direction here (a second material and the hanger springs share
the stiffness and the mass).  About 40 s of CPU (a read of the deck and a modal solve of
26,832 DOFs for the virtual test and for each of the two commands).
"""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))

import correlate_femap  # noqa: E402

needs_deck = pytest.mark.skipif(
    not correlate_femap.DECK.exists(), reason=f"shared data not found: {correlate_femap.DECK}"
)


@pytest.mark.slow
@needs_deck
def test_femap_exhaust_correlates_with_itself_and_its_thicknesses_are_seen(tmp_path):
    out = correlate_femap.run(tmp_path, all_e=False)
    assert out["pairs"] == [[i, i] for i in range(1, 11)]
    # per test DOF its model node: the GRID [model.test_points] maps the test node to
    grids = correlate_femap.GRIDS
    assert out["points"] == {f"{k}{d}": grids[k - 1] for k in range(1, 21) for d in "VH"}
    np.testing.assert_allclose(out["mac_diagonal"], 1.0, atol=1e-9)
    assert out["cross_orthogonality_diagonal_min"] == pytest.approx(1.0, abs=1e-6)
    assert out["cross_orthogonality_off_max"] < 1e-6
    names = out["candidates"]
    assert names == ["PSHELL 3 T", "PSHELL 5 T", "PSHELL 9 T", "PSHELL 10 T", "MAT1 2 RHO",
                     "MAT1 3 RHO", "MAT1 2 E"]  # fmt: skip
    s = np.asarray(out["sensitivity"])
    np.testing.assert_allclose(s[:, 4] + s[:, 5], -0.5, atol=1e-5)
    assert {"PSHELL 3 T", "PSHELL 9 T"} <= set(out["suggested"])
    assert out["rank"] == len(out["suggested"]) < len(names)
    assert out["groups"] == [] and -0.95 < out["cosine_e2_rho2"] < -0.7
    assert (tmp_path / "corr" / "report.html").exists()
    assert (tmp_path / "sens" / "figures" / "sensitivity.png").exists()
