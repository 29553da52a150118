"""The real mAEWing1 ground vibration test (../shared/data/gvt_maewing1): a shaker sine
sweep of about 1-35 Hz, 10 accelerometers roved over 5 runs, no driving point.

User path with default settings: ``bayesupdate frf`` per run, then one ``bayesupdate identify``
over the 5 files, automatic band and the band the authors give (GVT_Info.m FreqWin_Hz [3 35]),
both estimators.  References: the authors' peak picks (explog.txt: 7.797, 19.06, 23.82, 31.78
Hz) and their ranges for shallow or multiple peaks (8.8-9.8, 15.4-16.4, 30.2-31.2 Hz).  Skipped
when the data are not beside the checkout.
"""

import contextlib
import io
import json

import numpy as np
import pytest
from gvt_runs import GVT, frf_argv

from bayesupdate.cli import main
from bayesupdate.ema.uff_io import read_uff58

PEAK_PICKS_HZ = np.array([7.797, 19.06, 23.82, 31.78])
#: explog.txt "Peak Picking" ranges, a) to g)
RANGES_HZ = [(7.3, 8.3), (8.8, 9.8), (15.4, 16.4), (18.5, 19.5), (23.3, 24.3), (30.2, 31.2),
             (31.5, 32.5)]  # fmt: skip
SHALLOW_RANGES_HZ = [RANGES_HZ[1], RANGES_HZ[2], RANGES_HZ[5]]


def run_cli(argv, capsys):
    code = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.fixture(scope="module")
def gvt_frfs(tmp_path_factory):
    if not (GVT / "run_Run1.mat").is_file():
        pytest.skip(f"shared data not found at {GVT} (clone ../shared beside the repo)")
    folder = tmp_path_factory.mktemp("gvt")
    paths, texts = [], []
    for k in range(1, 6):
        out = folder / f"run{k}.uff"
        argv = frf_argv(k, out)
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            assert main([str(a) for a in argv]) == 0
        paths.append(out)
        texts.append(buf.getvalue())
    return folder, paths, texts


def test_sweep_frfs_end_at_the_sweep_top(gvt_frfs, capsys):
    """The force above 35 Hz (6-15 dB below its in-band level, coherence 0.97-0.99) is the
    shaker's harmonics: the lines written end where the sweep's fundamental ends."""
    _, paths, texts = gvt_frfs
    for path, text in zip(paths, texts, strict=True):
        assert "sine sweep up to" in text and "hold its harmonics" in text
        frfs = read_uff58(path)
        assert 34.5 < frfs.frequencies_hz[-1] < 36.0
        assert frfs.frequencies_hz[0] < 3.0
        assert frfs.df_hz < 0.02  # one whole-record spectrum: 1/60 s lines


def _identify(paths, folder, method, band, capsys):
    argv = ["identify", *paths, "--out", folder / "m.h5", "--json", "--force", "--method", method]
    code, text, err = run_cli(argv + (["--band", band] if band else []), capsys)
    assert code == 0, err
    return json.loads(text)


@pytest.mark.parametrize("method", ["lsce", "plscf"])
@pytest.mark.parametrize("band", [None, "3:35"])
def test_peak_picks_found_in_both_bands(gvt_frfs, method, band, capsys):
    folder, paths, _ = gvt_frfs
    summary = _identify(paths, folder, method, band, capsys)
    found = np.array([m["frequency_hz"] for m in summary["modes"]])
    nearest = np.array([found[np.argmin(np.abs(found - p))] for p in PEAK_PICKS_HZ])
    assert np.max(np.abs(nearest / PEAK_PICKS_HZ - 1)) < 0.005, found
    for lo, hi in SHALLOW_RANGES_HZ:
        assert np.any((found >= lo) & (found <= hi)), (lo, hi, found)
    others = [x for x in found if not any(lo <= x <= hi for lo, hi in RANGES_HZ)]
    # nothing at the shaker's harmonics above the sweep; at most one mode outside the authors'
    # ranges (LSCE, automatic band: the broad hump near 33.9 Hz of accelerometers 7-10)
    assert found.max() < 35.2 and len(others) <= 1, found
    assert any("unscaled" in n for n in summary["notes"])


def test_same_modes_whichever_band(gvt_frfs, capsys):
    """Band invariance: the peak-pick modes move by less than 0.1 % between the automatic
    band and bands typed around them (one band of order 60 over 3-35 Hz had the 31.7 Hz mode
    at 31.62 Hz; band limits at 23.77 Hz lost the 23.81 Hz mode)."""
    folder, paths, _ = gvt_frfs
    estimates = []
    for band in (None, "3:35", "5:35", "4:34"):
        found = np.array(
            [m["frequency_hz"] for m in _identify(paths, folder, "lsce", band, capsys)["modes"]]
        )
        estimates.append([found[np.argmin(np.abs(found - p))] for p in PEAK_PICKS_HZ])
    estimates = np.array(estimates)
    spread = (estimates.max(axis=0) - estimates.min(axis=0)) / PEAK_PICKS_HZ
    assert np.all(np.abs(estimates / PEAK_PICKS_HZ - 1) < 0.005)
    assert spread.max() < 0.001, estimates
