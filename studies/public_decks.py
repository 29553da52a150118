"""Public Nastran decks read as a new user reads them: which cards are refused, and, where a deck
has its solver's f06 beside it, how its real eigenvalues compare.

Point it at a folder of decks nobody here wrote, e.g. pyNastran's ``models`` folder (LGPL-3: read,
not copied into this repository; ``git clone https://github.com/SteveDoyle2/pyNastran`` or the
tool library's ``fetch``).  For every ``.bdf`` / ``.dat`` / ``.nas`` under it:

1. the deck is read and its cards sorted (``nastran.deck.read_deck`` + ``check_cards``, what every
   command does first); the refused card names are counted over all decks, with how many decks
   each keeps out;
2. for the decks in ``F06_DECKS`` (deck, its f06) that read with no refusal, ``bayesupdate modes
   --model DECK --json`` (the user's command) is compared mode by mode with the f06's first real
   eigenvalue table.

Measured on pyNastran 1d25a9244 (2026-11-30): 84 decks; 6 read with no refusal before the cards
of other analyses were ignored (loads, aero, dampers, plot cards), 27 after.  The refusals left
are solids (CTETRA, CHEXA, CPENTA, PSOLID), composites (PCOMP, MAT8), DMI, CSHEAR, MPC, RBAR
with partial components, CQUADR/CTRIAR, CQUAD8/CTRIA6, CTUBE, PBEND, ZONA's cards.  f06:
``2_mode_flutter`` 2.6671 / 10.6282 Hz against MSC's 2.66709 / 10.6282 (it was 11.7301 with
consistent shell mass); the Goland wing (``bugs/msc_dscmcol``, MSC 2018.1, one mode) 1.98144 Hz
against 1.981382 (+2.9e-5); MSC's beam_modes deck, modes 1-10 to the f06's printed digits.

Run: PYTHONPATH=. .venv/bin/python studies/public_decks.py /path/to/pyNastran/models
"""

import argparse
import collections
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

from bayesupdate.nastran.deck import Refusals, check_cards, read_deck

#: (deck, f06) under the models folder: decks whose f06 has a real eigenvalue table
F06_DECKS = (
    ("aero/2_mode_flutter/0012_flutter.bdf", "aero/2_mode_flutter/0012_flutter.f06"),
    ("bugs/msc_dscmcol/goland_final_test.bdf", "bugs/msc_dscmcol/goland_final_test.f06"),
    ("beam_modes/beam_modes.dat", "beam_modes/beam_modes.f06"),
)
CARD = re.compile(r"card (\S+) is not supported|PARAM (\S+) is not supported")


def refusals_of(path: Path) -> list[str] | None:
    """The refusals of the deck at ``path`` (None: it does not read at all)."""
    refusals = Refusals(str(path))
    try:
        check_cards(read_deck(path, refusals), refusals)
    except Exception:  # noqa: BLE001 - a sweep over other people's files: count, go on
        return None
    return list(refusals.items)


def f06_hz(path: Path) -> np.ndarray:
    """The cycles column of the f06's first real eigenvalue table [Hz], mode by mode."""
    table = path.read_text(errors="replace").split("R E A L   E I G E N V A L U E S")[1]
    rows = re.findall(r"^\s+(\d+)\s+\d+\s+\S+\s+\S+\s+(\S+)\s+\S+\s+\S+\s*$", table, re.M)
    out = []
    for mode, cycles in rows:
        if int(mode) != len(out) + 1:
            break
        out.append(float(cycles))
    return np.array(out)


def modes_hz(deck: Path, n: int) -> np.ndarray | str:
    """``bayesupdate modes --model deck --modes n --json``'s frequencies, or its error line."""
    command = [sys.executable, "-m", "bayesupdate", "modes", "--model", deck.name]
    out = subprocess.run([*command, "--modes", str(n), "--json"], cwd=deck.parent,
                         capture_output=True, text=True, check=False)  # fmt: skip
    if out.returncode:
        return out.stderr.strip()[:200]
    return np.array(json.loads(out.stdout)["frequencies_hz"])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("models", type=Path, help="a folder of decks (pyNastran's models)")
    args = ap.parse_args()
    paths = sorted(
        p for p in args.models.rglob("*") if p.suffix.lower() in (".bdf", ".dat", ".nas")
    )
    names, decks, clean, unread = collections.Counter(), collections.defaultdict(set), 0, 0
    for path in paths:
        items = refusals_of(path)
        if items is None:
            unread += 1
            continue
        clean += not items
        for item in items:
            m = CARD.search(item)
            name = (m.group(1) or f"PARAM {m.group(2)}") if m else "other"
            names[name] += 1
            decks[name].add(path)
    print(f"{len(paths)} decks: {clean} read with no refusal, {unread} did not read at all")
    for name, count in names.most_common(40):
        print(f"  {count:5d} x {name} (in {len(decks[name])} decks)")
    for deck, f06 in F06_DECKS:
        deck, f06 = args.models / deck, args.models / f06
        if not deck.exists():
            continue
        ref = f06_hz(f06)
        ours = modes_hz(deck, len(ref))
        if isinstance(ours, str):
            print(f"{deck.name}: {ours}")
            continue
        k = min(len(ref), len(ours))
        gap = 100 * (ours[:k] / ref[:k] - 1)
        print(f"{deck.name}: f06 {np.round(ref[:k], 5).tolist()} Hz, ours "
              f"{np.round(ours[:k], 5).tolist()} Hz, {np.round(gap, 4).tolist()} %")  # fmt: skip


if __name__ == "__main__":
    main()
