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

    python benchmarks/user_paths.py --only demo_quick --runs 3
    python benchmarks/user_paths.py --only calibrate_shell_first,calibrate_shell_cached --runs 1
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


def _calibrate_pairs(runs: int, wanted: set) -> dict:
    """The calibrate pair ``runs`` times, each in a fresh cache folder: {name: [run, ...]}."""
    out = {"calibrate_shell_first": [], "calibrate_shell_cached": []}
    for _ in range(runs):
        with tempfile.TemporaryDirectory() as cache:
            out["calibrate_shell_first"].append(run_cli(SHELL, cache, cache))
            if "calibrate_shell_cached" in wanted:
                out["calibrate_shell_cached"].append(run_cli(SHELL, cache, cache))
    first, cached = out["calibrate_shell_first"], out["calibrate_shell_cached"]
    for a, b in zip(first, cached, strict=False):
        fa = np.array(json.loads(a["stdout"])["frequencies_hz"])
        fb = np.array(json.loads(b["stdout"])["frequencies_hz"])
        b["optimum_gap"] = float(np.max(np.abs(fb / fa - 1)))
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
        gap = f"  optimum vs first run: {r['optimum_gap']:.1e}" if "optimum_gap" in r else ""
        print(
            f"{'':24s}   run {k + 1}: wall {r['wall_s']:7.1f} s  cpu {r['cpu_s']:7.1f} s  "
            f"load {r['load']:5.2f}{gap}"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default=",".join(PATHS), help="comma-separated path names")
    ap.add_argument("--runs", type=int, default=3, help="runs of each path (default 3)")
    args = ap.parse_args()
    wanted = [n.strip() for n in args.only.split(",") if n.strip()]
    unknown = sorted(set(wanted) - set(PATHS))
    if unknown or args.runs < 1:
        raise SystemExit(f"--only: unknown {unknown}; paths are {list(PATHS)}; --runs >= 1")
    print(f"{os.cpu_count()} CPUs; OPENBLAS_NUM_THREADS=1; load before: {os.getloadavg()[0]:.2f}")
    shell = {n for n in wanted if n.startswith("calibrate_shell")}
    results = _calibrate_pairs(args.runs, shell) if shell else {}
    for name in wanted:
        if name not in shell:
            results[name] = _repeated(name, args.runs)
    for name in wanted:
        report(name, results[name])


if __name__ == "__main__":
    main()
