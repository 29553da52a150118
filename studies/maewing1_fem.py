"""The mAEWing1 aircraft's own MSC Nastran decks, read as published, against their ``.f06``.

``../shared/data/gvt_maewing1/fem`` (README there) holds the pre-update model (v3.3) and the
authors' updated models (v4.2, v4.2.1), each with MSC Nastran's SOL 103 output.  Each deck is
read unmodified by ``bayesupdate.nastran`` (its own bulk-data reader) and its 20 lowest elastic
modes are solved; printed per deck: MSC's frequency, ours and the relative difference, the
rigid-body modes, and the mass / WTMASS against the f06's grid point weight generator [lbf].
The authors' SOL 200 deck (same structure, 34 DESVARs) is solved too: its parameters listed (all
34: the element cards' own fields, CBEAM offsets, CONM2 X1/I11/I22, CMASS2 M, are re-built), any
DESVAR that is not a parameter with the relation that keeps it out, and the model at the cards'
values, the bound model at the 34 XINITs, and the deck ``writer.write_design_deck`` writes at
the XINITs (every relation evaluated, read again), beside v4.2.

Run:  .venv/bin/python studies/maewing1_fem.py
"""

import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import numpy as np  # noqa: E402
from test_nastran_maewing1 import DECKS, FEM, f06_table  # noqa: E402

from bayesupdate.nastran import load_nastran_model  # noqa: E402

N_MODES = 20
SOL200 = "sol200_full_model/sol200_mAEWing1_FEMv4p2.bdf"


def compare(name: str, deck: str, f06: str) -> float:
    """Print one deck's table; returns the largest |relative difference|."""
    msc, weight = f06_table(FEM / Path(deck).parent / f06)
    model = load_nastran_model(str(FEM / deck))
    r = model.solve(n_modes=N_MODES)
    info = model.structure.metadata["nastran"]
    ref = msc[6 : 6 + N_MODES]
    rel = r.frequencies_hz / ref - 1
    print(f"\n{name}: {deck}  ({info['units']['system']}, {model.structure.n_dof} DOFs)")
    print(f"  rigid-body modes: {r.modes.n_rigid} (MSC: {int(np.sum(msc[:6] == 0))} at 0 Hz)")
    w = r.mass_kg / info["wtmass"]
    print(f"  weight: {w:.6f} lbf (f06 {weight:.6f}; {w / weight - 1:+.1e})")
    print("  mode   MSC [Hz]     ours [Hz]    rel. diff")
    for k, (a, b, d) in enumerate(zip(ref, r.frequencies_hz, rel, strict=True), start=7):
        print(f"  {k:4d} {a:11.5f} {b:13.6f}   {d:+.2e}")
    print(f"  largest |rel. diff| {np.abs(rel).max():.2e}")
    return float(np.abs(rel).max())


def sol200() -> None:
    """The SOL 200 deck: its DESVAR parameters; the model at the cards' values, the bound model
    at the parameters' XINIT, the deck written at every DESVAR's XINIT through all the
    relations (``writer.write_design_deck``: the deck SOL 200 starts from) and v4.2's."""
    import tempfile

    from bayesupdate.nastran.deck import read_deck
    from bayesupdate.nastran.desvar import unbound_reasons, xinit_values
    from bayesupdate.nastran.writer import write_design_deck

    deck = read_deck(FEM / SOL200)
    model = load_nastran_model(str(FEM / SOL200))
    xinit = xinit_values(deck, model)
    print(f"\nSOL 200 deck: {SOL200}")
    print(f"  {len(deck.of('DESVAR'))} DESVARs, {len(xinit)} parameters: "
          "name  card value  XINIT  [XLB, XUB]")  # fmt: skip
    bounds = model.default_bounds()
    for name, value in model.default_parameters().items():
        print(f"    {name:10s} {value:<12.6g} {xinit[name]:<12.6g} {list(bounds[name])}")
    reasons = unbound_reasons(deck)
    bound = {b.desvar for b in model.bindings.values()}
    for i, c in sorted(deck.table("DESVAR").items()):
        if i not in bound:
            print(f"    not a parameter: {c['LABEL']:8s} ({i}) XINIT {c.real('XINIT'):<10g} "
                  f"{reasons.get(i, '(see the deck note)')}")  # fmt: skip
    cards = model.solve(n_modes=10).frequencies_hz
    start = model.solve(xinit, n_modes=10).frequencies_hz
    with tempfile.TemporaryDirectory() as tmp:
        written = write_design_deck(FEM / SOL200, Path(tmp) / "sol200_at_xinit.bdf")
        design = load_nastran_model(str(written), parameters={}).solve(n_modes=10).frequencies_hz
    v42 = load_nastran_model(str(FEM / DECKS["v4.2"][0])).solve(n_modes=10).frequencies_hz
    print(f"  mode  cards [Hz]   {len(xinit)} params at XINIT   written at XINIT   v4.2 [Hz]   "
          "(cards - v4.2)")  # fmt: skip
    for k, (a, b, d, c) in enumerate(zip(cards, start, design, v42, strict=True), start=7):
        print(f"  {k:4d} {a:11.5f} {b:9.5f} ({b / a - 1:+.2e}) {d:9.5f} ({d / a - 1:+.2e}) "
              f"{c:10.5f} ({a / c - 1:+.2e})")  # fmt: skip
    gap = np.abs(start / design - 1).max()
    print(f"  bound model at XINIT against the written deck: largest |rel. diff| {gap:.1e}")


def main() -> None:
    worst = max(compare(name, *files) for name, files in DECKS.items())
    print(f"\nall three decks: largest |rel. diff| {worst:.2e} (target 1e-4)")
    sol200()


if __name__ == "__main__":
    main()
