"""The user paths of the heavy-work benchmark, side by side: each run through the CLI as a user
types it (a subprocess, the user's defaults), N times, medians printed.

    calibrate_shell_first   calibrate --model exhaust_shell --data paper:ema, empty cache folder
    calibrate_shell_cached  the same again in that folder (the reduced basis from the cache)
    demo_quick              demo --quick
    demo                    demo
    sample_exhaust          sample --model exhaust --data paper:ema

Every run gets its own output folder; the calibrate pair gets a fresh BAYESUPDATE_CACHE_DIR
per repetition, every other path one shared fresh cache folder for all its runs (a user's
second demo reads the bases its first built: the first run of each path is the fresh-clone
one, and is printed on its own).  Wall and CPU seconds (the child's user + system) and the
1-minute load average before each run are printed: on a shared machine the wall time says
little without them.

The calibrate pair also prints each run's phase timings (``timings`` of its ``--json``: the
basis's snapshots, certification or cached check, the starts, the check of the ends) and the
largest relative frequency and parameter gap of the cached run's optimum to the first run's;
``--workers N`` runs that pair on N local processes (the executor seam; default: serial, as a
user's plain command).

    python benchmarks/user_paths.py --only demo_quick --runs 3
    python benchmarks/user_paths.py --only calibrate_shell_first,calibrate_shell_cached --runs 1
    python benchmarks/user_paths.py --only calibrate_shell_first,calibrate_shell_cached --workers 2
"""

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

SHELL = ["calibrate", "--model", "exhaust_shell", "--data", "paper:ema", "--json"]
#: path name -> the CLI arguments (``{out}``: the run's own output folder)
PATHS = {
    "calibrate_shell_first": SHELL,
    "calibrate_shell_cached": SHELL,
    "demo_quick": ["demo", "--quick", "--out", "{out}", "--force"],
    "demo": ["demo", "--out", "{out}", "--force"],
    "sample_exhaust": ["sample", "--model", "exhaust", "--data", "paper:ema", "--json"],
}


def run_cli(arguments: list[str], cache: str, out: str) -> dict:
    """One CLI run: {"wall_s", "cpu_s", "load", "stdout"}; SystemExit when it fails."""
    env = dict(os.environ, BAYESUPDATE_CACHE_DIR=cache, OPENBLAS_NUM_THREADS="1")
    env.pop("BAYESUPDATE_NO_CACHE", None)
    cmd = [sys.executable, "-m", "bayesupdate", *(a.format(out=out) for a in arguments)]
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(cmd + ["--quiet"], capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed: {done.stderr.strip()[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall_s": wall, "cpu_s": cpu, "load": load, "stdout": done.stdout}


def _calibrate_pairs(runs: int, wanted: set, workers: int = 1) -> dict:
    """The calibrate pair ``runs`` times, each in a fresh cache folder, on ``workers`` local
    processes (1: serial): {name: [run, ...]}."""
    out = {"calibrate_shell_first": [], "calibrate_shell_cached": []}
    shell = SHELL + (["--workers", str(workers)] if workers > 1 else [])
    for _ in range(runs):
        with tempfile.TemporaryDirectory() as cache:
            out["calibrate_shell_first"].append(run_cli(shell, cache, cache))
            if "calibrate_shell_cached" in wanted:
                out["calibrate_shell_cached"].append(run_cli(shell, cache, cache))
    first, cached = out["calibrate_shell_first"], out["calibrate_shell_cached"]
    for a, b in zip(first, cached, strict=False):
        ja, jb = json.loads(a["stdout"]), json.loads(b["stdout"])
        fa, fb = np.array(ja["frequencies_hz"]), np.array(jb["frequencies_hz"])
        b["optimum_gap"] = float(np.max(np.abs(fb / fa - 1)))
        pa, pb = ja["parameters"], jb["parameters"]
        b["parameter_gap"] = max(abs(pb[k] / pa[k] - 1) for k in pa)
    for r in first + cached:
        r["timings"] = json.loads(r["stdout"]).get("timings", {})
    return {k: v for k, v in out.items() if k in wanted}


def _repeated(name: str, runs: int) -> list[dict]:
    """``runs`` runs of path ``name`` sharing one fresh cache folder, each its own output."""
    done = []
    with tempfile.TemporaryDirectory() as cache:
        for k in range(runs):
            out = str(Path(cache) / f"out{k}")
            done.append(run_cli(PATHS[name], cache, out))
    return done


def report(name: str, done: list[dict]) -> None:
    """The median line of a path, then each run."""
    wall = np.median([r["wall_s"] for r in done])
    cpu = np.median([r["cpu_s"] for r in done])
    print(f"{name:24s} median wall {wall:7.1f} s  cpu {cpu:7.1f} s  ({len(done)} runs)")
    for k, r in enumerate(done):
        gap = ""
        if "optimum_gap" in r:
            gap = (f"  optimum vs first run: frequencies {r['optimum_gap']:.1e}, "
                   f"parameters {r['parameter_gap']:.1e}")  # fmt: skip
        print(
            f"{'':24s}   run {k + 1}: wall {r['wall_s']:7.1f} s  cpu {r['cpu_s']:7.1f} s  "
            f"load {r['load']:5.2f}{gap}"
        )
        for phase, seconds in r.get("timings", {}).items():
            print(f"{'':24s}     {phase}: {seconds:.1f} s wall")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default=",".join(PATHS), help="comma-separated path names")
    ap.add_argument("--runs", type=int, default=3, help="runs of each path (default 3)")
    ap.add_argument("--workers", type=int, default=1, help="calibrate pair: local processes")
    args = ap.parse_args()
    wanted = [n.strip() for n in args.only.split(",") if n.strip()]
    unknown = sorted(set(wanted) - set(PATHS))
    if unknown or args.runs < 1:
        raise SystemExit(f"--only: unknown {unknown}; paths are {list(PATHS)}; --runs >= 1")
    print(f"{os.cpu_count()} CPUs; OPENBLAS_NUM_THREADS=1; load before: {os.getloadavg()[0]:.2f}")
    shell = {n for n in wanted if n.startswith("calibrate_shell")}
    results = _calibrate_pairs(args.runs, shell, args.workers) if shell else {}
    for name in wanted:
        if name not in shell:
            results[name] = _repeated(name, args.runs)
    for name in wanted:
        report(name, results[name])


if __name__ == "__main__":
    main()
