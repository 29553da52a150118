"""Reproducibility: a seeded run, repeated (in this process and in a fresh one), writes the same
numbers: every dataset and every attribute of the HDF5 result, except wall-clock times.

Covers calibrate + sample (shear building), simulate -> identify (exhaust virtual test).
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

from bayesupdate.cli import main
from bayesupdate.ema.uff_io import read_uff58

EXE = Path(sys.executable).with_name("bayesupdate")

#: attributes that are clocks, not results
TIME_ATTRS = {"created_utc", "wall_s", "timings_json"}

STUDY = """
[model]
source = "shear_building"
[data]
frequencies_hz = [4.30, 10.80]
weights = [1.0, 0.5]
[parameters.theta_1]
bounds = [0.2, 3.0]
prior = {kind = "lognormal", mu = 0.0, sigma = 0.5}
[parameters.theta_2]
bounds = [0.2, 3.0]
[optimizer]
starts = 6
[likelihood]
sigma_prior = {kind = "halfnormal", scale = 0.1}
[sampler]
walkers = 12
steps = 300
check_every = 100
min_autocorr_times = 1e9
predictive_draws = 30
adapt_steps = 60
"""


def h5_numbers(path: Path, skip: frozenset = frozenset()) -> dict:
    """Every dataset and attribute of an HDF5 file, keyed by path (clock attributes and the
    attribute names in ``skip`` left out)."""
    out = {}
    with h5py.File(path) as h5:

        def visit(name, obj):
            if isinstance(obj, h5py.Dataset):
                out[name] = obj[()]
            for key, value in obj.attrs.items():
                if key not in TIME_ATTRS | skip:
                    out[f"{name}@{key}"] = value

        visit("/", h5)
        h5.visititems(visit)
    return out


def assert_same_numbers(a: Path, b: Path, skip: frozenset = frozenset()) -> int:
    """Bitwise equality of two results (NaN == NaN); returns the number of entries compared."""
    na, nb = h5_numbers(a, skip), h5_numbers(b, skip)
    assert sorted(na) == sorted(nb)
    for key in na:
        x, y = np.asarray(na[key]), np.asarray(nb[key])
        assert x.dtype == y.dtype and x.shape == y.shape, key
        if x.dtype.kind in "fc":
            assert np.array_equal(x, y, equal_nan=True), key
        else:
            assert np.array_equal(x, y), key
    return len(na)


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    path = tmp_path_factory.mktemp("study") / "study.toml"
    path.write_text(STUDY)
    return path


@pytest.fixture(scope="module")
def in_process(study, tmp_path_factory):
    """command -> the result file of its seed-11 run in this process, run once for the module
    (the fresh-process comparison and the other-seed check read the same run)."""
    runs = {}

    def run(command: str) -> Path:
        if command not in runs:
            out = tmp_path_factory.mktemp(command) / "a.h5"
            assert main([command, str(study), "--out", str(out), "--seed", "11", "--json"]) == 0
            runs[command] = out
        return runs[command]

    return run


@pytest.mark.parametrize("command", ["calibrate", "sample"])
def test_seeded_run_in_process_and_in_a_fresh_process_are_identical(
    command, study, in_process, tmp_path
):
    a, b = in_process(command), tmp_path / "b.h5"
    proc = subprocess.run(
        [str(EXE), command, str(study), "--out", str(b), "--seed", "11", "--json"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    n = assert_same_numbers(a, b)
    assert n > (60 if command == "sample" else 30)
    with h5py.File(a) as h5:
        if command == "sample":
            chain = h5["posterior/chain"][()]
            assert chain.shape == (300, 12, 3)  # theta_1, theta_2, sigma
            # the study's three adaptation stages of 60 steps ran (not the default 3 x 250)
            assert json.loads(h5["posterior/state"].attrs["moves_json"])["adapt_steps"] == 180
            assert np.unique(chain[-1, :, 0]).size == 12  # walkers moved apart: a real run


def test_another_seed_gives_another_chain(study, in_process, tmp_path):
    # the equality above is not vacuous: the seed reaches the sampler
    a, b = in_process("sample"), tmp_path / "b.h5"
    assert main(["sample", str(study), "--out", str(b), "--seed", "12", "--json"]) == 0
    with h5py.File(a) as ha, h5py.File(b) as hb:
        assert not np.array_equal(ha["posterior/chain"][()], hb["posterior/chain"][()])


def test_simulate_then_identify_is_reproducible(tmp_path, capsys):
    uffs = [tmp_path / "a.uff", tmp_path / "b.uff"]
    for uff in uffs:
        args = ["simulate", "--model", "exhaust", "--noise", "0.01", "--seed", "4"]
        assert main([*args, "--out", str(uff)]) == 0
    fa, fb = read_uff58(uffs[0]), read_uff58(uffs[1])
    assert np.array_equal(fa.frf, fb.frf) and np.array_equal(fa.frequencies_hz, fb.frequencies_hz)
    assert fa.response_labels == fb.response_labels
    other = tmp_path / "c.uff"
    args = ["simulate", "--model", "exhaust", "--noise", "0.01", "--seed", "5"]
    assert main([*args, "--out", str(other)]) == 0
    assert not np.array_equal(read_uff58(other).frf, fa.frf)  # the noise follows the seed

    modes = [tmp_path / "a.h5", tmp_path / "b.h5"]
    for uff, out in zip(uffs, modes, strict=True):
        assert main(["identify", str(uff), "--band", "5:60", "--out", str(out)]) == 0
    # (the input file names differ by construction)
    assert assert_same_numbers(*modes, skip=frozenset({"source"})) > 5
    capsys.readouterr()


@pytest.mark.slow
@pytest.mark.skipif(
    not os.environ.get("BAYESUPDATE_DEMO_TEST"),
    reason="two `demo --quick` runs take ~2 min; set BAYESUPDATE_DEMO_TEST=1 to run",
)
def test_demo_quick_twice_gives_identical_results(tmp_path):
    if not (Path(__file__).parents[1] / "bayesupdate" / "commands" / "demo.py").exists():
        pytest.skip("demo command not installed")
    runs = [tmp_path / "one", tmp_path / "two"]
    for folder in runs:
        folder.mkdir()
        # the same relative --out, so the paths recorded in the results are the same
        proc = subprocess.run(
            [str(EXE), "demo", "--out", "demo", "--quick", "--seed", "0"],
            cwd=folder,
            capture_output=True,
            text=True,
            timeout=600,
        )
        assert proc.returncode == 0, proc.stderr
    results = sorted(p.name for p in (runs[0] / "demo").glob("*.h5"))
    assert len(results) >= 2
    for name in results:
        assert assert_same_numbers(runs[0] / "demo" / name, runs[1] / "demo" / name) > 5
    uffs = [read_uff58(next((r / "demo").glob("*.uff"))) for r in runs]
    assert np.array_equal(uffs[0].frf, uffs[1].frf)
