"""The executor seam (bayesupdate.parallel_executor) without Dask: which executor the options
choose, one-line errors for bad input, results in submission order on local processes whatever
order the tasks finish in, a killed local worker's tasks run again, and a discovery on two local
processes is the serial discovery bit for bit."""

import json
import os
import signal
import time
from pathlib import Path

import numpy as np
import pytest

# kept light: spawned workers import this module for its task functions
from bayesupdate.errors import BayesUpdateError
from bayesupdate.parallel_executor import (
    SCHEDULER_VARIABLE,
    SERIAL,
    ComputeSettings,
    ProcessExecutor,
    check_address,
    compute_settings,
)

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


def small_discovery_study(folder: Path) -> Path:
    path = folder / "small_discovery.toml"
    path.write_text(SMALL_DISCOVERY)
    return path


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
    from bayesupdate.config import parse_study

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
    with pytest.raises(BayesUpdateError, match=words) as err:
        compute_settings(**kwargs)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize(
    "table, words",
    [
        ({"workers": 0}, "must be >= 1"),
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
    assert check_address("head:8786") == "tcp://head:8786"
    assert check_address("tcp://[::1]:8786") == "tcp://[::1]:8786"
    assert check_address(" tls://node-3.cluster:1 ") == "tls://node-3.cluster:1"


def test_local_processes_return_submission_order_and_share_once():
    with ProcessExecutor(2) as ex:
        out = ex.map(_slow_square, [0, 1, 2, 3], shared=0.2)
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

    study = small_discovery_study(tmp_path)
    outs = []
    for extra in ([], ["--workers", "2"]):
        assert main(["discover", str(study), "--json", *extra]) == 0
        outs.append(json.loads(capsys.readouterr().out))
    serial, local = outs
    assert serial["compute"] == {"kind": "serial", "workers": 1}
    assert local.pop("compute") == {"kind": "processes", "workers": 2}
    serial.pop("compute")
    assert serial.pop("wall_s") > 0 and local.pop("wall_s") > 0
    assert local == serial
    assert np.isfinite(serial["baseline"]["log_evidence"])


def test_scheduler_without_dask_installed_says_how_to_install(monkeypatch, capsys):
    import sys

    from bayesupdate.cli import main

    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    assert main(["discover", "--model", "exhaust", "--scheduler", "tcp://127.0.0.1:8786"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "pip install 'bayesupdate[dask]'" in err
