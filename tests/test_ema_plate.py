"""Real measured data (plate_sweep, 5 repetitions): repetitions agree, sdypy-EMA agrees."""

import importlib.util
import os
from pathlib import Path

import numpy as np
import pytest

STUDY = Path(__file__).resolve().parents[1] / "studies" / "plate_sweep.py"


def _study():
    spec = importlib.util.spec_from_file_location("plate_sweep_study", STUDY)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def runs():
    study = _study()
    files = study.repetition_files()
    if len(files) < 5 or not os.access(files[0], os.R_OK):
        pytest.skip("plate_sweep data not available")
    from bayesupdate.ema import identify

    out = []
    for path in files:
        frfs = study.plate_frf(path)
        out.append((frfs, identify(frfs).modes))
    return study, out


def test_repetitions_agree_within_half_percent(runs):
    study, results = runs
    groups = study.group_modes([m.frequencies_hz for _, m in results])
    in_all = [g for g in groups if len(g) == len(results)]
    # five or more modes are found in every repetition, among them the 126 and 214 Hz peaks
    assert len(in_all) >= 5
    means = np.array([np.mean(g) for g in in_all])
    assert np.min(np.abs(means - 126.0)) < 1.5 and np.min(np.abs(means - 214.0)) < 2.0
    scatter = np.array([np.std(g, ddof=1) / np.mean(g) for g in in_all])
    assert scatter.max() <= 0.005


def test_sdypy_lsce_agrees_on_same_frf(runs):
    pytest.importorskip("sdypy.EMA")
    study, results = runs
    frfs, modes = results[0]
    peer = study.sdypy_frequencies(frfs, modes.frequencies_hz, 0.0)
    # modes both find: sdypy's nearest stable pole within 2 %; those must agree within 1 %
    rel = np.abs(peer - modes.frequencies_hz) / modes.frequencies_hz
    both = rel < 0.02
    assert both.sum() >= 5
    assert rel[both].max() <= 0.01
