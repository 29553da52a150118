"""The mAEWing1 GVT's accelerometer positions as a test geometry file, as a user would have it.

``GVT_Info.m`` (../shared/data/gvt_maewing1/data) gives ``AccelPos`` (X, Y) [in] of the 20
accelerometers in the test's own frame (origin at the nose, X left, Y aft, Z up) and
``ShakerPos`` (X, Y) of the shaker, which the README shows to be in centimetres (explog.txt: "25
inches back, 4.5 inches to the right wing").  ``gvt_geometry`` reads them into a
``testgeom.TestGeometry`` (test nodes 1-20 = the accelerometers, 25 = the shaker, as the
``frf`` commands of ``studies/gvt_maewing1.py`` name them; z = 0 on the wing's plane; the
leading and trailing edge lines of ``ForwardAccel`` / ``AftAccel`` as UFF 82 trace lines).

Run: .venv/bin/python studies/maewing1_test_geometry.py OUT.unv|OUT.csv
(a .unv is written as UFF 164 + 15 + 82 in inches; a .csv in inches), or with ``--table`` to
print the pairing tables of docs/guide/test-geometry.md: the accelerometers on v4.2's GRIDs
1-20 (nodes) and on v3.3's beams (points on elements; the v3.3 deck's GRIDs and CBEAM/CBAR
cards read by ``bayesupdate.nastran.deck``).
"""

import re
import sys
from pathlib import Path

import numpy as np

from bayesupdate.testgeom import make_geometry, write_csv_geometry, write_uff_geometry

GVT_INFO = Path(__file__).resolve().parents[2] / "shared/data/gvt_maewing1/data/GVT_Info.m"
INCH = 0.0254
#: test node of the shaker (the --reference of studies/gvt_maewing1.py)
SHAKER_NODE = 25


def _matrix(text: str, name: str) -> np.ndarray:
    """The numbers of a MATLAB assignment ``name = [ ... ];`` (rows by ';' or newline)."""
    body = re.search(rf"^{name}\s*=\s*\[(.*?)\];", text, re.S | re.M).group(1)
    return np.array([float(x) for x in re.split(r"[\s;,]+", body.strip()) if x])


def _ranges(text: str, name: str) -> list[int]:
    """A MATLAB row of ranges like ``[19:-2:11 1:2:9]`` as a list of integers."""
    body = re.search(rf"^{name}\s*=\s*\[(.*?)\];", text, re.M).group(1)
    out = []
    for token in body.split():
        a, step, b = (int(x) for x in token.split(":")) if token.count(":") == 2 else (
            int(token.split(":")[0]), 1, int(token.split(":")[-1]))  # fmt: skip
        out += list(range(a, b + (1 if step > 0 else -1), step))
    return out


def gvt_geometry(path=GVT_INFO):
    """``TestGeometry`` of GVT_Info.m (module docstring), coordinates in the test frame [m]."""
    text = Path(path).read_text()
    accel = _matrix(text, "AccelPos").reshape(-1, 2) * INCH
    shaker = _matrix(text, "ShakerPos") * 0.01  # centimetres (README)
    xy = np.vstack([accel, shaker])
    xyz = np.column_stack([xy, np.zeros(len(xy))])
    ids = [*range(1, len(accel) + 1), SHAKER_NODE]
    lines = (tuple(_ranges(text, "ForwardAccel")), tuple(_ranges(text, "AftAccel")))
    return make_geometry(ids, xyz, trace_lines=lines, unit="in", source=str(path))


#: test (nose, X left, Y aft; in) to FE (x aft, y right; origin 15.55 in aft of the nose)
TO_FE = ((0.0, 1.0, 0.0, -15.55), (-1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0))


def v42_grids():
    """``ModelMesh`` of v4.2's GRIDs 1-20 (gvt_accelerations.dat, small fields), inches."""
    from bayesupdate.testgeom import ModelMesh

    ids, xyz = [], []
    path = GVT_INFO.parents[1] / "fem/v4.2_updated/gvt_accelerations.dat"
    for line in path.read_text().splitlines():
        if line.startswith("GRID ") and int(line[8:16]) <= 20:
            ids.append(int(line[8:16]))
            xyz.append([float(line[24 + 8 * k : 32 + 8 * k]) for k in range(3)])
    none = [np.zeros((0, k), int) for k in (2, 4, 3)]
    return ModelMesh(np.array(xyz), np.array(ids), *none, "in", 0.0254)


def v33_beams():
    """``ModelMesh`` of v3.3's GRIDs and line elements (CBEAM, CBAR), read by
    ``bayesupdate.nastran``'s own reader."""
    from bayesupdate.nastran.deck import Refusals, read_deck
    from bayesupdate.nastran.frames import read_grids
    from bayesupdate.testgeom import ModelMesh

    path = GVT_INFO.parents[1] / "fem/v3.3_hati/sol103_mAEWing1_Hati_FEMv3p3.bdf"
    deck = read_deck(path)
    grids = read_grids(deck, Refusals(str(path)))
    ids = grids.ids
    row = {int(g): i for i, g in enumerate(ids)}
    lines = [[row[c["GA"]], row[c["GB"]]] for c in deck.of("CBEAM", "CBAR")]
    none = [np.zeros((0, k), int) for k in (4, 3)]
    return ModelMesh(grids.xyz, ids, np.array(lines), *none, "in", 0.0254)


def print_tables() -> None:
    from bayesupdate.testgeom import PairingSettings, pair_test, resolve_dofs

    geometry = gvt_geometry()
    dofs = resolve_dofs(geometry, [f"{k}V" for k in range(1, 21)])
    nodes = pair_test(geometry, dofs, v42_grids(), PairingSettings(TO_FE, tolerance=0.001,
                                                                   on_elements=False))  # fmt: skip
    mesh = v33_beams()
    beams = pair_test(geometry, dofs, mesh, PairingSettings(TO_FE, tolerance=0.1016))
    print("| accel | v4.2 GRID | distance [in] | v3.3 beam (its GRIDs) | nearest GRID | "
          "point on the beam (x, y) [in] | distance [in] |")  # fmt: skip
    print("|---|---|---|---|---|---|---|")
    for a, b in zip(nodes.points, beams.points, strict=True):
        ends = mesh.node_ids[mesh.lines[int(b.element.split()[1])]]
        x, y, _ = b.model_xyz
        print(
            f"| {a.test_node} | {a.model_node} | {a.distance:.3f} | {ends[0]}-{ends[1]} | "
            f"{b.model_node} | ({x:.3f}, {y:.3f}) | {b.distance:.3f} |"
        )


if __name__ == "__main__" and "--table" in sys.argv:
    print_tables()
elif __name__ == "__main__":
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "/tmp/maewing1_test.unv")
    geometry = gvt_geometry()
    if out.suffix.lower() == ".csv":
        write_csv_geometry(out, geometry, unit="in")
    else:
        write_uff_geometry(out, geometry, unit="in")
    print(f"wrote {out}: {len(geometry.node_ids)} nodes, {len(geometry.trace_lines)} trace lines")
