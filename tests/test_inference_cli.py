"""CLI calibrate/sample: JSON keys, result file schema, reproducibility, Ctrl-C and --resume."""

import contextlib
import io
import json
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np
import pytest

from bayesupdate.cli import main
from bayesupdate.inference import load_modal_data, read_result, to_datatree
from bayesupdate.inference.likelihood import LogPosterior
from bayesupdate.inference.moves.coverage import COVERAGE_DRAWS
from bayesupdate.inference.sampling import ADAPT_STEPS, check_schedule
from bayesupdate.models.exhaust_paper import TABLE2_EMA_HZ

STUDY = """
[model]
source = "shear_building"
[data]
source = "{csv}"
[parameters.theta_1]
bounds = [0.2, 3.0]
[parameters.theta_2]
bounds = [0.2, 3.0]
[optimizer]
starts = 8
[sampler]
walkers = 16
steps = 400
check_every = 100
min_autocorr_times = 1e9
predictive_draws = 50
"""


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """The study file (read only by the tests, so one for the module)."""
    folder = tmp_path_factory.mktemp("study")
    csv = folder / "freqs.csv"
    csv.write_text("# two floors\nmode,frequency_hz,weight\n1,4.30,1\n2,10.80,1\n")
    path = folder / "study.toml"
    path.write_text(STUDY.format(csv=csv))
    return path


@dataclass(frozen=True)
class SampleRun:
    """One ``sample`` run of the study: its result file, the JSON it printed, its stderr and
    the number of ``LogPosterior`` calls it made."""

    out: Path
    summary: dict
    err: str
    calls: int


def _sample_run(study: Path, out: Path, *args: str) -> SampleRun:
    """``sample`` the study into ``out`` (each run of the same seed is the same chain, so the
    tests that only read a run share one: the chain's bits are checked against a second run in
    test_sample_json_reproducible_file_and_datatree and tests/test_reproducibility.py)."""
    original, calls = LogPosterior.__call__, [0]

    def counted(self, theta):
        calls[0] += 1
        return original(self, theta)

    stdout, stderr = io.StringIO(), io.StringIO()
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(LogPosterior, "__call__", counted)
        with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
            code = main(["sample", str(study), "--out", str(out), "--json", *args])
    assert code == 0, stderr.getvalue()
    summary = json.loads(stdout.getvalue().splitlines()[-1])
    return SampleRun(out, summary, stderr.getvalue(), calls[0])


@pytest.fixture(scope="module")
def reference(study, tmp_path_factory) -> SampleRun:
    """The study's chain at its own seed, uninterrupted."""
    return _sample_run(study, tmp_path_factory.mktemp("reference") / "ref.h5")


@pytest.fixture(scope="module")
def seed3(study, tmp_path_factory) -> SampleRun:
    """The study's chain with ``--seed 3``."""
    return _sample_run(study, tmp_path_factory.mktemp("seed3") / "post.h5", "--seed", "3")


def test_csv_and_paper_data():
    data = load_modal_data("paper:ema")
    np.testing.assert_array_equal(data.frequencies_hz, TABLE2_EMA_HZ)


def test_calibrate_json_and_file(study, tmp_path, capsys):
    out = tmp_path / "cal.h5"
    assert main(["calibrate", str(study), "--out", str(out), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert set(result) == {
        "parameters",
        "objective",
        "mass_kg",
        "frequencies_hz",
        "targets_hz",
        "starts",
        "converged_starts",
        "measured_mass_kg",
        "mass_weight",
        "mass_properties",
        "compute",
        "test_modes",
        "pairing",
        "warnings",
        "timings",
    }
    # frequencies only: paired by tracking the model's shapes, nothing refused or warned
    assert result["pairing"]["method"] == "tracked" and result["pairing"]["refused"] == []
    assert result["test_modes"] == [1, 2] and result["warnings"] == []
    assert result["compute"] == {"kind": "serial", "workers": 1}
    assert result["measured_mass_kg"] is None and result["mass_weight"] == 0.0  # none measured
    assert result["mass_properties"] == []
    assert result["targets_hz"] == [4.30, 10.80]
    assert result["objective"] < 1e-14  # two frequencies, two stiffnesses: an exact fit
    assert result["starts"] == 9 and result["converged_starts"] == 9
    saved = read_result(out)
    assert saved["attrs"]["schema"] == "bayesupdate-result/1"
    assert saved["attrs"]["kind"] == "calibration"
    np.testing.assert_allclose(saved["optimum"]["residuals"]["model_hz"], [4.30, 10.80], rtol=1e-7)
    # an existing output without --force: exit 2, one line, file untouched
    before = out.read_bytes()
    assert main(["calibrate", str(study), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "already exists" in err and err.count("\n") == 1
    assert out.read_bytes() == before


def test_bad_input_leaves_no_file(tmp_path, capsys):
    out = tmp_path / "x.h5"
    bad = tmp_path / "bad.toml"
    bad.write_text('[model]\nsource = "shear_building"\n[sampler]\nwalkerz = 4\n')
    assert main(["sample", str(bad), "--out", str(out)]) == 2
    assert "sampler.walkerz: unknown key" in capsys.readouterr().err
    assert (
        main(
            [
                "calibrate",
                "--model",
                "shear_building",
                "--data",
                str(tmp_path / "no.csv"),
                "--out",
                str(out),
            ]
        )
        == 2
    )
    assert not out.exists()
    assert [p.name for p in tmp_path.iterdir()] == ["bad.toml"]


def test_sample_json_reproducible_file_and_datatree(study, seed3, tmp_path, capsys):
    outs = [seed3.out, tmp_path / "b.h5"]
    assert main(["sample", str(study), "--out", str(outs[1]), "--json", "--seed", "3"]) == 0
    result = json.loads(capsys.readouterr().out.splitlines()[-1])
    # how the run was executed depends on the machine at its start (times; a split of the
    # walkers' batches when a core is free): the rest, and the chain below, are the same bits
    volatile = {k: result[k] for k in ("wall_s", "timings", "split")}
    assert result == {**seed3.summary, **volatile}
    assert set(result["parameters"]) == {"theta_1", "theta_2"}
    for row in result["parameters"].values():
        assert set(row) == {"mean", "sd", "hdi_low", "hdi_high", "r_hat", "ess_bulk"}
        assert row["hdi_low"] < row["mean"] < row["hdi_high"]
    assert result["sigma"] == {"fixed": 0.05}
    # one model call per proposal inside the bounds (+ the starting walkers), the three
    # adaptation stages of the mixture moves (ADAPT_STEPS each) and the coverage check's draws
    # included
    adapt = 3 * ADAPT_STEPS
    assert result["moves"]["kind"] == "mixture" and result["moves"]["adapt_steps"] == adapt
    check = COVERAGE_DRAWS
    assert 0.5 * 400 * 16 < result["evaluations"] <= (400 + adapt) * 16 + 3 * 16 + check
    assert result["wall_s"] > 0
    assert len(result["autocorr_time"]) == 2
    assert result["compute"] == {"kind": "serial", "workers": 1}
    with h5py.File(outs[0]) as a, h5py.File(outs[1]) as b:
        assert a.attrs["status"] == "complete"
        for key in ("chain", "log_prob", "predictions/predictive_hz", "predictions/frequencies_hz"):
            assert np.array_equal(a["posterior"][key][()], b["posterior"][key][()])
        assert a["posterior/chain"].shape == (400, 16, 2)
        assert a["posterior/predictions/frequencies_hz"].shape == (50, 2)
    tree = to_datatree(outs[0])
    assert tree["posterior"]["theta_1"].shape[0] == 16
    assert tree["posterior_predictive"]["frequencies_hz"].shape == (1, 50, 2)


def test_ctrl_c_then_resume_gives_the_uninterrupted_chain(
    study, reference, tmp_path, monkeypatch, capsys
):
    original = LogPosterior.__call__
    # stop 100 calls before the end of the reference run: inside the kept run (~480 calls; the
    # mixture's adaptation stages take the first ~800)
    calls = {"n": 0, "stop": reference.calls - 100}

    def interrupting(self, theta):
        calls["n"] += 1
        if calls["n"] == calls["stop"]:
            raise KeyboardInterrupt
        return original(self, theta)

    monkeypatch.setattr(LogPosterior, "__call__", interrupting)
    partial = tmp_path / "run.h5"
    assert main(["sample", str(study), "--out", str(partial), "--json"]) == 130
    with h5py.File(partial) as h5:
        assert h5.attrs["status"] == "partial"
        assert 0 < h5["posterior/chain"].shape[0] < 400
    monkeypatch.setattr(LogPosterior, "__call__", original)
    assert main(["sample", str(study), "--out", str(partial), "--resume", "--json"]) == 0
    with h5py.File(partial) as a, h5py.File(reference.out) as b:
        assert a.attrs["status"] == "complete"
        assert np.array_equal(a["posterior/chain"][()], b["posterior/chain"][()])
    # resuming a finished run, or with other settings, is refused
    assert main(["sample", str(study), "--out", str(partial), "--resume"]) == 2
    assert main(["sample", str(study), "--out", str(partial), "--resume", "--seed", "9"]) == 2
    assert "different study" in capsys.readouterr().err


def test_modal_data_from_ema_h5_with_shapes_pairs_by_mac(tmp_path):
    modal_h5 = pytest.importorskip("bayesupdate.ema.modal_h5")
    from bayesupdate.inference import CalibrationSettings, ObjectiveSpec, build_problem, calibrate
    from bayesupdate.modal_data import ModalData
    from bayesupdate.models import get_model

    model = get_model("shear_building")
    truth = model.predict({"theta_1": 1.2, "theta_2": 0.8}, 2)
    path = tmp_path / "modes.h5"
    modal_h5.write_modal_h5(
        path,
        ModalData(frequencies_hz=truth.frequencies_hz, shapes=truth.shapes, dof_labels=("1", "2")),
    )
    data = load_modal_data(path)
    problem = build_problem(model, data, objective=ObjectiveSpec(mac_weight=1.0))
    assert problem.pairing.method == "mac"
    result = calibrate(problem, CalibrationSettings(starts=8, seed=0))
    # with MAC terms the shapes break the two-fold symmetry of frequencies alone
    np.testing.assert_allclose(result.theta, [1.2, 0.8], rtol=1e-5)
    assert len(result.distinct_optima) == 1
    np.testing.assert_allclose(result.table.mac, 1.0, atol=1e-9)


def test_plots_from_a_result_file(reference, tmp_path):
    from bayesupdate.inference.plots import save_all

    paths = save_all(read_result(reference.out), tmp_path / "figs")
    # no Table 3 names in the shear building: that figure is skipped
    assert sorted(p.stem for p in paths) == ["pair", "predictive", "residuals", "trace"]
    assert all(p.stat().st_size > 5000 for p in paths)


def test_the_pair_plot_draws_the_lower_triangle_with_shared_axes():
    from bayesupdate.inference.plots import plot_pair

    d = 4
    chain = np.random.default_rng(3).normal(size=(60, 8, d)) * [1e-3, 1.0, 1e4, 0.1]
    result = {"posterior": {"attrs": {"names": [f"p{k}" for k in range(d)], "burn": 10},
                            "chain": chain}}  # fmt: skip
    fig = plot_pair(result)
    # d (d + 1) / 2 panels: no hidden axes above the diagonal
    assert len(fig.axes) == d * (d + 1) // 2
    grid = {(ax.get_subplotspec().rowspan.start, ax.get_subplotspec().colspan.start): ax
            for ax in fig.axes}  # fmt: skip
    assert set(grid) == {(i, j) for i in range(d) for j in range(i + 1)}
    fig.canvas.draw()  # tick labels get their text when drawn
    for j in range(d):  # a column shares x; only the bottom row labels its ticks
        for i in range(j, d):
            if i < d - 1:
                assert grid[i, j].get_shared_x_axes().joined(grid[i, j], grid[d - 1, j])
            labelled = any(t.get_visible() and t.get_text() for t in grid[i, j].get_xticklabels())
            assert labelled == (i == d - 1)
    for i in range(2, d):  # a row's scatters share y
        assert grid[i, 1].get_shared_y_axes().joined(grid[i, 0], grid[i, i - 1])
        assert not grid[i, i].get_shared_y_axes().joined(grid[i, 0], grid[i, i])


def test_real_sigint_keeps_a_checkpoint_and_resume_completes(study, tmp_path):
    import os
    import signal
    import subprocess
    import sys
    import time

    # 1,600 kept steps, checked every 100: after the first checkpoint 1,500 steps (over 1 s)
    # remain, while the signal follows the checkpoint within the 50 ms poll (the study's 400
    # steps left 0.25 s, which a loaded machine could miss: the run then ended by itself)
    long = tmp_path / "long.toml"
    long.write_text(study.read_text().replace("steps = 400", "steps = 1600"))
    reference = _sample_run(long, tmp_path / "ref.h5")
    out = tmp_path / "run.h5"
    cmd = [sys.executable, "-m", "bayesupdate", "sample", str(long), "--out", str(out), "--json"]
    proc = subprocess.Popen(
        cmd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": os.getcwd()},
    )
    # the stop must land inside the kept run (after its first checkpoint): the optimum and the
    # mixture's two set-up stages come first, which takes minutes on a loaded machine
    deadline = time.monotonic() + 600
    while not out.exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    assert out.exists(), "no checkpoint within 600 s"
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "--resume" in err
    with h5py.File(out) as h5:
        assert h5.attrs["status"] == "partial"
        assert h5["posterior/chain"].shape[0] < 1600
    assert main(["sample", str(long), "--out", str(out), "--resume", "--json"]) == 0
    with h5py.File(out) as a, h5py.File(reference.out) as b:
        assert np.array_equal(a["posterior/chain"][()], b["posterior/chain"][()])


def test_sample_exhaust_screens_proposals_and_stops_on_the_targets(tmp_path, capsys):
    # the built-in exhaust: certified reduced basis, proposals screened on a coarser basis
    # (delayed acceptance); the R-hat / ESS targets are checked as the chain grows
    study = tmp_path / "exhaust.toml"
    study.write_text(
        '[model]\nsource = "exhaust"\n[data]\nsource = "paper:ema"\n'
        "[optimizer]\nstarts = 2\n[likelihood]\nsigma = 0.1\n"
        # the budget is well above where these 12 DE walkers meet the loose targets (500 steps
        # on one machine, 700 on another: the chain's bits follow the BLAS), so the test asks
        # that the run stops at a check before it, not at a given step
        "[sampler]\nwalkers = 12\nsteps = 1500\ncheck_every = 100\nmin_autocorr_times = 1\n"
        "target_rhat = 1.5\ntarget_ess = 20\npredictive_draws = 20\n"
        # DE: its proposals mostly fail the screen; the mixture's mostly pass it (the
        # mixture with screening is checked against the reference, test_posterior_reference)
        'moves = "de"\n'
    )
    out = tmp_path / "post.h5"
    assert main(["sample", str(study), "--out", str(out), "--json"]) == 0
    result = json.loads(capsys.readouterr().out.splitlines()[-1])
    assert result["rom"]["size"] > result["screen"]["size"] > 6
    assert result["rom"]["max_rel_error"] <= 1e-4 and result["screen"]["max_rel_error"] <= 5e-3
    # every proposal is screened, only the survivors are solved on the certified basis
    proposals = result["steps"] * result["walkers"]
    assert result["screen"]["evaluations"] >= proposals > 2 * result["evaluations"]
    assert result["moves"] == {"kind": "de", "requested": "de", "fallback": None}
    # loose targets: met at a check (sampling.check_schedule) before the budget, and they hold
    # in the summary
    checks, done = [], 0
    while done < 1500:
        checks.append(done := check_schedule(done, 100, 1500))
    assert result["converged"] and result["steps"] in checks[:-1]
    assert max(p["r_hat"] for p in result["parameters"].values()) <= 1.5
    assert min(p["ess_bulk"] for p in result["parameters"].values()) >= 20


def test_a_posterior_that_misses_its_targets_says_so_everywhere(study, seed3, tmp_path, capsys):
    """The step budget (400) ends the run before 1e9 tau: the terminal, the JSON
    and the HDF5 file say "not converged" and why; a converged run says nothing of the kind."""
    result = seed3.summary
    assert result["converged"] is False
    reason = result["convergence"]["reason"]
    assert "400 steps < 1e+09 autocorrelation times" in reason and "step budget" in reason
    assert "warning: the posterior did not converge: " + reason in seed3.err
    with h5py.File(seed3.out) as h5:
        assert not h5["posterior"].attrs["converged"]
        assert h5["posterior"].attrs["convergence_reason"] == reason
    met = tmp_path / "met.toml"
    met.write_text(
        study.read_text().replace("min_autocorr_times = 1e9", "min_autocorr_times = 1")
        + "target_rhat = 1.5\ntarget_ess = 50\n"
    )
    assert main(["sample", str(met), "--json", "--seed", "3"]) == 0
    captured = capsys.readouterr()
    result = json.loads(captured.out.splitlines()[-1])
    assert result["converged"] is True and result["convergence"]["reason"] is None
    assert result["convergence"]["max_r_hat"] <= 1.5 and "warning" not in captured.err


def test_sample_tmcmc_is_the_pipeline_with_the_study_settings(study, capsys):
    """``sample --sampler tmcmc``: the JSON is ``pipelines.sample_tmcmc`` on the study's own
    posterior and seed, bit for bit; --out (emcee's checkpointed file) is refused with exit 2."""
    from bayesupdate.config import load_study
    from bayesupdate.inference.tmcmc import TMCMCSettings
    from bayesupdate.pipelines.sample_tmcmc import sample_tmcmc, tmcmc_json
    from bayesupdate.pipelines.study import prepare

    assert main(["sample", str(study), "--sampler", "tmcmc", "--particles", "300", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["sampler"] == "tmcmc" and out["particles"] == 300 and out["failed"] == 0
    config = load_study(study)
    run = sample_tmcmc(prepare(config), TMCMCSettings(particles=300, seed=config.sampler.seed))
    expected = tmcmc_json(run, config.sampler.hdi_prob)
    assert out["log_evidence"] == expected["log_evidence"] and np.isfinite(out["log_evidence"])
    assert out["parameters"] == expected["parameters"]
    assert main(["sample", str(study), "--sampler", "tmcmc", "--out", "x.h5"]) == 2
