"""The executor seam (bayesupdate.compute) without Dask: which executor the options
choose, one-line errors for bad input, results in submission order on local processes whatever
order the tasks finish in, a killed local worker's tasks run again, and a discovery on two local
processes is the serial discovery bit for bit, and so is a calibration of a user's model (its
starts on the executor, ``calibrate --workers``)."""

import contextlib
import copy
import io
import json
import os
import signal
import time
from pathlib import Path

import numpy as np
import pytest

# kept light: spawned workers import this module for its task functions
from bayesupdate.compute.executors import ProcessExecutor
from bayesupdate.compute.settings import SERIAL, ComputeSettings
from bayesupdate.errors import BayesUpdateError

#: ``config.SCHEDULER_VARIABLE``, spelled out: config (the study file) is not imported here
SCHEDULER_VARIABLE = "BAYESUPDATE_SCHEDULER"

# the smallest discovery through the CLI: the exhaust against the paper's test, added masses
# only, one baseline start, three quick refits, one full refit
SMALL_DISCOVERY = """
[model]
source = "exhaust"
[data]
source = "paper:ema"
[discovery]
kinds = ["added_mass"]
baseline_starts = 1
quick_refits = 3
per_kind = 1
max_refits = 1
max_nfev = 8
loo_top = 1
loo_draws = 100
"""


# a user's model that cannot batch (``package.module:function``): three 1 kg masses in a chain,
# springs k1 (ground to mass 1), k2 (1-2) and 3e4 N/m (2-3); its data are the frequencies at
# k1 = 1.2e4, k2 = 2.5e4 N/m times (1.01, 0.99, 1.005), so no point fits them exactly
USER_STUDY = """
[model]
source = "test_parallel_executor:spring_chain"
[parameters.k1]
bounds = [5e3, 5e4]
start = 1e4
[parameters.k2]
bounds = [5e3, 5e4]
start = 2e4
[data]
frequencies_hz = [8.95318171, 29.17649417, 46.52579198]
[optimizer]
starts = 6
[sampler]
walkers = 8
steps = 60
check_every = 30
min_autocorr_times = 1e9
moves = "de"
predictive_draws = 20
"""


def spring_chain(params) -> np.ndarray:
    """Natural frequencies [Hz] (3,) of the chain in ``USER_STUDY`` (unit masses)."""
    k1, k2, k3 = params["k1"], params["k2"], 3e4
    stiffness = np.array([[k1 + k2, -k2, 0.0], [-k2, k2 + k3, -k3], [0.0, -k3, k3]])
    return np.sqrt(np.linalg.eigvalsh(stiffness)) / (2 * np.pi)


def user_problem():
    """The calibration problem of ``USER_STUDY`` built from the library (frequencies in order)."""
    from bayesupdate.inference import build_problem
    from bayesupdate.inference.user_model import load_user_model
    from bayesupdate.modal_data import ModalData

    bounds = {"k1": {"bounds": [5e3, 5e4], "start": 1e4}, "k2": {"bounds": [5e3, 5e4]}}
    model = load_user_model("test_parallel_executor:spring_chain", bounds)
    data = ModalData(frequencies_hz=np.array([8.95318171, 29.17649417, 46.52579198]))
    return build_problem(model, data, pairing="order")


def user_model_study(folder: Path) -> Path:
    path = folder / "user_model.toml"
    path.write_text(USER_STUDY)
    return path


def small_discovery_study(folder: Path) -> Path:
    path = folder / "small_discovery.toml"
    path.write_text(SMALL_DISCOVERY)
    return path


_SERIAL_DISCOVERY: dict = {}


def serial_small_discovery(folder: Path) -> dict:
    """The serial ``discover --json`` of ``SMALL_DISCOVERY`` (a copy), run once per test session:
    the Dask tests (tests/test_dask_executor.py) compare against it too."""
    if not _SERIAL_DISCOVERY:
        from bayesupdate.cli import main

        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            assert main(["discover", str(small_discovery_study(folder)), "--json"]) == 0
        _SERIAL_DISCOVERY.update(json.loads(out.getvalue()))
    return copy.deepcopy(_SERIAL_DISCOVERY)


def _slow_square(delay_s: float, x: int) -> tuple[int, int]:
    # later items finish first: arrival order is the reverse of submission order
    time.sleep(delay_s * (4 - x))
    return x * x, os.getpid()


def _die_once(marker: str, x: int) -> int:
    path = Path(marker)
    if x == 2 and not path.exists():
        path.write_text("killed")
        os.kill(os.getpid(), signal.SIGKILL)
    return 10 * x


def test_options_choose_the_executor():
    from bayesupdate import config
    from bayesupdate.config import compute_settings, parse_study

    assert config.SCHEDULER_VARIABLE == SCHEDULER_VARIABLE
    env = {SCHEDULER_VARIABLE: "head:8786"}
    assert compute_settings(environ={}) == SERIAL and SERIAL.kind == "serial"
    assert compute_settings(workers=3, environ=env) == ComputeSettings(workers=3)
    assert compute_settings(workers=3).kind == "processes"
    assert compute_settings(workers=1).kind == "serial"
    dask = compute_settings(environ=env)
    assert (dask.kind, dask.scheduler) == ("dask", "tcp://head:8786")
    study = parse_study({"compute": {"workers": 2}}).extensions["compute"]
    # the study file's table beats the environment, the command line beats the study file
    assert compute_settings(study=study, environ=env) == ComputeSettings(workers=2)
    assert (
        compute_settings(scheduler="tls://10.0.0.1:1", study=study).scheduler == "tls://10.0.0.1:1"
    )


@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"workers": 0}, "--workers: must be >= 1"),
        ({"workers": 2, "scheduler": "tcp://h:1"}, "not both"),
        ({"scheduler": "tcp://head"}, "not a Dask scheduler address"),
        ({"scheduler": "http://head:8786"}, "not a Dask scheduler address"),
        ({"scheduler": "tcp://head:99999"}, "not a Dask scheduler address"),
        ({"environ": {SCHEDULER_VARIABLE: "head 8786"}}, SCHEDULER_VARIABLE),
    ],
)
def test_bad_compute_options_are_one_line_errors(kwargs, words):
    from bayesupdate.config import compute_settings

    with pytest.raises(BayesUpdateError, match=words) as err:
        compute_settings(**kwargs)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize(
    "table, words",
    [
        ({"workers": 0}, r"compute.workers: must be in 1\.\.1024, got 0"),
        ({"workers": 2000}, r"compute.workers: must be in 1\.\.1024, got 2000"),
        ({"workers": "2"}, "compute.workers: must be an integer"),
        ({"workers": 2, "scheduler": "tcp://h:1"}, "not both"),
        ({"scheduler": "h"}, "compute.scheduler"),
        ({"nodes": 2}, "compute.nodes: unknown key"),
    ],
)
def test_bad_compute_table(table, words):
    from bayesupdate.config import parse_study

    with pytest.raises(BayesUpdateError, match=words):
        parse_study({"compute": table}, "s.toml")


@pytest.mark.parametrize(
    "argv, words",
    [
        (["--workers", "0"], "--workers: must be >= 1"),
        (["--workers", "2", "--scheduler", "tcp://127.0.0.1:8786"], "not both"),
        (["--scheduler", "tcp://127.0.0.1"], "not a Dask scheduler address"),
    ],
)
def test_cli_bad_compute_input_exits_2_with_one_line(capsys, argv, words):
    from bayesupdate.cli import main

    assert main(["discover", "--model", "exhaust", "--data", "paper:ema", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err


def test_address_forms():
    from bayesupdate.config import check_address

    assert check_address("head:8786") == "tcp://head:8786"
    assert check_address("tcp://[::1]:8786") == "tcp://[::1]:8786"
    assert check_address(" tls://node-3.cluster:1 ") == "tls://node-3.cluster:1"


@pytest.fixture(scope="module")
def two_local_workers():
    """Two spawned local workers, started once for the tests that can share them (each worker
    imports numpy and bayesupdate when it starts: seconds on a loaded machine)."""
    with ProcessExecutor(2) as ex:
        yield ex


def test_local_processes_return_submission_order_and_share_once(two_local_workers):
    seen = {}
    out = two_local_workers.map(_slow_square, [0, 1, 2, 3], 0.2, lambda i, r: seen.setdefault(i, r))
    assert seen == dict(enumerate(out))  # progress saw every task once, with its own result
    assert [v for v, _ in out] == [0, 1, 4, 9]
    assert len({pid for _, pid in out} - {os.getpid()}) == 2  # both workers ran tasks


def test_a_killed_local_worker_is_restarted_and_its_task_run_again(tmp_path):
    marker = tmp_path / "killed"
    with ProcessExecutor(1, retries=1) as ex:
        assert ex.map(_die_once, range(5), shared=str(marker)) == [0, 10, 20, 30, 40]
    assert marker.read_text() == "killed"
    with ProcessExecutor(1, retries=0) as ex, pytest.raises(BayesUpdateError, match="died"):
        marker.unlink()
        ex.map(_die_once, range(5), shared=str(marker))


def test_discovery_on_two_local_processes_is_serial_bit_for_bit(tmp_path, capsys):
    """The user's path: ``discover --workers 2`` against the serial run, the whole JSON (less
    the wall time and the "compute" record) compared exactly."""
    from bayesupdate.cli import main

    serial = serial_small_discovery(tmp_path)
    study = small_discovery_study(tmp_path)
    assert main(["discover", str(study), "--json", "--workers", "2"]) == 0
    local = json.loads(capsys.readouterr().out)
    assert serial["compute"] == {"kind": "serial", "workers": 1}
    assert local.pop("compute") == {"kind": "processes", "workers": 2}
    serial.pop("compute")
    assert serial.pop("wall_s") > 0 and local.pop("wall_s") > 0
    assert serial.pop("timings") and local.pop("timings")  # wall times: differ run to run
    assert local == serial
    assert np.isfinite(serial["baseline"]["log_evidence"])


def test_scheduler_without_dask_installed_says_how_to_install(monkeypatch, capsys):
    import sys

    from bayesupdate.cli import main

    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    assert main(["discover", "--model", "exhaust", "--scheduler", "tcp://127.0.0.1:8786"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "pip install 'bayesupdate[dask]'" in err


def test_calibration_starts_on_two_local_processes_are_serial_bit_for_bit(tmp_path, capsys):
    """``calibrate --workers 2`` of a user's model: one task per start; the whole JSON (less the
    "compute" record) is the serial run's, and the fit is not exact (a number that could move)."""
    from bayesupdate.cli import main

    study = str(user_model_study(tmp_path))
    outs = []
    for extra in ([], ["--workers", "2"]):
        assert main(["calibrate", study, "--json", *extra]) == 0
        outs.append(json.loads(capsys.readouterr().out))
    serial, local = outs
    assert serial.pop("compute") == {"kind": "serial", "workers": 1}
    assert local.pop("compute") == {"kind": "processes", "workers": 2}
    serial.pop("timings"), local.pop("timings")  # wall times, like wall_s
    assert local == serial
    assert serial["starts"] == 7 and 1e-6 < serial["objective"] < 1e-3


def test_calibrate_with_refine_on_local_processes_is_serial_bit_for_bit(two_local_workers):
    """The library call with ``refine`` (the exact model polishing a surrogate's ends, here the
    problem itself): starts and polishes on a local executor give the serial result's bits,
    evaluation counts included."""
    from dataclasses import fields

    from bayesupdate.inference import CalibrationSettings, calibrate

    problem = user_problem()
    assert problem.model.function is spring_chain  # the workers import it by this name too
    settings = CalibrationSettings(starts=4, seed=3, max_nfev=30, polish=True)
    serial = calibrate(problem, settings, refine=problem)
    local = calibrate(problem, settings, refine=problem, executor=two_local_workers)
    for f in fields(serial):
        a, b = getattr(serial, f.name), getattr(local, f.name)
        if f.name == "wall_s":
            continue
        if isinstance(a, np.ndarray):
            np.testing.assert_array_equal(a, b, err_msg=f.name)
        elif f.name != "table":
            assert a == b, f.name
    assert serial.evaluations > 4 * 30  # each start's least squares and polish were counted


def test_posterior_of_a_user_model_on_local_processes_is_the_serial_chain(two_local_workers):
    """The sampler's likelihood of a model that cannot batch, its walkers evaluated on two local
    workers (``LogPosterior(..., executor=...)``, the problem shared once): the same chain,
    log-densities and evaluation counts as the serial run, bit for bit."""
    from bayesupdate.inference import CalibrationSettings, calibrate, sample_posterior
    from bayesupdate.inference.likelihood import LikelihoodSpec, LogPosterior
    from bayesupdate.inference.sampling import SamplerSettings

    problem = user_problem()
    optimum = calibrate(problem, CalibrationSettings(starts=2, seed=0, max_nfev=30))
    spec = LikelihoodSpec(sigma=0.01)
    settings = SamplerSettings(
        walkers=8, steps=60, seed=4, check_every=30, min_autocorr_times=1e9, moves="de"
    )
    serial_posterior = LogPosterior(problem, spec)
    serial = sample_posterior(serial_posterior, optimum, settings)
    remote_posterior = LogPosterior(problem, spec, executor=two_local_workers)
    assert serial_posterior.mode == "points" and remote_posterior._remote is not None
    local = sample_posterior(remote_posterior, optimum, settings)
    assert serial.chain.shape == (60, 8, 2)
    np.testing.assert_array_equal(local.chain, serial.chain)
    np.testing.assert_array_equal(local.log_prob, serial.log_prob)
    # proposals outside the bounds are not evaluated: fewer than 8 x 60, the same count
    assert remote_posterior.evaluations == serial_posterior.evaluations > 8 * 30
    assert np.ptp(serial.chain[-1, :, 0]) > 0  # the walkers moved apart: a chain that could differ


def test_sample_of_a_user_model_with_two_workers_is_the_serial_run(tmp_path, capsys):
    """The user's path: ``sample --workers 2`` of a model that cannot batch (its optimum's starts
    and every walker's evaluation on the workers): the JSON summary of the chain (less the wall
    time) is the serial run's, bit for bit."""
    from bayesupdate.cli import main

    study = str(user_model_study(tmp_path))
    outs = []
    for extra in ([], ["--workers", "2"]):
        assert main(["sample", study, "--json", *extra]) == 0
        outs.append(json.loads(capsys.readouterr().out.splitlines()[-1]))
    serial, local = outs
    assert serial.pop("wall_s") > 0 and local.pop("wall_s") > 0
    assert serial.pop("timings") and local.pop("timings")  # wall times: differ run to run
    assert serial.pop("compute") == {"kind": "serial", "workers": 1}
    assert local.pop("compute") == {"kind": "processes", "workers": 2}
    assert local == serial
    assert serial["pairing"] == "points" and serial["steps"] == 60
    assert serial["parameters"]["k1"]["sd"] > 0
