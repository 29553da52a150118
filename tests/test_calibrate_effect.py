"""calibrate/sample take the effects discovery names (--effect or a study's [effects] table).

Both runs skip the full-model Nelder-Mead polish (--no-polish, ``[optimizer] polish = false``):
what is checked is that the effect's parameter is calibrated with the design variables (named,
within its kind's bounds, stored), which the reduced-basis search already decides; the polish,
checked elsewhere (test_calibration_exhaust), would cost most of the run."""

import json

import h5py

from bayesupdate.cli import main


def test_calibrate_with_an_effect_calibrates_its_parameter_too(tmp_path, capsys):
    out = tmp_path / "cal.h5"
    code = main(
        [
            "calibrate",
            "--model",
            "exhaust",
            "--data",
            "paper:ema",
            "--starts",
            "1",
            "--no-polish",
            "--effect",
            "bend_flexibility@hot_bend1:factor=3",
            "--out",
            str(out),
            "--json",
        ]
    )
    assert code == 0
    result = json.loads(capsys.readouterr().out)
    factor = result["parameters"]["bend_flexibility@hot_bend1:factor"]
    assert 1.0 <= factor <= 6.0  # the kind's bounds
    assert len(result["parameters"]) == 6
    with h5py.File(out) as h5:
        assert "bend_flexibility@hot_bend1:factor" in list(h5["/optimum"].attrs["parameter_names"])


def test_study_file_effects_table(tmp_path, capsys):
    study = tmp_path / "s.toml"
    study.write_text(
        '[model]\nsource = "exhaust"\n[data]\nsource = "paper:ema"\n'
        '[optimizer]\nstarts = 1\npolish = false\n[effects]\nadd = ["added_mass@14:m=0.2"]\n'
    )
    code = main(["calibrate", str(study), "--json"])
    assert code == 0
    assert "added_mass@14:m" in json.loads(capsys.readouterr().out)["parameters"]
