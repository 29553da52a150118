"""Faults: a killed sampling run loses nothing, a crash while writing keeps the previous result,
and a model that fails at some parameter points is counted, not fatal.

The SIGINT-in-a-subprocess and Ctrl-C-in-process resume checks live in
tests/test_inference_cli.py; here: SIGTERM (what a batch scheduler sends), the resume through the
real console script, writer crashes for every command that writes, and failing model points.
"""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from bayesupdate.cli import main

EXE = Path(sys.executable).with_name("bayesupdate")

STUDY = """
[model]
source = "shear_building"
[data]
frequencies_hz = [4.30, 10.80]
[parameters.theta_1]
bounds = [0.2, 3.0]
[parameters.theta_2]
bounds = [0.2, 3.0]
[optimizer]
starts = 4
[sampler]
walkers = 16
steps = {steps}
check_every = {check}
min_autocorr_times = 1e9
predictive_draws = 20
seed = 5
adapt_steps = 60
"""


def _catches_sigterm(pid: int) -> bool:
    """True once process ``pid`` has a SIGTERM handler (Linux: SigCgt mask in /proc)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("SigCgt:"):
            return bool(int(line.split()[1], 16) & (1 << (signal.SIGTERM - 1)))
    return False


def _files(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


# -- SIGTERM during sampling, resume through the console script ------------------------------
def test_sigterm_keeps_a_checkpoint_and_cli_resume_equals_uninterrupted(tmp_path, capsys):
    study = tmp_path / "study.toml"
    study.write_text(STUDY.format(steps=500, check=50))
    reference = tmp_path / "ref.h5"
    assert main(["sample", str(study), "--out", str(reference), "--json"]) == 0
    capsys.readouterr()

    out = tmp_path / "run.h5"
    proc = subprocess.Popen(
        [str(EXE), "sample", str(study), "--out", str(out), "--no-progress"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 60
    while not out.exists() and time.monotonic() < deadline:  # the first checkpoint is written
        time.sleep(0.02)
    assert out.exists(), "no checkpoint within 60 s"
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "--resume" in err
    with h5py.File(out) as h5:
        assert h5.attrs["status"] == "partial"
        done = h5["posterior/chain"].shape[0]
        assert 0 < done < 500
        assert h5["posterior/state"].attrs["failed"] == 0
    # no temporary file is left beside the checkpoint
    assert _files(tmp_path) == ["ref.h5", "run.h5", "study.toml"]

    proc = subprocess.run(
        [str(EXE), "sample", str(study), "--out", str(out), "--resume", "--json"],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)
    assert summary["steps"] == 500
    with h5py.File(out) as a, h5py.File(reference) as b:
        assert a.attrs["status"] == "complete"
        for key in ("chain", "log_prob", "predictions/predictive_hz"):
            assert np.array_equal(a["posterior"][key][()], b["posterior"][key][()]), key


def test_sigterm_before_first_checkpoint_leaves_no_file(tmp_path):
    # killed during the multi-start (no checkpoint yet): nothing half-written is left behind
    study = tmp_path / "study.toml"
    study.write_text(STUDY.format(steps=3000, check=50).replace("starts = 4", "starts = 4000"))
    out = tmp_path / "run.h5"
    proc = subprocess.Popen(
        [str(EXE), "sample", str(study), "--out", str(out), "--no-progress"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    # wait until `sample` has installed its SIGTERM handler (then it is optimizing: 4000 starts)
    deadline = time.monotonic() + 60
    while not _catches_sigterm(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.02)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    assert _files(tmp_path) == ["study.toml"]


# -- a crash while writing keeps the previous result -----------------------------------------
class _Boom(RuntimeError):
    pass


def _fail_after(monkeypatch, cls, method: str, n_ok: int, exc=_Boom):
    """Make ``cls.method`` raise ``exc`` on its (n_ok + 1)-th call (midway through a write)."""
    original = getattr(cls, method)
    calls = {"n": 0}

    def wrapper(self, *args, **kwargs):
        calls["n"] += 1
        if calls["n"] > n_ok:
            raise exc("disk pulled out")
        return original(self, *args, **kwargs)

    monkeypatch.setattr(cls, method, wrapper)
    return calls


@pytest.mark.parametrize("exc", [_Boom, KeyboardInterrupt])
def test_crash_while_writing_a_calibration_keeps_the_previous_file(tmp_path, monkeypatch, exc):
    study = tmp_path / "study.toml"
    study.write_text(STUDY.format(steps=10, check=10))
    out = tmp_path / "cal.h5"
    assert main(["calibrate", str(study), "--out", str(out)]) == 0
    before = out.read_bytes()
    calls = _fail_after(monkeypatch, h5py.Group, "create_dataset", 3, exc)
    code = main(["calibrate", str(study), "--out", str(out), "--force", "--seed", "7"])
    assert code == (130 if exc is KeyboardInterrupt else 1)
    assert calls["n"] == 4  # it did fail midway, after three datasets
    assert out.read_bytes() == before
    assert _files(tmp_path) == ["cal.h5", "study.toml"]


def test_crash_while_writing_a_checkpoint_keeps_the_previous_checkpoint(tmp_path, monkeypatch):
    # the sampler writes a checkpoint every 50 steps; the third write fails: the file on disk is
    # still the (valid, partial) second checkpoint
    from bayesupdate.inference import results

    study = tmp_path / "study.toml"
    study.write_text(STUDY.format(steps=200, check=50))
    out = tmp_path / "run.h5"
    original = results.write_result
    snapshots = []

    def flaky(path, *args, **kwargs):
        if len(snapshots) == 2:
            raise _Boom("disk full")
        original(path, *args, **kwargs)
        snapshots.append(Path(path).read_bytes())

    monkeypatch.setattr(results, "write_result", flaky)
    assert main(["sample", str(study), "--out", str(out), "--no-progress"]) == 1
    assert out.read_bytes() == snapshots[-1]
    with h5py.File(out) as h5:
        assert h5.attrs["status"] == "partial" and h5["posterior/chain"].shape[0] == 100
    assert _files(tmp_path) == ["run.h5", "study.toml"]
    monkeypatch.setattr(results, "write_result", original)
    assert main(["sample", str(study), "--out", str(out), "--resume", "--no-progress"]) == 0
    with h5py.File(out) as h5:
        assert h5.attrs["status"] == "complete" and h5["posterior/chain"].shape[0] == 200


def test_crash_while_writing_identify_and_simulate_outputs(tmp_path, monkeypatch, capsys):
    import pyuff

    uff = tmp_path / "test.uff"
    args = ["simulate", "--model", "exhaust", "--out", str(uff), "--noise", "0", "--seed", "1"]
    assert main(args) == 0
    uff_before = uff.read_bytes()
    modes = tmp_path / "modes.h5"
    assert main(["identify", str(uff), "--band", "5:60", "--out", str(modes)]) == 0
    modes_before = modes.read_bytes()
    capsys.readouterr()

    with monkeypatch.context() as m:
        calls = _fail_after(m, pyuff.UFF, "_write_set", 5)
        assert main([*args, "--force", "--seed", "2"]) == 1
        assert calls["n"] == 6
    assert uff.read_bytes() == uff_before
    with monkeypatch.context() as m:
        calls = _fail_after(m, h5py.Group, "create_dataset", 2)
        argv = ["identify", str(uff), "--band", "5:60", "--out", str(modes), "--force"]
        assert main(argv) == 1
        assert calls["n"] == 3
    assert modes.read_bytes() == modes_before
    err = capsys.readouterr().err
    assert err.count("internal error") == 2 and "Traceback" not in err
    assert _files(tmp_path) == ["modes.h5", "test.uff"]


# -- failing model points are counted, not fatal ----------------------------------------------
FLAKY_MODEL = """
import math

def frequencies(p):
    a = p["a"]
    if a > 1.6:
        raise ArithmeticError("eigen-solve did not converge")
    if a < 0.6:
        return [math.nan, 10.8]
    return [4.30 * math.sqrt(a), 10.80 * math.sqrt(a)]
"""


@pytest.fixture
def flaky_study(tmp_path, monkeypatch):
    package = tmp_path / "lib" / "flaky_models_faults"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text("")
    (package / "model.py").write_text(FLAKY_MODEL)
    monkeypatch.syspath_prepend(str(tmp_path / "lib"))
    study = tmp_path / "study.toml"
    study.write_text(
        '[model]\nsource = "flaky_models_faults.model:frequencies"\n'
        "[data]\nfrequencies_hz = [4.30, 10.80]\n[parameters.a]\nbounds = [0.3, 2.5]\n"
        "[optimizer]\nstarts = 8\n[likelihood]\nsigma = 0.3\n"
        "[sampler]\nwalkers = 8\nsteps = 300\ncheck_every = 100\nmin_autocorr_times = 1e9\n"
        "predictive_draws = 20\n"
    )
    return study


def test_failing_points_during_calibrate_are_counted(flaky_study, tmp_path, capsys):
    out = tmp_path / "cal.h5"
    assert main(["calibrate", str(flaky_study), "--out", str(out)]) == 0
    captured = capsys.readouterr()
    assert "a = 1" in captured.out  # the optimum a = 1 fits both frequencies exactly
    assert "model failed at" in captured.err
    with h5py.File(out) as h5:
        failed = int(h5["optimum"].attrs["failed_evaluations"])
        total = int(h5["optimum"].attrs["evaluations"])
    # 8 Sobol starts in [0.3, 2.5]: about half lie in the failing regions
    assert 2 <= failed < total
    assert f"model failed at {failed} of {total} points" in captured.err


def test_failing_points_during_sampling_are_counted(flaky_study, tmp_path, capsys):
    out = tmp_path / "post.h5"
    assert main(["sample", str(flaky_study), "--out", str(out), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["failed_evaluations"] > 0
    with h5py.File(out) as h5:
        chain = h5["posterior/chain"][()]
        assert int(h5["posterior"].attrs["failed_evaluations"]) == result["failed_evaluations"]
    # a failed point has zero posterior density: no walker ever sits in a failing region
    assert 0.6 <= chain.min() and chain.max() <= 1.6


def test_eigen_solve_failure_in_the_fe_model_is_counted(tmp_path, monkeypatch, capsys):
    # the built-in FE model: the eigen-solver raises at every 7th call
    import bayesupdate.fe.model as fe_model

    original = fe_model.solve_modes
    calls = {"n": 0, "raised": 0}

    def flaky_solve(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] % 7 == 0:
            calls["raised"] += 1
            raise np.linalg.LinAlgError("ARPACK error -9999: could not build an Arnoldi factor")
        return original(*args, **kwargs)

    monkeypatch.setattr(fe_model, "solve_modes", flaky_solve)
    out = tmp_path / "cal.h5"
    argv = [
        "calibrate",
        "--model",
        "exhaust",
        "--data",
        "paper:ema",
        "--starts",
        "1",
        "--no-polish",
    ]
    # full solves: every failure is one failed evaluation of the fit
    assert main([*argv, "--full", "--out", str(out), "--json"]) == 0, capsys.readouterr().err
    result = json.loads(capsys.readouterr().out)
    assert np.isfinite(result["objective"])
    with h5py.File(out) as h5:
        assert int(h5["optimum"].attrs["failed_evaluations"]) == calls["raised"] > 0
    # the default reduced-basis search: failed snapshot solves are left out of the basis, the
    # full-model polish counts its own failures; the run still ends with a finite optimum
    calls.update(n=0, raised=0)
    assert main([*argv, "--out", str(out), "--force", "--json"]) == 0, capsys.readouterr().err
    result = json.loads(capsys.readouterr().out)
    assert np.isfinite(result["objective"]) and calls["raised"] > 0
    with h5py.File(out) as h5:
        assert 0 < int(h5["optimum"].attrs["failed_evaluations"]) < calls["raised"]


def test_a_stop_landing_in_a_checkpoint_write_ends_with_a_resumable_file(
    tmp_path, monkeypatch, capsys
):
    """A SIGTERM that lands while the first checkpoint is being written (as on a loaded
    machine): the write completes, the run stops before the next block with the resume hint,
    exit 130, and --resume completes it."""
    from bayesupdate.inference import results

    original = results.write_result
    calls = []

    def signalled(path, *args, **kwargs):
        calls.append(path)
        if len(calls) == 1:
            os.kill(os.getpid(), signal.SIGTERM)  # lands mid-write, in the command's handler
            time.sleep(0.05)
        original(path, *args, **kwargs)

    monkeypatch.setattr(results, "write_result", signalled)
    study = tmp_path / "study.toml"
    study.write_text(STUDY.format(steps=200, check=50))
    out = tmp_path / "run.h5"
    assert main(["sample", str(study), "--out", str(out), "--no-progress"]) == 130
    err = capsys.readouterr().err
    assert "stopped after 50 steps" in err and "--resume" in err, err
    with h5py.File(out) as h5:
        assert h5.attrs["status"] == "partial" and h5["posterior/chain"].shape[0] == 50
    monkeypatch.setattr(results, "write_result", original)
    assert main(["sample", str(study), "--out", str(out), "--resume", "--no-progress"]) == 0
    with h5py.File(out) as h5:
        assert h5.attrs["status"] == "complete" and h5["posterior/chain"].shape[0] == 200


def test_deferred_stop_is_recorded_not_raised():
    from bayesupdate.compute.stop import StopRequest

    stop = StopRequest()
    with stop.deferred():
        stop.handler(signal.SIGTERM, None)  # no exception inside the block
        assert stop.requested()
    with pytest.raises(KeyboardInterrupt):
        stop.handler(signal.SIGTERM, None)  # outside it interrupts at once
    assert not StopRequest().requested()  # each run has its own request: nothing global


def test_a_stop_request_swallowed_by_an_extension_still_stops_sampling(tmp_path, monkeypatch):
    # a SIGTERM whose KeyboardInterrupt a compiled extension swallowed (scipy's Sobol set-up
    # reports "Exception ignored" and goes on): the recorded request stops the run at the next
    # optimizer start, exit 130, and nothing is written
    import bayesupdate.pipelines.sample as runner

    original = runner.sampling_problem

    def swallowed(*args, **kwargs):
        try:  # the command's handler records the request, its KeyboardInterrupt is lost
            os.kill(os.getpid(), signal.SIGTERM)
            time.sleep(0.05)
        except KeyboardInterrupt:
            pass
        return original(*args, **kwargs)

    monkeypatch.setattr(runner, "sampling_problem", swallowed)
    study = tmp_path / "study.toml"
    study.write_text(STUDY.format(steps=300, check=50))
    out = tmp_path / "run.h5"
    assert main(["sample", str(study), "--out", str(out), "--no-progress"]) == 130
    assert _files(tmp_path) == ["study.toml"]
    # the next command in this process starts with its own, clear request
    assert signal.getsignal(signal.SIGTERM) is not None


def test_swallowed_stop_request_is_not_reported_but_other_errors_are(capsys):
    import gc
    import sys

    from bayesupdate.compute.stop import StopRequest

    class RaisesOnDelete:  # an exception Python can only report as "Exception ignored"
        def __init__(self, exc):
            self.exc = exc

        def __del__(self):
            raise self.exc

    stop = StopRequest()
    previous, sys.unraisablehook = sys.unraisablehook, stop.quiet_unraisable
    stop.request()
    try:
        RaisesOnDelete(KeyboardInterrupt())
        gc.collect()
        assert capsys.readouterr().err == ""
        RaisesOnDelete(ValueError("real problem"))
        gc.collect()
        assert "real problem" in capsys.readouterr().err
    finally:
        sys.unraisablehook = previous


def test_swallowed_stop_traceback_printed_by_an_extension_is_silenced(capsys):
    """Cython prints a swallowed exception with sys.excepthook (PyErr_PrintEx) before the
    unraisable hook: a recorded stop request's traceback is dropped, anything else is shown."""
    from bayesupdate.compute.stop import StopRequest

    stop = StopRequest()

    def report(exc):
        try:
            raise exc
        except BaseException as caught:
            stop.quiet_excepthook(type(caught), caught, caught.__traceback__)
        return capsys.readouterr().err

    assert "KeyboardInterrupt" in report(KeyboardInterrupt())  # no stop request: a real one
    stop.request()
    assert report(KeyboardInterrupt()) == ""
    assert "real problem" in report(ValueError("real problem"))
