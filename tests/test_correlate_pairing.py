"""``correlate`` pairs test modes with model modes by the one rule ``calibrate``, ``sample`` and
``discover`` keep pairs by (``inference.pairing.screen_pairs``: a MAC threshold and a relative
frequency window, the study's ``[pairing]`` or ``--mac-threshold`` / ``--frequency-window``),
and reports every test mode: paired, or refused with the rule that refused it.

- Synthetic: unit shapes on a few DOFs, where the window or the threshold decides a pair, and
  where the assignment must give a model mode to the test mode of higher admissible MAC.
- The exhaust: a virtual test whose sixth mode sits 40 % above the model's; a 20 % window
  refuses it in ``correlate`` (study key or flag) and in ``calibrate``'s problem alike.
- The real pair (slow): the packaged mAEWing1 decks against their GVT (identified from the
  packaged FRFs): ``correlate`` and ``calibrate`` keep the same pairs on v3.3 and v4.2, and
  GVT mode 5 (15.96 Hz), which MAC alone pairs with v3.3's 38.3 Hz mode (+140 %), is refused
  with that reason.
- Bad input, one line and exit 2: a window of 0 or less (flag or study), a threshold outside
  [0, 1], a ``[data] modes`` entry the file lacks, a weight for a mode not selected, and a
  test point farther than ``pair_tolerance`` from the deck (named with its distance).
"""

import json
from pathlib import Path

import h5py
import numpy as np
import pytest

from bayesupdate.cli import main
from bayesupdate.inference.pairing import (
    PairingRules,
    pair_modes,
    screen_pairs,
    screen_test_modes,
)
from bayesupdate.modal_data import ModalData
from bayesupdate.model_protocol import Prediction
from bayesupdate.pipelines.correlate import CorrelateSettings, correlate


class _UnitModes:
    """A model whose modes are unit vectors on DOFs a, b, c (and d, seen by none) at
    10, 20, 30 Hz: MAC with a test shape is the share of its squared norm on that DOF."""

    labels = ("a", "b", "c", "d")

    def default_parameters(self) -> dict:
        return {}

    def predict(self, params, n_modes: int) -> Prediction:
        shapes = np.eye(4)[:, :3]
        return Prediction(np.array([10.0, 20.0, 30.0]), shapes, self.labels)


def _data(freqs, columns) -> ModalData:
    shapes = np.sqrt(np.column_stack(columns))  # columns: squared components, MAC shares
    return ModalData(np.asarray(freqs, float), shapes=shapes, dof_labels=_UnitModes.labels,
                     source="synthetic")  # fmt: skip


def _correlate(data, rules, extra_modes=0):
    return correlate(_UnitModes(), data, CorrelateSettings(rules, extra_modes))


def test_the_window_decides_a_pair_and_names_why():
    # test mode 1: model mode 3's shape (MAC 0.8) at 12 Hz, model mode 1 (MAC 0.2) nearby
    data = _data([12.0], [[0.2, 0.0, 0.8, 0.0]])
    none = _correlate(data, PairingRules(0.6, np.inf))
    assert none.pairs.test.tolist() == [0] and none.pairs.model.tolist() == [2]
    np.testing.assert_allclose(none.pairs.mac, [0.8])
    np.testing.assert_allclose(none.error_pct, [150.0])  # 30 Hz against 12 Hz
    windowed = _correlate(data, PairingRules(0.6, 0.5))
    assert windowed.pairs.test.size == 0 and windowed.pairs.unpaired_test == (0,)
    (refused,) = windowed.refused
    assert (refused.number, refused.model_mode, refused.reason) == (1, 3, "window")
    assert refused.error_pct == pytest.approx(150.0) and refused.mac == pytest.approx(0.8)
    assert refused.why(windowed.rules) == "+150.0 % outside +-50 %"
    assert windowed.pairs.refused == ((0, 2, pytest.approx(0.8)),)
    # a window of 1.6 (160 %) takes the pair back
    assert _correlate(data, PairingRules(0.6, 1.6)).pairs.model.tolist() == [2]


def test_a_pair_that_will_be_refused_never_takes_the_partner_of_one_kept():
    # A: MAC 0.65 with model mode 2 and nothing else; B: MAC 0.70 with it and 0.30 with mode 3.
    # The total MAC of all pairs prefers A-2 + B-3 (0.95) to B-2 (0.70), but B-3 is refused
    # anyway: of the admissible pairs, B-2 has the higher MAC, so B is kept and A refused
    data = _data([19.0, 21.0], [[0.0, 0.65, 0.0, 0.35], [0.0, 0.7, 0.3, 0.0]])
    rules = PairingRules(0.6, 0.5)
    result = _correlate(data, rules, extra_modes=1)
    assert result.pairs.test.tolist() == [1] and result.pairs.model.tolist() == [1]
    np.testing.assert_allclose(result.pairs.mac, [0.7])
    (refused,) = result.refused
    assert (refused.number, refused.reason, refused.other) == (1, "taken", 2)
    assert refused.why(rules) == "model mode 2 taken by test mode 2"
    # calibrate's screen (shapes) and the MAC-matrix form give the same verdict
    model = _UnitModes().predict({}, 3)
    kept, again = screen_test_modes(data.frequencies_hz, data.shapes, model.frequencies_hz,
                                    model.shapes, rules, (1, 2))  # fmt: skip
    assert kept.tolist() == [1] and again == result.refused
    mac = np.array([[0.0, 0.65, 0.0], [0.0, 0.7, 0.3]])
    screened = screen_pairs(mac, data.frequencies_hz, model.frequencies_hz, rules, (1, 2))
    assert screened.test.tolist() == [1] and screened.model.tolist() == [1]


def test_the_threshold_refuses_and_every_test_mode_is_listed(capsys):
    from bayesupdate.commands.correlate import correlation_json, format_correlation

    # 1: model mode 1 (MAC 0.9, +0 %); 2: model mode 2 at MAC 0.5 (below 0.6); 3: mode 3
    data = _data([10.0, 20.0, 33.0], [[0.9, 0.1, 0, 0], [0.5, 0.5, 0, 0], [0, 0, 1.0, 0]])
    result = _correlate(data, PairingRules(0.6, 0.5))
    out = correlation_json(result)
    assert out["rules"] == {"mac_threshold": 0.6, "frequency_window": 0.5}
    assert [(r["test"], r["status"], r["model"], r["reason"]) for r in out["tests"]] == [
        (1, "paired", 1, None),
        (2, "refused", 1, "mac"),  # its best MAC: 0.5 with model mode 1 (first of a tie)
        (3, "paired", 3, None),
    ]
    assert out["tests"][2]["error_pct"] == pytest.approx(100 * (30 / 33 - 1))
    assert [(r["test"], r["reason"], r["mac"]) for r in out["refused"]] == [(2, "mac", 0.5)]
    assert out["unpaired_test"] == [2]
    text = format_correlation(result).splitlines()
    assert "(MAC >= 0.6 within +-50 %)" in text[0]
    assert text[3].split()[:2] == ["2", "1"] and text[3].endswith("refused: MAC < 0.6")
    json.dumps(out)  # a window of inf is written as null: the object stays JSON
    assert correlation_json(_correlate(data, PairingRules(0.6, np.inf)))["rules"] == {
        "mac_threshold": 0.6,
        "frequency_window": None,
    }


# --- the exhaust: a 20 % window on the study or the command line, as calibrate keeps it ------


@pytest.fixture(scope="module")
def shifted(tmp_path_factory):
    """The exhaust's first 6 modes at its defaults, the 6th at 1.4 x its frequency (the model
    then 28.6 % low), as identify writes them."""
    from bayesupdate.ema.modal_h5 import write_modal_h5
    from bayesupdate.models import get_model

    model = get_model("exhaust")
    truth = model.predict(model.default_parameters(), n_modes=6)
    freqs = np.asarray(truth.frequencies_hz, float) * np.array([1, 1, 1, 1, 1, 1.4])
    path = tmp_path_factory.mktemp("shifted") / "shifted.h5"
    data = ModalData(freqs, shapes=np.asarray(truth.shapes), dof_labels=tuple(truth.dof_labels),
                     source="shifted")  # fmt: skip
    write_modal_h5(path, data)
    return path, float(truth.frequencies_hz[5])


def _exhaust_study(tmp_path, h5, pairing: str = "") -> str:
    path = tmp_path / "study.toml"
    path.write_text(
        f'[model]\nsource = "exhaust"\n[data]\nsource = "{h5}"\n'
        f"[parameters.t_hot_pipe]\nbounds = [0.5e-3, 3.0e-3]\n{pairing}"
    )
    return str(path)


def _correlate_json(capsys, argv) -> dict:
    code = main(["correlate", *argv, "--json"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    return json.loads(captured.out)


def test_a_window_on_the_study_or_the_flag_refuses_what_calibrate_refuses(
    shifted, tmp_path, capsys
):
    from bayesupdate.config import load_study
    from bayesupdate.pipelines.study import prepare

    h5, model_hz6 = shifted
    plain = _exhaust_study(tmp_path, h5)
    out = _correlate_json(capsys, [plain])  # the default window, 50 %: all six pair
    assert [(m["test"], m["model"]) for m in out["modes"]] == [(i, i) for i in range(1, 7)]
    assert out["modes"][5]["error_pct"] == pytest.approx(100 * (1 / 1.4 - 1))  # -28.57 %
    assert out["rules"] == {"mac_threshold": 0.6, "frequency_window": 0.5}
    narrow = _exhaust_study(tmp_path, h5, "[pairing]\nfrequency_window = 0.2\n")
    h5_out = tmp_path / "corr.h5"
    by_flag = _correlate_json(capsys, [plain, "--frequency-window", "0.2", "--out", str(h5_out)])
    by_study = _correlate_json(capsys, [narrow])
    for out in (by_flag, by_study):
        assert [m["test"] for m in out["modes"]] == [1, 2, 3, 4, 5]
        (refused,) = out["refused"]
        assert (refused["test"], refused["model"], refused["reason"]) == (6, 6, "window")
        assert refused["model_hz"] == pytest.approx(model_hz6, rel=1e-9)
        assert refused["error_pct"] == pytest.approx(-28.571, abs=1e-3)
        assert out["tests"][5]["status"] == "refused"
    with h5py.File(h5_out, "r") as fh:
        g = fh["correlation"]
        assert g.attrs["frequency_window"] == 0.2 and g.attrs["mac_threshold"] == 0.6
        assert g["refused/test"][()].tolist() == [6] and g["refused/model"][()].tolist() == [6]
        assert g["refused/reason"].asstr()[()].tolist() == ["window"]
        assert g["refused/error_pct"][0] == pytest.approx(-28.571, abs=1e-3)
    # calibrate's problem from the same study file keeps the same five and refuses mode 6
    problem = prepare(load_study(narrow)).problem
    assert problem.mode_numbers.tolist() == [1, 2, 3, 4, 5]
    assert [(r.number, r.model_mode, r.reason) for r in problem.pairing.refused] == [
        (6, 6, "window")
    ]
    # the flag wins over the study
    assert len(_correlate_json(capsys, [narrow, "--frequency-window", "0.5"])["modes"]) == 6


def test_a_test_that_missed_the_lower_modes_still_pairs_in_correlate_and_calibrate(
    tmp_path, capsys
):
    """A test holding only the exhaust's modes 9-12 (a band or a sensor set that missed the
    lower eight; numbered 1-4 in its file): the model's first 4 + 2 modes stop below the
    test's highest, so both compute more (``pairing.reach_modes``) and pair each test mode
    with its own model mode (MAC 1); before, all four were refused at MACs of their best
    partners among the six."""
    from bayesupdate.config import load_study
    from bayesupdate.ema.modal_h5 import write_modal_h5
    from bayesupdate.models import get_model
    from bayesupdate.pipelines.study import prepare

    model = get_model("exhaust")
    truth = model.predict(model.default_parameters(), n_modes=12)
    upper = ModalData(np.asarray(truth.frequencies_hz[8:12], float),
                      shapes=np.asarray(truth.shapes)[:, 8:12],
                      dof_labels=tuple(truth.dof_labels), source="upper")  # fmt: skip
    write_modal_h5(tmp_path / "upper.h5", upper)
    study = _exhaust_study(tmp_path, tmp_path / "upper.h5")
    out = _correlate_json(capsys, [study])
    assert [(m["test"], m["model"]) for m in out["modes"]] == [(1, 9), (2, 10), (3, 11), (4, 12)]
    assert min(m["mac"] for m in out["modes"]) > 0.999
    assert "the model's first 6 modes stop at" in out["notes"][0]
    problem = prepare(load_study(study)).problem
    assert problem.pairing.refused == ()
    assert pair_modes(problem.reference, problem.pairing).model_index.tolist() == [8, 9, 10, 11]


@pytest.mark.parametrize(
    ("flags", "needle"),
    [
        (["--frequency-window", "0"], "--frequency-window: 0.0; give a relative window > 0"),
        (["--frequency-window", "-0.3"], "--frequency-window: -0.3; give a relative window > 0"),
        (["--frequency-window", "nan"], "--frequency-window: nan; give a relative window > 0"),
        (["--mac-threshold", "1.5"], "--mac-threshold: 1.5; give a MAC in [0, 1]"),
    ],
)
def test_a_bad_window_or_threshold_is_one_line_exit_2(tmp_path, capsys, flags, needle):
    argv = ["correlate", "--model", "exhaust", "--data", "paper:ema", *flags]
    for command in ("correlate", "sensitivity"):
        argv[0] = command
        assert main([*argv, "--out", str(tmp_path / "c.h5")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and needle in err[0]
        assert not (tmp_path / "c.h5").exists()


def test_a_study_window_of_zero_is_one_line_exit_2(tmp_path, capsys):
    study = tmp_path / "study.toml"
    study.write_text(
        '[model]\nsource = "exhaust"\n[data]\nsource = "paper:ema"\n'
        "[pairing]\nfrequency_window = 0.0\n"
    )
    assert main(["correlate", str(study)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pairing.frequency_window: 0.0; give a relative window" in err[0]


# --- the real pair: the packaged mAEWing1 decks against their GVT -------------------------


@pytest.fixture(scope="module")
def gvt_modes(tmp_path_factory):
    """The GVT identified from the 10 packaged FRF files (``identify``, defaults)."""
    from bayesupdate.pipelines import aircraft as ac

    out = tmp_path_factory.mktemp("gvt") / "modes.h5"
    runs = [str(ac.data_folder() / f"run{k}.uff") for k in range(1, ac.N_RUNS + 1)]
    assert main(["identify", *runs, "--out", str(out), "--quiet"]) == 0
    return out


def _aircraft_study(tmp_path, deck: str, modes_h5, window: bool = True) -> str:
    """The demo's study of ``deck`` against every GVT mode (``aircraft.study_text``, with its
    ``[pairing]`` window of 60 %, or without it: the default 50 %), one wing bending scale."""
    from bayesupdate.pipelines import aircraft as ac

    text = ac.study_text(ac.data_folder() / deck, modes_h5, None, ac.DISCOVER_PARAMETERS, False)
    if not window:
        text = text.replace(f"[pairing]\nfrequency_window = {ac.FREQUENCY_WINDOW}\n", "")
    path = tmp_path / f"{deck.split('/')[0]}{'' if window else '_default'}.toml"
    path.write_text(text)
    return str(path)


def _calibrate_pairs(path) -> tuple[dict, list]:
    """({test: model} kept at the reference design, [(test, reason)] refused) as ``calibrate``
    sets its problem up from the study file."""
    from bayesupdate.config import load_study
    from bayesupdate.pipelines.study import prepare

    problem = prepare(load_study(path)).problem
    at_reference = problem.evaluate(problem.start)
    kept = problem.mode_numbers.tolist()
    pairs = dict(zip(kept, (at_reference.paired.model_index + 1).tolist(), strict=True))
    return pairs, [(r.number, r.reason) for r in problem.pairing.refused]


@pytest.mark.slow
@pytest.mark.parametrize(
    ("deck", "pairs", "mode5"),
    [
        # v3.3's 38.33 Hz mode: MAC 0.63 with GVT mode 5, +140.2 %
        ("v3.3/sol103_mAEWing1_Hati_FEMv3p3.bdf", {1: 1, 7: 2, 10: 5}, (9, 38.328, 140.2)),
        # v4.2's 66.41 Hz mode: MAC 0.65, +316.2 %
        ("v4.2/sol103_mAEWing1_FEMv4p2.bdf", {1: 1, 7: 4, 10: 5}, (11, 66.413, 316.2)),
    ],
)
def test_correlate_and_calibrate_keep_the_same_pairs_on_the_packaged_decks(
    tmp_path, gvt_modes, capsys, deck, pairs, mode5
):
    path = _aircraft_study(tmp_path, deck, gvt_modes)
    out = _correlate_json(capsys, [path])
    assert {m["test"]: m["model"] for m in out["modes"]} == pairs
    assert out["rules"] == {"mac_threshold": 0.6, "frequency_window": 0.6}
    refused = {r["test"]: r for r in out["refused"]}
    assert set(refused) | set(pairs) == set(range(1, 12))  # every GVT mode accounted for
    five = refused[5]
    assert (five["model"], five["reason"]) == (mode5[0], "window")
    assert five["model_hz"] == pytest.approx(mode5[1], abs=1e-3)
    assert five["error_pct"] == pytest.approx(mode5[2], abs=0.05)
    assert five["mac"] >= 0.6  # MAC alone would pair it
    assert f"{mode5[2]:+.1f} % off, outside the frequency window +-60 %" in five["message"]
    kept, why = _calibrate_pairs(path)
    assert kept == pairs
    assert why == [(r["test"], r["reason"]) for r in out["refused"]]


@pytest.mark.slow
def test_the_default_window_refuses_v33s_pair_of_the_19_hz_mode_and_the_text_says_so(
    tmp_path, gvt_modes, capsys
):
    path = _aircraft_study(tmp_path, "v3.3/sol103_mAEWing1_Hati_FEMv3p3.bdf", gvt_modes, False)
    assert main(["correlate", path]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert "(MAC >= 0.6 within +-50 %)" in lines[0]
    rows = {int(line.split()[0]): line for line in lines[2:13]}
    assert rows[1].endswith("paired") and rows[10].endswith("paired")
    # v3.3's mode 2 (9.47 Hz, MAC 0.65) is 50.3 % below the 19.07 Hz GVT mode
    assert rows[7].split()[1] == "2" and rows[7].endswith("refused: -50.3 % outside +-50 %")
    assert rows[5].endswith("refused: +140.2 % outside +-50 %")
    kept, _ = _calibrate_pairs(path)
    assert kept == {1: 1, 10: 5}


@pytest.mark.parametrize(
    ("data", "needle"),
    [
        ("modes = [1, 9]", "data.modes: test mode 9 is not in"),
        ("modes = [1, 9]", "which has 6 modes (numbered 1 to 6"),
        (
            "modes = [1, 2]\nweights = [1.0, 2.0, 3.0]",
            "data.weights: 3 values for 2 selected test modes [1, 2]; give one per selected mode",
        ),
    ],
)
def test_a_mode_the_file_lacks_or_a_weight_for_an_unselected_mode_is_one_line(
    shifted, tmp_path, capsys, data, needle
):
    h5, _ = shifted
    study = tmp_path / "study.toml"
    study.write_text(f'[model]\nsource = "exhaust"\n[data]\nsource = "{h5}"\n{data}\n')
    for command in ("correlate", "sensitivity", "calibrate"):
        assert main([command, str(study)]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and needle in err[0], (command, err)


@pytest.mark.slow
def test_a_test_point_beyond_the_tolerance_is_named_with_its_distance(tmp_path, gvt_modes, capsys):
    path = _aircraft_study(tmp_path, "v3.3/sol103_mAEWing1_Hati_FEMv3p3.bdf", gvt_modes)
    text = Path(path).read_text().replace('pair_tolerance = "5 in"', 'pair_tolerance = "0.5 in"')
    Path(path).write_text(text)
    assert main(["correlate", path]) == 2
    (err,) = capsys.readouterr().err.strip().splitlines()
    # the farthest accelerometer from v3.3's beams (3.47 in, studies/maewing1_correlate.py)
    assert "test point 3 is 3.475 in (88.26 mm) from the model" in err
    assert "beyond pair_tolerance 12.7 mm" in err
