"""The mAEWing1 aircraft's own Nastran models against its own GVT, before any updating.

Every step is a ``bayesupdate`` command a user types, with its defaults:

1. ``identify`` on the packaged GVT FRFs (``bayesupdate/data/maewing1/run1..10.uff``: 20
   accelerometers over 10 sine sweeps, one shaker);
2. the accelerometer positions of ``GVT_Info.m`` as a UFF 15 geometry file
   (``studies/maewing1_test_geometry.py``), aligned to the decks' frame by the matrix the
   README derives (test X left, Y aft, origin at the nose -> deck x aft, y right, origin
   15.55 in aft of the nose; no mirror: the test's accelerometers 1-10 are on the right wing,
   where the shaker was; the authors' GRIDs 1-20 in v4.2 are the mirror image);
3. ``correlate`` of the authors' pre-update model v3.3 and of their updated v4.2 (both as
   published, read by bayesupdate's own reader) with the GVT through a study file's ``[test]``
   table: the accelerometers paired with points on the decks' beams.

Prints, per paired GVT mode, the model frequencies and MACs of both decks, and each command's
wall time.  Run: ``python studies/maewing1_correlate.py [--out DIR]``.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FEM = ROOT.parent / "shared" / "data" / "gvt_maewing1" / "fem"
DECKS = {
    "v3.3": FEM / "v3.3_hati" / "sol103_mAEWing1_Hati_FEMv3p3.bdf",
    "v4.2": FEM / "v4.2_updated" / "sol103_mAEWing1_FEMv4p2.bdf",
}
#: test frame (X left, Y aft, Z up, origin at the nose) -> the decks' frame (x aft, y right)
ALIGN = [[0, 1, 0, -15.55], [-1, 0, 0, 0], [0, 0, 1, 0]]


def _cli(*args) -> tuple[float, str]:
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", PYTHONPATH=str(ROOT))
    t0 = time.perf_counter()
    cmd = [sys.executable, "-m", "bayesupdate", *map(str, args)]
    out = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if out.returncode != 0:
        raise SystemExit(f"{' '.join(cmd[2:])} failed: {out.stderr.strip()}")
    return time.perf_counter() - t0, out.stdout


def _study(folder: Path, deck: Path) -> Path:
    path = folder / f"{deck.stem}.toml"
    path.write_text(
        f'[model]\nsource = "{deck}"\n[data]\nsource = "{folder / "modes.h5"}"\n'
        f'[test]\ngeometry = "{folder / "gvt.unv"}"\nalign = {ALIGN}\n'
        'pair_tolerance = "5 in"\n'
    )
    return path


def run(folder: Path) -> dict:
    """Identify, write the geometry, correlate both decks; the JSON of each and the times."""
    runs = sorted((ROOT / "bayesupdate" / "data" / "maewing1").glob("run*.uff"))
    times = {}
    times["identify"], out = _cli("identify", *runs, "--out", folder / "modes.h5", "--force",
                                  "--json", "--quiet")  # fmt: skip
    identified = json.loads(out)
    geometry = subprocess.run(
        [sys.executable, str(ROOT / "studies" / "maewing1_test_geometry.py"),
         str(folder / "gvt.unv")], capture_output=True, text=True,
        env=dict(os.environ, PYTHONPATH=str(ROOT)),
    )  # fmt: skip
    if geometry.returncode != 0:
        raise SystemExit(geometry.stderr)
    result = {"identify": identified}
    for name, deck in DECKS.items():
        times[f"correlate {name}"], out = _cli("correlate", _study(folder, deck), "--json",
                                               "--quiet")  # fmt: skip
        result[name] = json.loads(out)
    result["times"] = times
    return result


def table(result: dict) -> str:
    test_hz = [m["frequency_hz"] for m in result["identify"]["modes"]]
    rows = ["| GVT mode | GVT [Hz] | v3.3 [Hz] | v3.3 error | MAC v3.3 | v4.2 [Hz] | v4.2 error "
            "| MAC v4.2 |", "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    pairs = {name: {m["test"]: m for m in result[name]["modes"]} for name in DECKS}
    for k, f in enumerate(test_hz, start=1):
        cells = [str(k), f"{f:.3f}"]
        for name in DECKS:
            m = pairs[name].get(k)
            if m is None:
                cells += ["-", "-", "-"]
            else:
                cells += [f"{m['model_hz']:.3f}", f"{m['error_pct']:+.1f} %", f"{m['mac']:.2f}"]
        rows.append("| " + " | ".join(cells) + " |")
    return "\n".join(rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=None, help="folder for the files (default: a temporary one)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(args.out or tmp)
        folder.mkdir(parents=True, exist_ok=True)
        result = run(folder)
    print(table(result))
    for name in DECKS:
        r = result[name]
        far = max(p["distance"] for p in r["points"])
        refused = [(x["test"], x["model"], round(x["mac"], 2)) for x in r["refused"]]
        print(f"{name}: refused (test, model, MAC) {refused}; unpaired GVT modes "
              f"{r['unpaired_test']}; farthest test point {far:.2f} in")  # fmt: skip
    print("wall times [s]: " + ", ".join(f"{k} {v:.1f}" for k, v in result["times"].items()))


if __name__ == "__main__":
    main()
