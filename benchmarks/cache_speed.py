"""A command's first run against its second on the same model: the reduced-basis cache.

Runs ``bayesupdate calibrate --model MODEL --data DATA --json`` through the CLI (a user's
path, a user's defaults) in a fresh cache folder, then again; repeats the pair and prints the
median of each, their ratio, and whether the optimum is the same to the certified tolerance.

    python benchmarks/cache_speed.py                         # the beam exhaust, 3 pairs
    python benchmarks/cache_speed.py --model exhaust_shell --pairs 1
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np


def _run(model: str, data: str, cache: str) -> tuple[float, dict]:
    env = dict(os.environ, BAYESUPDATE_CACHE_DIR=cache, OPENBLAS_NUM_THREADS="1")
    env.pop("BAYESUPDATE_NO_CACHE", None)
    cmd = [sys.executable, "-m", "bayesupdate", "calibrate", "--model", model, "--data", data]
    t0 = time.perf_counter()
    out = subprocess.run(cmd + ["--json", "--quiet"], capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    if out.returncode != 0:
        raise SystemExit(f"calibrate failed: {out.stderr.strip()}")
    return wall, json.loads(out.stdout)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", default="exhaust")
    ap.add_argument("--data", default="paper:ema")
    ap.add_argument("--pairs", type=int, default=3)
    args = ap.parse_args()
    first, second, gaps = [], [], []
    for k in range(args.pairs):
        with tempfile.TemporaryDirectory() as cache:
            t1, r1 = _run(args.model, args.data, cache)
            t2, r2 = _run(args.model, args.data, cache)
        first.append(t1)
        second.append(t2)
        f1, f2 = np.array(r1["frequencies_hz"]), np.array(r2["frequencies_hz"])
        gaps.append(float(np.max(np.abs(f2 / f1 - 1))))
        print(f"pair {k + 1}: first {t1:.1f} s, cached {t2:.1f} s, "
              f"objective {r1['objective']:.6f} / {r2['objective']:.6f}, "
              f"largest frequency gap {gaps[-1]:.1e}", flush=True)  # fmt: skip
    m1, m2 = np.median(first), np.median(second)
    print(f"{args.model}: median first run {m1:.1f} s, cached {m2:.1f} s, ratio {m1 / m2:.2f}; "
          f"largest frequency gap between the two optima {max(gaps):.1e}")  # fmt: skip


if __name__ == "__main__":
    main()
