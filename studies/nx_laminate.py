"""A laminate (PCOMPG of MAT8 plies) as NX Nastran reads it: the package's own path on NX's
own static solution.

Data nobody here made, from pyNastran's ``models`` folder (BSD-3-Clause, commit 1d25a92; text
files, no pyNastran needed): ``nx/laminate/laminate_elstrn_fiber_center.bdf`` and its ``.f06``
(Simcenter Nastran 2306, SOL 101, mm and mN): four CQUAD4 in the x-z plane (a 20 x 25 mm
patch), one PCOMPG of ten 0.19558 mm plies of one woven MAT8 (E1 6.7141e7, E2 6.6727e7,
NU12 0.053, G12 = G1Z = G2Z 5.0676e6) at 0 / 90 / 0 / 90 / 0 / 0 / 90 / 0 / 90 / 0 degrees, its
bottom edge clamped (SPC 123456), 100 N pulled along z on its top edge (50 on the middle GRID,
25 on each corner).  The f06 prints each GRID's displacements to seven digits.

What is checked: the deck read as published (``load_nastran_model``), K from the package's
``matrices``, the static solution K_ff u_f = F_f on the GRIDs the SPC leaves free, against NX's
translations.  The in-plane rotations (R2 here, the shells' drilling DOF) are not compared:
NX's drilling stiffness (PARAM K6ROT 100) is not this package's penalty, and neither moves the
translations of this membrane problem.

Measured (2026-11-30, this script): the translations are NX's to 4.5e-8 (T3, the pull) and
1.4e-6 (T1, the Poisson contraction held at the clamped edge), relative to the largest of each:
the f06's seven digits.  The drilling rotation R2 differs (8.7e-7 against NX's 4.5e-7 rad).

``--write DIR`` stores the deck as published and NX's translations
(``tests/data/nx_laminate_pcompg.bdf`` / ``.json``) for ``tests/test_nastran_pcomp.py``.

Run: PYTHONPATH=. python studies/nx_laminate.py <pyNastran>/models [--write tests/data]
"""

import argparse
import json
import re
import shutil
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla

from bayesupdate.nastran import load_nastran_model

DECK = "nx/laminate/laminate_elstrn_fiber_center"
#: FORCE 17 (the deck's LOAD = 17): GRID -> its load along z [mN]
LOADS = {4: 50000.0, 6: 25000.0, 9: 25000.0}
#: SPC 18: the clamped GRIDs
CLAMPED = (3, 7, 8)


def nx_displacements(f06: Path) -> dict[int, list[float]]:
    """{GRID: [T1, T2, T3, R1, R2, R3]} of the f06's displacement table."""
    text = f06.read_text(errors="replace")
    table = text.split("D I S P L A C E M E N T   V E C T O R")[1].split("PAGE")[0]
    rows = re.findall(r"^\s+(\d+)\s+G\s+(.*)$", table, re.M)
    return {int(g): [float(v) for v in values.split()] for g, values in rows}


def static_solution(deck: Path) -> tuple[np.ndarray, np.ndarray]:
    """(GRID ids (n,), displacements (n, 6)) of the deck's static problem with this package's
    K: the clamped GRIDs held, ``LOADS`` along z."""
    model = load_nastran_model(str(deck))
    K, _ = model.matrices()
    grids = list(model.structure.metadata["nastran"]["grid_ids"])
    F = np.zeros(K.shape[0])
    for g, load in LOADS.items():
        F[6 * grids.index(g) + 2] = load
    held = np.concatenate([6 * grids.index(g) + np.arange(6) for g in CLAMPED])
    free = np.setdiff1d(np.arange(K.shape[0]), held)
    u = np.zeros(K.shape[0])
    u[free] = spla.spsolve(K.tocsc()[free][:, free], F[free])
    return np.array(grids), u.reshape(-1, 6)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("models", type=Path, help="pyNastran's models folder")
    ap.add_argument("--write", type=Path, help="write the tests' deck and data in this folder")
    args = ap.parse_args()
    bdf, f06 = (args.models / f"{DECK}{suffix}" for suffix in (".bdf", ".f06"))
    nx = nx_displacements(f06)
    grids, u = static_solution(bdf)
    U = np.array([nx[int(g)] for g in grids])
    for name, c in (("T1", 0), ("T3", 2), ("R2 (drilling)", 4)):
        err = np.abs(u[:, c] - U[:, c]).max() / np.abs(U[:, c]).max()
        print(f"{name:14s} largest |ours - NX| / largest |NX|: {err:.2e}")
    if args.write:
        shutil.copyfile(bdf, args.write / "nx_laminate_pcompg.bdf")
        data = {"grids": [int(g) for g in nx], "translations": [nx[g][:3] for g in nx],
                "loads_z": {str(g): v for g, v in LOADS.items()},
                "clamped": list(CLAMPED)}  # fmt: skip
        (args.write / "nx_laminate_pcompg.json").write_text(json.dumps(data) + "\n")


if __name__ == "__main__":
    main()
