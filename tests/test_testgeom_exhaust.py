"""A virtual test of the FEMAP exhaust (``shared/data/nastran/femap_exhaust``, inch deck, 4,466
shells): its 20 test points (the three hanger GRIDs and 17 shell GRIDs of the worked example,
``test_nastran_femap_roundtrip.GRIDS``) written as UFF 15 in mm in a turned and shifted test
frame, each point moved 2 mm in a random direction (seeded).  Alignment by ICP alone (no pairs)
recovers the transform, every point pairs with the GRID it came from, and the observation reads
rigid-body motions of the deck at the aligned points exactly.  The deck is read once."""

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from bayesupdate.testgeom import (
    PairingSettings,
    make_geometry,
    pair_structure,
    read_geometry,
    write_uff_geometry,
)

DECK = Path(__file__).resolve().parents[2] / "shared/data/nastran/femap_exhaust/exhaust.bdf"
GRIDS = (15661, 17406, 20494, 20505, 20718, 16509, 20652, 17368, 21321, 21706, 22177, 16225,
         15676, 15546, 15414, 15611, 15492, 16745, 15944, 17232)  # fmt: skip
INCH = 0.0254
#: the test frame: model = R test + T (metres)
R = Rotation.from_euler("zyx", [30.0, -20.0, 50.0], degrees=True).as_matrix()
T = np.array([1.0, -2.0, 0.5])


@pytest.fixture(scope="module")
def deck():
    if not DECK.exists():
        pytest.skip(f"shared data not found: {DECK}")
    from bayesupdate.nastran import load_nastran_model

    try:
        return load_nastran_model(str(DECK))
    except ImportError as exc:
        pytest.skip(f"the Nastran reader needs {exc.name}")


@pytest.fixture(scope="module")
def virtual_test(deck, tmp_path_factory):
    """(paired, true model points [in], UFF path): the UFF 15 test in mm, paired by ICP."""
    deck = deck.structure
    ids = np.asarray(deck.metadata["nastran"]["grid_ids"])
    rows = [int(np.flatnonzero(ids == g)[0]) for g in GRIDS]
    model_m = deck.nodes[rows] * INCH
    rng = np.random.default_rng(0)
    scatter = rng.normal(size=(20, 3))
    scatter *= 0.002 / np.linalg.norm(scatter, axis=1)[:, None]
    test = (model_m - T) @ R + scatter  # test = R^T (model - T) + 2 mm
    path = tmp_path_factory.mktemp("exhaust") / "test.unv"
    write_uff_geometry(path, make_geometry(range(1, 21), test, source="virtual"), unit="mm")
    labels = [f"{k}{d}" for k in range(1, 21) for d in "VH"]
    settings = PairingSettings(align="auto", tolerance=0.005)
    return pair_structure(deck, read_geometry(path), labels, settings), deck.nodes[rows], path


def test_icp_recovers_the_test_frame(virtual_test):
    pairing, truth, _ = virtual_test
    t = pairing.transform
    assert t.method == "icp" and abs(t.scale - 1.0) < 1e-12
    angle = np.degrees(np.arccos(np.clip((np.trace(t.rotation.T @ R) - 1) / 2, -1, 1)))
    # the rotation to 0.3 deg (measured 0.144), over a 2 m part with 2 mm scatter
    assert angle < 0.3, angle
    # translation: where the true transform puts the test points' centroid, in mm
    centroid_test = ((truth * INCH - T) @ R).mean(axis=0)
    moved = t.apply(centroid_test / INCH)[0] * INCH
    error_mm = np.linalg.norm(moved - (R @ centroid_test + T)) * 1e3
    assert error_mm < 3.0, error_mm  # measured 1.55 mm: the scatter's mean over 20 points
    # residual per point: the scatter's part normal to the shell, under 2 mm each
    assert t.residuals.shape == (20,) and t.residuals.max() * INCH < 0.002
    assert 0.0005 < t.rms * INCH < 0.002


def test_every_point_pairs_with_the_grid_it_came_from(virtual_test):
    pairing, truth, _ = virtual_test
    assert [p.model_node for p in pairing.points] == list(GRIDS)
    assert pairing.shared == ()
    # each lies within its 2 mm of the model, on a shell (the hangers' GRIDs are shell nodes,
    # each with a grounded spring end at the same place: reported as coincident)
    assert all(p.distance * INCH <= 0.002 for p in pairing.points)
    assert [p.coincident for p in pairing.points[:3]] == [(50000,), (50001,), (50002,)]
    # the paired point is its GRID moved by the scatter along the shell and the alignment error
    for p, x in zip(pairing.points, truth, strict=True):
        assert np.linalg.norm(p.model_xyz - x) * INCH < 0.005


def test_observation_reads_rigid_motions_at_the_aligned_points(virtual_test, deck):
    pairing, _, path = virtual_test
    deck = deck.structure
    H = pairing.observation
    assert H.shape == (40, 6 * deck.n_nodes)
    aligned = pairing.transform.apply(read_geometry(path).xyz / INCH)
    rng = np.random.default_rng(2)
    v, w = rng.normal(size=3), rng.normal(size=3) / 50.0
    u = np.zeros((deck.n_nodes, 6))
    u[:, :3], u[:, 3:] = v + np.cross(w, deck.nodes), w
    point = np.repeat(aligned, 2, axis=0)  # labels kV, kH per point
    expected = np.einsum("ij,ij->i", pairing.directions, v + np.cross(w, point))
    np.testing.assert_allclose(H @ u.ravel(), expected, atol=1e-9)


def test_noise_free_shapes_at_the_paired_points_match_the_grids(virtual_test, deck):
    """What ``correlate`` checks (MAC diagonal >= 0.999): the first 10 modes read by the
    observation at the paired points against the same modes at the GRIDs the points came
    from, along the same directions."""
    pairing, _, _ = virtual_test
    shapes = deck.solve(n_modes=10, method="sparse").modes.shapes
    ids = np.asarray(deck.structure.metadata["nastran"]["grid_ids"])
    rows = np.repeat([int(np.flatnonzero(ids == g)[0]) for g in GRIDS], 2)
    at_grids = np.einsum("sk,skm->sm", pairing.directions,
                         shapes[6 * rows[:, None] + np.arange(3)])  # fmt: skip
    paired = pairing.observation @ shapes
    mac = (np.sum(at_grids * paired, axis=0) ** 2
           / (np.sum(at_grids**2, axis=0) * np.sum(paired**2, axis=0)))  # fmt: skip
    assert mac.min() >= 0.999, mac


@pytest.mark.slow
def test_the_correlate_command_pairs_the_turned_test_and_its_noise_free_modes(
    virtual_test, deck, tmp_path, capsys
):
    """The user's path: ``bayesupdate correlate --model exhaust.bdf --data modes.h5 --geometry
    test.unv --length-unit mm`` on the noise-free virtual test (the deck's first 10 modes read
    at the GRIDs the points came from, along the test's directions): the command finds the
    turned frame (ICP), pairs all 20 points with their GRIDs, and the MAC diagonal is >= 0.999
    (the 2 mm scatter moves each point along the shell)."""
    import json

    from bayesupdate.cli import main
    from bayesupdate.ema.modal_h5 import write_modal_h5
    from bayesupdate.modal_data import ModalData

    pairing, _, path = virtual_test
    solved = deck.solve(n_modes=10, method="sparse")
    shapes = solved.modes.shapes
    ids = np.asarray(deck.structure.metadata["nastran"]["grid_ids"])
    rows = np.repeat([int(np.flatnonzero(ids == g)[0]) for g in GRIDS], 2)
    at_grids = np.einsum("sk,skm->sm", pairing.directions,
                         shapes[6 * rows[:, None] + np.arange(3)])  # fmt: skip
    data = ModalData(solved.frequencies_hz, shapes=at_grids, dof_labels=pairing.dof_labels,
                     source="virtual")  # fmt: skip
    write_modal_h5(tmp_path / "modes.h5", data)
    assert main(["correlate", "--model", str(DECK), "--data", str(tmp_path / "modes.h5"),
                 "--geometry", str(path), "--length-unit", "mm", "--pair-tolerance", "5 mm",
                 "--json", "--quiet"]) == 0  # fmt: skip
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    rotation = np.asarray(out["transform"]["matrix"])[:3, :3]
    angle = np.degrees(np.arccos(np.clip((np.trace(rotation.T @ R) - 1) / 2, -1, 1)))
    assert angle < 0.3, angle  # as the library's pairing above (measured 0.144 deg)
    by_node = {int(p["test_node"]): p["model_node"] for p in out["points"]}
    assert [by_node[k] for k in range(1, 21)] == list(GRIDS)
    assert [(m["test"], m["model"]) for m in out["modes"]] == [(i, i) for i in range(1, 11)]
    assert min(m["mac"] for m in out["modes"]) >= 0.999
