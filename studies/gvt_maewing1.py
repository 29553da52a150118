"""Real data: the mAEWing1 "Hati" ground vibration test, from time signals to modes through the
command line, with defaults.

Data: ../shared/data/gvt_maewing1 beside the checkout (zhaowei0566/mAEWing1, MIT; see its
README): 10 sine sweeps (about 1-35 Hz, 60 s at 2 kHz), one shaker (force 0.4684 V/lbf) as
reference 25V, two accelerometers per run (1.028 V/g), run K holding accelerometers 2K-1 and
2K (1-10 on the right wing, 11-20 on the left; odd: leading edge).  The authors' peak picks
(explog.txt): 7.797, 19.06, 23.82, 31.78 Hz, and shallow peaks in 8.8-9.8, 15.4-16.4
(multiple) and 30.2-31.2 Hz.

The chain: ``bayesupdate frf`` on each of the 10 runs (the force is found to be a sine sweep:
one whole-record spectrum, 1/60 Hz lines, written from the lowest line the run's force
excites to the sweep's top, 35.15 Hz), then one ``bayesupdate identify`` on the 10 files,
defaults (their common lines, run groups found where poles shift), for both estimators
(LSCE, pLSCF).  Prints the wall time of each command, the run groups, and per mode the
frequency with its sd, the per-group frequencies and spread, and the MPC with one pole over
all runs and assembled from the groups; the nearest mode to each peak pick.

``--package DIR`` also writes the 10 FRF files in single precision (UFF 58 ordinate type 5,
6 digits) to DIR: the compact copy shipped as ``bayesupdate/data/maewing1``.

Run: .venv/bin/python studies/gvt_maewing1.py [OUT] [--package DIR]
"""

import contextlib
import io
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bayesupdate.cli import main

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "gvt_maewing1" / "data"
PEAKS_HZ = np.array([7.797, 9.3, 15.9, 19.06, 23.82, 30.7, 31.78])
N_RUNS = 10


def frf_argv(k: int, out: Path) -> list[str]:
    """``bayesupdate frf`` arguments of run k (1..10), defaults otherwise."""
    return [str(a) for a in [
        "frf", DATA / f"run_Run{k}.mat", "--force-channel", "Force",
        "--response", f"Accel1={2 * k - 1}V", "--response", f"Accel2={2 * k}V",
        "--reference", "25V", "--force-unit", "lbf", "--force-sensitivity", "0.4684",
        "--response-unit", "g", "--response-sensitivity", "1.028", "--out", out, "--force",
    ]]  # fmt: skip


def make_frfs(folder: Path) -> tuple[list[Path], list[float]]:
    """The 10 FRF files and the wall time [s] of each ``frf`` command."""
    paths, times = [], []
    for k in range(1, N_RUNS + 1):
        out = folder / f"run{k}.uff"
        t0 = time.perf_counter()
        with contextlib.redirect_stdout(io.StringIO()):
            code = main(frf_argv(k, out))
        times.append(time.perf_counter() - t0)
        if code != 0:
            raise SystemExit(f"frf failed on run {k}")
        paths.append(out)
    return paths, times


def identify_json(paths, out, method) -> tuple[dict, float]:
    argv = ["identify", *map(str, paths), "--out", str(out), "--json", "--force"]
    argv += ["--method", method]
    buf = io.StringIO()
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(buf):
        code = main(argv)
    if code != 0:
        raise SystemExit(f"identify failed ({method})")
    return json.loads(buf.getvalue()), time.perf_counter() - t0


def print_modes(summary: dict) -> None:
    groups = summary["groups"]
    print("  run groups: " + " | ".join(f"{g['files'][0]}-{g['files'][-1]}" for g in groups))
    head = "  mode   f [Hz]    sd [Hz]  " + " ".join(
        f"group{k + 1:<4d}" for k in range(len(groups))
    )
    print(head + " spread [Hz]  MPC one pole  MPC groups")
    for r, m in enumerate(summary["modes"], 1):
        per = m.get("per_group", [])
        cells = " ".join(
            f"{g['frequency_hz']:8.3f}{'' if g['sees'] else '*'}{' ' if g['sees'] else ''}"
            for g in per
        )
        print(
            f"  {r:4d} {m['frequency_hz']:8.3f} {m['identification_sd_hz']:9.4f}  {cells} "
            f"{m.get('frequency_spread_hz', 0.0):10.4f} {m.get('mpc_one_pole', m['mpc']):12.3f} "
            f"{m['mpc']:11.3f}"
        )
    print("  (* the group does not see the mode: its frequency sd exceeds its half-width)")


def write_package(paths, folder: Path) -> None:
    """The FRF files in single precision in ``folder`` (the package's compact copy)."""
    from bayesupdate.ema.uff_io import read_uff58, write_uff58

    folder.mkdir(parents=True, exist_ok=True)
    for path in paths:
        write_uff58(folder / path.name, read_uff58(path), single=True)
    total = sum((folder / p.name).stat().st_size for p in paths)
    print(f"packaged {len(paths)} FRF files in {folder}: {total / 1e6:.2f} MB")


def main_study(out_dir: Path, package: Path | None = None) -> int:
    if not (DATA / "run_Run1.mat").is_file():
        print(f"data not found at {DATA}")
        return 1
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        paths, times = make_frfs(Path(tmp))
        print("frf wall time per run [s]: " + " ".join(f"{t:.1f}" for t in times))
        if package is not None:
            write_package(paths, package)
        for method in ("lsce", "plscf"):
            summary, wall = identify_json(paths, out_dir / f"{method}.h5", method)
            found = np.array([m["frequency_hz"] for m in summary["modes"]])
            print(f"\n== identify on {N_RUNS} files, {method}: {found.size} modes, {wall:.1f} s")
            print_modes(summary)
            for p in PEAKS_HZ:
                n = found[np.argmin(np.abs(found - p))]
                print(f"  peak pick {p:6.2f} Hz -> {n:6.2f} Hz ({100 * (n / p - 1):+.2f} %)")
            for note in summary["notes"]:
                print(f"  note: {note}")
    return 0


if __name__ == "__main__":
    args = sys.argv[1:]
    pkg = None
    if "--package" in args:
        i = args.index("--package")
        pkg = Path(args[i + 1])
        del args[i : i + 2]
    raise SystemExit(main_study(Path(args[0] if args else "/tmp/gvt_study"), pkg))
