"""The mAEWing1 GVT's accelerometer positions as a test geometry file, as a user would have it.

``GVT_Info.m`` (../shared/data/gvt_maewing1/data) gives ``AccelPos`` (X, Y) [in] of the 20
accelerometers in the test's own frame (origin at the nose, X left, Y aft, Z up) and
``ShakerPos`` (X, Y) of the shaker, which the README shows to be in centimetres (explog.txt: "25
inches back, 4.5 inches to the right wing").  ``gvt_geometry`` reads them into a
``testgeom.TestGeometry`` (test nodes 1-20 = the accelerometers, 25 = the shaker, as the
``frf`` commands of ``studies/gvt_maewing1.py`` name them; z = 0 on the wing's plane; the
leading and trailing edge lines of ``ForwardAccel`` / ``AftAccel`` as UFF 82 trace lines).

Run: .venv/bin/python studies/maewing1_test_geometry.py OUT.unv|OUT.csv
(a .unv is written as UFF 164 + 15 + 82 in inches; a .csv in inches).
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


if __name__ == "__main__":
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "/tmp/maewing1_test.unv")
    geometry = gvt_geometry()
    if out.suffix.lower() == ".csv":
        write_csv_geometry(out, geometry, unit="in")
    else:
        write_uff_geometry(out, geometry, unit="in")
    print(f"wrote {out}: {len(geometry.node_ids)} nodes, {len(geometry.trace_lines)} trace lines")
