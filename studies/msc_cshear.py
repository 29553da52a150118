"""What MSC Nastran's CSHEAR is: its shear panels' stresses on MSC's own solution, and the whole
deck's static solution beside MSC's.

Data nobody here made, from pyNastran's ``models`` folder (BSD-3-Clause, commit 1d25a92; read
with pyNastran's OP2 reader, which this script alone needs): ``msc/64_bit/d173.bdf`` and its
``d173.op2`` (MSC Nastran, SOL 101, Patran 2016's wing-box test deck d173grav): 141 CSHEAR
spar and rib webs (PSHEAR of MAT1 E 70000, G 26315.8, NU 0.33, F1 = F2 = 0; panels up to 37 %
from parallelograms), 88 CQUAD4 and 13 CTRIA3 skins (PSHELL, and PCOMP of MAT8 plies
[45/-45/0/90/0/45/...] with Z0 offsets), 360 CROD caps, 4 CBAR, 6 CONM2, MPCs, 162 FORCEs (LOAD
203: FORCE 201).  The op2 holds the displacements (float32) and each CSHEAR's largest and
average corner shear stress.

Checked: the package's shear panel (``fe.elements.shear_panel``, Garvey's panel of the NASTRAN
Theoretical Manual) recovers MSC's stresses from MSC's displacements, and with which tolerance
on parallel sides; then the whole deck, read by the package's reader, is solved under FORCE 201
with its SPCs, MPCs and AUTOSPC, beside MSC's displacements.

Measured (2026-11-30, this script): the panels' average and largest stresses are MSC's to
2.6e-6 and 2.9e-6 of their scale (the median |tau_avg|; medians over the 141 panels), 1.1e-4
and 2.0e-4 at most, with sides parallel within 1e-3; with NASTRAN-95's 0.01 the panels whose
sides are between the two tolerances miss the largest stress by up to 0.19 of that scale (18 %
of the panel's own).  The whole deck:
the largest displacement (T2, 195 mm) differs from MSC's by up to 2.0 % of it, T3 2.6 %, T1 16 %
and the rotations more: not explained (the deck mixes PSHELL and unsymmetric offset PCOMP
skins, whose drilling stiffness is MSC's PARAM K6ROT 100 there and this package's penalty
here, with CBARs, CRODs, MPCs and the panels).

``--write DIR`` stores what the tests need (``tests/data/msc_cshear.json``: each panel's
corners, G, NU, corner displacements and MSC's two stresses), so that the tests do not need
pyNastran.

Run: PYTHONPATH=. python studies/msc_cshear.py <pyNastran>/models [--write tests/data]
"""

import argparse
import json
from pathlib import Path

import numpy as np
import scipy.sparse.linalg as spla

from bayesupdate.fe.elements import shear_panel
from bayesupdate.nastran import load_nastran_model
from bayesupdate.nastran.deck import read_deck

DECK = "msc/64_bit/d173"


def msc_panels(models: Path) -> dict:
    """MSC's solution read with pyNastran: per panel corners (n, 4, 3), G, NU, t (n,), corner
    displacements (n, 4, 3), largest and average stress (n,); the GRIDs' displacements."""
    from pyNastran.bdf.bdf import read_bdf
    from pyNastran.op2.op2 import read_op2

    op2 = read_op2(str(models / f"{DECK}.op2"), debug=None, build_dataframe=False)
    bdf = read_bdf(str(models / f"{DECK}.bdf"), debug=None, xref=True)
    disp = op2.displacements[1]
    u = {int(g): row for g, row in zip(disp.node_gridtype[:, 0], disp.data[0], strict=True)}
    stress = op2.op2_results.stress.cshear_stress[1]
    cards = [bdf.elements[int(e)] for e in stress.element]
    mats = [c.pid_ref.mid_ref for c in cards]
    return dict(
        corners=np.array([[bdf.nodes[g].get_position() for g in c.node_ids] for c in cards]),
        G=np.array([m.g for m in mats]), nu=np.array([m.nu for m in mats]),
        u=np.array([[u[g][:3] for g in c.node_ids] for c in cards]).astype(float),
        tau_max=stress.data[0, :, 0].astype(float), tau_avg=stress.data[0, :, 1].astype(float),
        grids=u,
    )  # fmt: skip


def stress_misses(p: dict, parallel: float) -> tuple[np.ndarray, np.ndarray]:
    """(average, largest) |ours - MSC| / median |MSC average| per panel, sides parallel within
    ``parallel``."""
    modes = shear_panel.panel_modes(p["corners"], p["nu"], parallel)
    tau = shear_panel.panel_stresses(modes, p["G"], p["u"])
    scale = np.median(np.abs(p["tau_avg"]))
    return (np.abs(tau.mean(axis=1) - p["tau_avg"]) / scale,
            np.abs(np.abs(tau).max(axis=1) - p["tau_max"]) / scale)  # fmt: skip


def static_misses(models: Path, msc: dict) -> dict:
    """Per component, max |ours - MSC| / max |MSC| of the whole deck under FORCE 201."""
    path = str(models / f"{DECK}.bdf")
    model = load_nastran_model(path)
    K, _ = model.matrices()
    grids = list(model.structure.metadata["nastran"]["grid_ids"])
    F = np.zeros(K.shape[0])
    for c in read_deck(path).of("FORCE"):
        if c.value(0) == 201:  # CID 0 on every FORCE of this deck
            row = 6 * grids.index(c.value(1))
            F[row : row + 3] += c.value(3) * np.array([c.value(k) or 0.0 for k in (4, 5, 6)])
    tr = model.general.transform
    u = (tr.T @ spla.spsolve(tr.reduce(K).tocsc(), tr.T.T @ F)).reshape(-1, 6)
    U = np.array([msc[g] for g in grids], dtype=float)
    names = ("T1", "T2", "T3", "R1", "R2", "R3")
    return {n: float(np.abs(u[:, c] - U[:, c]).max() / np.abs(U[:, c]).max())
            for c, n in enumerate(names)}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("models", type=Path, help="pyNastran's models folder")
    ap.add_argument("--write", type=Path, help="write the tests' data in this folder")
    args = ap.parse_args()
    p = msc_panels(args.models)
    for parallel in (shear_panel.PARALLEL, 0.01):
        avg, big = stress_misses(p, parallel)
        print(f"sides parallel within {parallel:g}: average stress median {np.median(avg):.2e}, "
              f"largest {avg.max():.2e}; largest stress median {np.median(big):.2e}, largest "
              f"{big.max():.2e} (of the median |tau_avg|)")  # fmt: skip
    print(
        "whole deck, FORCE 201: max |ours - MSC| / max |MSC|:",
        static_misses(args.models, p["grids"]),
    )
    if args.write:
        keys = ("corners", "G", "nu", "u", "tau_max", "tau_avg")
        data = {k: np.asarray(p[k]).tolist() for k in keys}
        (args.write / "msc_cshear.json").write_text(json.dumps(data) + "\n")


if __name__ == "__main__":
    main()
