"""Scale-out: wall time of two parallel phases on 1 and 2 workers, local and through Dask.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/scale_out.py [--snapshots 8] [--no-deck]
        [--starts 8] [--phases snapshots discovery calibration]

Needs ``bayesupdate[dask]`` (and pyNastran for the deck).  Phases:

* snapshots: the reduced basis's snapshot phase (``fe.reduced.basis.full_solves``, one full
  solve per scrambled-Sobol point, the deck's PSHELL 3 thickness in [2.5, 3.5]) of the largest
  model the project has, the FEMAP exhaust deck (4,466 shells, 26,832 DOFs; ``--no-deck``: the
  built-in exhaust instead);
* discovery: one ``discover`` of the built-in exhaust against the paper's test (one baseline
  start, 8 quick refits, 2 full refits; the baseline calibration and the LOO are serial);
* calibration: the multi-start calibration of ``calibrate --model exhaust --data paper:ema``
  (the reference start and ``--starts`` Sobol starts, one task each: least squares and
  Nelder-Mead on the reduced basis, then the near-best ends polished on the full model, one
  task each); the reduced basis is built once before the timings.

Executors: serial (this process), local processes (``ProcessExecutor``) with 1 and 2 workers, and
a ``dask scheduler`` with 1 then 2 ``dask worker`` processes (one thread each) started on
127.0.0.1.  Start-up (spawning the pool, or connecting) is timed apart; a phase's time includes
sending its shared payload (the model) to the workers.  Each phase's result must equal the serial
one bit for bit (checked, printed).  Speed-up S = T_serial / T_n, efficiency S / n, and the
serial fraction of the Karp-Flatt / Amdahl fit f = (n / S - 1) / (n - 1) at n = 2.  Nothing is
asserted: on a shared 2-core machine the numbers are noisy.
"""

import argparse
import os
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

PHASES = ("snapshots", "discovery", "calibration")
DECK = Path(__file__).resolve().parents[2] / "shared/data/nastran/femap_exhaust/exhaust.bdf"


def snapshot_phase(use_deck: bool, n_points: int):
    """(callable(executor) -> (frequencies, shapes), label) of the snapshot phase."""
    from scipy.stats import qmc

    from bayesupdate.fe.reduced.basis import full_solves

    if use_deck:
        from bayesupdate.nastran import load_nastran_model

        fe = load_nastran_model(DECK, {"t3": {"binds": "PSHELL 3 T", "bounds": [2.5, 3.5]}})
        label = f"femap exhaust deck, {n_points} snapshots"
    else:
        from bayesupdate.models import get_model

        fe = get_model("exhaust")
        label = f"built-in exhaust, {n_points} snapshots"
    names = fe.parameter_names
    low = np.array([fe.default_bounds()[n][0] for n in names])
    high = np.array([fe.default_bounds()[n][1] for n in names])
    u = qmc.Sobol(len(names), scramble=True, seed=0).random(n_points)
    theta = low + u * (high - low)
    return (lambda ex: full_solves(fe, names, theta, 12, ex)), label


def calibration_phase(starts: int):
    """(callable(executor) -> (end points, end objectives, evaluations), label)."""
    from bayesupdate.config import StudyConfig, with_overrides
    from bayesupdate.inference.optimize import CalibrationSettings, calibrate
    from bayesupdate.pipelines.study import prepare
    from bayesupdate.pipelines.surrogates import sampling_problem

    study = with_overrides(StudyConfig(), model__source="exhaust", data__source="paper:ema")
    prepared = prepare(study)
    search, _ = sampling_problem(prepared.problem, None, True, study.sampler.reduced_tol)
    settings = CalibrationSettings(starts=starts, seed=study.optimizer.seed)

    def run(ex):
        result = calibrate(search, settings, refine=prepared.problem, executor=ex)
        return result.end_points, result.end_objectives, result.evaluations

    return run, f"calibration of the built-in exhaust ({starts + 1} starts, full-model polish)"


def discovery_phase():
    """(callable(executor) -> the discovery JSON less its wall time, label)."""
    from bayesupdate.discovery.workflow import DiscoverySettings, discover
    from bayesupdate.inference.data import load_modal_data
    from bayesupdate.models import get_model

    model, data = get_model("exhaust"), load_modal_data("paper:ema")
    settings = DiscoverySettings(
        baseline_starts=1, quick_refits=8, per_kind=1, max_refits=2, loo_top=1
    )

    def run(ex):
        result = discover(model, data, settings, executor=ex)
        if ex.kind == "serial":
            _print_structure(result)
        out = result.to_json()
        out.pop("wall_s")
        return out

    return run, "discovery of the built-in exhaust (58 candidates, 8+ quick, 2 full refits)"


def _print_structure(result) -> None:
    """The serial run's phase times and the share of its wall time outside the parallel phases
    (scan and refits): the serial fraction by construction, whatever the machine's load."""
    t = result.timings
    parallel = t["localization_s"] + t["refits_s"]
    phases = ", ".join(f"{k} {v:.1f}" for k, v in t.items())
    print(f"  discovery phases [s]: {phases}, wall {result.wall_s:.1f}; outside the scan and "
          f"refits: {1 - parallel / result.wall_s:.2f} of the wall time", flush=True)  # fmt: skip


def same(a, b) -> bool:
    if isinstance(a, tuple):
        return all(same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, np.ndarray):
        return a.shape == b.shape and bool(np.array_equal(a, b, equal_nan=True))
    return a == b


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def _square(_, x):
    return x * x


class DaskProcesses:
    """A ``dask scheduler`` on 127.0.0.1 and the ``dask worker`` processes added to it."""

    def __init__(self):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        self.address = f"tcp://127.0.0.1:{port}"
        self.env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
        self.procs = [self._start("distributed.cli.dask_scheduler", "--host", "127.0.0.1",
                                  "--port", str(port))]  # fmt: skip

    def _start(self, *args):
        cmd = [sys.executable, "-m", *args, "--no-dashboard"]
        return subprocess.Popen(cmd, env=self.env, stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)  # fmt: skip

    def add_worker(self, n_total: int) -> None:
        from distributed import Client

        self.procs.append(self._start("distributed.cli.dask_worker", self.address, "--nthreads",
                                      "1", "--host", "127.0.0.1"))  # fmt: skip
        with Client(self.address, timeout=120) as client:
            client.wait_for_workers(n_total, timeout=300)

    def close(self) -> None:
        for p in reversed(self.procs):
            p.terminate()
            p.wait(timeout=30)


def run_all(phases, dask: DaskProcesses) -> list[dict]:
    from bayesupdate.compute.dask import DaskExecutor
    from bayesupdate.compute.executors import ProcessExecutor, SerialExecutor

    rows, reference = [], {}
    setups = [("serial", 1, SerialExecutor), ("local", 1, lambda: ProcessExecutor(1)),
              ("local", 2, lambda: ProcessExecutor(2))]  # fmt: skip
    setups += [("dask", n, lambda: DaskExecutor(dask.address)) for n in (1, 2)]
    for kind, n, make in setups:
        if kind == "dask":
            dask.add_worker(n)
        t_start, ex = timed(lambda: make())  # noqa: B023 - called at once
        with ex:
            t_warm, _ = timed(lambda: ex.map(_square, range(2 * n)))  # noqa: B023
            for name, (fn, _) in phases.items():
                t, out = timed(lambda: fn(ex))  # noqa: B023
                ok = same(out, reference.setdefault(name, out))
                start = t_start + t_warm
                rows.append(dict(phase=name, kind=kind, workers=n, wall_s=t, startup_s=start,
                                 identical=ok))  # fmt: skip
                print(f"  {name:10s} {kind:6s} n={n}: {t:7.1f} s (start-up {start:5.1f} s), "
                      f"same bits as serial: {ok}", flush=True)  # fmt: skip
    return rows


def report(rows: list[dict], phases) -> None:
    print("\nS: speed-up vs serial; S1: vs the same executor with 1 worker; f: Amdahl serial"
          " fraction from S at n = 2")  # fmt: skip
    print("phase       executor  n   wall [s]      S   S/n     f     S1")
    for name, (_, label) in phases.items():
        serial = next(r["wall_s"] for r in rows if r["phase"] == name and r["kind"] == "serial")
        for r in (r for r in rows if r["phase"] == name):
            s, n = serial / r["wall_s"], r["workers"]
            one = next(q["wall_s"] for q in rows if q["phase"] == name and q["kind"] == r["kind"])
            f = f"{(n / s - 1) / (n - 1):5.2f}" if n > 1 else "    -"
            print(f"{name:10s}  {r['kind']:7s}  {n}  {r['wall_s']:8.1f}  {s:5.2f} {s / n:5.2f} "
                  f"{f}  {one / r['wall_s']:5.2f}")  # fmt: skip
        print(f"  ({label})")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--snapshots", type=int, default=8)
    parser.add_argument("--no-deck", action="store_true", help="built-in exhaust snapshots")
    parser.add_argument("--starts", type=int, default=8, help="calibration: Sobol starts")
    parser.add_argument("--phases", nargs="+", default=list(PHASES), choices=PHASES)
    args = parser.parse_args(argv)
    print(f"cores: {os.cpu_count()}, load average: {os.getloadavg()}")
    make = {
        "snapshots": lambda: snapshot_phase(not args.no_deck, args.snapshots),
        "discovery": discovery_phase,
        "calibration": lambda: calibration_phase(args.starts),
    }
    phases = {name: make[name]() for name in args.phases}
    dask = DaskProcesses()
    try:
        rows = run_all(phases, dask)
    finally:
        dask.close()
    report(rows, phases)
    print(f"load average at the end: {os.getloadavg()}")


if __name__ == "__main__":
    main()
