"""The mAEWing1 aircraft's own Nastran model (v3.3) updated against its own GVT through the
command line, beside the authors' own update (v4.2).

Every step is a ``bayesupdate`` command run as a user runs it (a subprocess), timed (wall and
CPU seconds):

1. ``frf`` on each of the 10 sine-sweep runs (the original ``.mat`` time signals, in
   ``../shared/data/gvt_maewing1/data`` beside the checkout, or ``--data DIR``);
2. ``identify`` on the 10 FRF files (defaults);
3. ``correlate`` of the authors' v3.3 and v4.2 (as packaged in ``bayesupdate/data/maewing1``)
   with the accelerometers' UFF 15 geometry (``bayesupdate.pipelines.aircraft``: alignment,
   5 in pair tolerance);
4. ``sensitivity`` of v3.3 to the four parameters of ``pipelines.aircraft.PARAMETERS``
   (the root segment's flap bending, one flap bending section for the outer wing, the wing's
   foam point masses and its beams' density, so that mass can move between them at the
   same weight; why those: that module);
5. ``calibrate`` v3.3 on the GVT modes it pairs below 20 Hz (``[data] modes``) with the
   authors' measured weight and inertias as data, ``--write-bdf updated.bdf``;
6. ``sample`` the posterior (``--write-bdf posterior_mean.bdf``);
7. ``correlate`` of the updated deck; the posterior predictive band of every paired mode
   (the deck solved at posterior draws, in this process);
8. ``discover`` on v3.3 and on the updated deck.

Prints the comparison (per paired GVT mode: test, v3.3, v4.2, ours with its MAC, posterior
mean with its 5-95 % band, held out or not), RMS frequency error and mean MAC per model on the
calibrated and held-out modes, the mass properties against the authors' measured ranges, what
discover names, and the time of each command.

``calibrate`` builds the reduced basis of the study files (``pipelines.aircraft.REDUCED``)
into the on-disk cache (``BAYESUPDATE_CACHE_DIR``, default the user cache folder) and ``sample``
loads it; point ``BAYESUPDATE_CACHE_DIR`` at an empty folder to time a first run.

Run: python studies/maewing1_update.py [--out DIR] [--seed 103] [--data DIR] [--quick]
    [--skip-discover]
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

from bayesupdate.commands._demo_aircraft import AircraftSettings, report_markdown, run_aircraft
from bayesupdate.errors import BayesUpdateError

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data" / "gvt_maewing1" / "data"


class SubprocessChain:
    """Runs ``python -m bayesupdate ...`` as a user would; records wall and CPU seconds."""

    def __init__(self):
        self.times, self.cpu = {}, {}

    def __call__(self, key: str, *argv) -> dict:
        env = dict(os.environ, OPENBLAS_NUM_THREADS="1", PYTHONPATH=str(ROOT))
        json_out = argv[0] != "frf"  # frf writes a file and prints a summary
        cmd = [sys.executable, "-m", "bayesupdate", *map(str, argv), "--quiet"]
        cmd += ["--json"] if json_out else []
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        out = subprocess.run(cmd, capture_output=True, text=True, env=env)
        self.times[key] = round(time.perf_counter() - t0, 2)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        self.cpu[key] = round(after.ru_utime + after.ru_stime - before.ru_utime
                              - before.ru_stime, 2)  # fmt: skip
        print(f"  {key}: {self.times[key]:.1f} s wall, {self.cpu[key]:.1f} s CPU", flush=True)
        if out.returncode != 0:
            raise BayesUpdateError(f"{' '.join(map(str, argv))}: {out.stderr.strip()}")
        return json.loads(out.stdout) if json_out else {}


def frf_argv(k: int, data: Path, out: Path) -> list:
    """``bayesupdate frf`` arguments of run k (1..10): the calibrations of GVT_Info.m."""
    return ["frf", data / f"run_Run{k}.mat", "--force-channel", "Force",
            "--response", f"Accel1={2 * k - 1}V", "--response", f"Accel2={2 * k}V",
            "--reference", "25V", "--force-unit", "lbf", "--force-sensitivity", "0.4684",
            "--response-unit", "g", "--response-sensitivity", "1.028", "--out", out,
            "--force"]  # fmt: skip


def make_frfs(chain: SubprocessChain, data: Path, folder: Path) -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    paths = [folder / f"run{k}.uff" for k in range(1, 11)]
    for k, path in enumerate(paths, start=1):
        chain(f"frf run {k}", *frf_argv(k, data, path))
    return paths


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=None, help="folder for the files (default: temporary)")
    ap.add_argument("--seed", type=int, default=103)
    ap.add_argument("--data", default=str(DATA), help="folder of run_Run1..10.mat")
    ap.add_argument("--quick", action="store_true", help="the demo's quick settings")
    ap.add_argument("--skip-discover", action="store_true", help="the chain without discover")
    args = ap.parse_args()
    if not (Path(args.data) / "run_Run1.mat").is_file():
        raise SystemExit(f"GVT time signals not found in {args.data} (give --data DIR)")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(args.out or tmp)
        out.mkdir(parents=True, exist_ok=True)
        chain = SubprocessChain()
        runs = make_frfs(chain, Path(args.data), out / "frf")
        settings = AircraftSettings(out, args.quick, args.seed, not args.skip_discover)
        result = run_aircraft(settings, lambda line: print(line, flush=True), chain, runs)
        print()
        print(report_markdown(result))
        frf = sum(v for k, v in chain.times.items() if k.startswith("frf"))
        frf_cpu = sum(v for k, v in chain.cpu.items() if k.startswith("frf"))
        # run_aircraft adds its own "total" to the times it was given: not a command
        steps = {k: v for k, v in chain.times.items() if k != "total"}
        rest = {k: (v, chain.cpu.get(k)) for k, v in steps.items() if
                not k.startswith("frf")}  # fmt: skip
        print(f"frf (10 runs): {frf:.1f} s wall, {frf_cpu:.1f} s CPU")
        for k, (w, c) in rest.items():
            print(f"{k}: {w:.1f} s wall" + ("" if c is None else f", {c:.1f} s CPU"))
        total = sum(steps.values())  # the predictive band (in this process) included
        cpu = sum(chain.cpu.values())
        print(f"whole chain: {total:.1f} s wall ({total / 60:.1f} min), commands' CPU {cpu:.1f} s")
        (out / "study.json").write_text(json.dumps({**result, "cpu_s": chain.cpu,
                                                    "wall_s": chain.times}, indent=1))  # fmt: skip


if __name__ == "__main__":
    main()
