"""``bayesupdate discover`` bad input: one-line errors (exit 2) before any computation, and no
output file left behind."""

import json

import numpy as np
import pytest

from bayesupdate.cli import main


@pytest.fixture()
def csv_three_modes(tmp_path):
    path = tmp_path / "three.csv"
    path.write_text("frequency_hz\n9.2\n11.7\n25.6\n")
    return path


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--effect", "added_mas@14:m=0.4"], "unknown kind"),
        (["--effect", "added_mass@14:m=9"], "outside the bounds"),
        (["--effect", "added_mass@99:m=0.1"], "unknown location"),
        (["--kinds", "added_mass,teleport"], "unknown effect kind"),
        (["--sigma", "-0.1"], "sigma"),
    ],
)
def test_bad_effects_and_settings(tmp_path, capsys, extra, message):
    out = tmp_path / "r.h5"
    code = main(
        ["discover", "--model", "exhaust", "--data", "paper:ema", "--out", str(out), *extra]
    )
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_too_few_modes_cannot_decide(tmp_path, capsys, csv_three_modes):
    out = tmp_path / "r.h5"
    code = main(
        ["discover", "--model", "exhaust", "--data", str(csv_three_modes), "--out", str(out)]
    )
    err = capsys.readouterr().err
    # 5 design variables + 1 effect parameter need at least 7 modes
    assert code == 2 and "cannot decide" in err and "at least 7 modes" in err
    assert not out.exists()


def test_study_file_tables_are_strict(tmp_path, capsys):
    study = tmp_path / "s.toml"
    study.write_text('[model]\nsource = "exhaust"\n[discovery]\nthreshold = 3\n')
    code = main(["discover", str(study)])
    assert code == 2 and "discovery.threshold: unknown key" in capsys.readouterr().err
    study.write_text('[model]\nsource = "exhaust"\n[effects]\nadd = ["bend_flexibility@nowhere"]\n')
    code = main(["discover", str(study)])
    assert code == 2 and "unknown location" in capsys.readouterr().err


def test_existing_output_is_refused(tmp_path, capsys):
    out = tmp_path / "r.h5"
    out.write_text("keep me")
    code = main(["discover", "--model", "exhaust", "--data", "paper:ema", "--out", str(out)])
    assert code == 2 and "already exists" in capsys.readouterr().err
    assert out.read_text() == "keep me"


def test_simulate_geometry_changes_only_the_true_structure(tmp_path, capsys):
    """--geometry: one exhaust geometry quantity of the 'true' structure (an out-of-library
    change for discovery); an unknown name or a non-length is a one-line error."""
    out = tmp_path / "t.uff"
    assert main(["simulate", "--out", str(out), "--json", "--noise", "0"]) == 0
    base = json.loads(capsys.readouterr().out)["true_frequencies_hz"]
    assert main(["simulate", "--geometry", "tail_length=0.15", "--out", str(out), "--force",
                 "--json", "--noise", "0"]) == 0  # fmt: skip
    longer = json.loads(capsys.readouterr().out)
    assert longer["geometry"] == ["tail_length=0.15"]
    shift = np.abs(np.array(longer["true_frequencies_hz"]) / np.array(base) - 1)
    assert 0.005 < shift.max() < 0.05  # a 50 mm longer tail pipe moves a mode by ~0.8 %
    for bad, words in (("tail_lenth=0.15", "unknown quantities"), ("tail_length=-1", "> 0 m")):
        assert main(["simulate", "--geometry", bad, "--out", str(out), "--force"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and words in err
