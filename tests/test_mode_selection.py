"""Test modes chosen, weighted and paired as a test engineer would: ``[data] modes`` /
``weights`` on a file source, MAC pairs refused below ``[pairing] mac_threshold`` or outside
``frequency_window``, and the warnings after a calibration (``inference.checks``).

The file source is a virtual test of the built-in exhaust model written as an identify HDF5
file (``ema.modal_h5``): its frequencies and shapes at t_hot_pipe = 1.2 mm, so the numbers each
test expects are the model's own.
"""

import json

import h5py
import numpy as np
import pytest

from bayesupdate.cli import main
from bayesupdate.config import parse_study
from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.checks import piled_warnings, start_warnings
from bayesupdate.inference.pairing import PairingRules, pair_batch, pair_modes, screen_test_modes
from bayesupdate.modal_data import ModalData
from bayesupdate.model_protocol import Prediction
from bayesupdate.pipelines.study import prepare

modal_h5 = pytest.importorskip("bayesupdate.ema.modal_h5")

#: the virtual test's design: the exhaust's hot pipe 20 % thicker than its default 1 mm
TRUE_T_HOT = 1.2e-3


@pytest.fixture(scope="module")
def truth():
    from bayesupdate.models import get_model

    model = get_model("exhaust")
    params = {**model.default_parameters(), "t_hot_pipe": TRUE_T_HOT}
    return model.predict(params, n_modes=12)


def _write(path, freqs, shapes, labels) -> str:
    order = np.argsort(freqs)
    modal_h5.write_modal_h5(
        path, ModalData(freqs[order], shapes=shapes[:, order], dof_labels=labels, source="gvt")
    )
    return str(path)


@pytest.fixture(scope="module")
def gvt(truth, tmp_path_factory):
    """The exhaust's first 12 modes at the true design, as identify writes them."""
    path = tmp_path_factory.mktemp("gvt") / "gvt.h5"
    freqs = np.asarray(truth.frequencies_hz, dtype=float)
    return _write(path, freqs, np.asarray(truth.shapes), tuple(truth.dof_labels))


@pytest.fixture(scope="module")
def planted(truth, tmp_path_factory):
    """The first 6 modes and a wrong one: mode 1's shape at 4 times its frequency (35.3 Hz,
    listed 6th of 7)."""
    path = tmp_path_factory.mktemp("gvt") / "planted.h5"
    freqs = np.asarray(truth.frequencies_hz, dtype=float)[:6]
    shapes = np.asarray(truth.shapes)[:, :6]
    freqs = np.append(freqs, 4.0 * freqs[0])
    shapes = np.column_stack([shapes, shapes[:, 0]])
    return _write(path, freqs, shapes, tuple(truth.dof_labels))


def _study(source: str, **data):
    document = {
        "model": {"source": "exhaust"},
        "data": {"source": source, **data},
        "parameters": {"t_hot_pipe": {"bounds": [0.5e-3, 3.0e-3]}},
    }
    return parse_study(document, "study.toml")


def test_modes_choose_the_file_sources_modes_by_number(gvt, truth):
    problem = prepare(_study(gvt, modes=[10, 1, 7])).problem
    f = np.asarray(truth.frequencies_hz)
    np.testing.assert_array_equal(problem.data.frequencies_hz, f[[0, 6, 9]])
    assert problem.mode_numbers.tolist() == [1, 7, 10]
    table = problem.table(problem.evaluate(np.array([TRUE_T_HOT])))
    assert [row["mode"] for row in table.rows()] == [1, 7, 10]
    # each selected test mode finds its own model mode, in order: no swap
    assert table.model_mode.tolist() == [1, 7, 10] and not table.swapped
    np.testing.assert_allclose(table.mac, 1.0, atol=1e-9)


def test_weights_act_on_a_file_source(gvt):
    plain = prepare(_study(gvt, modes=[1, 7, 10])).problem
    # weights in the order of [data] modes: 4 on mode 10, 1 on modes 1 and 7
    weighted = prepare(_study(gvt, modes=[10, 1, 7], weights=[4.0, 1.0, 1.0])).problem
    np.testing.assert_array_equal(weighted.weights, [1.0, 1.0, 4.0])
    theta = np.array([1.0e-3])  # away from the truth: every term is non-zero
    at = plain.evaluate(theta)
    terms = ((at.frequencies_hz - plain.data.frequencies_hz) / plain.data.frequencies_hz) ** 2
    assert terms[2] > 1e-6
    expr_plain = plain.expr(at.frequencies_hz)
    expr_weighted = weighted.expr(weighted.evaluate(theta).frequencies_hz)
    # eq. 19: the weight 4 on mode 10 adds three times its term
    assert expr_weighted - expr_plain == pytest.approx(3.0 * terms[2], rel=1e-12)


def test_modes_and_weights_of_an_inline_table():
    study = parse_study(
        {
            "model": {"source": "shear_building"},
            "data": {"frequencies_hz": [4.3, 10.8, 30.0], "modes": [2], "weights": [2.5]},
        }
    )
    problem = prepare(study).problem
    assert problem.data.frequencies_hz.tolist() == [10.8]
    assert problem.weights.tolist() == [2.5]
    assert problem.mode_numbers.tolist() == [2]
    # table mode 2 is the model's second mode, tracked by its shape
    from bayesupdate.models.shear_building import shear_building_frequencies

    at = problem.evaluate(np.array([1.0, 1.0]))
    expected = shear_building_frequencies(np.array([1.0, 1.0]))[1]
    assert at.frequencies_hz.tolist() == [pytest.approx(expected, rel=1e-12)]
    assert at.paired.model_index.tolist() == [1] and not at.paired.swapped


def test_a_planted_wrong_mode_is_refused_and_named(planted, tmp_path, capsys):
    out = tmp_path / "result.h5"
    study = tmp_path / "study.toml"
    study.write_text(
        f'[model]\nsource = "exhaust"\n[data]\nsource = "{planted}"\n'
        "[parameters.t_hot_pipe]\nbounds = [0.5e-3, 3.0e-3]\n"
    )
    args = ["calibrate", str(study), "--full", "--starts", "1", "--out", str(out), "--json"]
    assert main(args) == 0
    captured = capsys.readouterr()
    result = json.loads(captured.out)
    (refused,) = result["pairing"]["refused"]
    # mode 1's shape (best MAC with model mode 1: 0.999 at the 1 mm reference) at 4 x 8.83 Hz
    assert (refused["test_mode"], refused["model_mode"], refused["reason"]) == (6, 1, "window")
    assert refused["test_hz"] == pytest.approx(35.328, abs=1e-3)
    assert refused["model_hz"] == pytest.approx(8.960, abs=1e-3)
    assert refused["mac"] == pytest.approx(0.9992, abs=1e-4)
    line = (
        "pairing: test mode 6 (35.33 Hz): best model mode 1 at 8.96 Hz, MAC 1.00: refused "
        "(-74.6 % off, outside the frequency window +-50 %)"
    )
    assert line in captured.err.splitlines()
    assert result["test_modes"] == [1, 2, 3, 4, 5, 7]
    # without the planted mode the six true modes give back the true design
    assert result["parameters"]["t_hot_pipe"] == pytest.approx(TRUE_T_HOT, rel=1e-7)
    assert result["warnings"] == []
    with h5py.File(out) as h5:
        record = json.loads(h5["inputs"].attrs["pairing_json"])
        assert record["refused"][0]["test_mode"] == 6
        assert h5["inputs/test_modes"][()].tolist() == [1, 2, 3, 4, 5, 7]
        assert json.loads(h5.attrs["warnings_json"]) == []


def test_discovery_leaves_the_refused_mode_out_too_with_one_reference_solve(planted):
    """Discovery applies the study's pairing rules where it pairs (``discovery_problem``):
    the planted mode 6 is refused and left out, the record names it, and setting the problem up
    solves the model once (the reference design), not once to screen and again to pair."""
    from bayesupdate.discovery.workflow import discovery_problem
    from bayesupdate.inference.data import load_modal_data
    from bayesupdate.pipelines.model_source import problem_parameters, study_model

    study = _study(planted)
    data = load_modal_data(planted)
    model = study_model(study, data.dof_labels)
    solves = []
    predict = model.predict

    def counted(*args, **kwargs):
        solves.append(1)
        return predict(*args, **kwargs)

    object.__setattr__(model, "predict", counted)
    parameters = problem_parameters(study.parameters)
    problem, record = discovery_problem(model, data, parameters, rules=study.pairing.rules())
    assert len(solves) == 1
    np.testing.assert_array_equal(problem.data.frequencies_hz, np.delete(data.frequencies_hz, 5))
    assert [r["test_mode"] for r in record["refused"]] == [6]
    assert record["method"] == "mac" and record["mac_threshold"] == 0.6
    assert problem.test_modes == (1, 2, 3, 4, 5, 7)
    # the candidates pair without a window, so the baseline does too (same pairing both sides)
    assert problem.pairing.window is None
    assert discovery_problem(model, data, parameters)[1] == {}  # no rules, no record


def test_screening_names_each_reason_with_its_mac():
    # three model modes on three DOFs (unit shapes), at 10, 20, 30 Hz
    model_hz = np.array([10.0, 20.0, 30.0])
    model_shapes = np.eye(3)
    test_hz = np.array([10.5, 11.0, 21.0, 100.0])
    test_shapes = np.column_stack(
        [
            [1.0, 0.0, 0.0],  # mode 1 itself: kept, MAC 1
            [1.0, 0.1, 0.0],  # mode 1 again: its best partner is taken by test mode 1
            [0.0, 1.0, 1.0],  # half mode 2, half mode 3: MAC 0.5 with each
            [0.0, 0.0, 1.0],  # mode 3's shape at 100 Hz: -70 %, outside the window
        ]
    )
    rules = PairingRules(0.6, 0.5)
    kept, refused = screen_test_modes(
        test_hz, test_shapes, model_hz, model_shapes, rules, (1, 2, 3, 4)
    )
    assert kept.tolist() == [0]
    assert [(r.number, r.model_mode, r.reason) for r in refused] == [
        (2, 1, "taken"),
        (3, 2, "mac"),
        (4, 3, "window"),
    ]
    np.testing.assert_allclose([r.mac for r in refused], [1.0 / 1.01, 0.5, 1.0])
    assert refused[1].message(rules) == (
        "test mode 3 (21 Hz): best model mode 2 at 20 Hz, MAC 0.50: refused (below 0.6)"
    )
    assert "paired with test mode 1" in refused[0].message(rules)


def test_the_pairing_is_redone_inside_the_window_batched_or_not():
    shapes = np.eye(3)
    test_shapes = np.column_stack([[1.0, 0.3, 0.0], [0.0, 0.0, 1.0]])
    test_hz = np.array([10.0, 30.0])
    rules = PairingRules(0.6, 0.5)
    from bayesupdate.inference.pairing import ModePairing

    pairing = ModePairing("mac", 2, 3, ("a", "b", "c"), None, test_shapes, rules, test_hz)
    # model mode 1 (best MAC 0.92 for test mode 1) has moved to 40 Hz (+300 %); mode 2
    # (MAC 0.08) sits at 12 Hz, inside the window: the pairing takes mode 2
    freqs = np.array([40.0, 12.0, 31.0])
    prediction = Prediction(freqs, shapes, ("a", "b", "c"))
    paired = pair_modes(prediction, pairing)
    assert paired.model_index.tolist() == [1, 2]
    np.testing.assert_allclose(paired.mac, [0.09 / 1.09, 1.0])
    index, mac = pair_batch(test_shapes, shapes[None], (test_hz, freqs[None], 0.5))
    assert index.tolist() == [[1, 2]]
    np.testing.assert_allclose(mac, [[0.09 / 1.09, 1.0]])
    # no model mode inside the window: the best MAC outside it still counts
    far = np.array([40.0, 60.0, 31.0])
    paired = pair_modes(Prediction(far, shapes, ("a", "b", "c")), pairing)
    assert paired.model_index.tolist() == [0, 2]


SHEAR = """
[model]
source = "shear_building"
[data]
source = "{csv}"
[parameters.theta_1]
bounds = [0.2, 1.5]
[parameters.theta_2]
bounds = [0.2, 1.5]
[optimizer]
starts = 4
"""


def _stiff_study(tmp_path, extra: str = ""):
    """The shear building against a test whose storeys are twice the nominal stiffness: out of
    reach of bounds up to 1.5."""
    from bayesupdate.models.shear_building import shear_building_frequencies

    f = shear_building_frequencies(np.array([2.0, 2.0]))
    csv = tmp_path / "freqs.csv"
    csv.write_text(f"frequency_hz\n{float(f[0])!r}\n{float(f[1])!r}\n")
    study = tmp_path / "study.toml"
    study.write_text(SHEAR.format(csv=csv) + extra)
    return study


def test_an_optimum_on_a_bound_is_warned(tmp_path, capsys):
    study = _stiff_study(tmp_path)
    assert main(["calibrate", str(study), "--json"]) == 0
    captured = capsys.readouterr()
    result = json.loads(captured.out)
    # least squares keep their ends strictly inside the box (trust-region reflective): one ulp
    # below the bound now that a smooth end is not polished onto it
    assert result["parameters"] == pytest.approx({"theta_1": 1.5, "theta_2": 1.5}, abs=1e-12)
    assert result["warnings"] == [
        f"{name} = 1.5 sits on its upper bound 1.5: the bounds, not the test, set it; widen "
        "the range or check the parameter"
        for name in ("theta_1", "theta_2")
    ]
    assert captured.err.count("warning: theta_") == 2


def test_a_posterior_piled_at_its_bounds_is_warned(tmp_path, capsys):
    sampler = (
        "[sampler]\nwalkers = 4\nsteps = 100\ncheck_every = 100\nmin_autocorr_times = 1e9\n"
        'predictive_draws = 10\nmoves = "de"\nscreen = false\n'
    )
    study = _stiff_study(tmp_path, sampler)
    out = tmp_path / "post.h5"
    assert main(["sample", str(study), "--json", "--no-progress", "--out", str(out)]) == 0
    captured = capsys.readouterr()
    warnings = json.loads(captured.out)["warnings"]
    assert [w.split(":")[0] for w in warnings] == ["theta_1", "theta_2"]
    # both storeys want 2.0: the posterior presses on the upper bounds, far above the 2 % a
    # posterior flat over [0.2, 1.5] would put next to them
    shares = [float(w.split("% of the posterior")[0].split(":")[1]) for w in warnings]
    assert min(shares) > 20
    assert all("of its upper bound 1.5" in w for w in warnings)
    with h5py.File(out) as h5:
        assert json.loads(h5.attrs["warnings_json"]) == warnings
    assert captured.err.count("warning: theta_") == 2


def test_few_starts_at_the_best_and_a_posterior_piled_at_a_bound_are_warned(gvt):
    from dataclasses import replace

    from bayesupdate.inference import CalibrationSettings, calibrate

    problem = prepare(_study(gvt, modes=[1, 2])).problem
    result = calibrate(problem, CalibrationSettings(starts=2, seed=0, max_nfev=5))
    assert start_warnings(replace(result, starts=5, converged_starts=3)) == []
    (line,) = start_warnings(replace(result, starts=5, converged_starts=2))
    assert line.startswith("only 2 of 5 starts reach the best objective")
    # t_hot_pipe on [0.5, 3] mm: 1000 draws evenly over [2.96, 3] mm, the 1.6 % of the range
    # next to the upper bound, and 1000 in the middle: half of them piled there
    draws = np.concatenate([np.linspace(2.96e-3, 3e-3, 1000), np.full(1000, 1.7e-3)])
    (piled,) = piled_warnings(problem, draws[:, None])
    assert piled.startswith("t_hot_pipe: 50 % of the posterior lies within 2 % of the range")
    assert piled_warnings(problem, np.full((1000, 1), 1.7e-3)) == []


@pytest.mark.parametrize(
    ("data", "pairing", "message"),
    [
        (
            {"modes": [1, 13]},
            {},
            "data.modes: test mode 13 is not in '{gvt}', which has 12 modes (numbered 1 to 12",
        ),
        (
            {"modes": [1, 7], "weights": [1.0, 2.0, 3.0]},
            {},
            "data.weights: 3 values for 2 selected test modes [1, 7]; give one per selected mode",
        ),
        (
            {"weights": [1.0, 2.0]},
            {},
            "data.weights: 2 values for the source's 12 test modes",
        ),
        ({"modes": [1, 1]}, {}, "data.modes: test mode(s) [1] listed twice"),
        ({"modes": [1.5]}, {}, "data.modes: give 1-based mode numbers (integers)"),
        ({}, {"mac_threshold": 1.5}, "pairing.mac_threshold: 1.5; give a MAC in [0, 1]"),
        ({}, {"frequency_window": 0}, "pairing.frequency_window: 0.0; give a relative window"),
        (
            {"modes": [1]},  # MAC 0.9992 between the 1.2 mm test and the 1 mm reference
            {"mac_threshold": 1.0},
            "pairing: no test mode of 'gvt' pairs with the model at its reference design",
        ),
    ],
)
def test_bad_choices_are_one_line_and_exit_2(gvt, tmp_path, capsys, data, pairing, message):
    lines = [f'[model]\nsource = "exhaust"\n[data]\nsource = "{gvt}"']
    lines += [f"{key} = {json.dumps(value)}" for key, value in data.items()]
    lines += ["[pairing]"] + [f"{key} = {json.dumps(value)}" for key, value in pairing.items()]
    study = tmp_path / "study.toml"
    study.write_text("\n".join(lines) + "\n")
    assert main(["calibrate", str(study), "--starts", "1", "--full"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert message.format(gvt=gvt) in err[0]


def test_study_tables_reject_bad_rules_when_read():
    with pytest.raises(BayesUpdateError, match="mac_threshold"):
        parse_study({"pairing": {"mac_threshold": -0.1}})
