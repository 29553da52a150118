"""Bad GVT runs for ``bayesupdate frf``: a run whose force channel is missing, whose force
signal is zero (a zero calibration in the DAQ) or whose force calibration is given as zero is
refused with one line naming the run (exit 2)."""

import numpy as np
import pytest
import scipy.io

from bayesupdate.cli import main

COLUMNS = ["DriveIn", "Force", "Accel1", "Accel2"]


def _run(path, columns, force_scale=1.0):
    """A MATLAB run like the GVT's: signalIn (n, 4) volts with chanInNameList, timeIn_s."""
    t = np.arange(4000) / 2000.0
    sweep = np.sin(2 * np.pi * (1 + 8 * t) * t)
    sig = np.stack([sweep, force_scale * sweep, 0.5 * sweep, 0.3 * sweep], axis=1)
    keep = [COLUMNS.index(c) for c in columns]
    scipy.io.savemat(
        path,
        {"signalIn": sig[:, keep], "chanInNameList": np.array(columns, dtype=object),
         "timeIn_s": t},
    )  # fmt: skip
    return path


def _frf(path, tmp_path, capsys, *extra) -> tuple[int, list[str]]:
    argv = [
        "frf", str(path), "--force-channel", "Force", "--response", "Accel1=1V",
        "--response", "Accel2=2V", "--reference", "25V", "--out", str(tmp_path / "o.uff"),
        *extra,
    ]  # fmt: skip
    code = main(argv)
    err = [x for x in capsys.readouterr().err.splitlines() if x.strip()]
    return code, err


@pytest.mark.parametrize(
    "columns, scale, extra, words",
    [
        (["DriveIn", "Accel1", "Accel2"], 1.0, (), "no channel 'Force'"),
        (COLUMNS, 0.0, (), "'Force' is constant"),
        (COLUMNS, 1.0, ("--force-sensitivity", "0"), "--force-sensitivity 0 must be"),
    ],
)
def test_bad_run_named_in_one_line(tmp_path, capsys, columns, scale, extra, words):
    path = _run(tmp_path / "run_Run7.mat", columns, scale)
    code, err = _frf(path, tmp_path, capsys, *extra)
    assert code == 2
    assert len(err) == 1 and "run_Run7.mat" in err[0] and words in err[0], err
