"""Shear-rigid CQUAD4 (PSHELL with MID3 blank) against NX Nastran's own static solution: which
of this package's quadrilaterals bends as NX's does on a coarse mesh.

Data nobody here made, from pyNastran's ``models`` folder (BSD-3-Clause, commit 1d25a92; text,
no pyNastran needed): ``real/loads/loads.bdf`` and its ``.f06`` (NX Nastran, SOL 101): a 4 x 2
cantilever plate of eight 1 x 1 CQUAD4, T 0.1 (a / t = 10), MAT1 E 1e7, NU 0.3, PSHELL MID1 =
MID2, MID3 blank (no transverse shear flexibility, MSC/NX QRG PSHELL), GRIDs 1, 6 and 11 held
(PS 123456); the f06 prints each subcase's displacements to seven digits.  The deck has no
density (its problem is static), so it is read with ``read_structure`` and its stiffness taken
from ``NastranModel.matrices`` (``load_nastran_model`` refuses a deck without mass: modes need
it).  Subcases compared (loads on the GRIDs as Nastran spreads them on flat elements: a
quadrilateral's pressure in four equal parts, a triangle's in three):

* 1: PLOAD4 3.0 on CQUAD4 500 (0.75 on GRIDs 7 and 12 along z);
* 2: subcase 1 and FORCE 1.0 along z at the free corner, GRID 15;
* 3: PLOAD 9.0 on GRIDs 1, 2, 7, 6 (2.25 on GRIDs 2 and 7);
* 4: PLOAD 9.0 on the triangle of GRIDs 1, 2, 6 (area 1/2: 1.5 on GRID 2).

(Subcases 5 and 6 push PLOAD4 along a given vector, partly in the plane: not a bending check.)

Printed, per subcase, the largest |T3 - NX's T3| relative to NX's largest T3, for the deck as
published (its quads are Discrete Kirchhoff quadrilaterals, ``fe.elements.shell_dkq``) and for
the same deck with MID3 = MID2 and TS/T 1000 (this package's MITC4 with a stiff shear: the
other reading of a shear-rigid quad); and the unit tip force alone (subcase 2 less subcase 1)
on meshes 4 x 2 to 32 x 16 of both elements, whose limit is the Kirchhoff plate's.

Measured (2026-11-30, this script): the deck as published (DKQ) is NX's to 2.3e-2, 5.9e-3,
2.3e-2 and 5.1e-2 (subcases 1-4), the stiff-shear MITC4 to 4.9e-2, 2.3e-2, 4.9e-2 and 5.4e-2:
NX's shear-rigid QUAD4 is nearer the DKQ in every subcase.  The tip force: NX 0.013610 on its
4 x 2 mesh, the DKQ 0.013683 (+0.54 %), the MITC4 0.013347 (-1.9 %); both elements converge to
0.01366 (32 x 16: DKQ 0.013661, MITC4 0.013652), so on this mesh NX's quad is 0.37 % stiffer
than the limit, the DKQ 0.16 % more flexible and the MITC4 2.3 % stiffer.  NX's element is
neither of these, but it bends as the DKQ does to within a few percent where the MITC4 does
not.  On MSC's d173 wing box (PCOMP skins with offsets) an earlier session found the MITC4
nearer MSC's static answer; that gap has another cause, not yet found.

Run: PYTHONPATH=. python studies/nx_shear_rigid_quads.py <pyNastran>/models
"""

import argparse
import re
import tempfile
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla

from bayesupdate.fe.shell_model import ShellAssembly, shell_mesh
from bayesupdate.nastran.model import NastranModel
from bayesupdate.nastran.reader import read_structure

DECK = "real/loads/loads"
PSHELL = "PSHELL, 1000, 10000, 0.1, 10000"
#: the stiff-shear reading: MID3 = MID2, TS/T 1000 (this package's MITC4)
STIFF_SHEAR = "PSHELL, 1000, 10000, 0.1, 10000, , 10000, 1000."
#: subcase -> {GRID: load along z} (module docstring)
LOADS = {1: {7: 0.75, 12: 0.75}, 2: {7: 0.75, 12: 0.75, 15: 1.0}, 3: {2: 2.25, 7: 2.25},
         4: {2: 1.5}}  # fmt: skip
HELD = (1, 6, 11)


def nx_displacements(f06: Path) -> list[dict[int, np.ndarray]]:
    """Per subcase, {GRID: [T1, T2, T3, R1, R2, R3]} of the f06's displacement tables."""
    text = f06.read_text(errors="replace")
    out = []
    for table in text.split("D I S P L A C E M E N T   V E C T O R")[1:]:
        rows = re.findall(r"^\s+(\d+)\s+G\s+(.*)$", table.split("PAGE")[0], re.M)
        out.append({int(g): np.array([float(v) for v in vals.split()]) for g, vals in rows})
    return out


def held_solve(K, held_nodes, loads_z: dict[int, float]) -> np.ndarray:
    """u (n_dof,) of K u = F with every DOF of the nodes ``held_nodes`` held and F the loads
    {node index: force along z}."""
    F = np.zeros(K.shape[0])
    for node, load in loads_z.items():
        F[6 * node + 2] = load
    held = np.concatenate([6 * n + np.arange(6) for n in held_nodes])
    free = np.setdiff1d(np.arange(K.shape[0]), held)
    u = np.zeros(K.shape[0])
    u[free] = spla.spsolve(K.tocsc()[free][:, free], F[free])
    return u


def static_solution(bdf: Path, loads: dict[int, float]) -> dict[int, np.ndarray]:
    """{GRID: displacements (6,)} of the deck's K with ``HELD`` held and ``loads`` along z."""
    structure, info, deck = read_structure(bdf)
    K, _ = NastranModel(structure, {}, {}, {}, name=info["deck"], deck=bdf, bdf=deck).matrices()
    grids = list(info["grid_ids"])
    on = {grids.index(g): load for g, load in loads.items()}
    u = held_solve(K, [grids.index(g) for g in HELD], on)
    return {g: u[6 * i : 6 * i + 6] for i, g in enumerate(grids)}


def t3_miss(ours: dict, nx: dict) -> float:
    """Largest |T3 - NX's T3| / largest |NX's T3|."""
    w = np.array([ours[g][2] - nx[g][2] for g in nx])
    return float(np.abs(w).max() / max(abs(nx[g][2]) for g in nx))


def tip_deflection(nx_el: int, ny_el: int, shear_ratio: float) -> float:
    """T3 at the free corner under a unit force there, the plate (4 x 2, T 0.1, E 1e7, NU 0.3)
    clamped along x = 0, meshed in nx_el x ny_el quads (shear_ratio inf: the DKQ)."""
    xs, ys = np.linspace(0, 4, nx_el + 1), np.linspace(0, 2, ny_el + 1)
    nodes = np.array([[x, y, 0.0] for y in ys for x in xs])

    def node(i, j):
        return j * (nx_el + 1) + i

    quads = [[node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)]
             for j in range(ny_el) for i in range(nx_el)]  # fmt: skip
    mesh = shell_mesh(nodes, quads=quads, thickness=0.1, E=1e7, nu=0.3, rho=1.0,
                      shear_ratio=shear_ratio)  # fmt: skip
    K, _ = ShellAssembly(mesh).assemble()
    tip = node(nx_el, ny_el)
    u = held_solve(K, [node(0, j) for j in range(ny_el + 1)], {tip: 1.0})
    return float(u[6 * tip + 2])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("models", type=Path, help="pyNastran's models folder")
    args = ap.parse_args()
    bdf, f06 = (args.models / f"{DECK}{suffix}" for suffix in (".bdf", ".f06"))
    nx = nx_displacements(f06)
    with tempfile.TemporaryDirectory() as tmp:
        stiff = Path(tmp) / "loads_stiff_shear.bdf"
        stiff.write_text(bdf.read_text().replace(PSHELL, STIFF_SHEAR))
        for label, path in (("as published (DKQ)", bdf), ("MID3, TS/T 1000 (MITC4)", stiff)):
            misses = [t3_miss(static_solution(path, LOADS[s]), nx[s - 1]) for s in LOADS]
            print(f"{label:26s} T3 against NX, subcases 1-4: "
                  + ", ".join(f"{m:.1e}" for m in misses))  # fmt: skip
    print(f"unit tip force, NX 4 x 2: {nx[1][15][2] - nx[0][15][2]:.6f}")
    for n in (1, 2, 4, 8):
        dkq, mitc = tip_deflection(4 * n, 2 * n, np.inf), tip_deflection(4 * n, 2 * n, 1e3)
        print(f"  {4 * n:2d} x {2 * n:2d}: DKQ {dkq:.6f}, MITC4 (TS/T 1000) {mitc:.6f}")


if __name__ == "__main__":
    main()
