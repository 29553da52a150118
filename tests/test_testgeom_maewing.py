"""The mAEWing1 GVT's accelerometers (``shared/data/gvt_maewing1``, real test metadata) paired
with the aircraft's Nastran models.

``studies/maewing1_test_geometry.gvt_geometry`` turns ``GVT_Info.m`` (test frame: origin at the
nose, X left, Y aft, Z up, inches; the shaker in cm) into a test geometry, written as UFF 15 in
inches as a user would have it.  The FE frame (README): x aft, y right, z up, origin 15.55 in aft
of the nose, so x = Y - 15.55, y = -X, z = Z: the 3x4 matrix ``TO_FE``.

- v4.2's GRIDs 1-20 (``gvt_accelerations.dat``, parsed here: the deck itself does not read with
  the package's reader yet) are the authors' accelerometer points, mirrored: through ``TO_FE``
  accelerometer k sits exactly on GRID k + 10 (k <= 10) or k - 10.
- ICP alone cannot tell the two sides apart (the layout is symmetric and flat: a half turn about
  the FE x axis maps it onto itself) and says so; three named pairs give ``TO_FE`` back.
- v3.3's beams (points on elements, not nodes): ``test_v33_beams`` runs once
  ``load_nastran_model`` reads that deck (it stops at PARAM PRTMAXIM today).
"""

import sys
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.testgeom import (
    ModelMesh,
    PairingSettings,
    pair_structure,
    pair_test,
    read_geometry,
    resolve_dofs,
    write_uff_geometry,
)

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
from maewing1_test_geometry import GVT_INFO, gvt_geometry  # noqa: E402

FEM = GVT_INFO.parents[1] / "fem"
needs_data = pytest.mark.skipif(not GVT_INFO.exists(), reason=f"shared data not found: {GVT_INFO}")
#: test (nose, X left, Y aft; in) to FE (x aft, y right; origin 15.55 in aft of the nose)
TO_FE = ((0.0, 1.0, 0.0, -15.55), (-1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0))
LABELS = [f"{k}V" for k in range(1, 21)]


def _grids(path) -> ModelMesh:
    """GRIDs of a small-field bulk data file (id cols 9-16, x y z cols 25-48), inches."""
    ids, xyz = [], []
    for line in Path(path).read_text().splitlines():
        if line.startswith("GRID "):
            ids.append(int(line[8:16]))
            xyz.append([float(line[24 + 8 * k : 32 + 8 * k]) for k in range(3)])
    none2, none4, none3 = (np.zeros((0, k), int) for k in (2, 4, 3))
    return ModelMesh(np.array(xyz), np.array(ids), none2, none4, none3, "in", 0.0254)


@pytest.fixture(scope="module")
def test_file(tmp_path_factory):
    if not GVT_INFO.exists():
        pytest.skip(f"shared data not found: {GVT_INFO}")
    path = tmp_path_factory.mktemp("gvt") / "maewing1_test.unv"
    write_uff_geometry(path, gvt_geometry(), unit="in")
    return read_geometry(path)


@needs_data
def test_gvt_info_as_a_test_geometry(test_file):
    g = test_file
    assert g.unit == "in" and g.node_ids.tolist() == [*range(1, 21), 25]
    # accelerometer 1 at (X, Y) = (-17.87, 19.03) in; the shaker 60.96 cm = 24 in aft and
    # 11.43 cm = 4.5 in to the right (explog.txt: "25 inches back, 4.5 inches to the right")
    np.testing.assert_allclose(g.xyz[0] / 0.0254, [-17.87, 19.03, 0.0], atol=1e-4)
    np.testing.assert_allclose(g.xyz[-1] / 0.0254, [-4.5, 24.0, 0.0], atol=1e-4)
    assert g.trace_lines == ((19, 17, 15, 13, 11, 1, 3, 5, 7, 9),
                             (20, 18, 16, 14, 12, 2, 4, 6, 8, 10))  # fmt: skip


@needs_data
def test_accelerometers_pair_with_the_v42_grids_mirrored(test_file):
    mesh = _grids(FEM / "v4.2_updated/gvt_accelerations.dat")
    dofs = resolve_dofs(test_file, LABELS)
    settings = PairingSettings(align=TO_FE, tolerance=0.0005, on_elements=False)
    pairing = pair_test(test_file, dofs, mesh, settings)
    mirrored = [k + 10 if k <= 10 else k - 10 for k in range(1, 21)]
    assert [p.model_node for p in pairing.points] == mirrored
    # the GRIDs hold the test's positions to their printed digits (0.01 in)
    assert max(p.distance for p in pairing.points) < 0.006
    # the test's vertical is the FE model's
    np.testing.assert_allclose(pairing.directions, np.tile([0.0, 0.0, 1.0], (20, 1)), atol=0)


@needs_data
def test_icp_sees_the_symmetry_and_named_pairs_resolve_it(test_file):
    mesh = _grids(FEM / "v4.2_updated/gvt_accelerations.dat")
    dofs = resolve_dofs(test_file, LABELS)
    with pytest.raises(BayesUpdateError, match="ambiguous"):
        pair_test(test_file, dofs, mesh, PairingSettings(on_elements=False))
    pairs = ((1, 11), (9, 19), (20, 10))
    settings = PairingSettings(pairs=pairs, tolerance=0.0005, on_elements=False)
    t = pair_test(test_file, dofs, mesh, settings).transform
    np.testing.assert_allclose(t.matrix[:3], np.array(TO_FE), atol=0.01)
    assert t.rms < 0.006  # inches: the printed digits


def test_v33_beams():
    """Points on elements: each accelerometer on the v3.3 wing's beams, 3-4 in off the spar
    (leading and trailing edge), read through the beam's rotations (the rigid arm); the deck
    as published, read by the package's own reader."""
    deck = FEM / "v3.3_hati/sol103_mAEWing1_Hati_FEMv3p3.bdf"
    if not deck.exists():
        pytest.skip(f"shared data not found: {deck}")
    from bayesupdate.nastran import load_nastran_model

    structure = load_nastran_model(str(deck)).structure
    g = gvt_geometry()
    settings = PairingSettings(align=TO_FE, tolerance=4 * 0.0254)
    # its MAT1 moduli (2.01e9, 6.66e6, 6.66e10) match no unit system: inches, as the README says
    pairing = pair_structure(structure, g, LABELS, settings, model_length_unit="in")
    assert all(p.element is not None and p.element.startswith("line") for p in pairing.points)
    # 3.47 in (leading edge) and 1.53 in (trailing edge) off the spar
    # (docs/guide/test-geometry.md)
    assert all(0.5 < p.distance < 4.0 for p in pairing.points)
    rotations = pairing.sensor_weights[:, [3, 4, 9, 10]]  # rx, ry of the element's two nodes
    assert (np.abs(rotations).sum(axis=1) > 0.5).all()  # the arm: torsion and bending seen
