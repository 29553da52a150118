"""``discover`` and ``calibrate`` on Dask (bayesupdate.compute.dask), needs ``distributed``
(the ``dask`` extra, also in ``test``).

A ``dask scheduler`` and two ``dask worker`` processes (each with a nanny, one thread) are started
on 127.0.0.1 at a free port, as a user would by hand; ``bayesupdate discover --scheduler`` must
give the serial run's JSON bit for bit (verdict, every candidate's evidence, parameters), and so
must a ``LocalCluster`` of two threaded workers talking tcp (``processes=False``: no worker
start-up cost, but every task and result still goes through the scheduler's serialization), and
``calibrate --scheduler`` of a user's model (its starts on the workers).  A worker with another
bayesupdate version, or no scheduler at the address, is a one-line error and exit 2.

These run in CI (tens of seconds, most of it the discoveries).  With BAYESUPDATE_LONG_TESTS=1
also: a worker killed while it holds tasks changes nothing (one more discovery)."""

import contextlib
import io
import json
import os
import re
import signal
import socket
import subprocess
import sys
import threading
import time

import pytest

pytest.importorskip("distributed")

from distributed import Client, LocalCluster  # noqa: E402
from test_parallel_executor import (  # noqa: E402
    serial_small_discovery,
    small_discovery_study,
    user_model_study,
)

from bayesupdate.cli import main  # noqa: E402

START_TIMEOUT_S = 120
TESTS = os.path.dirname(os.path.abspath(__file__))
long_test = pytest.mark.skipif(
    not os.environ.get("BAYESUPDATE_LONG_TESTS"),
    reason="long: set BAYESUPDATE_LONG_TESTS=1 (one more discovery, a worker killed mid-run)",
)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _run_json(argv: list[str]) -> dict:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(argv) == 0
    return json.loads(out.getvalue())


def _comparable(summary: dict) -> dict:
    """The JSON less what legitimately differs between runs: wall times and where it ran."""
    return {k: v for k, v in summary.items() if k not in ("wall_s", "compute", "timings")}


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    return str(small_discovery_study(tmp_path_factory.mktemp("dask")))


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    return serial_small_discovery(tmp_path_factory.mktemp("serial"))


@contextlib.contextmanager
def _dask_processes():
    """(address, scheduler process) of a ``dask scheduler`` with two ``dask worker`` processes
    on 127.0.0.1, all stopped at the end."""
    address = f"tcp://127.0.0.1:{_free_port()}"
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    # the workers import the user's model module (``test_parallel_executor``) as users' workers
    # import theirs: from their path
    env["PYTHONPATH"] = os.pathsep.join(p for p in (TESTS, env.get("PYTHONPATH")) if p)
    python = [sys.executable, "-m"]
    common = ["--no-dashboard"]
    port = address.rsplit(":", 1)[1]
    commands = [[*python, "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port", port]]
    worker = [*python, "distributed.cli.dask_worker", address, "--nthreads", "1"]
    commands += [[*worker, "--host", "127.0.0.1"]] * 2
    procs = [
        subprocess.Popen(
            [*command, *common], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
        )
        for command in commands
    ]
    try:
        with Client(address, timeout=START_TIMEOUT_S) as client:
            client.wait_for_workers(2, timeout=START_TIMEOUT_S)
        yield address, procs[0]
    finally:
        # workers whose scheduler is gone (the lost-scheduler test) have nothing to hand back:
        # they are not waited for while they retry the connection
        grace_s = 20 if procs[0].poll() is None else 1
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=grace_s)
            except subprocess.TimeoutExpired:
                p.kill()


@pytest.fixture(scope="module")
def scheduler():
    """Address of a ``dask scheduler`` with two ``dask worker`` processes on 127.0.0.1."""
    with _dask_processes() as (address, _):
        yield address


def test_scheduler_and_two_worker_processes_give_the_serial_result(study, serial, scheduler):
    on_dask = _run_json(["discover", study, "--json", "--scheduler", scheduler])
    assert on_dask["compute"] == {"kind": "dask", "workers": 2, "scheduler": scheduler}
    assert on_dask["verdict"] == serial["verdict"]
    assert [c["log_evidence"] for c in on_dask["candidates"]] == [
        c["log_evidence"] for c in serial["candidates"]
    ]
    assert _comparable(on_dask) == _comparable(serial)


def _kill_a_busy_worker(address: str, done: threading.Event, killed: list) -> None:
    """SIGKILL the first worker seen holding a task (its nanny starts a fresh one)."""
    with Client(address, timeout=30) as client:
        pids = client.run(os.getpid)
        while not done.is_set():
            busy = [w for w, keys in client.processing().items() if keys]
            if busy:
                os.kill(pids[busy[0]], signal.SIGKILL)
                killed.append(busy[0])
                return
            time.sleep(0.02)


@long_test
def test_a_worker_killed_mid_run_changes_nothing(study, serial, scheduler):
    done, killed = threading.Event(), []
    watcher = threading.Thread(target=_kill_a_busy_worker, args=(scheduler, done, killed))
    watcher.start()
    try:
        on_dask = _run_json(["discover", study, "--json", "--scheduler", scheduler])
    finally:
        done.set()
        watcher.join()
    assert len(killed) == 1  # a worker died holding tasks; they ran again on the other
    assert _comparable(on_dask) == _comparable(serial)


def test_local_cluster_of_two_workers_gives_the_serial_result(study, serial):
    with LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=False,
        protocol="tcp://",
        dashboard_address=":0",
    ) as cluster:
        on_dask = _run_json(["discover", study, "--json", "--scheduler", cluster.scheduler_address])
    assert on_dask["compute"]["workers"] == 2
    assert _comparable(on_dask) == _comparable(serial)


def test_calibration_starts_on_dask_worker_processes_are_serial_bit_for_bit(tmp_path, scheduler):
    """``calibrate --scheduler`` of a user's model that cannot batch: its starts on the two
    ``dask worker`` processes; the JSON (less "compute") is the serial run's."""
    study = str(user_model_study(tmp_path))
    serial = _run_json(["calibrate", study, "--json"])
    on_dask = _run_json(["calibrate", study, "--json", "--scheduler", scheduler])
    assert serial.pop("compute") == {"kind": "serial", "workers": 1}
    assert on_dask.pop("compute") == {"kind": "dask", "workers": 2, "scheduler": scheduler}
    assert serial.pop("timings") and on_dask.pop("timings")  # wall times: differ run to run
    assert on_dask == serial
    assert 1e-6 < serial["objective"] < 1e-3  # not an exact fit: digits that could move


def _cube(offset, x):
    time.sleep(0.05 * (3 - x))  # later items finish first
    return offset + x**3


def test_dask_map_is_in_submission_order_with_progress_in_arrival_order(scheduler):
    from bayesupdate.compute.dask import DaskExecutor

    arrived = []
    with DaskExecutor(scheduler) as ex:
        out = ex.map(_cube, range(4), 100, lambda i, r: arrived.append((i, r)))
    assert out == [100, 101, 108, 127]
    assert sorted(arrived) == list(enumerate(out))


def test_other_bayesupdate_version_on_the_workers_is_refused(study, scheduler, monkeypatch, capsys):
    import bayesupdate.compute.dask as pd

    monkeypatch.setattr(pd, "client_version", lambda: "0.0.0-other")
    assert main(["discover", study, "--json", "--scheduler", scheduler]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "this client 0.0.0-other" in err and "runs bayesupdate" in err


def test_no_scheduler_at_the_address_is_a_one_line_error(study, monkeypatch, capsys):
    import bayesupdate.compute.dask as pd

    monkeypatch.setattr(pd, "CONNECT_TIMEOUT_S", 2)
    address = f"tcp://127.0.0.1:{_free_port()}"
    assert main(["discover", study, "--scheduler", address]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cannot reach the Dask scheduler" in err


def test_pool_evaluator_on_dask_is_the_per_point_model_bit_for_bit(scheduler):
    """The sampler's batch wrapper of a model that cannot batch, on the Dask workers."""
    import numpy as np

    from bayesupdate.compute.dask import DaskExecutor
    from bayesupdate.inference.evaluators import PoolEvaluator
    from bayesupdate.models import get_model

    fe = get_model("exhaust")
    names = fe.parameter_names
    low, high = np.array([fe.default_bounds()[n] for n in names]).T
    theta = low + np.array([[0.3], [0.7]]) * (high - low)  # two points inside the box
    serial = np.array(
        [fe.predict(dict(zip(names, row, strict=True)), 6).frequencies_hz[:6] for row in theta]
    )
    with DaskExecutor(scheduler) as ex, PoolEvaluator(fe, executor=ex) as pool:
        assert pool.n_workers == 2
        out = pool.predict_frequencies_batch(theta, names, 6)
    np.testing.assert_array_equal(out, serial)


def test_scheduler_lost_mid_run_stops_sample_and_resume_gives_the_serial_chain(tmp_path):
    """The user's path: ``bayesupdate sample --scheduler ADDR --out post.h5`` of a model that
    cannot batch (its walkers on the two ``dask worker`` processes); the ``dask scheduler``
    process killed after the first checkpoint.  The run stops with one line naming the
    scheduler and exit 2, the file holds the complete steps so far, and ``--resume`` (serial)
    ends with the uninterrupted serial run's chain, bit for bit."""
    h5py = pytest.importorskip("h5py")
    import numpy as np

    steps = 600  # about a minute on Dask: the kill lands long before the end
    study = user_model_study(tmp_path)
    study.write_text(study.read_text().replace("steps = 60", f"steps = {steps}"))
    reference, out = tmp_path / "ref.h5", tmp_path / "post.h5"
    _run_json(["sample", str(study), "--out", str(reference), "--json"])
    with _dask_processes() as (address, scheduler_process):
        cmd = [sys.executable, "-m", "bayesupdate", "sample", str(study), "--json"]
        env = dict(os.environ, OPENBLAS_NUM_THREADS="1")
        env["PYTHONPATH"] = os.pathsep.join(p for p in (TESTS, env.get("PYTHONPATH")) if p)
        proc = subprocess.Popen(
            [*cmd, "--scheduler", address, "--out", str(out)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
        )
        deadline = time.monotonic() + START_TIMEOUT_S
        while not out.exists() and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.02)
        assert out.exists() and proc.poll() is None, "no checkpoint while the run was going"
        scheduler_process.kill()
        stdout, stderr = proc.communicate(timeout=START_TIMEOUT_S)
    assert proc.returncode == 2, stderr
    # the phases that finished before the loss said so (compute.progress: "name: N unit in
    # T s"); the error itself is one line, the last
    *progress, last = stderr.splitlines()
    assert all(re.fullmatch(r".+: (\d+ \w+|done) in \d+\.\d s", line) for line in progress)
    assert stdout == "" and last.startswith("error: ") and "error" not in "".join(progress), stderr
    assert f"--scheduler {address}: lost the Dask scheduler mid-run" in stderr
    with h5py.File(out) as h5:
        assert h5.attrs["status"] == "partial"
        assert 30 <= h5["posterior/chain"].shape[0] < steps
    resumed = _run_json(["sample", str(study), "--out", str(out), "--resume", "--json"])
    assert resumed["steps"] == steps
    with h5py.File(out) as a, h5py.File(reference) as b:
        assert a.attrs["status"] == "complete"
        for name in ("posterior/chain", "posterior/log_prob"):
            np.testing.assert_array_equal(a[name][()], b[name][()], err_msg=name)
        assert np.ptp(b["posterior/chain"][-1, :, 0]) > 0  # walkers apart: a chain that can differ
