"""``bayesupdate frf``: time signals to FRFs, checked on a simulated hammer test and a simulated
shaker sine sweep with harmonics (known modes), and on bad input (one line, exit 2, or a stated
warning; never a traceback or RuntimeWarning).  The real mAEWing1 sweep: tests/test_ema_gvt.py."""

import numpy as np
import pytest
from synthetic_models import exhaust_like_model

from bayesupdate.cli import main
from bayesupdate.ema.uff_io import read_uff58
from bayesupdate.ema.virtual_test import virtual_impact_test


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
    # a UFF time record carries its own step: --time is refused, --fs must agree with it
    code, _, err = run_cli([*argv, "--time", "t", "--out", tmp_path / "f.uff"], capsys)
    assert code == 2 and "a UFF time record carries its own time step" in err
    code, _, err = run_cli([*argv, "--fs", 1000, "--out", tmp_path / "f.uff"], capsys)
    assert code == 2 and "--fs 1000 Hz disagrees" in err and "1024 Hz from 1V's time step" in err


@pytest.mark.parametrize(
    ("stored", "extra", "needle"),
    [
        (None, ["--fs", 2048], "--fs 2048 Hz disagrees with the file's own sample rate, 1024 Hz"),
        (1024.0, ["--fs", 2048], "1024 Hz from 'fs'; --fs is for a file that has none"),
        (None, ["--time", "clock"], "no time variable 'clock'"),
        (1000.0, ["--time", "time"], "time variable 'time' gives 1024 Hz, 'fs' 1000 Hz"),
    ],
)
def test_a_sample_rate_that_contradicts_the_file_is_refused(
    stored, extra, needle, hammer, capsys, tmp_path
):
    """``--fs`` is for a file without a rate, and ``--time`` names a variable that is there and
    agrees with a stored rate; before, either was silently obeyed or silently ignored."""
    _, sig, _ = hammer
    arrays = {k: sig[k][:4096] for k in ("force", "a1", "time")}  # 1024 Hz
    if stored is not None:
        arrays["fs"] = np.array(stored)
    np.savez(tmp_path / "x.npz", **arrays)
    argv = ["frf", tmp_path / "x.npz", "--force-channel", "force", "--response", "a1=1V"]
    code, _, err = run_cli([*argv, "--reference", "1V", *extra, "--out", tmp_path / "f"], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and needle in err, err
    # the same --fs as the file's own rate, and --time naming its time vector, are taken
    agree = ["--fs", 1024] if stored is None else ["--fs", stored]
    code, _, err = run_cli([*argv, "--reference", "1V", *agree, "--out", tmp_path / "g"], capsys)
    assert code == 0, err


@pytest.mark.parametrize(
    ("df", "needle"),
    [
        (1e6, "shorter than 8; the coarsest line spacing is 128 Hz"),
        (0.01, "longer than the record (4096); the finest line spacing is 0.25 Hz"),
    ],
)
def test_a_line_spacing_outside_the_record_names_the_limit(df, needle, hammer, capsys, tmp_path):
    _, sig, _ = hammer
    np.savez(tmp_path / "x.npz", **{k: sig[k][:4096] for k in ("force", "a1", "time")})
    argv = ["frf", tmp_path / "x.npz", "--force-channel", "force", "--response", "a1=1V"]
    argv += ["--reference", "1V", "--method", "welch", "--df", df, "--out", tmp_path / "f"]
    code, _, err = run_cli(argv, capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and needle in err, err


@pytest.mark.parametrize(
    ("arrays", "extra", "needle"),
    [
        ({"fs": 0.0}, [], "its sample rate 'fs' is 0; give the file's rate in Hz"),
        ({"fs": np.nan}, [], "its sample rate 'fs' is nan"),
        ({}, ["--record", "0.001"], "--record 0.001 s: 1 samples at 1024 Hz; give at least"),
        ({"empty": True}, [], "the channels hold 0 samples; at least 8"),
        ({"no_time": True}, ["--fs", "inf"], "--fs inf: must be a finite rate > 0 Hz"),
    ],
)
def test_a_rate_or_record_no_spectrum_can_use_is_one_line(
    arrays, extra, needle, hammer, capsys, tmp_path
):
    """A stored rate of 0 or NaN, a record under 8 samples, empty channels, an infinite --fs:
    one line each (were internal ZeroDivisionError, ValueError and OverflowError)."""
    _, sig, _ = hammer
    n = 0 if arrays.get("empty") else 20000
    data = {k: sig[k][:n] for k in ("force", "a1", "time")}
    if arrays.get("no_time") or arrays.get("empty"):
        data.pop("time")
        data["fs"] = np.array(1024.0) if arrays.get("empty") else None
    data.update({k: np.array(v) for k, v in arrays.items() if k == "fs"})
    np.savez(tmp_path / "x.npz", **{k: v for k, v in data.items() if v is not None})
    argv = ["frf", tmp_path / "x.npz", "--force-channel", "force", "--response", "a1=1V"]
    argv += ["--reference", "1V", "--method", "impact", *extra, "--out", tmp_path / "f.uff"]
    code, _, err = run_cli(argv, capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and needle in err, err


def _sweep_test(folder):
    """A shaker sweep 2 -> 40 Hz in 60 s (then 4 s of rest) at 512 Hz whose force carries 10 % and
    5 % of 2nd and 3rd harmonic (up to 120 Hz), on 3 modes (8, 17, 31 Hz; 0.3, 0.5, 1 %
    damping), two accelerances computed exactly (FFT with 4x zero padding), 0.1 % noise."""
    from bayesupdate.ema.synthesis import synthesize_frf

    fs, n = 512.0, 32768
    t = np.arange(n) / fs
    phase = 2 * np.pi * (2.0 * t + 0.5 * 38.0 / 60.0 * t**2)
    force = np.sin(phase) + 0.1 * np.sin(2 * phase) + 0.05 * np.sin(3 * phase)
    force[t >= 60.0] = 0.0
    fn, zeta = np.array([8.0, 17.0, 31.0]), np.array([0.003, 0.005, 0.01])
    wd = 2 * np.pi * fn * np.sqrt(1 - zeta**2)
    poles = -zeta * 2 * np.pi * fn + 1j * wd
    residues = np.array([[1.0, 0.6, -0.8], [0.5, -1.0, 0.7]]) / (2j * wd)
    f_pad = np.fft.rfftfreq(4 * n, 1 / fs)
    h_pad = synthesize_frf(f_pad, poles, residues, "accelerance")
    acc = np.fft.irfft(h_pad * np.fft.rfft(force, 4 * n), 4 * n, axis=-1)[:, :n]
    noise = np.random.default_rng(0).standard_normal(acc.shape)
    acc += 1e-3 * acc.std(axis=1, keepdims=True) * noise
    np.savez(folder / "sweep.npz", force=force, a1=acc[0], a2=acc[1], time=t)
    return fn, zeta


def test_sine_sweep_with_harmonics_whole_record(tmp_path, capsys):
    import json

    fn, zeta = _sweep_test(tmp_path)
    argv = ["frf", tmp_path / "sweep.npz", "--force-channel", "force", "--response", "a1=1V"]
    argv += ["--response", "a2=2V", "--reference", "1V"]
    code, text, err = run_cli([*argv, "--out", tmp_path / "f.uff"], capsys)
    assert code == 0 and err == "", err
    assert "sine sweep up to" in text and "no coherence" in text
    frfs = read_uff58(tmp_path / "f.uff")
    # the fundamental ends at 40 Hz; its harmonics (to 120 Hz) are not written
    assert 39.5 < frfs.frequencies_hz[-1] < 42.0 and frfs.coherence is None
    modes = []
    for method in ("sweep", "welch"):
        out = tmp_path / f"{method}.uff"
        assert run_cli([*argv, "--method", method, "--out", out], capsys)[0] == 0
        identify = ["identify", out, "--out", tmp_path / "m.h5", "--json", "--force"]
        code, text, err = run_cli(identify, capsys)
        assert code == 0, err
        modes.append(json.loads(text)["modes"])
    found = np.array([m["frequency_hz"] for m in modes[0]])
    damping = np.array([m["damping_ratio"] for m in modes[0]])
    assert found.size == 3 and np.max(np.abs(found / fn - 1)) < 1e-3
    assert np.max(np.abs(damping / zeta - 1)) < 0.05
    # Welch segments of the same sweep (the former default) cut each ring-down from the force
    # that caused it: the 0.3 % mode comes out more than twice as damped
    welch = min(modes[1], key=lambda m: abs(m["frequency_hz"] - fn[0]))
    assert welch["damping_ratio"] > 2 * zeta[0]


def test_sweep_top_ignores_harmonics_at_force_dropouts():
    """While the structure absorbs the fundamental at a resonance (force drop-out), the
    shaker's 2nd harmonic dominates the force for a few seconds: the sweep's top stays the
    fundamental's (35 Hz, within one 1 Hz short-spectrum line), not the harmonic's 2 x 20 Hz;
    white noise is no sweep."""
    from bayesupdate.ema.excitation import sine_sweep_top

    fs = 2000.0
    t = np.arange(int(60 * fs)) / fs
    phase = 2 * np.pi * (1.0 * t + 0.5 * 34.0 / 60.0 * t**2)  # 1 -> 35 Hz
    fundamental = np.ones_like(t)
    for start in (11.0, 30.0):  # passing about 7.5 and 18 Hz: the force drops 30 dB
        fundamental[(t > start) & (t < start + 3.0)] = 0.03
    force = fundamental * np.sin(phase) + 0.1 * np.sin(2 * phase) + 0.03 * np.sin(3 * phase)
    assert 35.0 <= sine_sweep_top(force, fs) <= 36.5
    noise = np.random.default_rng(1).standard_normal((2, t.size))
    assert sine_sweep_top(noise, fs) is None
