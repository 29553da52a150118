"""``bayesupdate identify`` end to end on a virtual test written as UFF 58."""

import json

import numpy as np
import pytest

from bayesupdate.cli import main
from bayesupdate.ema.modal_h5 import read_modal_h5
from bayesupdate.ema.uff_io import write_uff58
from bayesupdate.ema.virtual_test import virtual_impact_test

FN = np.array([18.0, 33.0, 52.0])
ZETA = np.array([0.01, 0.015, 0.02])


@pytest.fixture(scope="module")
def uff_file(tmp_path_factory):
    x = np.linspace(0, 1, 5)
    shapes = np.stack([np.cos(np.pi * x), np.cos(2 * np.pi * x), np.cos(3 * np.pi * x)], 1)
    labels = tuple(f"{k}V" for k in range(1, 6))
    layout = [("1V", lab) for lab in labels]
    frfs = virtual_impact_test(
        FN,
        ZETA,
        shapes / 2,
        labels,
        layout=layout,
        f_max_hz=64.0,
        sample_rate_hz=512.0,
        pulse_s=0.008,
        duration_s=8.0,
        noise=0.005,
        seed=1,
    )
    path = tmp_path_factory.mktemp("cli") / "test.uff"
    write_uff58(path, frfs)
    return path


def test_identify_cli_json_and_output(uff_file, tmp_path, capsys):
    out = tmp_path / "modes.h5"
    plots = tmp_path / "plots"
    code = main(["identify", str(uff_file), "--out", str(out), "--plots", str(plots), "--json"])
    assert code == 0
    summary = json.loads(capsys.readouterr().out)
    freqs = np.array([m["frequency_hz"] for m in summary["modes"]])
    assert freqs.size == 3
    assert np.max(np.abs(freqs - FN) / FN) < 0.002
    assert all(m["stable_orders"] >= 4 and m["mpc"] > 0.95 for m in summary["modes"])
    modes = read_modal_h5(out)
    assert np.allclose(modes.frequencies_hz, freqs)
    for name in ("stabilization", "frf_fit", "automac", "mode_shapes"):
        assert (plots / f"{name}.png").stat().st_size > 10_000


def test_identify_cli_band(uff_file, tmp_path, capsys):
    out = tmp_path / "band.h5"
    assert (
        main(
            [
                "identify",
                str(uff_file),
                "--band",
                "25:60",
                "--max-order",
                "30",
                "--out",
                str(out),
                "--json",
            ]
        )
        == 0
    )
    freqs = [m["frequency_hz"] for m in json.loads(capsys.readouterr().out)["modes"]]
    assert np.allclose(freqs, FN[1:], rtol=0.002)


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--band", "70:90"], "outside"),
        (["--band", "20:23", "--max-order", "60"], "too few"),
        (["--band", "abc"], "LO:HI"),
    ],
)
def test_identify_cli_user_errors_leave_no_output(uff_file, tmp_path, capsys, extra, message):
    out = tmp_path / "x.h5"
    assert main(["identify", str(uff_file), "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1
    assert not out.exists()


def test_identify_cli_truncated_file(uff_file, tmp_path, capsys):
    cut = tmp_path / "cut.uff"
    text = uff_file.read_text()
    cut.write_text(text[: len(text) // 3])
    assert main(["identify", str(cut), "--out", str(tmp_path / "y.h5")]) == 2
    assert "truncated" in capsys.readouterr().err
    assert not (tmp_path / "y.h5").exists()
