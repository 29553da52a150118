"""Shear-rigid CQUAD4 (PSHELL MID3 blank, read as Discrete Kirchhoff quadrilaterals) against NX
Nastran's own static solution of a coarse cantilever plate (``studies/nx_shear_rigid_quads.py``).

The deck (``tests/data/nx_shear_rigid_quads.bdf``) is pyNastran's ``real/loads/loads.bdf`` as
published (BSD-3-Clause): eight 1 x 1 CQUAD4 of T 0.1 (4 x 2), E 1e7, NU 0.3, GRIDs 1, 6, 11
held; ``nx_shear_rigid_quads.json`` holds NX's T3 of subcases 1-4 and their loads on the GRIDs.
"""

import json
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla

from bayesupdate.nastran.model import NastranModel
from bayesupdate.nastran.reader import read_structure

DATA = Path(__file__).parent / "data"
NX = json.loads((DATA / "nx_shear_rigid_quads.json").read_text())
PSHELL = "PSHELL, 1000, 10000, 0.1, 10000"


def _t3(bdf: Path) -> dict[str, dict[str, float]]:
    """{subcase: {GRID: T3}} of the deck's static problems (loads along z, ``held`` held)."""
    structure, info, deck = read_structure(bdf)
    K, _ = NastranModel(structure, {}, {}, {}, name=info["deck"], deck=bdf, bdf=deck).matrices()
    grids = list(info["grid_ids"])
    held = np.concatenate([6 * grids.index(g) + np.arange(6) for g in NX["held"]])
    free = np.setdiff1d(np.arange(K.shape[0]), held)
    Kf = K.tocsc()[free][:, free]
    out = {}
    for case, loads in NX["loads_z"].items():
        F = np.zeros(K.shape[0])
        for g, load in loads.items():
            F[6 * grids.index(int(g)) + 2] = load
        u = np.zeros(K.shape[0])
        u[free] = spla.spsolve(Kf, F[free])
        out[case] = {str(g): float(u[6 * i + 2]) for i, g in enumerate(grids)}
    return out


def _miss(ours: dict, nx: dict) -> float:
    return max(abs(ours[g] - v) for g, v in nx.items()) / max(abs(v) for v in nx.values())


def test_deck_as_published_bends_as_nx_and_nearer_than_the_stiff_shear_quad(tmp_path):
    ours = _t3(DATA / "nx_shear_rigid_quads.bdf")
    stiff = tmp_path / "stiff_shear.bdf"
    text = (DATA / "nx_shear_rigid_quads.bdf").read_text()
    assert PSHELL in text
    stiff.write_text(text.replace(PSHELL, PSHELL + ", , 10000, 1000."))
    mitc = _t3(stiff)
    for case, nx in NX["t3"].items():
        assert _miss(ours[case], nx) < _miss(mitc[case], nx), case
    # the tip force (subcase 2 less subcase 1): NX 0.013610, the DKQ +0.54 %, the MITC4 -1.9 %
    tip = {k: r["2"]["15"] - r["1"]["15"] for k, r in (("ours", ours), ("nx", NX["t3"]))}
    assert abs(tip["ours"] / tip["nx"] - 1) < 6e-3
    assert _miss(ours["2"], NX["t3"]["2"]) < 7e-3  # 5.9e-3
