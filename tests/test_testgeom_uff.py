"""Test geometry readers (``bayesupdate.testgeom``): UFF 15, 2411, 2420 (rectangular,
cylindrical, spherical), 82, 164 written by pyuff and by hand, and the CSV form; test DOF
directions from UFF direction codes in a node's displacement frame and from skewed vectors.

The hand-written file's expected values are worked out by hand from the UFF 2420 convention
(global = local Cartesian @ R + origin, rows of R the frame's axes) in the comments.  The
installed pyuff ships no example files, so there are none of its own to read here.
"""

import numpy as np
import pytest

from bayesupdate.testgeom import (
    CoordinateFrame,
    DeclaredDof,
    make_geometry,
    read_csv_geometry,
    read_geometry,
    resolve_dofs,
    write_csv_geometry,
    write_uff_geometry,
)
from bayesupdate.testgeom.frames import displacement_axes, to_global, to_local

# a cylindrical frame 7, axes turned 90 deg about z (x' = +y, y' = -x), origin (100, 0, 50) mm
HAND = """\
    -1
   164
         5                  mm         1
   1.0000000000000000D+03   1.0000000000000000D+03   1.0000000000000000D+00
   2.7314999999999998D+02
    -1
    -1
  2420
         1
hand part
         7         1         8
cylinder
   0.0000000000000000D+00   1.0000000000000000D+00   0.0000000000000000D+00
  -1.0000000000000000D+00   0.0000000000000000D+00   0.0000000000000000D+00
   0.0000000000000000D+00   0.0000000000000000D+00   1.0000000000000000D+00
   1.0000000000000000D+02   0.0000000000000000D+00   5.0000000000000000D+01
    -1
    -1
    15
         1         7         0         1  2.00000E+02  3.00000E+01  1.00000E+01
         2         0         7         1  1.00000E+02  5.00000E+01  5.00000E+01
    -1
    -1
  2411
         3         7         7         1
   1.0000000000000000D+02   9.0000000000000000D+01  -5.0000000000000000D+01
    -1
    -1
    82
         1         3         1
edge
         1         2         3
    -1
"""


def test_hand_written_file_with_a_cylindrical_frame(tmp_path):
    path = tmp_path / "hand.unv"
    path.write_text(HAND)
    g = read_geometry(path)
    assert g.unit == "mm" and g.node_ids.tolist() == [1, 2, 3]
    # node 1 at (r, theta, z) = (200 mm, 30 deg, 10 mm) in frame 7: local Cartesian
    # (173.205, 100, 10) -> 173.205 (0, 1, 0) + 100 (-1, 0, 0) + 10 (0, 0, 1) + origin
    np.testing.assert_allclose(g.xyz[0], [0.0, 0.1732050808, 0.060], atol=1e-9)
    # node 2 is given in the global frame
    np.testing.assert_allclose(g.xyz[1], [0.100, 0.050, 0.050], atol=1e-12)
    # node 3 (2411) at (100 mm, 90 deg, -50 mm): local (0, 100, -50) -> (-100, 0, -50) + origin
    np.testing.assert_allclose(g.xyz[2], [0.0, 0.0, 0.0], atol=1e-12)
    assert g.trace_lines == ((1, 2, 3),)
    frame = g.frame(7)
    assert frame.kind == "cylindrical"
    np.testing.assert_allclose(frame.origin, [0.1, 0.0, 0.05])
    # node 2's displacement frame is 7: it sits at local (50, 0, 0) mm, theta = 0, so
    # e_r = x' = +y, e_theta = y' = -x, e_z = +z in global
    d = resolve_dofs(g, ["2+1", "2-2", "2V", "2H", "2L"])
    np.testing.assert_allclose([x.direction for x in d],
                               [[0, 1, 0], [1, 0, 0], [0, 0, 1], [-1, 0, 0], [0, 1, 0]],
                               atol=1e-12)  # fmt: skip
    # node 3 sits at theta = 90 deg in frame 7: e_r = y' = -x, e_theta = -x' = -y
    d3 = resolve_dofs(g, ["3+1", "3+2"])
    np.testing.assert_allclose([x.direction for x in d3], [[-1, 0, 0], [0, -1, 0]], atol=1e-12)


# the layout LMS Test.Lab exports (pyuff's data/"TestLab 161 164 18 15 82.uff"): units "user
# defined" with factor 1 (m), frames as dataset 18 (origin, +x point, +xz point), a trace
# line padded with zeros; the numbers are ours
TESTLAB = """\
    -1
   164
         9USER_DEFINED
  1.00000000000000000D+00  1.00000000000000000D+00  1.00000000000000000D+00
 -2.73149999999999960D+02
    -1
    -1
    18
         1         0         0         8         1
SYS1
  1.00000e+00  0.00000e+00  0.00000e+00  1.00000e+00  0.00000e+00 -1.00000e+00
  2.00000e+00  0.00000e+00 -1.00000e+00
         2         0         1         8         1
SYS2
  0.00000e+00  0.00000e+00  0.00000e+00  0.00000e+00  1.00000e+00  0.00000e+00
  0.00000e+00  1.00000e+00  1.00000e+00
    -1
    -1
    15
         1         0         1         8  5.00000e-01  0.00000e+00  0.00000e+00
         2         0         2         8  0.00000e+00  1.00000e+00  0.00000e+00
         3         1         0         8  1.00000e+00  2.00000e+00  3.00000e+00
    -1
    -1
    82
         1         3         8
Edge
         1         2         3         0         0         0         0         0
    -1
"""


def test_test_lab_layout_with_dataset_18_frames(tmp_path):
    path = tmp_path / "testlab.uff"
    path.write_text(TESTLAB)
    g = read_geometry(path)
    assert g.unit == "m" and g.trace_lines == ((1, 2, 3),)
    # SYS1: origin (1, 0, 0), x toward (1, 0, -1): x' = -Z; z' = x' x ((2, 0, -1) - o) = -Y;
    # y' = z' x x' = +X
    np.testing.assert_allclose(g.frame(1).rotation, [[0, 0, -1], [1, 0, 0], [0, -1, 0]],
                               atol=1e-15)  # fmt: skip
    # SYS2 in SYS1: origin (1, 0, 0), x toward (2, 0, 0), xz plane through (2, -1, 0) in
    # global: a half turn about X
    np.testing.assert_allclose(g.frame(2).rotation, [[1, 0, 0], [0, -1, 0], [0, 0, -1]],
                               atol=1e-15)  # fmt: skip
    # node 3 at (1, 2, 3) in SYS1: 1 (0, 0, -1) + 2 (1, 0, 0) + 3 (0, -1, 0) + (1, 0, 0)
    np.testing.assert_allclose(g.xyz[2], [3.0, -3.0, -1.0], atol=1e-12)
    d = resolve_dofs(g, ["1+1", "1+2", "1+3", "2+3", "3+3"])
    np.testing.assert_allclose([x.direction for x in d],
                               [[0, 0, -1], [1, 0, 0], [0, -1, 0], [0, 0, -1], [0, 0, 1]],
                               atol=1e-15)  # fmt: skip


def _geometry_with_frames():
    c, s = np.cos(0.3), np.sin(0.3)
    R = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    frames = (
        CoordinateFrame(3, "rectangular", R, np.array([0.1, 0.2, -0.3])),
        CoordinateFrame(4, "cylindrical", R.T, np.array([1.0, 0.0, 0.5])),
        CoordinateFrame(9, "spherical", np.eye(3)[[1, 2, 0]], np.array([0.0, -1.0, 0.0])),
    )
    rng = np.random.default_rng(4)
    xyz = rng.uniform(-2.0, 2.0, size=(6, 3))
    return make_geometry([11, 12, 13, 14, 15, 102], xyz, [0, 3, 4, 9, 4, 0], frames,
                         ((11, 12, 0, 13, 14), (15, 102)), unit="m", source="made")  # fmt: skip


@pytest.mark.parametrize(("unit", "dataset"), [("mm", 15), ("in", 2411), ("ft", 15), ("m", 2411)])
def test_pyuff_round_trip_keeps_nodes_frames_lines_and_units(tmp_path, unit, dataset):
    g = _geometry_with_frames()
    path = tmp_path / "g.unv"
    write_uff_geometry(path, g, unit=unit, dataset=dataset)
    back = read_geometry(path)
    assert back.unit == unit
    assert back.node_ids.tolist() == g.node_ids.tolist()
    assert back.disp_frame.tolist() == g.disp_frame.tolist()
    assert back.trace_lines == g.trace_lines
    # dataset 15 holds 6 significant digits (1P3E13.5), 2411 holds 17 (1P3D25.16)
    rtol = 1e-5 if dataset == 15 else 1e-14
    np.testing.assert_allclose(back.xyz, g.xyz, rtol=rtol, atol=rtol * 2)
    for a, b in zip(back.frames, g.frames, strict=True):
        assert (a.id, a.kind) == (b.id, b.kind)
        np.testing.assert_allclose(a.rotation, b.rotation, atol=1e-15)
        np.testing.assert_allclose(a.origin, b.origin, atol=1e-14)
    labels = ["11V", "12+1", "13-2", "14+3", "15L"]
    for a, b in zip(resolve_dofs(back, labels), resolve_dofs(g, labels), strict=True):
        np.testing.assert_allclose(a.direction, b.direction, atol=1e-4)


def test_spherical_frame_by_hand():
    """Frame axes (y, z, x) of global: local x' = +y, y' = +z, z' = +x; origin (0, -1, 0)."""
    frame = CoordinateFrame(9, "spherical", np.eye(3)[[1, 2, 0]], np.array([0.0, -1.0, 0.0]))
    # (r, theta, phi) = (2, 90, 0): local Cartesian (2, 0, 0) -> 2 x' = (0, 2, 0), + origin
    np.testing.assert_allclose(to_global(frame, [[2.0, 90.0, 0.0]]), [[0.0, 1.0, 0.0]],
                               atol=1e-12)  # fmt: skip
    np.testing.assert_allclose(to_local(frame, [[0.0, 1.0, 0.0]]), [[2.0, 90.0, 0.0]], atol=1e-12)
    # there e_theta = -z' = -x, e_phi = +y' = +z, e_r = +x' = +y (global)
    axes = displacement_axes(frame, [[0.0, 1.0, 0.0]])[0]
    np.testing.assert_allclose(axes, [[-1, 0, 0], [0, 0, 1], [0, 1, 0]], atol=1e-12)


def test_csv_with_frames_and_a_skewed_dof(tmp_path):
    path = tmp_path / "g.csv"
    path.write_text(
        "node,x,y,z,frame\n# lengths in mm\n1, 0, 0, 0\n2, 1000, 0, 0, 5\n"
        "frame, 5, rectangular, 0,0,1, 0,1,0, -1,0,0, 0,0,0\n"
        "dof, 2S, 2, 1, 1, 0\n"
    )
    g = read_csv_geometry(path, "mm")
    np.testing.assert_allclose(g.xyz, [[0, 0, 0], [1.0, 0, 0]])
    d = resolve_dofs(g, ["2S", "2+1", "1V"])
    # frame 5: x' = +z, y' = +y: the skewed vector (1, 1, 0) in it is (0, 1, 1) / sqrt 2
    np.testing.assert_allclose(d[0].direction, np.array([0, 1, 1]) / np.sqrt(2), atol=1e-15)
    np.testing.assert_allclose(d[1].direction, [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(d[2].direction, [0, 0, 1], atol=1e-15)
    out = tmp_path / "back.csv"
    write_csv_geometry(out, g, unit="in")
    back = read_csv_geometry(out, "in")
    np.testing.assert_allclose(back.xyz, g.xyz, rtol=1e-15, atol=1e-15)
    assert back.declared == (DeclaredDof("2S", 2, (1.0, 1.0, 0.0)),)
    assert [f.id for f in back.frames] == [5]


GROUPS_2467 = """\
    -1
  2467
         1         0         0         0         0         0         0         2
Left_Side
         8         1         0         0         8         2         0         0
    -1
"""


def test_a_geometry_file_with_groups_prints_nothing(tmp_path, capsys):
    """Modal test programs write groups (dataset 2467) beside the geometry; pyuff 2.5 prints
    each group it reads to stdout, which would precede ``correlate --json``'s JSON.  The
    reader keeps stdout clean and still reads the nodes (``bayesupdate.uff_read``)."""
    geometry = make_geometry([1, 2], [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    path = tmp_path / "with_groups.uff"
    write_uff_geometry(path, geometry)
    path.write_text(path.read_text() + GROUPS_2467)
    capsys.readouterr()
    back = read_geometry(path)
    assert capsys.readouterr().out == ""
    assert list(back.node_ids) == [1, 2]
    assert back.xyz == pytest.approx(geometry.xyz)
