"""Solve time of the mAEWing1 authors' SOL 200 deck with its 34 DESVARs as the parameters.

The deck is ``../shared/data/gvt_maewing1/fem/sol200_full_model/sol200_mAEWing1_FEMv4p2.bdf``
as published (README there).  ``load_nastran_model`` makes its DESVARs the parameters
(``nastran.desvar``): PBEAM A/I1/J/NSM and MAT1 E/G/RHO relations act on the bound line
elements' records (``nastran.lines.LineFields``), while the CBEAM offsets W1A-W2B (44 beams),
CONM2 M/X1/I11/I22 (35) and CMASS2 M (12) are element-card fields.  Those are solved from
records fitted once (``nastran.card_records``: offsets, masses, inertias affine in the
fields; a beam's axis, frame and lumped end masses derived from them at each solve); before,
their cards were converted again at every solve (``LineRebuild``, still the reference).

Printed, each the median CPU (process) time of a full solve (20 modes, ``model.predict``) over
the points solved in turn, so that no assembly is the cached one: with every DESVAR moved, with
only the element-card DESVARs (offsets, masses) moved, with only the others moved (the offset
beams' PBEAMs are among them); the element-card group again, alternating point by point with a
model whose cards are read again at every solve (the reference, the package before
``card_records``), and the ratio;
the one-off cost of fitting the records (the first solve away from the deck's values); and the
solve at one point again, its assembly cached (the eigen-solve and the expansion alone).  The
points: the DESVARs' initial values moved by a seeded uniform fraction (up to ``--spread`` of
each half-box, default 0.1), seed ``--seed`` (default 0).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/design_solve.py [--points 6]
        [--repeats 3] [--seed 0] [--spread 0.1]
"""

import argparse
import os
import time
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from bayesupdate.nastran import load_nastran_model  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DECK = "shared/data/gvt_maewing1/fem/sol200_full_model/sol200_mAEWing1_FEMv4p2.bdf"
N_MODES = 20


def _deck() -> Path:
    for up in (ROOT.parent, ROOT.parents[1]):
        if (up / DECK).is_file():
            return up / DECK
    raise SystemExit(f"{DECK} not found beside the checkout")


def card_parameters(model) -> set[str]:
    """The parameters whose relations write element cards (CBAR/CBEAM offsets, CONM2, CMASS2)."""
    return {n for n, b in model.bindings.items() if getattr(b, "relations", ())}


def moved_points(model, names, n: int, seed: int, spread: float) -> list[dict]:
    """``n`` points: the defaults with ``names`` moved by up to ``spread`` of each half-box."""
    rng = np.random.default_rng(seed)
    d, b = model.default_parameters(), model.default_bounds()
    out = []
    for _ in range(n):
        p = dict(d)
        for k in names:
            half = 0.5 * (b[k][1] - b[k][0])
            p[k] = float(np.clip(d[k] + spread * half * rng.uniform(-1, 1), *b[k]))
        out.append(p)
    return out


def cycled_ms(model, pts, repeats: int) -> float:
    """Median CPU time [ms] of one ``predict`` while the points are solved in turn."""
    times = []
    for _ in range(repeats):
        for p in pts:
            t = time.process_time()
            model.predict(p, n_modes=N_MODES)
            times.append(time.process_time() - t)
    return 1e3 * float(np.median(times))


def side_by_side(models, pts, repeats: int) -> list[float]:
    """Median CPU time [ms] of one ``predict`` of each model, the models alternating at every
    point (so that a change of the machine's speed falls on both alike)."""
    times = [[] for _ in models]
    for _ in range(repeats):
        for p in pts:
            for model, out in zip(models, times, strict=True):
                t = time.process_time()
                model.predict(p, n_modes=N_MODES)
                out.append(time.process_time() - t)
    return [1e3 * float(np.median(t)) for t in times]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--points", type=int, default=6)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--spread", type=float, default=0.1)
    args = ap.parse_args()
    t = time.process_time()
    model = load_nastran_model(_deck())
    print(f"load: {time.process_time() - t:.2f} s CPU; {len(model.parameter_names)} DESVARs "
          f"as parameters; {model.structure.n_dof} DOFs")  # fmt: skip
    cards = card_parameters(model)
    first = moved_points(model, sorted(cards), 1, args.seed + 1, args.spread)[0]
    t = time.process_time()
    model.predict(first, n_modes=N_MODES)
    print(
        f"first solve away from the deck's values (the records fitted once): "
        f"{time.process_time() - t:.2f} s CPU; {model.general.card_notes or 'no card fields'}"
    )
    groups = {
        "every DESVAR moved": list(model.parameter_names),
        f"only the {len(cards)} element-card DESVARs moved (offsets, CONM2, CMASS2)": sorted(cards),
        f"only the other {len(model.parameter_names) - len(cards)} moved (PBEAM, MAT1)":
            [n for n in model.parameter_names if n not in cards],
    }  # fmt: skip
    model.predict(model.default_parameters(), n_modes=N_MODES)  # the fields found once
    for label, names in groups.items():
        pts = moved_points(model, names, args.points, args.seed, args.spread)
        model.predict(pts[0], n_modes=N_MODES)
        ms = cycled_ms(model, pts, args.repeats)
        print(f"full solve ({N_MODES} modes), {label}: median CPU {ms:.1f} ms")
    pts = moved_points(model, sorted(cards), args.points, args.seed, args.spread)
    reference = load_nastran_model(_deck())
    # the reference path (the package before ``card_records``): the cards read at every solve
    reference.general._card_records = [None] * len(reference.general.cards)  # noqa: SLF001
    reference.predict(pts[0], n_modes=N_MODES)
    fitted, again = side_by_side((model, reference), pts, args.repeats)
    print(f"element-card DESVARs moved, the two paths alternating: fitted records {fitted:.1f} "
          f"ms, cards read again (before) {again:.1f} ms: {again / fitted:.1f}x")  # fmt: skip
    t = time.process_time()
    for _ in range(args.repeats * args.points):
        model.solve(model.default_parameters(), N_MODES)
    each = 1e3 * (time.process_time() - t) / (args.repeats * args.points)
    print(f"solve at the initial values again (the assembly cached: the eigen-solve and the "
          f"expansion): {each:.1f} ms CPU")  # fmt: skip


if __name__ == "__main__":
    main()
