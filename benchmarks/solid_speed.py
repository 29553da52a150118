"""Solid decks on the user's path: a free steel bar meshed in CHEXA bricks and the same bar in
CTETRA tetrahedra (six per brick, Kuhn's split), read and solved by ``bayesupdate modes --model
DECK --modes 20 --json`` in a fresh process, beside the element matrices alone.

Printed, medians over ``--repeats`` runs (BLAS on one thread; the machine's other jobs count in
the wall time):
* the command's wall time for each deck (read, assemble, 20 elastic modes, mass properties);
* the element kernels alone on the same corners: ``fe.elements.hexa.stiffness`` and
  ``mass_matrix`` for the bricks, ``Tetrahedra.matrices`` for the tetrahedra, per element;
  the bricks' K and the traced peak memory of forming it.

The bar is 1 x 0.05 x 0.08 m in nx x ny x nz cells (default 120 x 12 x 12: 17,280 bricks or
103,680 tetrahedra on 20,449 GRIDs, 61,347 DOFs).

Measured (2026-11-30, 2 shared cores, medians of 3): the brick deck 26.0-27.5 s (two runs of
this script), the tetrahedra deck 23.2-23.8 s (of which SuperLU's factorization and 53 solves
take about 15 s on the bricks, the reading's AUTOSPC pass, which assembles K once more, 4.6 s;
7.0 s before its per-node loop was one pass: the brick deck's command 28.3 -> 25.9 s, medians
of 5 interleaved runs of the two trees, x 0.91); ``hexa.stiffness`` 1.02 s
(59 us per brick; 3.86 s, 224 us, before its products were batched matrix products, its shear
lines' points computed once and its elements taken 2,048 at a time), its traced peak memory
181 MB for an 80 MB K (854 MB before the chunks); ``Tetrahedra.matrices`` 1.1-1.8 s (11-18 us
per tetrahedron, two runs).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/solid_speed.py [--cells 120 12 12]
        [--repeats 3]
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np
from timing import time_median

from bayesupdate.fe.assembly import ElementProperties
from bayesupdate.fe.elements import hexa
from bayesupdate.fe.elements.base import ElementSettings
from bayesupdate.fe.elements.solid import elasticity
from bayesupdate.fe.elements.tetra import Tetrahedra

E, NU, RHO = 2.1e11, 0.3, 7850.0
SIZE = (1.0, 0.05, 0.08)
#: Kuhn's six tetrahedra of a cube around its diagonal 0-6 (the cube's corner pairs)
KUHN = ((1, 2), (2, 3), (3, 7), (7, 4), (4, 5), (5, 1))


def cells(shape):
    """(GRID positions (N, 3), bricks (n, 8) 1-based GRID ids in Nastran's order)."""
    nx, ny, nz = shape
    axes = [np.linspace(0, s, n + 1) for s, n in zip(SIZE, shape, strict=True)]
    xyz = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    ids = np.arange(1, len(xyz) + 1).reshape(nx + 1, ny + 1, nz + 1)
    i, j, k = (a.ravel() for a in np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz),
                                              indexing="ij"))  # fmt: skip
    corners = [
        (0, 0, 0),
        (1, 0, 0),
        (1, 1, 0),
        (0, 1, 0),
        (0, 0, 1),
        (1, 0, 1),
        (1, 1, 1),
        (0, 1, 1),
    ]
    bricks = np.stack([ids[i + a, j + b, k + c] for a, b, c in corners], axis=1)
    return xyz, bricks


def write_deck(path: Path, shape, kind: str) -> int:
    """Write the bar in bricks (kind "hexa") or tetrahedra ("tetra"); returns the element count."""
    xyz, bricks = cells(shape)
    lines = ["SOL 103", "CEND", "METHOD = 1", "BEGIN BULK", "EIGRL,1,,,20",
             f"MAT1,1,{E:.4E},,{NU},{RHO}", "PSOLID,1,1"]  # fmt: skip
    lines += [f"GRID,{n},,{x:.7f},{y:.7f},{z:.7f}" for n, (x, y, z) in enumerate(xyz, 1)]
    if kind == "hexa":
        elements = [f"CHEXA,{e},1,{','.join(map(str, b[:6]))}\n,{b[6]},{b[7]}"
                    for e, b in enumerate(bricks, 1)]  # fmt: skip
    else:
        tets = [(b[0], b[p], b[q], b[6]) for b in bricks for p, q in KUHN]
        elements = [f"CTETRA,{e},1,{','.join(map(str, t))}" for e, t in enumerate(tets, 1)]
    path.write_text("\n".join([*lines, *elements, "ENDDATA"]) + "\n")
    return len(elements)


def command_time(deck: Path) -> tuple[float, dict]:
    """Wall time [s] of ``bayesupdate modes --model deck --modes 20 --json`` and its result."""
    env = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "bayesupdate", "modes", "--model", str(deck),
                          "--modes", "20", "--json"], capture_output=True, text=True, env=env,
                         check=True)  # fmt: skip
    return time.perf_counter() - t0, json.loads(out.stdout)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, nargs=3, default=(120, 12, 12))
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    shape = tuple(args.cells)
    xyz, bricks = cells(shape)
    print(f"bar {SIZE} m in {shape} cells: {len(xyz)} GRIDs, {3 * len(xyz)} DOFs")
    with tempfile.TemporaryDirectory() as tmp:
        for kind in ("hexa", "tetra"):
            deck = Path(tmp) / f"bar_{kind}.bdf"
            n = write_deck(deck, shape, kind)
            runs = [command_time(deck) for _ in range(args.repeats)]
            wall = float(np.median([r[0] for r in runs]))
            hz = runs[-1][1]["frequencies_hz"]
            modes = f"modes 1, 20: {hz[0]:.2f}, {hz[19]:.2f} Hz"
            print(f"  {kind}: {n} elements, `bayesupdate modes --modes 20`: {wall:.1f} s wall "
                  f"(median of {args.repeats}); {modes}")  # fmt: skip
    corners = xyz[bricks - 1]
    D = elasticity(np.full(len(corners), E), np.full(len(corners), NU))
    t_k, _ = time_median(lambda: hexa.stiffness(corners, D), args.repeats)
    tracemalloc.start()
    K = hexa.stiffness(corners, D)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    print(f"  hexa.stiffness memory: K {K.nbytes / 1e6:.0f} MB, peak {peak / 1e6:.0f} MB (traced)")
    rho, lumped = np.full(len(corners), RHO), np.ones(len(corners), bool)
    t_m, _ = time_median(lambda: hexa.mass_matrix(corners, rho, lumped), args.repeats)
    print(
        f"  hexa.stiffness: {t_k:.2f} s ({t_k / len(corners) * 1e6:.1f} us per brick), "
        f"mass_matrix: {t_m:.2f} s"
    )
    tets = np.array([(b[0], b[p], b[q], b[6]) for b in bricks - 1 for p, q in KUHN])
    family = Tetrahedra(tets, xyz[tets], np.full(len(tets), E), np.full(len(tets), NU),
                        np.full(len(tets), RHO), np.ones(len(tets), bool),
                        np.zeros(len(tets), np.int64))  # fmt: skip
    props = ElementProperties(family.nominal())
    t_t, _ = time_median(lambda: family.matrices(props, ElementSettings()), args.repeats)
    print(f"  Tetrahedra.matrices: {t_t:.2f} s ({t_t / len(tets) * 1e6:.1f} us per tetrahedron)")


if __name__ == "__main__":
    main()
