"""One reader of a study's measured mass keys (``pipelines.study.study_mass_terms``): calibrate's
``prepare`` and discover's ``study_mass_properties`` take ``[data] mass / mass_sd`` and the
``[objective]`` mass term from it, so they fit the same numbers."""

import pytest

from bayesupdate.config import parse_study
from bayesupdate.pipelines.discover import study_mass_properties
from bayesupdate.pipelines.model_source import study_model
from bayesupdate.pipelines.study import prepare, study_data, study_mass_terms

LB = 0.45359237  # kg, exact (international avoirdupois pound)


def _study(**likelihood):
    return parse_study({
        "model": {"source": "exhaust"},
        "data": {"source": "paper:ema", "mass": "27 lb", "mass_sd": "2 %"},
        "likelihood": likelihood,
    })  # fmt: skip


def test_the_mass_keys_in_units_are_read_once_for_calibrate_and_discover():
    study = _study()
    data, _ = study_data(study)
    model = study_model(study)
    read, objective = study_mass_terms(study, data, model)
    assert read.mass_kg == pytest.approx(27 * LB, rel=1e-12)
    assert read.mass_sd_kg == pytest.approx(0.02 * 27 * LB, rel=1e-12)
    assert objective.mass_target_kg == read.mass_kg and objective.mass_unit == "kg"
    assert objective.mass_weight == 10.0 and objective.mass_properties is None
    found, theirs = study_mass_properties(study, data, model)
    prepared = prepare(study)
    assert found.mass_kg == read.mass_kg and found.mass_sd_kg == read.mass_sd_kg
    assert theirs == objective == prepared.problem.objective


def test_discover_applies_the_likelihood_mass_sd_to_the_data_as_calibrate_does():
    study = _study(mass_sd=0.05)
    data, _ = study_data(study)
    found, _ = study_mass_properties(study, data, study_model(study))
    prepared = prepare(study)
    assert found.mass_sd_rel == pytest.approx(0.05, rel=1e-12)
    assert prepared.likelihood.mass_sd_rel == 0.05
