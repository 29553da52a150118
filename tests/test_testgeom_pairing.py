"""Alignment and pairing (``bayesupdate.testgeom``): Umeyama's fit recovers a known similarity
transform, ICP recovers a known pose, the observation of a point on a beam, a triangle, a quad
or a shell edge reads every rigid-body motion exactly (u_p = v + w x p: linear shape functions
and the rigid arm reproduce rigid motions), a quad's bilinear weights are its natural
coordinates', and a study's ``[test]`` table pairs the built-in exhaust's own sensor points
back onto it, so its shapes there equal the built-in sensors' shapes."""

import numpy as np
from scipy.spatial.transform import Rotation

from bayesupdate.config import parse_study
from bayesupdate.models import get_model
from bayesupdate.pipelines.model_source import paired_study_model
from bayesupdate.testgeom import (
    CoordinateFrame,
    ModelMesh,
    PairingSettings,
    icp,
    make_geometry,
    pair_test,
    resolve_dofs,
    umeyama,
    write_csv_geometry,
)
from bayesupdate.testgeom.locate import bilinear_weights, locate


def test_umeyama_recovers_a_similarity_transform():
    rng = np.random.default_rng(1)
    src = rng.normal(size=(7, 3))
    R = Rotation.from_rotvec([0.4, -1.1, 0.7]).as_matrix()
    dst = 1.7 * src @ R.T + [3.0, -2.0, 0.5]
    R_fit, t, s = umeyama(src, dst, with_scale=True)
    np.testing.assert_allclose(R_fit, R, atol=1e-12)
    np.testing.assert_allclose(t, [3.0, -2.0, 0.5], atol=1e-12)
    assert abs(s - 1.7) < 1e-12


def test_icp_recovers_a_pose_on_an_asymmetric_cloud():
    """Test points = 15 of 300 model nodes scattered in an uneven box, spread over it as a
    test engineer spreads them (farthest-point sampling), moved by a known rigid transform:
    ICP from the principal-axes seeds brings them back exactly."""
    rng = np.random.default_rng(3)
    nodes = rng.uniform(0, 1, size=(300, 3)) * [3.0, 1.5, 0.5]
    nodes[:40, 2] += 0.8  # a lump on one side: no symmetry
    chosen = [0]
    for _ in range(14):
        gap = np.min(np.linalg.norm(nodes[:, None] - nodes[chosen][None], axis=2), axis=1)
        chosen.append(int(np.argmax(gap)))
    pick = nodes[chosen]
    R = Rotation.from_euler("zyx", [70, 20, -35], degrees=True).as_matrix()
    test = (pick - [0.5, 0.2, 0.1]) @ R  # test = R^T (model - t)
    found = icp(test, nodes)
    assert found.rms < 1e-9
    np.testing.assert_allclose(found.rotation, R, atol=1e-9)
    np.testing.assert_allclose(found.matrix[:3, 3], [0.5, 0.2, 0.1], atol=1e-9)


def _mesh():
    """A beam, a warped-free quad and a triangle: model unit metres."""
    nodes = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [3, 0.5, 0.2]],
                     float)  # fmt: skip
    return ModelMesh(nodes, np.arange(10, 16), np.array([[0, 1]]), np.array([[1, 2, 3, 4]]),
                     np.array([[2, 5, 3]]), "m", 1.0)  # fmt: skip


def test_observation_reads_rigid_motions_exactly():
    mesh = _mesh()
    # a point off the beam (arm 0.1 z), one on the quad, one over the triangle, one near an edge
    points = np.array([[0.25, 0.0, 0.1], [1.3, 0.6, 0.02], [2.5, 0.5, 0.15], [1.5, 1.02, 0.0]])
    geometry = make_geometry([1, 2, 3, 4], points)
    labels = [f"{n}{d}" for n in range(1, 5) for d in ("L", "H", "V")] + ["2+3"]
    dofs = resolve_dofs(geometry, labels)
    pairing = pair_test(geometry, dofs, mesh, PairingSettings(align="none", tolerance=0.2))
    kinds = [p.element.split()[0] for p in pairing.points]
    assert kinds == ["line", "quad", "tria", "shell"]  # "shell edge 14-13"
    rng = np.random.default_rng(0)
    for _ in range(3):
        v, w = rng.normal(size=3), rng.normal(size=3)
        u = np.zeros((len(mesh.nodes), 6))
        u[:, :3], u[:, 3:] = v + np.cross(w, mesh.nodes), w
        read = pairing.observation @ u.ravel()
        row = {n: i for i, n in enumerate([1, 2, 3, 4])}
        expected = [d.direction @ (v + np.cross(w, points[row[d.node]])) for d in dofs]
        np.testing.assert_allclose(read, expected, atol=1e-12)


def test_bilinear_weights_of_a_parallelogram():
    corners = np.array([[0, 0, 0], [2, 0, 0], [2.5, 1, 0], [0.5, 1, 0]], float)
    xi, eta = 0.3, -0.6
    N = 0.25 * np.array([(1 - xi) * (1 - eta), (1 + xi) * (1 - eta), (1 + xi) * (1 + eta),
                         (1 - xi) * (1 + eta)])  # fmt: skip
    np.testing.assert_allclose(bilinear_weights(corners, N @ corners), N, atol=1e-13)
    found = locate([N @ corners + [0, 0, 0.05]], ModelMesh(corners, np.arange(4),
                   np.zeros((0, 2), int), np.array([[0, 1, 2, 3]]), np.zeros((0, 3), int),
                   "m", 1.0))[0]  # fmt: skip
    assert found.kind == "quad" and abs(found.distance - 0.05) < 1e-13
    np.testing.assert_allclose(found.weights, N, atol=1e-12)


def test_study_test_table_pairs_the_built_in_exhaust_with_its_own_sensors(tmp_path):
    """The exhaust's 20 sensor points as a CSV geometry in mm, turned and shifted; named pairs
    align it back; the paired model's shapes at 7V, 7H ... equal the built-in sensors'."""
    base = get_model("exhaust")
    s = base.structure
    labels = s.sensor_labels
    points = {int(label[:-1]): s.nodes[n] for label, n in zip(labels, s.sensor_node,
                                                               strict=True)}  # fmt: skip
    ids = sorted(points)
    R = Rotation.from_euler("xyz", [10, -30, 80], degrees=True).as_matrix()
    test = (np.array([points[i] for i in ids]) - [0.2, -0.1, 0.3]) @ R
    csv = tmp_path / "exhaust_test.csv"
    # each node's displacement frame 1 has the model's axes (rows of R in the test frame), so
    # "7V" is the model's vertical as the built-in sensor's
    frame = CoordinateFrame(1, "rectangular", R, np.zeros(3))
    geometry = make_geometry(ids, test, np.ones(len(ids), int), (frame,), source="t")
    write_csv_geometry(csv, geometry, unit="mm")
    node_of = {i: int(s.sensor_node[labels.index(f"{i}V")]) for i in ids}
    pairs = ", ".join(f"[{i}, {node_of[i]}]" for i in (1, 8, 14, 20))
    study = parse_study({"model": {"source": "exhaust"},
                         "test": {"geometry": str(csv), "length_unit": "mm", "pairs": eval(
                             f"[{pairs}]"), "pair_tolerance": "1 mm"}})  # fmt: skip
    model, pairing = paired_study_model(study, labels)
    assert [p.model_node for p in pairing.points] == [node_of[i] for i in ids]
    # sensor 6 sits on a joint: nodes 12 and 14 coincide (reported, the lower one taken)
    assert pairing.points[5].coincident == (14,)
    assert pairing.transform.rms < 1e-9 and pairing.shared == ()
    np.testing.assert_allclose(pairing.transform.rotation, R, atol=1e-9)
    want, got = base.predict(), model.predict()
    np.testing.assert_allclose(got.frequencies_hz, want.frequencies_hz, rtol=1e-12)
    np.testing.assert_allclose(got.shapes, want.shapes, atol=1e-9 * np.abs(want.shapes).max())


def test_a_study_with_a_test_table_prepares_without_a_test_point_table(tmp_path):
    """The study path calibrate, sample and discover take (``pipelines.study.prepare``): data
    with shapes at 1V ... 20H, a [test] geometry in a turned frame (mm, pairs named), no
    [model.test_points]; at the model's defaults the problem's paired MACs are 1."""
    from bayesupdate.ema import write_modal_h5
    from bayesupdate.modal_data import ModalData
    from bayesupdate.pipelines.study import prepare

    base = get_model("exhaust")
    s = base.structure
    truth = base.predict(n_modes=6)
    data = ModalData(truth.frequencies_hz, shapes=truth.shapes, dof_labels=truth.dof_labels,
                     source="virtual")  # fmt: skip
    write_modal_h5(tmp_path / "modes.h5", data)
    R = Rotation.from_euler("xyz", [0, 0, 90], degrees=True).as_matrix()
    frame = CoordinateFrame(1, "rectangular", R, np.zeros(3))
    points = s.nodes[s.sensor_node[::2]]
    geometry = make_geometry(range(1, 21), points @ R, np.ones(20, int), (frame,))
    write_csv_geometry(tmp_path / "test.csv", geometry, unit="mm")
    node = [int(n) for n in s.sensor_node[::2]]
    study = parse_study({
        "model": {"source": "exhaust"},
        "data": {"source": str(tmp_path / "modes.h5")},
        "test": {"geometry": str(tmp_path / "test.csv"), "length_unit": "mm",
                 "pairs": [[1, node[0]], [10, node[9]], [20, node[19]]]},
    })  # fmt: skip
    problem = prepare(study).problem
    assert problem.model.structure.sensor_read is not None
    evaluation = problem.evaluate(problem.start)
    np.testing.assert_allclose(evaluation.frequencies_hz, truth.frequencies_hz, rtol=1e-10)
    np.testing.assert_allclose(evaluation.paired.mac, 1.0, atol=1e-10)
    # the result file of a run on it records the pairing (calibrate, sample: inference.results)
    import json

    import h5py

    from bayesupdate.inference.optimize import CalibrationSettings, calibrate
    from bayesupdate.inference.results import write_result

    optimum = calibrate(problem, CalibrationSettings(starts=1, seed=0, max_nfev=5))
    out = write_result(tmp_path / "run.h5", problem, optimum, study.to_dict(), command="test")
    with h5py.File(out) as h5:
        record = json.loads(h5["inputs"].attrs["test_pairing_json"])
    assert [p["nearest_node"] for p in record["points"]] == node
    np.testing.assert_allclose(np.asarray(record["transform"]["matrix"])[:3, :3], R, atol=1e-9)
    assert max(p["distance"] for p in record["points"]) < 1e-9


def test_pairing_record_to_dict():
    mesh = _mesh()
    g = make_geometry([1], [[0.5, 0.0, 0.0]])
    pairing = pair_test(g, resolve_dofs(g, ["1V"]), mesh, PairingSettings(align="none"))
    record = pairing.to_dict()
    assert record["transform"]["matrix"] == np.eye(4).tolist()
    point = record["points"][0]
    assert point["model_node"] is None and point["element"] == "line 0"
    assert point["nearest_node"] in (10, 11) and point["model_xyz"] == [0.5, 0.0, 0.0]
    assert record["dofs"] == [{"label": "1V", "direction": [0.0, 0.0, 1.0]}]


def test_two_test_points_on_one_model_node_are_reported():
    mesh = _mesh()
    g = make_geometry([1, 2, 3], [[1.0, 0.0, 0.001], [1.0, 0.0, -0.001], [2.0, 1.0, 0.0]])
    dofs = resolve_dofs(g, ["1V", "2V", "3V"])
    pairing = pair_test(g, dofs, mesh, PairingSettings(align="none", on_elements=False))
    assert pairing.shared == ((1, 2),)
    assert [p.model_node for p in pairing.points] == [11, 11, 13]


def test_the_pairing_record_is_found_on_a_model_and_on_a_reduced_model_of_it():
    """``inference.results.test_pairing_record``: what calibrate, sample and discover write
    (``inputs`` attrs ``test_pairing_json``), from the model's structure or, for a reduced
    model, its FE model's; None for a model without one."""
    from types import SimpleNamespace

    from bayesupdate.inference.results import test_pairing_record
    from bayesupdate.testgeom import with_pairing

    mesh = _mesh()
    g = make_geometry([1], [[0.5, 0.0, 0.0]])
    pairing = pair_test(g, resolve_dofs(g, ["1V"]), mesh, PairingSettings(align="none"))
    base = get_model("exhaust")
    assert test_pairing_record(base) is None
    paired = SimpleNamespace(structure=with_pairing(base.structure, pairing))
    record = test_pairing_record(paired)
    assert record == pairing.to_dict() and record["points"][0]["test_node"] == 1
    assert test_pairing_record(SimpleNamespace(fe=paired)) == record
