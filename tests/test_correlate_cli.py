"""``bayesupdate correlate`` on the beam exhaust: against the seed's Table 2 (frequencies only,
paired in order) and against a virtual test of the unchanged model (``pipelines.simulate``: its
true, mass-normalized shapes at the 40 sensor DOFs), whose MAC diagonal is 1, whose pairs are
the identity and whose cross-orthogonality through the SEREP TAM is the identity; a test with
two shapes exchanged is paired back and the swap named; bad input is one line, exit 2, no file.
"""

import json

import h5py
import numpy as np
import pytest

from bayesupdate.cli import main
from bayesupdate.ema.modal_h5 import write_modal_h5
from bayesupdate.modal_data import ModalData
from bayesupdate.models import get_model
from bayesupdate.models.exhaust_paper import TABLE2_EMA_HZ


def _json(capsys, argv) -> dict:
    code = main(argv)
    captured = capsys.readouterr()
    assert code == 0, captured.err
    return json.loads(captured.out.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def virtual(tmp_path_factory):
    """The exhaust's virtual test (noise-free truth of ``simulate``) as modal data, and the
    model's frequencies [Hz] solved independently."""
    from bayesupdate.pipelines.simulate import VirtualTestSettings, simulate_test

    truth = simulate_test(get_model("exhaust"), VirtualTestSettings(noise=0.0, seed=0, n_modes=12))
    folder = tmp_path_factory.mktemp("virtual")
    data = ModalData(truth.frequencies_hz, shapes=truth.shapes, dof_labels=truth.dof_labels,
                     source="virtual", extra={"mass_normalized": np.ones(12, bool)})  # fmt: skip
    write_modal_h5(folder / "virtual.h5", data)
    return folder, data


def test_correlate_against_the_seed_table2_pairs_in_order_with_the_percent_differences(capsys):
    out = _json(capsys, ["correlate", "--model", "exhaust", "--data", "paper:ema", "--json"])
    # 12 test modes and [pairing] extra_modes (2), as calibrate solves
    model_hz = get_model("exhaust").solve(None, 14).frequencies_hz
    assert out["pairing"] == "order" and out["mac"] is None and out["comac"] is None
    assert [(m["test"], m["model"]) for m in out["modes"]] == [(i, i) for i in range(1, 13)]
    np.testing.assert_allclose([m["test_hz"] for m in out["modes"]], TABLE2_EMA_HZ)
    np.testing.assert_allclose([m["model_hz"] for m in out["modes"]], model_hz[:12], rtol=1e-9)
    # the first mode: 8.960 Hz against the seed's 9.19 Hz, -2.50 %
    assert out["modes"][0]["error_pct"] == pytest.approx(100 * (model_hz[0] / 9.19 - 1))
    assert out["modes"][0]["error_pct"] == pytest.approx(-2.50, abs=0.01)
    assert out["unpaired_model"] == [13, 14] and out["rules"] is None
    assert out["transform"]["matrix"] == np.eye(4).tolist() and out["points"] == []


def test_correlate_against_a_virtual_test_of_the_unchanged_model(virtual, tmp_path, capsys):
    folder, data = virtual
    h5, report = tmp_path / "corr.h5", tmp_path / "report"
    out = _json(capsys, ["correlate", "--model", "exhaust", "--data", str(folder / "virtual.h5"),
                         "--out", str(h5), "--report", str(report), "--json"])  # fmt: skip
    assert [(m["test"], m["model"]) for m in out["modes"]] == [(i, i) for i in range(1, 13)]
    assert min(m["mac"] for m in out["modes"]) >= 0.999
    mac = np.asarray(out["mac"])
    assert mac.shape == (12, 14)
    np.testing.assert_allclose(np.diag(mac), 1.0, atol=1e-9)
    np.testing.assert_allclose(out["cross_orthogonality"], np.eye(12), atol=1e-5)
    np.testing.assert_allclose(out["pseudo_orthogonality"], np.eye(12), atol=1e-5)
    np.testing.assert_allclose([c["comac"] for c in out["comac"]], 1.0, atol=1e-9)
    assert out["swapped"] == [] and out["unpaired_test"] == [] and out["refused"] == []
    # per test DOF its model node and direction (the built-in sensors): 7V reads +z
    point = next(p for p in out["points"] if p["dof"] == "7V")
    assert point["test_node"] == "7" and point["direction"] == [0.0, 0.0, 1.0]
    assert point["distance"] is None
    with h5py.File(h5, "r") as fh:
        g = fh["correlation"]
        np.testing.assert_allclose(g["mac"][()], mac, atol=1e-6)
        # SEREP expands the test shapes to every DOF: the model's own mode shapes
        full = get_model("exhaust").solve(None, 14).modes.shapes[:, :12]  # as correlate solves
        expanded = g["expanded"][()]
        scale = np.sign(np.sum(expanded * full, axis=0))
        np.testing.assert_allclose(expanded * scale, full, atol=1e-6 * np.abs(full).max())
    assert (report / "report.html").stat().st_size > 10_000
    assert (report / "figures" / "mac.png").exists()
    # the test points on the model: 20 sensor points over the exhaust's nodes
    assert (report / "figures" / "points.png").stat().st_size > 10_000
    assert "figures/points.png" in (report / "report.md").read_text()


def test_two_exchanged_test_shapes_are_paired_back_and_named_as_a_swap(virtual, tmp_path, capsys):
    _, data = virtual
    shapes = data.shapes.copy()
    shapes[:, [2, 3]] = shapes[:, [3, 2]]  # test modes 3 and 4 carry each other's shapes
    swapped = ModalData(data.frequencies_hz, shapes=shapes, dof_labels=data.dof_labels)
    write_modal_h5(tmp_path / "swapped.h5", swapped)
    out = _json(capsys, ["correlate", "--model", "exhaust", "--data",
                         str(tmp_path / "swapped.h5"), "--json"])  # fmt: skip
    assert [(m["test"], m["model"]) for m in out["modes"]][2:4] == [(3, 4), (4, 3)]
    assert out["swapped"] == [{"test": 3, "model": 4}, {"test": 4, "model": 3}]
    assert out["cross_orthogonality"] is None  # not mass-normalized: said so in the notes
    assert any("mass-normalized" in n for n in out["notes"])
    main(["correlate", "--model", "exhaust", "--data", str(tmp_path / "swapped.h5")])
    text = capsys.readouterr().out
    assert "swapped" in text and "test 3 - model 4" in text


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--mac-threshold", "1.5"], "--mac-threshold"),
        (["--extra-modes", "-1"], "--extra-modes"),
        (["--data", "missing.h5"], "not found"),
    ],
)
def test_bad_input_is_one_line_exit_2_and_no_file(tmp_path, capsys, extra, needle):
    out, report = tmp_path / "c.h5", tmp_path / "report"
    argv = ["correlate", "--model", "exhaust", "--data", "paper:ema", "--out", str(out),
            "--report", str(report), *extra]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err
    assert not out.exists() and not report.exists()


def test_a_test_dof_the_model_lacks_is_named(tmp_path, capsys):
    data = ModalData([9.0], shapes=np.ones((2, 1)), dof_labels=("1V", "99V"))
    write_modal_h5(tmp_path / "bad.h5", data)
    out = tmp_path / "c.h5"
    argv = [
        "correlate",
        "--model",
        "exhaust",
        "--data",
        str(tmp_path / "bad.h5"),
        "--out",
        str(out),
    ]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "99V" in err and not out.exists()
    assert main(["correlate"]) == 2
    assert "give a STUDY.toml or --model" in capsys.readouterr().err


@pytest.mark.slow
def test_the_user_path_simulate_identify_correlate(tmp_path, capsys):
    """The commands a user types: ``simulate --noise 0`` of the unchanged exhaust, ``identify``,
    ``correlate``.  Each pair's 1 - MAC lies within 3 times identify's own E[1 - MAC] ~
    shape_sd_rel^2 (modes 3 and 4 at MAC 0.992 and 0.994: their shape sd is 0.08)."""
    uff, modes = tmp_path / "v.uff", tmp_path / "v.h5"
    assert main(["simulate", "--model", "exhaust", "--noise", "0", "--out", str(uff)]) == 0
    assert main(["identify", str(uff), "--out", str(modes)]) == 0
    capsys.readouterr()
    out = _json(capsys, ["correlate", "--model", "exhaust", "--data", str(modes), "--json"])
    from bayesupdate.ema.modal_h5 import read_modal_h5

    sd = read_modal_h5(modes).shape_sd_rel
    assert [(m["test"], m["model"]) for m in out["modes"]] == [(i, i) for i in range(1, 13)]
    one_minus = 1 - np.array([m["mac"] for m in out["modes"]])
    assert np.all(one_minus <= 3 * sd**2 + 1e-4), (one_minus, sd)
    assert max(abs(m["error_pct"]) for m in out["modes"]) < 0.01
    xor = np.abs(np.diag(out["cross_orthogonality"]))
    assert np.all(np.abs(xor - 1) < 0.05), xor


def test_correlate_with_a_test_geometry_in_another_frame(virtual, tmp_path, capsys):
    """The study's ``[test]`` table on the user's path: the exhaust's 20 sensor points as a CSV
    in mm, turned and shifted, aligned by four named pairs; ``correlate --json`` gives the
    transform back, each test point on the model node its DOFs came from at distance ~0, and
    the noise-free virtual test's MAC diagonal at 1."""
    from scipy.spatial.transform import Rotation

    from bayesupdate.testgeom import make_geometry, write_csv_geometry
    from bayesupdate.testgeom.frames import CoordinateFrame

    folder, data = virtual
    s = get_model("exhaust").structure
    labels = s.sensor_labels
    points = {int(k[:-1]): s.nodes[n] for k, n in zip(labels, s.sensor_node, strict=True)}
    ids = sorted(points)
    R = Rotation.from_euler("xyz", [25, 40, -70], degrees=True).as_matrix()
    shift = np.array([0.5, -0.2, 1.1])
    test = (np.array([points[i] for i in ids]) - shift) @ R  # model = test @ R.T + shift
    frame = CoordinateFrame(1, "rectangular", R, np.zeros(3))  # model axes as node frames
    csv = tmp_path / "geometry.csv"
    write_csv_geometry(csv, make_geometry(ids, test, np.ones(len(ids), int), (frame,), source="t"),
                       unit="mm")  # fmt: skip
    node_of = {i: int(s.sensor_node[labels.index(f"{i}V")]) for i in ids}
    pairs = ", ".join(f"[{i}, {node_of[i]}]" for i in (1, 8, 14, 20))
    study = tmp_path / "study.toml"
    study.write_text(
        f'[model]\nsource = "exhaust"\n[data]\nsource = "{folder / "virtual.h5"}"\n'
        f'[test]\ngeometry = "{csv}"\nlength_unit = "mm"\npairs = [{pairs}]\n'
        'pair_tolerance = "1 mm"\n'
    )
    out = _json(capsys, ["correlate", str(study), "--json"])
    T = np.asarray(out["transform"]["matrix"])
    np.testing.assert_allclose(T[:3, :3], R, atol=1e-6)
    np.testing.assert_allclose(T[:3, 3], shift, atol=1e-6)
    assert out["transform"]["rms_residual"] < 1e-6
    assert out["transform"]["source"].startswith("[test] geometry (pairs")
    by_dof = {p["dof"]: p for p in out["points"]}
    assert set(by_dof) == set(data.dof_labels)
    for label, p in by_dof.items():
        assert p["model_node"] == node_of[int(label[:-1])] or p["test_node"] == "6"
        assert p["distance"] < 1e-6
    np.testing.assert_allclose(by_dof["7V"]["direction"], [0.0, 0.0, 1.0], atol=1e-9)
    assert [(m["test"], m["model"]) for m in out["modes"]] == [(i, i) for i in range(1, 13)]
    assert min(m["mac"] for m in out["modes"]) >= 0.999


def test_correlate_geometry_flags_write_the_pairing_to_the_file_and_the_report(
    virtual, tmp_path, capsys
):
    """``--geometry FILE --length-unit mm`` (no study file): the exhaust's sensor points as a
    CSV in the model's frame (millimetres), aligned automatically (ICP: the identity back) and
    paired; the HDF5 file holds each point's distance and the fit's residual, the report's
    point table names the geometry and the transform."""
    from bayesupdate.testgeom import make_geometry, write_csv_geometry
    from bayesupdate.testgeom.frames import CoordinateFrame

    folder, data = virtual
    s = get_model("exhaust").structure
    labels = s.sensor_labels
    points = {int(k[:-1]): s.nodes[n] for k, n in zip(labels, s.sensor_node, strict=True)}
    ids = sorted(points)
    csv = tmp_path / "geometry.csv"
    frame = CoordinateFrame(1, "rectangular", np.eye(3), np.zeros(3))
    geometry = make_geometry(ids, np.array([points[i] for i in ids]), np.ones(len(ids), int),
                             (frame,), source="t")  # fmt: skip
    write_csv_geometry(csv, geometry, unit="mm")
    h5, report = tmp_path / "corr.h5", tmp_path / "report"
    out = _json(capsys, ["correlate", "--model", "exhaust", "--data", str(folder / "virtual.h5"),
                         "--geometry", str(csv), "--length-unit", "mm", "--pair-tolerance",
                         "1 mm", "--out", str(h5), "--report", str(report), "--json"])  # fmt: skip
    assert out["transform"]["source"].startswith("[test] geometry")
    assert out["transform"]["rms_residual"] < 1e-6
    np.testing.assert_allclose(np.asarray(out["transform"]["matrix"]), np.eye(4), atol=1e-6)
    assert min(m["mac"] for m in out["modes"]) >= 0.999
    with h5py.File(h5, "r") as fh:
        g = fh["correlation"]
        distance = g["points/distance"][()]
        assert distance.shape == (len(data.dof_labels),) and np.all(distance < 1e-6)
        assert g.attrs["rms_residual"] < 1e-6
    md = (report / "report.md").read_text()
    assert "Test DOFs on the model ([test] geometry (" in md and "transform: identity" in md


def test_geometry_options_without_a_geometry_are_refused(capsys):
    code = main(["correlate", "--model", "exhaust", "--data", "paper:ema", "--length-unit", "mm"])
    err = capsys.readouterr().err
    assert code == 2 and "--length-unit and --pair-tolerance need --geometry" in err


def test_data_modes_choose_the_test_modes_paired_and_reported(virtual, tmp_path, capsys):
    """``[data] modes = [2, 5, 9]``: only those test modes are paired (by MAC: each with the
    model mode of its own number, the test being the unchanged model) and reported, numbered as
    in the file; the HDF5 file keeps the numbers."""
    folder, data = virtual
    study = tmp_path / "study.toml"
    study.write_text(
        f'[model]\nsource = "exhaust"\n[data]\nsource = "{folder / "virtual.h5"}"\n'
        "modes = [9, 2, 5]\n"
    )
    h5 = tmp_path / "corr.h5"
    out = _json(capsys, ["correlate", str(study), "--out", str(h5), "--json"])
    assert [(m["test"], m["model"]) for m in out["modes"]] == [(2, 2), (5, 5), (9, 9)]
    np.testing.assert_allclose([m["test_hz"] for m in out["modes"]], data.frequencies_hz[[1, 4, 8]])
    assert len(out["mac"]) == 3 and out["unpaired_test"] == [] and out["refused"] == []
    np.testing.assert_allclose([m["mac"] for m in out["modes"]], 1.0, atol=1e-6)
    with h5py.File(h5) as fh:
        assert fh["correlation/test_numbers"][()].tolist() == [2, 5, 9]


def test_data_modes_without_shapes_pair_each_mode_with_the_model_mode_of_its_number(
    tmp_path, capsys
):
    """Frequencies only (the seed's Table 2), modes 3 and 7: paired in order by their numbers
    in the source (test 3 with model 3, not model 1)."""
    study = tmp_path / "study.toml"
    study.write_text('[model]\nsource = "exhaust"\n[data]\nsource = "paper:ema"\nmodes = [3, 7]\n')
    out = _json(capsys, ["correlate", str(study), "--json"])
    model_hz = get_model("exhaust").solve(None, 11).frequencies_hz
    assert [(m["test"], m["model"]) for m in out["modes"]] == [(3, 3), (7, 7)]
    np.testing.assert_allclose([m["model_hz"] for m in out["modes"]], model_hz[[2, 6]], rtol=1e-9)
    np.testing.assert_allclose([m["test_hz"] for m in out["modes"]], TABLE2_EMA_HZ[[2, 6]])


def test_a_data_mode_the_file_lacks_is_one_line_exit_2(virtual, tmp_path, capsys):
    folder, _ = virtual
    study = tmp_path / "study.toml"
    study.write_text(
        f'[model]\nsource = "exhaust"\n[data]\nsource = "{folder / "virtual.h5"}"\n'
        "modes = [2, 13]\n"
    )
    assert main(["correlate", str(study), "--out", str(tmp_path / "c.h5")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "13" in err
    assert not (tmp_path / "c.h5").exists()
