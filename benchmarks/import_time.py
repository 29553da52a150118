"""Import time per CLI command: the median time to import the modules each command loads, over N
fresh processes (no asserts: numbers to read, side by side with another checkout's).

For each command, one recording run executes it through the CLI as a user types it and lists
``sys.modules`` at its end (in the order the modules were first entered); then N fresh processes
(``python -X importtime``) import that list in that order and nothing else.  Printed per command:
the median wall time of those imports [s] (the interpreter's own start excluded), the number of
modules, the median self time (``-X importtime``'s own figures) summed per package or
``bayesupdate`` room, largest first, and whether the costly optional packages were loaded at all.
With ``--root`` given more than once, each command is timed for every checkout, the checkouts
taking turns run by run (a shared machine's load falls on all alike), printed one under another.

The data some commands need (a UFF file and its identified modes) is made once by ``simulate``
and ``identify`` in a temporary folder; every run gets its own cache folder
(``BAYESUPDATE_CACHE_DIR``), so a cached basis never changes what is loaded.

    python benchmarks/import_time.py --runs 5
    python benchmarks/import_time.py --runs 5 --root /path/to/main --root .   # before, after
    python benchmarks/import_time.py --only sample,discover --runs 7
"""

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
#: command name -> the CLI arguments ({tmp}: the folder holding the fixture files)
COMMANDS = {
    "demo --help": ["demo", "--help"],
    "modes": ["modes", "--model", "exhaust", "--json"],
    "identify": ["identify", "{tmp}/test.uff", "--out", "{tmp}/identified.h5", "--force"],
    "correlate": ["correlate", "--model", "exhaust", "--data", "{tmp}/modes.h5", "--json"],
    "calibrate": ["calibrate", "--model", "exhaust", "--data", "paper:ema", "--json"],
    "sample": ["sample", "--model", "exhaust", "--data", "paper:ema", "--json", "--workers", "1"],
    "discover": ["discover", "--model", "exhaust", "--data", "{tmp}/modes.h5", "--json"],
    "calibrate_shell": ["calibrate", "--model", "exhaust_shell", "--data", "paper:ema", "--json"],
}
#: the shell calibration builds a reduced basis of ~100 full solves: on request only
DEFAULT = [name for name in COMMANDS if name != "calibrate_shell"]
#: packages whose import costs a second or more on their own: loaded or not, per command
HEAVY = ["bayesupdate.discovery.workflow", "scipy.stats", "scipy.optimize", "emcee", "h5py", "tqdm",
         "arviz_base", "arviz_stats", "xarray", "pandas", "dask", "matplotlib"]  # fmt: skip

RECORD = """
import json, sys
from bayesupdate.cli import main
try:
    code = main(sys.argv[2:])
except SystemExit as exc:  # --help exits through argparse
    code = exc.code or 0
with open(sys.argv[1], "w") as f:
    json.dump({"code": code, "modules": list(sys.modules)}, f)
"""

IMPORT = """
import importlib, json, sys, time
names = json.load(open(sys.argv[1]))
t0 = time.perf_counter()
failed = []
for name in names:
    try:
        importlib.import_module(name)
    except Exception:  # a name that only exists as an alias another module made
        failed.append(name)
print(json.dumps({"seconds": time.perf_counter() - t0, "failed": failed}))
"""


def environment(root: Path, cache: str) -> dict:
    """The children's environment: ``root``'s package first on the path (every child also runs
    in a temporary folder, since ``python -c`` and ``-m`` put the working folder before it)."""
    env = dict(os.environ, PYTHONPATH=str(root), BAYESUPDATE_CACHE_DIR=cache)
    env.update(OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
    env.pop("BAYESUPDATE_NO_CACHE", None)
    return env


def cli(root: Path, arguments: list[str], tmp: str) -> None:
    """A fixture-making CLI run; SystemExit when it fails."""
    cmd = [sys.executable, "-m", "bayesupdate", *arguments, "--quiet"]
    done = subprocess.run(cmd, capture_output=True, text=True, env=environment(root, tmp), cwd=tmp)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed: {done.stderr.strip()[-2000:]}")


def record(root: Path, arguments: list[str], tmp: str) -> list[str]:
    """The modules one run of the command has loaded at its end, in first-entered order."""
    listing = Path(tmp) / "modules.json"
    argv = [a.format(tmp=tmp) for a in arguments]
    if "--help" not in argv:
        argv.append("--quiet")
    with tempfile.TemporaryDirectory() as cache:
        cmd = [sys.executable, "-c", RECORD, str(listing), *argv]
        done = subprocess.run(
            cmd, capture_output=True, text=True, env=environment(root, cache), cwd=cache
        )
    if done.returncode != 0 or json.loads(listing.read_text())["code"] != 0:
        raise SystemExit(f"bayesupdate {' '.join(argv)} failed: {done.stderr.strip()[-2000:]}")
    return [m for m in json.loads(listing.read_text())["modules"] if m != "__main__"]


def group(module: str) -> str:
    """Where a module's time is counted: ``bayesupdate.<room>``, ``scipy.<subpackage>``, or
    the top-level package."""
    parts = module.split(".")
    return ".".join(parts[:2]) if parts[0] in ("bayesupdate", "scipy") else parts[0]


def self_times(stderr: str) -> dict:
    """``-X importtime``'s own (self) microseconds of every import, summed per ``group``."""
    out: dict = {}
    for line in stderr.splitlines():
        match = re.match(r"import time:\s+(\d+) \|\s+\d+ \| \s*(\S+)$", line)
        if match:
            key = group(match.group(2))
            out[key] = out.get(key, 0) + int(match.group(1))
    return out


def import_once(root: Path, listing: Path, tmp: str) -> tuple[float, dict, list[str]]:
    """One fresh process importing the modules listed in ``listing``: (wall seconds of the
    imports, self time per ``group`` [us], the names that failed to import)."""
    cmd = [sys.executable, "-X", "importtime", "-c", IMPORT, str(listing)]
    done = subprocess.run(cmd, capture_output=True, text=True, env=environment(root, tmp), cwd=tmp)
    result = json.loads(done.stdout)
    return result["seconds"], self_times(done.stderr), result["failed"]


def time_imports(roots: list[Path], modules: list[list[str]], tmp: str, runs: int) -> list[dict]:
    """Per root: the median wall time of importing its ``modules`` over ``runs`` fresh
    processes, the median self time of each ``group`` of modules, and the names that failed to
    import.  The roots take turns, run by run, so that a change in the machine's load falls on
    all of them alike."""
    listings = []
    for k, names in enumerate(modules):
        listings.append(Path(tmp) / f"import{k}.json")
        listings[-1].write_text(json.dumps(names))
    done = [[import_once(root, listing, tmp) for root, listing in zip(roots, listings, strict=True)]
            for _ in range(runs)]  # fmt: skip
    out = []
    for k in range(len(roots)):
        seconds = [run[k][0] for run in done]
        levels = [run[k][1] for run in done]
        names = set().union(*levels)
        by_group = {n: float(np.median([lv.get(n, 0) for lv in levels])) / 1e6 for n in names}
        out.append({"median_s": float(np.median(seconds)), "all_s": seconds,
                    "groups_s": by_group, "failed": done[-1][k][2]})  # fmt: skip
    return out


def report(name: str, root: Path, modules: list[str], timed: dict, top: int) -> None:
    heavy = [h for h in HEAVY if h in modules]
    runs = ", ".join(f"{s:.2f}" for s in timed["all_s"])
    print(f"{name:16s} {str(root)[-28:]:>28s}  imports median {timed['median_s']:5.2f} s  "
          f"({len(modules)} modules; runs: {runs})")  # fmt: skip
    print(f"{'':16s}   heavy packages loaded: {', '.join(heavy) or 'none'}")
    largest = sorted(timed["groups_s"].items(), key=lambda kv: -kv[1])[:top]
    print(f"{'':16s}   largest: " + ", ".join(f"{n} {s:.2f} s" for n, s in largest))
    if timed["failed"]:
        print(f"{'':16s}   not importable by name (left out): {', '.join(timed['failed'])}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default=",".join(DEFAULT), help="comma-separated command names")
    ap.add_argument("--runs", type=int, default=5, help="fresh import processes per command")
    ap.add_argument("--root", type=Path, action="append",
                    help="checkout to time (repeat to compare; default: this one)")  # fmt: skip
    ap.add_argument("--top", type=int, default=5, help="groups of modules listed per command")
    args = ap.parse_args()
    wanted = [n.strip() for n in args.only.split(",") if n.strip()]
    unknown = sorted(set(wanted) - set(COMMANDS))
    if unknown or args.runs < 1:
        raise SystemExit(f"--only: unknown {unknown}; commands are {list(COMMANDS)}; --runs >= 1")
    roots = [r.resolve() for r in (args.root or [ROOT])]
    print(f"{os.cpu_count()} CPUs; load {os.getloadavg()[0]:.2f}; packages from {roots}")
    with tempfile.TemporaryDirectory() as tmp:
        if {"identify", "correlate", "discover"} & set(wanted):
            uff = f"{tmp}/test.uff"
            cli(roots[0], ["simulate", "--noise", "0.01", "--seed", "24", "--out", uff], tmp)
            cli(roots[0], ["identify", uff, "--out", f"{tmp}/modes.h5"], tmp)
        for name in wanted:
            modules = [record(root, COMMANDS[name], tmp) for root in roots]
            timed = time_imports(roots, modules, tmp, args.runs)
            for root, names, result in zip(roots, modules, timed, strict=True):
                report(name, root, names, result, args.top)


if __name__ == "__main__":
    main()
