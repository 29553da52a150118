"""``bayesupdate frf``: time signals to FRFs, checked on a simulated hammer test (known modes),
on the real mAEWing1 ground vibration test (shaker sweep, the authors' peak picks) and on bad
input (one line, exit 2, or a stated warning; never a traceback or RuntimeWarning)."""

from pathlib import Path

import numpy as np
import pytest

from bayesupdate.cli import main
from bayesupdate.ema.uff_io import read_uff58
from bayesupdate.ema.virtual_test import exhaust_like_model, virtual_impact_test

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
GVT = DATA / "gvt_maewing1" / "data"
#: explog.txt peak picks (7.797, 19.06, 23.82, 31.78 Hz) and shallow peaks (8.8-9.8, 15.4-16.4,
#: 30.2-31.2 Hz ranges, centres given here)
GVT_PEAKS_HZ = np.array([7.797, 9.3, 15.9, 19.06, 23.82, 30.7, 31.78])


def run_cli(argv, capsys):
    code = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.fixture(scope="module")
def hammer(tmp_path_factory):
    """Driving point 1V of the 12-mode beam: 5 hits, 16 s apart, written end to end to .npz."""
    fn, zeta, shapes, labels = exhaust_like_model()
    _, (t, force, accel) = virtual_impact_test(
        fn, zeta, shapes, labels, layout=[("1V", "1V"), ("5V", "1V")], noise=0.01, seed=2,
        return_signals=True,
    )  # fmt: skip
    folder = tmp_path_factory.mktemp("hammer")
    signals = {
        "force": force[0].reshape(-1),
        "a1": accel[0].reshape(-1),
        "a5": accel[1].reshape(-1),
        "time": np.arange(force[0].size) / 1024.0,
    }
    np.savez(folder / "hits.npz", **signals)
    # modes the V hammer and accelerometers see (the model's "H" modes have no V motion)
    seen = np.abs(shapes[labels.index("1V")]) > 0
    return folder, signals, fn[seen]


def test_hammer_signals_to_frfs_to_modes(hammer, capsys):
    folder, _, fn = hammer
    out = folder / "frf.uff"
    argv = [
        "frf",
        folder / "hits.npz",
        "--force-channel",
        "force",
        "--response",
        "a1=1V",
        "--reference",
        "1V",
    ]
    code, text, err = run_cli([*argv, "--response", "a5=5V", "--out", out], capsys)
    assert code == 0, err
    assert "5 hits averaged" in text and err == ""
    frfs = read_uff58(out)
    assert frfs.response_labels == ("1V", "5V") and frfs.reference_labels == ("1V", "1V")
    assert frfs.coherence is not None and frfs.coherence.shape == frfs.frf.shape
    code, text, err = run_cli(["identify", out, "--out", folder / "m.h5", "--json"], capsys)
    assert code == 0, err
    import json

    found = np.array([m["frequency_hz"] for m in json.loads(text)["modes"]])
    # every mode with V motion in the data's range is found within 0.1 %
    in_band = fn[fn < frfs.frequencies_hz[-1] * 0.95]
    err_rel = np.array([np.min(np.abs(found - f)) / f for f in in_band])
    assert in_band.size >= 6 and np.max(err_rel) < 1e-3


def test_double_impact_and_clipping_are_stated(hammer, capsys, tmp_path):
    _, sig, _ = hammer
    force = sig["force"].copy()
    n_rec = force.size // 5
    hit = np.flatnonzero(np.abs(force[n_rec : 2 * n_rec]) > 50)[0] + n_rec
    force[hit + 12 : hit + 16] += 60.0  # the hammer bounces 12 ms later on the 2nd hit
    accel = np.clip(sig["a1"], None, 0.5 * sig["a1"].max())  # flat tops
    np.savez(tmp_path / "bad.npz", force=force, a1=accel, time=sig["time"])
    argv = [
        "frf",
        tmp_path / "bad.npz",
        "--force-channel",
        "force",
        "--response",
        "a1=1V",
        "--reference",
        "1V",
    ]
    code, text, err = run_cli([*argv, "--out", tmp_path / "f.uff"], capsys)
    assert code == 0, err
    assert "1 of 5 hits are double impacts" in text and "4 hits averaged" in text
    assert "'a1' is clipped" in text
    assert "Warning" not in err and "Traceback" not in err


@pytest.mark.parametrize(
    ("case", "needle"),
    [
        ("no_force", "no channel 'force'"),
        ("unequal", "unequal lengths"),
        ("no_rate", "give --fs"),
        ("nan", "NaN"),
    ],
)
def test_bad_time_files_one_line(case, needle, hammer, capsys, tmp_path):
    _, sig, _ = hammer
    n = 20000
    arrays = {"force": sig["force"][:n], "a1": sig["a1"][:n], "time": sig["time"][:n]}
    if case == "no_force":
        arrays.pop("force")
    elif case == "unequal":
        arrays["a1"] = arrays["a1"][:-7]
    elif case == "no_rate":
        arrays.pop("time")
    elif case == "nan":
        arrays["a1"] = arrays["a1"].copy()
        arrays["a1"][100] = np.nan
    np.savez(tmp_path / "x.npz", **arrays)
    argv = [
        "frf",
        tmp_path / "x.npz",
        "--force-channel",
        "force",
        "--response",
        "a1=1V",
        "--reference",
        "1V",
    ]
    code, _, err = run_cli([*argv, "--out", tmp_path / "f.uff"], capsys)
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and needle in err, err
    assert not (tmp_path / "f.uff").exists()


def test_uff_time_records_with_disagreeing_rates(tmp_path, capsys):
    import pyuff

    sets = []
    for node, rate in ((1, 1024.0), (2, 1000.0)):
        sets.append(
            pyuff.prepare_58(
                func_type=1,
                rsp_node=node,
                rsp_dir=3,
                ref_node=1,
                ref_dir=3,
                ordinate_spec_data_type=12,
                orddenom_spec_data_type=0,
                abscissa_spec_data_type=17,
                abscissa_spacing=1,
                abscissa_min=0.0,
                abscissa_inc=1 / rate,
                x=np.arange(256) / rate,
                data=np.sin(np.arange(256) * 0.3),
                id1=f"ch{node}",
            )  # fmt: skip
        )
    pyuff.UFF(str(tmp_path / "t.uff")).write_sets(sets, mode="add")
    argv = ["frf", tmp_path / "t.uff", "--force-channel", "1V", "--response", "2V"]
    code, _, err = run_cli([*argv, "--out", tmp_path / "f.uff"], capsys)
    assert code == 2 and "sample rates differ" in err and len(err.strip().splitlines()) == 1


@pytest.fixture(scope="module")
def gvt_frfs(tmp_path_factory):
    if not (GVT / "run_Run1.mat").is_file():
        pytest.skip(f"shared data not found at {GVT} (clone ../shared beside the repo)")
    folder = tmp_path_factory.mktemp("gvt")
    paths = []
    for k in range(1, 6):
        out = folder / f"run{k}.uff"
        argv = [
            "frf", GVT / f"run_Run{k}.mat", "--force-channel", "Force",
            "--response", f"Accel1={2 * k - 1}V", "--response", f"Accel2={2 * k}V",
            "--reference", "25V", "--force-unit", "lbf", "--force-sensitivity", "0.4684",
            "--response-unit", "g", "--response-sensitivity", "1.028", "--out", out,
        ]  # fmt: skip
        assert main([str(a) for a in argv]) == 0
        paths.append(out)
    return folder, paths


def test_gvt_five_runs_identified_as_one_roving_test(gvt_frfs, capsys):
    folder, paths = gvt_frfs
    # the band the authors give for the input (GVT_Info.m FreqWin_Hz = [3 35])
    argv = ["identify", *paths, "--band", "3:35", "--out", folder / "m.h5", "--json"]
    code, text, err = run_cli(argv, capsys)
    assert code == 0, err
    import json

    summary = json.loads(text)
    found = np.array([m["frequency_hz"] for m in summary["modes"]])
    nearest = np.array([found[np.argmin(np.abs(found - p))] for p in GVT_PEAKS_HZ])
    # peak picks within 0.5 %; the shallow peaks are ranges of +-0.5 Hz in the log
    assert np.all(np.abs(nearest[[0, 3, 4, 6]] / GVT_PEAKS_HZ[[0, 3, 4, 6]] - 1) < 0.005)
    assert np.all(np.abs(nearest[[1, 2, 5]] - GVT_PEAKS_HZ[[1, 2, 5]]) < 0.5)
    assert len(found) <= len(GVT_PEAKS_HZ) + 1
    assert any("unscaled" in n for n in summary["notes"])
