"""CQUAD4/CTRIA3 ZOFFS (MSC Nastran QRG CQUAD4: the offset from the plane of the grid points to
the element's reference plane, positive along the element normal G1 -> G2 -> G3).

A cantilever steel strip (1 m x 0.1 m x 10 mm, 20 x 2 quads, clamped at x = 0) carries a bar
along its centre line whose own offset puts it 20 mm above the grids.  The deck with ZOFFS =
+t/2 is compared with the same deck whose GRIDs sit at +t/2 (no ZOFFS) and whose bar offset is
20 mm - t/2, so that the bar is at the same place: equal to the shells' drilling penalty (which
acts at the grids in one deck and at the mid-surface in the other; measured 5.3e-6 relative).  With
the quads' nodes in the other order (normal -z) the mid-surface is at -t/2, and the modes are
those of the GRIDs at -t/2 (bar offset 20 mm + t/2).  The two sides are told apart: the bar's
distance from the plate is 15 or 25 mm, and modes 1, 3 and 5 differ by 28-48 %.  The mass is
offset with the stiffness (a note says so: MSC's QRG PSHELL remark 6 says it is not).
"""

import json

import numpy as np
import pytest

from bayesupdate.cli import main
from bayesupdate.fe import shell_mesh as sm

T, BAR = 0.01, 0.02


def _deck(path, z: float, zoffs: float, bar_offset: float, flip: bool = False):
    """The strip with its GRIDs at height ``z``, shells with ZOFFS ``zoffs`` (node order reversed
    by ``flip``: normal -z) and the centre-line CBARs offset by ``bar_offset`` along z."""
    nodes, quads, _ = sm.plate(1.0, 0.1, 20, 2)
    lines = ["SOL 103", "CEND", "SPC = 1", "METHOD = 1", "BEGIN BULK", "EIGRL,1,,,6"]
    lines += [f"GRID,{i + 1},,{p[0]:.6f},{p[1]:.6f},{z!r}" for i, p in enumerate(nodes)]
    order = quads[:, ::-1] if flip else quads
    zo = f",,{zoffs!r}" if zoffs else ""
    lines += [f"CQUAD4,{e + 1},1,{','.join(str(g + 1) for g in q)}{zo}"
              for e, q in enumerate(order)]  # fmt: skip
    centre = np.flatnonzero(np.isclose(nodes[:, 1], 0.05))
    centre = centre[np.argsort(nodes[centre, 0])]
    w = f"0.,0.,{bar_offset!r}"
    lines += [f"CBAR,{100 + k},2,{a + 1},{b + 1},0.,1.,0.\n,,,{w},{w}"
              for k, (a, b) in enumerate(zip(centre[:-1], centre[1:], strict=True))]  # fmt: skip
    lines += [f"PSHELL,1,1,{T},1", "PBAR,2,1,1.0E-4,1.0E-9,1.0E-9,2.0E-9"]
    lines += ["MAT1,1,2.0E+11,,0.30,7800.0"]
    lines += [f"SPC1,1,123456,{g + 1}" for g in np.flatnonzero(nodes[:, 0] < 1e-9)]
    path.write_text("\n".join([*lines, "ENDDATA", ""]))
    return path


def _modes(path, capsys) -> tuple[np.ndarray, list]:
    assert main(["modes", "--model", str(path), "--modes", "6", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    return np.array(out["frequencies_hz"]), out["notes"]


@pytest.mark.parametrize("flip", [False, True])
def test_zoffs_moves_the_mid_surface_along_the_element_normal(tmp_path, capsys, flip):
    side = -1.0 if flip else 1.0
    offset, notes = _modes(_deck(tmp_path / "z.bdf", 0.0, T / 2, BAR, flip), capsys)
    moved, _ = _modes(_deck(tmp_path / "m.bdf", side * T / 2, 0.0, BAR - side * T / 2), capsys)
    np.testing.assert_allclose(offset, moved, rtol=1e-5)
    assert any("ZOFFS" in n and "mass" in n for n in notes)
    other, _ = _modes(_deck(tmp_path / "o.bdf", -side * T / 2, 0.0, BAR + side * T / 2), capsys)
    assert np.max(np.abs(offset / other - 1)) > 0.01  # the other side is told apart
