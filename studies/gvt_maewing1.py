"""Real data: the mAEWing1 "Hati" ground vibration test, from time signals to modes.

Data: ../shared/data/gvt_maewing1 beside the checkout (zhaowei0566/mAEWing1, MIT; see its
README): 5 sine sweeps (about 3-35 Hz, 60 s at 2 kHz), one shaker (force 0.4684 V/lbf), two
accelerometers per run (1.028 V/g), runs 1-5 holding accelerometers 1-10 (odd: leading edge,
even: trailing edge).  The authors' peak picks (explog.txt): 7.797, 19.06, 23.82, 31.78 Hz, and
shallow peaks in 8.8-9.8, 15.4-16.4 (multiple) and 30.2-31.2 Hz.

Path a user takes, default settings: ``bayesupdate frf`` per run (the force is found to be a
sine sweep: one whole-record spectrum, 1/60 Hz lines, written up to the sweep's top, 35.2 Hz,
as the lines above hold the shaker's harmonics), then one ``bayesupdate identify`` on the 5
files as one roving test, with the band the authors give for the input (GVT_Info.m
FreqWin_Hz = [3 35]) and with the automatic band, for both estimators (LSCE, pLSCF).  Prints
the modes, the nearest mode to each peak pick, the shapes over the 10 accelerometers (real part
after rotation to the best real line, largest = 1) and writes the stabilization diagram of the
chosen run to OUT (default /tmp/gvt_study).

Run: .venv/bin/python studies/gvt_maewing1.py [OUT]
"""

import json
import sys
import tempfile
from pathlib import Path

import numpy as np

from bayesupdate.cli import main

DATA = Path(__file__).resolve().parents[2] / "shared" / "data" / "gvt_maewing1" / "data"
PEAKS_HZ = np.array([7.797, 9.3, 15.9, 19.06, 23.82, 30.7, 31.78])


def make_frfs(folder: Path) -> list[Path]:
    paths = []
    for k in range(1, 6):
        out = folder / f"run{k}.uff"
        argv = [
            "frf", DATA / f"run_Run{k}.mat", "--force-channel", "Force",
            "--response", f"Accel1={2 * k - 1}V", "--response", f"Accel2={2 * k}V",
            "--reference", "25V", "--force-unit", "lbf", "--force-sensitivity", "0.4684",
            "--response-unit", "g", "--response-sensitivity", "1.028", "--out", out, "--force",
        ]  # fmt: skip
        if main([str(a) for a in argv]) != 0:
            raise SystemExit(f"frf failed on run {k}")
        paths.append(out)
    return paths


def identify_json(paths, out, method, band=None, plots=None) -> dict:
    import contextlib
    import io

    argv = ["identify", *map(str, paths), "--out", str(out), "--json", "--force"]
    argv += ["--method", method] + (["--band", band] if band else [])
    argv += ["--plots", str(plots)] if plots else []
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main(argv)
    if code != 0:
        raise SystemExit(f"identify failed ({method}, {band})")
    return json.loads(buf.getvalue())


def main_study(out_dir: Path) -> int:
    from bayesupdate.ema.lsfd import realise
    from bayesupdate.ema.modal_h5 import read_modal_h5

    if not (DATA / "run_Run1.mat").is_file():
        print(f"data not found at {DATA}")
        return 1
    out_dir.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        paths = make_frfs(Path(tmp))
        for method in ("lsce", "plscf"):
            for band in ("3:35", None):
                plots = out_dir / f"{method}_{band or 'auto'}".replace(":", "-")
                h5 = Path(tmp) / f"{method}.h5"
                summary = identify_json(paths, h5, method, band, plots)
                found = np.array([m["frequency_hz"] for m in summary["modes"]])
                nearest = [found[np.argmin(np.abs(found - p))] for p in PEAKS_HZ]
                print(f"\n== {method}, band {band or 'automatic'}: {found.size} modes")
                print("  modes [Hz]:", " ".join(f"{x:.2f}" for x in found))
                for p, n in zip(PEAKS_HZ, nearest, strict=True):
                    print(f"  peak pick {p:6.2f} Hz -> {n:6.2f} Hz ({100 * (n / p - 1):+.2f} %)")
                if method == "lsce" and band == "3:35":
                    modes = read_modal_h5(h5)
                    shapes = realise(modes.shapes)
                    shapes = (
                        shapes / shapes[np.argmax(np.abs(shapes), axis=0), range(shapes.shape[1])]
                    )
                    print("  shapes (accelerometer: odd = leading edge, even = trailing edge)")
                    print("    acc " + " ".join(f"{f:7.2f}" for f in modes.frequencies_hz))
                    for lab, row in zip(modes.dof_labels, shapes, strict=True):
                        print(f"    {lab:>3s} " + " ".join(f"{v:+7.2f}" for v in row))
                    print(f"  stabilization diagram: {plots / 'stabilization.png'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main_study(Path(sys.argv[1] if len(sys.argv) > 1 else "/tmp/gvt_study")))
