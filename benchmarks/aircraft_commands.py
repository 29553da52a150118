"""Wall and CPU time of ``calibrate``, ``sample`` and ``discover`` with their defaults on the
mAEWing1 v3.3 deck with the aircraft's parameters (``pipelines.aircraft.PARAMETERS``) against
the packaged GVT, as a user runs them (``python -m bayesupdate ...``, one process each).

The study is the one ``demo --case aircraft`` calibrates on (``aircraft.study_text``: the GVT
modes v3.3 pairs below 20 Hz, the measured weight and inertias), made here by ``identify`` on
the 10 packaged FRF files and ``correlate`` of v3.3; ``discover`` gets the demo's discovery
study (``DISCOVER_PARAMETERS``, every paired mode).  The study files say ``[sampler] reduced
= true`` (``aircraft.REDUCED`` says why), and the commands share one fresh cache folder
(``BAYESUPDATE_CACHE_DIR``): ``calibrate`` runs twice, the first run builds and certifies the
basis, the second loads it, then ``sample`` loads it.  ``--full`` times ``calibrate`` and
``sample`` on full solves too (a copy of the study with ``reduced = false``).  Printed per
command: wall time, CPU time of the child (user + system; on a shared machine the wall time
also counts waits for a core), the progress phases it reports, and its headline (objective,
convergence or verdict).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/aircraft_commands.py [--skip-discover]
        [--full] [--basis-only]
"""

import argparse
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def command(argv, env, cwd) -> tuple[float, float, str, str]:
    """(wall [s], child CPU [s], stdout, stderr) of ``python -m bayesupdate argv``."""
    before = os.times()
    t = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "bayesupdate", *map(str, argv)], cwd=cwd,
                          env=env, capture_output=True, text=True, check=False)  # fmt: skip
    wall = time.perf_counter() - t
    after = os.times()
    cpu = (after.children_user - before.children_user) + (
        after.children_system - before.children_system
    )
    if done.returncode != 0:
        raise SystemExit(f"{argv[0]} failed: {done.stderr.strip().splitlines()[-1:]}")
    return wall, cpu, done.stdout, done.stderr


def report(name: str, timed, headline) -> None:
    wall, cpu, out, err = timed
    print(f"{name}: {wall:.1f} s wall, {cpu:.1f} s CPU")
    for line in err.splitlines():
        if re.search(r" in \d", line) or line.startswith("warning:"):
            print(f"    {line.strip()}")
    print(f"    {headline(out)}")


def studies(folder: Path, env) -> tuple[Path, Path]:
    """(the calibration study, the discovery study) of the demo, written into ``folder``."""
    from bayesupdate.pipelines import aircraft as ac

    data, modes = ac.data_folder(), folder / "modes.h5"
    runs = [data / f"run{k}.uff" for k in range(1, ac.N_RUNS + 1)]
    out = command(["identify", *runs, "--out", modes, "--json", "--quiet"], env, folder)[2]
    test_hz = [m["frequency_hz"] for m in json.loads(out)["modes"]]
    deck = data / ac.V33_DECK
    v33 = folder / "v33.toml"
    v33.write_text(ac.study_text(deck, modes, parameters=None, measured=False))
    corr = json.loads(command(["correlate", v33, "--json", "--quiet"], env, folder)[2])
    update, discover = folder / "update.toml", folder / "discover.toml"
    update.write_text(ac.study_text(deck, modes, ac.calibration_modes(test_hz, corr)))
    paired = sorted(ac.pairs_of(corr))
    discover.write_text(ac.study_text(deck, modes, paired, ac.DISCOVER_PARAMETERS))
    print(f"GVT modes {len(test_hz)}; calibrated on {ac.calibration_modes(test_hz, corr)}; "
          f"discover on {paired}")  # fmt: skip
    return update, discover


def _line_with(text: str, word: str) -> str:
    return next((ln for ln in text.splitlines() if word in ln), "")


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--skip-discover", action="store_true")
    parser.add_argument("--full", action="store_true", help="time full solves too")
    parser.add_argument("--basis-only", action="store_true",
                        help="time calibrate's basis build and load alone")  # fmt: skip
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        env = dict(os.environ, BAYESUPDATE_CACHE_DIR=str(folder / "cache"), PYTHONPATH=str(ROOT),
                   OPENBLAS_NUM_THREADS="1")  # fmt: skip
        update, discover = studies(folder, env)

        def first_line(out: str) -> str:
            return out.strip().splitlines()[0] if out.strip() else ""

        def walkers_line(out: str) -> str:
            return _line_with(out, "walkers")

        for run in ("first run (basis built)", "second run (basis cached)"):
            timed = command(["calibrate", update, "--out", folder / "cal.h5", "--force"], env,
                            folder)  # fmt: skip
            report(f"calibrate, defaults, {run}", timed, first_line)
        if args.basis_only:
            return
        timed = command(["sample", update, "--out", folder / "post.h5", "--force"], env, folder)
        report("sample, defaults (basis cached)", timed, walkers_line)
        if args.full:
            full = folder / "update_full.toml"
            full.write_text(update.read_text().replace("reduced = true", "reduced = false"))
            timed = command(["calibrate", full, "--out", folder / "cal_full.h5", "--force"], env,
                            folder)  # fmt: skip
            report("calibrate on full solves", timed, first_line)
            timed = command(["sample", full, "--out", folder / "post_full.h5", "--force"], env,
                            folder)  # fmt: skip
            report("sample on full solves", timed, walkers_line)
        if not args.skip_discover:
            timed = command(["discover", discover], env, folder)
            report("discover, defaults", timed, first_line)


if __name__ == "__main__":
    main()
