"""Public Nastran decks read as a new user reads them: which cards are refused, and, where a deck
has its solver's f06 beside it, how its real eigenvalues compare.

Point it at a folder of decks nobody here wrote, e.g. pyNastran's ``models`` folder
(BSD-3-Clause at the commit below; read, not copied into this repository; ``git clone
https://github.com/SteveDoyle2/pyNastran`` or the tool library's ``fetch``).  For every
``.bdf`` / ``.dat`` / ``.nas`` under it:

1. the deck is read and its cards sorted (``nastran.deck.read_deck`` + ``check_cards``, what every
   command does first), then, where no card is refused, read to a model (``reader``); the
   refused card names are counted over all decks, with how many decks each keeps out;
2. for the decks in ``F06_DECKS`` (deck, its f06) that read with no refusal, ``bayesupdate modes
   --model DECK --json`` (the user's command) is compared mode by mode with the f06's first real
   eigenvalue table.

Measured on pyNastran 1d25a9244 (2026-11-30): 84 decks; 6 read with no refusal before the cards
of other analyses were ignored (loads, aero, dampers, plot cards, aeroelastic DMI), 30 after
MPC and GRDSET were read too; 24 of those read to a model (the others: include fragments with
no elements or no mass, PBEAM warping fields, template variables).  The refusals left are
solids (CTETRA, CHEXA, CPENTA, PSOLID), composites (PCOMP, MAT8), DMI, DMIG, CSHEAR,
CQUADR/CTRIAR, CQUAD8/CTRIA6, CTUBE, PBEND, ZONA's cards.  f06: MSC's BAH plane
(``aero/bah_plane``, a half aircraft of CBARs, CONM2s, RBE2s and RBARs), its 6 elastic modes
within 2.3e-7 of the f06's 7 printed digits (2.454016 ... 22.15915 Hz), its 2 rigid modes;
MSC's pt145 (CBARs with I2 = 0,
coupled mass, CONM2s), its 30 modes within 4.6e-7 (with rotary and torsional inertia in the
CBARs' coupled mass, as before, modes 1-10 were off by up to -0.048 %);
``2_mode_flutter`` 2.6671 / 10.6282 Hz against MSC's 2.66709 / 10.6282 (it was 11.7301 with
consistent shell mass); the Goland wing (``bugs/msc_dscmcol``, MSC 2018.1, one mode) 1.98144 Hz
against 1.981382 (+2.9e-5); MSC's beam_modes deck, modes 1-10 to the f06's printed digits.

On every deck of the same commit's ``models`` folder (231, taken file by file with ``git show``;
one file's object is missing from the mirror), 2026-11-30: 41 read to a model with no refusal,
39 before the four-node CTETRA (2,929 cards in 42 decks) and CTUBE were read.  The refusals
were led by CHEXA (4,997 cards in 68 decks), CPENTA (457 in 43), PCOMP (360 in 48) and CSHEAR
(164 in 21).  With the eight-node CHEXA read (the same day): 43 read to a model; of the 41
decks with a CHEXA card, 2 read whole (``ogs/nx_ogstr``, ``unit/pload4/chexa``), the others
kept out by other cards (PARAMs in 24, CPENTA in 14, CQUAD8 in 10, CTRIA6 and the reader's
other refusals in 9 each, ...).  The refusals are now led by CPENTA (457 in 43), PCOMP (360 in
48) and CSHEAR (164 in 21).  pyNastran's ``unit/pload4/cpenta.op2`` holds the CHEXA model's
displacements (the same numbers as ``chexa.op2``), so no CPENTA check could be made there.
With PCOMP/PCOMPG and MAT8 read (laminates, unsymmetric ones too) and a large-field
continuation marker with a name read as large fields (the same day): 49 read to a model; of the
18 model files with a PCOMP or PCOMPG, 5 read whole (``plate/plate_mixed``, ``nx/laminate``,
``bugs/flat_plate_pcomp_test``, ``other/v10112``, ``unit/pcomp/pcomp_ctria3``), the others kept
out by other cards (CSHEAR, PARAM PCOMPRM, thermal and hyperelastic cards, ...).  With CSHEAR
read (PSHEAR F1-F4 refused): 50 read to a model (``msc/64_bit/d173`` joins them).  The refusals
are now led by CPENTA (457 in 43), CTRIA6 (79 in 23) and CQUADR (78 in 22).  With a DMIG that
no K2GG or M2GG selects ignored (2026-11-30): 51 read to a model; MSC's ``aero/fmondsp`` (a
glider of tapered PBEAML TUBEs and PBEAML BOXes, its DMIG only in K2PP) joins the f06 decks:
with each PBEAML the PBEAM of its stations' sections and MSC's TUBE and BOX shear factors, as
its f06 prints them, its 12 elastic modes within 6.0e-6 of MSC's (they were up to 3.7 % low
with the mean of the exact section and Cowper's factors).  With PBARL/PBEAML T, T2 and CHAN
read (the same day): 54 (pyNastran's one-shape decks of them; they hold no mass, so ``modes``
refuses them for that).  The NASA N2A blended wing body (``bwb``: 52 CBARs on a PBARL T2, which
kept it out) now stops at its connectivity: two GRIDs with a 77.78 CONM2 each and no element
(MSC's AUTOSPC would hold them; here the deck is refused, naming them).

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

from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran.deck import Refusals, check_cards, read_deck
from bayesupdate.nastran.reader import read_structure

#: (deck, f06) under the models folder: decks whose f06 has a real eigenvalue table
F06_DECKS = (
    ("aero/bah_plane/bah_plane.bdf", "aero/bah_plane/bah_plane.f06"),
    ("aero/pt145.bdf", "aero/pt145.f06"),
    ("aero/2_mode_flutter/0012_flutter.bdf", "aero/2_mode_flutter/0012_flutter.f06"),
    ("bugs/msc_dscmcol/goland_final_test.bdf", "bugs/msc_dscmcol/goland_final_test.f06"),
    ("beam_modes/beam_modes.dat", "beam_modes/beam_modes.f06"),
    ("aero/fmondsp.dat", "aero/fmondsp.f06"),
)
CARD = re.compile(r"card (\S+) is not supported|PARAM (\S+) is not supported")


def refusals_of(path: Path) -> list[str] | None:
    """The refusals of the deck at ``path`` (None: it does not read at all): its cards' (as
    ``check_cards`` sorts them), and, where none, the reader's on its way to a model
    (``reader.read_structure``: an element's fields, an RBAR's components, a mechanism ...)."""
    refusals = Refusals(str(path))
    try:
        check_cards(read_deck(path, refusals), refusals)
    except Exception:  # noqa: BLE001 - a sweep over other people's files: count, go on
        return None
    if refusals.items:
        return list(refusals.items)
    try:
        read_structure(path)
    except BayesUpdateError as exc:
        return [item for item in re.split(r"; (?=\S+:\d+ )", str(exc))]
    except Exception as exc:  # noqa: BLE001
        return [f"internal error: {type(exc).__name__}"]
    return []


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


def modes_hz(deck: Path, n: int) -> tuple[np.ndarray, int] | str:
    """(``bayesupdate modes --model deck --modes n --json``'s elastic frequencies, its rigid
    mode count), or its error line."""
    command = [sys.executable, "-m", "bayesupdate", "modes", "--model", deck.name]
    out = subprocess.run([*command, "--modes", str(n), "--json"], cwd=deck.parent,
                         capture_output=True, text=True, check=False)  # fmt: skip
    if out.returncode:
        return out.stderr.strip()[:200]
    result = json.loads(out.stdout)
    return np.array(result["frequencies_hz"]), int(result["rigid_modes"])


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
    print(f"{len(paths)} decks: {clean} read to a model with no refusal, {unread} did not read")
    for name, count in names.most_common(40):
        print(f"  {count:5d} x {name} (in {len(decks[name])} decks)")
    for deck, f06 in F06_DECKS:
        deck, f06 = args.models / deck, args.models / f06
        if not deck.exists():
            continue
        ref = f06_hz(f06)
        solved = modes_hz(deck, len(ref))
        if isinstance(solved, str):
            print(f"{deck.name}: {solved}")
            continue
        ours, rigid = solved
        ref = ref[rigid:]  # the f06 lists the rigid modes first
        k = min(len(ref), len(ours))
        gap = 100 * (ours[:k] / ref[:k] - 1)
        print(f"{deck.name} ({rigid} rigid): f06 {np.round(ref[:k], 5).tolist()} Hz, ours "
              f"{np.round(ours[:k], 5).tolist()} Hz, {np.round(gap, 4).tolist()} %")  # fmt: skip


if __name__ == "__main__":
    main()
