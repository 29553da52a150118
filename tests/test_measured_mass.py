"""The measured mass is test data: carried by ``ModalData``, read from
paper:ema, CSV, inline study data and HDF5 results, used by the objective and the likelihood by
default, switched off by ``--no-mass``."""

import json

import numpy as np
import pytest

from bayesupdate.cli import main
from bayesupdate.config import parse_study
from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.data import load_modal_data
from bayesupdate.inference.results import read_result
from bayesupdate.modal_data import ModalData
from bayesupdate.models.exhaust_paper import MEASURED_MASS_KG, PAPER_MASS_SD_REL
from bayesupdate.pipelines.study import DEFAULT_MASS_WEIGHT, prepare

SHEAR_STUDY = """
[model]
source = "shear_building"
[data]
source = "{csv}"
{mass}
[optimizer]
starts = 4
"""


def test_paper_ema_carries_the_weighed_mass():
    data = load_modal_data("paper:ema")
    assert data.mass_kg == 12.29 == MEASURED_MASS_KG
    assert data.mass_sd_rel == pytest.approx(PAPER_MASS_SD_REL)
    assert data.subset([0, 3]).mass_kg == 12.29  # a subset of the modes keeps the mass


def test_default_study_on_paper_ema_uses_the_mass_in_objective_and_likelihood():
    prepared = prepare(parse_study({"model": {"source": "exhaust"}}))
    objective = prepared.problem.objective
    assert objective.mass_target_kg == 12.29 and objective.mass_weight == DEFAULT_MASS_WEIGHT
    assert prepared.likelihood.mass_sd_rel == pytest.approx(0.01)
    off = prepare(parse_study({"objective": {"use_measured_mass": False}}))
    assert off.problem.objective.mass_weight == 0.0 and off.likelihood.mass_sd_rel is None
    assert off.problem.data.mass_kg is None


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), float("inf")])
def test_non_positive_mass_is_rejected(bad):
    with pytest.raises(BayesUpdateError, match="mass_kg must be a finite number > 0"):
        ModalData(np.array([1.0, 2.0]), mass_kg=bad)
    with pytest.raises(BayesUpdateError, match="mass_sd_kg needs mass_kg"):
        ModalData(np.array([1.0, 2.0]), mass_sd_kg=0.1)


def _study(tmp_path, mass_lines: str = "", csv_mass: str = ""):
    csv = tmp_path / "f.csv"
    csv.write_text(f"{csv_mass}frequency_hz\n4.30\n10.80\n")
    path = tmp_path / "study.toml"
    path.write_text(SHEAR_STUDY.format(csv=csv, mass=mass_lines))
    return path


def test_csv_comment_lines_carry_a_mass(tmp_path):
    data = load_modal_data(
        str(_study(tmp_path, csv_mass="# mass_kg = 3.5\n# mass_sd_kg = 0.07\n").parent / "f.csv")
    )
    assert data.mass_kg == 3.5 and data.mass_sd_rel == pytest.approx(0.02)


def test_study_mass_reaches_the_result_file_and_no_mass_switches_it_off(tmp_path, capsys):
    study = _study(tmp_path, "mass_kg = 2.0\nmass_sd_kg = 0.02")
    out = tmp_path / "cal.h5"
    assert main(["calibrate", str(study), "--json", "--out", str(out)]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["measured_mass_kg"] == 2.0 and result["mass_weight"] == DEFAULT_MASS_WEIGHT
    attrs = read_result(out)["inputs"]["attrs"]
    assert attrs["measured_mass_kg"] == 2.0 and attrs["measured_mass_sd_kg"] == 0.02
    assert main(["calibrate", str(study), "--json", "--no-mass"]) == 0
    off = json.loads(capsys.readouterr().out)
    assert off["measured_mass_kg"] is None and off["mass_weight"] == 0.0
    assert off["objective"] < 1e-12  # two stiffnesses fit two frequencies


def test_bad_measured_mass_in_a_study_exits_2_with_one_line(tmp_path, capsys):
    study = _study(tmp_path, "mass_kg = -3.0")
    assert main(["calibrate", str(study)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "mass_kg must be a finite number > 0" in err


def test_modes_file_round_trips_the_measured_mass(tmp_path):
    from bayesupdate.ema.modal_h5 import read_modal_h5, write_modal_h5

    data = ModalData(np.array([9.0, 11.0]), mass_kg=12.29, mass_sd_kg=0.05, source="weighed")
    write_modal_h5(tmp_path / "m.h5", data)
    back = read_modal_h5(tmp_path / "m.h5")
    assert back.mass_kg == 12.29 and back.mass_sd_kg == 0.05
    write_modal_h5(tmp_path / "n.h5", ModalData(np.array([9.0])))
    assert read_modal_h5(tmp_path / "n.h5").mass_kg is None
