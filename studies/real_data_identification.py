"""Every real dataset, both estimators, on the path a user takes.

Data (../shared/data beside the checkout, each folder's README gives source and references):
- beam_frf_sdpy: one measured accelerance of the LADISK free beam (UFF 58, 1-10000 Hz); the
  authors' frequencies 176.07, 476.46, 932.29, 1534.79, 2286.32, 3162.16, 4181.72 Hz (LSCF
  over 10-5000 Hz).  Other poles are split into those within the authors' range, bending modes
  8-11 above it (within 1 % of the free-free Timoshenko sequence fitted to the authors' 7,
  tests/free_beam_theory.py; the pole-by-pole table is studies/beam_frf_poles.py) and
  unexplained ones.
- plate_sweep: ``bayesupdate frf`` (default settings: a sine sweep, one whole-record spectrum
  per repetition, 0.5 Hz lines) on the four view-0 repetitions, then the automatic band and
  60:500, 100:480, 80:470; peaks near 126, 214, 264, 348, 450 Hz (README: 126, 214, 265, 350,
  452 from an H1 at 0.5 Hz), other poles counted in 60-500 Hz.
- gvt_maewing1: ``bayesupdate frf`` per run (5 runs, 10 roving accelerometers), one
  ``identify`` over the 5 files, automatic band and 3:35; the authors' peak picks 7.797, 19.06,
  23.82, 31.78 Hz and shallow peaks near 9.3, 15.9 (15.4-16.4, "multiple") and 30.7 Hz.

Each ``bayesupdate identify`` runs with default settings and ``--method lsce`` and
``--method plscf``.  sdypy-EMA (optional peer, in .venv) runs its LSCE and LSCF on the beam
(order 40 up to 4500 Hz; LSCF from 100 Hz, LSCE from 0 Hz, as its LSCE keeps the full-band
time step and a lower limit above 0 biases it, see studies/plate_sweep.py; its stable pole
nearest each reference by ``select_closest_poles``).

Run: .venv/bin/python studies/real_data_identification.py
"""

import contextlib
import io
import json
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from free_beam_theory import timoshenko_fit, timoshenko_hz  # noqa: E402

from bayesupdate.cli import main as cli  # noqa: E402

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"
BEAM_UFF = SHARED / "beam_frf_sdpy" / "data" / "measurement.uff"
BEAM_HZ = np.array([176.07, 476.46, 932.29, 1534.79, 2286.32, 3162.16, 4181.72])
PLATE_HZ = np.array([126.0, 214.0, 264.0, 348.0, 450.0])
PLATE_TOL = np.array([0.015, 0.015, 0.015, 0.015, 0.025])
GVT_HZ = np.array([7.797, 9.3, 15.9, 19.06, 23.82, 30.7, 31.78])
METHODS = ("lsce", "plscf")


def run_cli(argv: list) -> str:
    """stdout of one ``bayesupdate`` call; SystemExit if it fails."""
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = cli([str(a) for a in argv])
    if code != 0:
        raise SystemExit(f"bayesupdate {' '.join(map(str, argv[:2]))} failed ({code})")
    return buf.getvalue()


def identify_hz(paths: list, out: Path, method: str, band: str | None = None) -> np.ndarray:
    argv = ["identify", *paths, "--out", out, "--json", "--force", "--method", method]
    argv += ["--band", band] if band else []
    summary = json.loads(run_cli(argv))
    return np.array([m["frequency_hz"] for m in summary["modes"]])


def nearest(found: np.ndarray, ref: np.ndarray) -> np.ndarray:
    if found.size == 0:
        return np.full(ref.size, np.nan)
    return np.array([found[np.argmin(np.abs(found - r))] for r in ref])


def others(found: np.ndarray, matched: np.ndarray, lo: float, hi: float) -> list[float]:
    """Found modes in lo..hi that are not one of the matched ones."""
    taken = matched[np.isfinite(matched)]
    return [x for x in found if lo <= x <= hi and not np.any(np.isclose(x, taken))]


def print_table(title: str, ref: np.ndarray, columns: dict, tol: np.ndarray) -> None:
    """Reference vs each column's nearest mode; '-' where it is farther than tol."""
    print(f"\n== {title}")
    print(f"{'reference':>10} " + " ".join(f"{name:>17}" for name in columns))
    for k, r in enumerate(ref):
        cells = []
        for near in columns.values():
            err = near[k] / r - 1
            ok = np.isfinite(err) and abs(err) <= tol[k]
            cells.append(f"{near[k]:9.2f} {100 * err:+6.2f}%" if ok else f"{'-':>17}")
        print(f"{r:10.2f} " + " ".join(cells))


def beam(tmp: Path) -> None:
    cols, extra = {}, {}
    for method in METHODS:
        found = identify_hz([BEAM_UFF], tmp / "beam.h5", method)
        near = nearest(found, BEAM_HZ)
        hit = np.abs(near / BEAM_HZ - 1) <= 0.005
        cols[method] = np.where(hit, near, np.nan)
        extra[method] = others(found, cols[method], 0.0, np.inf)
    for method, near in sdypy_beam().items():
        cols[f"sdypy {method}"] = near
    print_table("beam FRF (measurement.uff), automatic band; within 0.5 %", BEAM_HZ, cols,
                np.full(BEAM_HZ.size, 0.005))  # fmt: skip
    bending = timoshenko_hz(np.arange(8, 12), timoshenko_fit())
    fmt = ", ".join
    for method, x in extra.items():
        x = np.array(x)
        inside, above = x[x <= 5000.0], x[x > 5000.0]
        is_bending = np.array([np.min(np.abs(v / bending - 1)) < 0.01 for v in above], bool)
        print(f"  {method} other poles: {x.size}; within 5 kHz: {inside.size} ("
              + fmt(f"{v:.1f}" for v in inside) + "); bending modes 8-11 above it: "
              + fmt(f"{v:.1f}" for v in above[is_bending]) + " (predicted "
              + fmt(f"{v:.0f}" for v in bending) + "); unexplained above 5 kHz: "
              + fmt(f"{v:.1f}" for v in above[~is_bending]))  # fmt: skip


def sdypy_beam() -> dict:
    """sdypy-EMA's LSCE and LSCF on the beam FRF: its stable pole nearest each reference."""
    try:
        from sdypy import EMA
    except ImportError:
        print("(sdypy-EMA not installed: peer columns left out)")
        return {}
    from bayesupdate.ema.uff_io import read_uff58

    frfs = read_uff58(BEAM_UFF)
    out = {}
    for method, lower in (("lsce", 0.0), ("lscf", 100.0)):
        model = EMA.Model(
            frf=frfs.frf, freq=frfs.frequencies_hz, lower=lower, upper=4500,
            pol_order_high=40, frf_form="accelerance",
        )  # fmt: skip
        quiet = contextlib.redirect_stderr(io.StringIO())  # its progress bars
        with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()), quiet:
            warnings.simplefilter("ignore")
            model.get_poles(method=method, show_progress=False)
            model.select_closest_poles(list(BEAM_HZ), f_window=50)
        out[method] = np.asarray(model.nat_freq, dtype=float)
    return out


def plate(tmp: Path) -> None:
    files = sorted((SHARED / "plate_sweep").glob("view_0*.hdf5"))
    uff = tmp / "plate.uff"
    argv = ["frf", *files, "--force-channel", "force", "--response", "acc=1V"]
    run_cli(argv + ["--reference", "1V", "--out", uff])
    for band in (None, "60:500", "100:480", "80:470"):
        cols, extra = {}, {}
        for method in METHODS:
            found = identify_hz([uff], tmp / "plate.h5", method, band)
            near = nearest(found, PLATE_HZ)
            cols[method] = np.where(np.abs(near / PLATE_HZ - 1) <= PLATE_TOL, near, np.nan)
            extra[method] = others(found, cols[method], 60.0, 500.0)
        print_table(f"plate, band {band or 'automatic'}", PLATE_HZ, cols, PLATE_TOL)
        for method, x in extra.items():
            print(f"  {method} other poles in 60-500 Hz: {len(x)} (" + ", ".join(
                f"{v:.1f}" for v in x) + ")")  # fmt: skip


def gvt(tmp: Path) -> None:
    data = SHARED / "gvt_maewing1" / "data"
    paths = []
    for k in range(1, 6):
        out = tmp / f"run{k}.uff"
        run_cli([
            "frf", data / f"run_Run{k}.mat", "--force-channel", "Force",
            "--response", f"Accel1={2 * k - 1}V", "--response", f"Accel2={2 * k}V",
            "--reference", "25V", "--force-unit", "lbf", "--force-sensitivity", "0.4684",
            "--response-unit", "g", "--response-sensitivity", "1.028", "--out", out, "--force",
        ])  # fmt: skip
        paths.append(out)
    tol = np.full(GVT_HZ.size, 0.02)
    for band in (None, "3:35"):
        cols, extra = {}, {}
        for method in METHODS:
            found = identify_hz(paths, tmp / "gvt.h5", method, band)
            near = nearest(found, GVT_HZ)
            cols[method] = np.where(np.abs(near / GVT_HZ - 1) <= tol, near, np.nan)
            extra[method] = others(found, cols[method], 0.0, np.inf)
        title = f"GVT, 5 runs as one roving test, band {band or 'automatic'}; within 2 %"
        print_table(title, GVT_HZ, cols, tol)
        for method, x in extra.items():
            print(f"  {method} other modes: {len(x)} (" + ", ".join(f"{v:.2f}" for v in x) + ")")


def main() -> int:
    if not BEAM_UFF.is_file():
        print(f"shared data not found at {SHARED}", file=sys.stderr)
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        beam(Path(tmp))
        plate(Path(tmp))
        gvt(Path(tmp))
    return 0


if __name__ == "__main__":
    sys.exit(main())
