"""A deck written as one file of large-field cards, for readers stricter than MSC Nastran
(MYSTRAN): the same model, in the subset of the format every reader takes.

MYSTRAN 18 refuses the mAEWing1 decks as published (``benchmarks/deck_solve.py``): first for
format (tab characters inside fields: its reader takes a tab as a character, "TOO LONG AN
ENTRY", an integer with 15 digits; a PBEAM with no end-B station: "MUST BE YES, YESA OR NO",
and a one-line PBEAM "REQUIRED CONTINUATION ... MISSING"), then, with those fixed, for the
model: a grounded CBUSH stops it (ELMGM1_BUSH), and it has no CBEAM element ("CODE NOT WRITTEN
FOR BEAM ELEMENT MATRICES AS YET").  The flat deck makes these edits, none of which changes the
model as MSC reads it:

1. the executive and case control are copied (tabs expanded); ``INCLUDE``d files are read in
   (``deck.read_deck``: case-insensitive names);
2. every bulk card is written from its parsed fields as large-field lines
   (``bulk.large_field_text``: 16-character fields, no tabs, no continuation markers);
3. a PBEAM of one section (no end-B station: end B is end A, QRG PBEAM) without warping, NSI,
   shear-relief or neutral-axis terms is the PBAR of the same beam (A, I1, I2, I12, J, NSM,
   and K1, K2, whose PBEAM default 1.0 is written: a PBAR's blank K is shear-rigid), and a
   CBEAM on it the CBAR with the same orientation, OFFT, pin flags and offsets (QRG CBAR,
   CBEAM: the same fields 2-17); with lumped mass (COUPMASS < 1) a CBEAM's lumped twist
   inertia rho (I1 + I2) L / 2 about its axis at each end, which a CBAR has not
   (``cards.beams``), is written as two massless CONM2 (3.4 % on v3.3's mode 3 without them);
4. (``mystran=True``) a grounded CBUSH (GB blank: MYSTRAN 18 stops in
   ELMGM1_BUSH, "Index '0' of dimension 1 of array 'grid'"; it refuses a grounded CELAS2 too,
   "INVALID COMPONENT NUMBER = 0 IN FIELD 7") gets a GB of its own, a new GRID at GA's place
   held by its PS field 123456 (QRG CBUSH remark 6: a grounded terminal is a point constrained
   to zero, so MSC reads the same model).  This reader takes a fully held GRID as a support, so
   that with SUPORT it finds no free rigid motion: it reads the deck written with
   ``mystran=False`` (edits 4 and 5 left out) instead;
5. (``mystran=True``) SUPORT is dropped: MYSTRAN computes the elastic modes of the structure
   held at the SUPORT DOFs (its L-set with the R-set removed: on mAEWing1 v3.3 the two wings
   then vibrate apart, in pairs from 3.70 Hz), where MSC gives those of the free structure
   and SUPORT only names its rigid modes; without it the soft suspension springs give six
   modes near 0 Hz, and the elastic modes follow;
6. ``ENDDATA`` closes the file.
"""

from pathlib import Path

import numpy as np

from bayesupdate.nastran.bulk import Card, large_field_text, real16, with_fields
from bayesupdate.nastran.cards.beams import pbeam_layout
from bayesupdate.nastran.deck import Refusals, read_deck
from bayesupdate.nastran.frames import read_grids
from bayesupdate.nastran.reader import deck_settings

#: the edits ``write_flat_deck`` makes (module docstring), for reports
EDITS = (
    "INCLUDE files read in, one file",
    "every bulk card in large-field format (no tabs, no continuation markers)",
    "PBEAM of one section -> PBAR (K1, K2 written), CBEAM on it -> CBAR + 2 CONM2 (twist)",
    "grounded CBUSH: GB a new GRID at GA's place with PS 123456 (for MYSTRAN)",
    "SUPORT dropped (for MYSTRAN: it solves the elastic modes held at the SUPORT DOFs)",
    "ENDDATA appended",
)


def write_flat_deck(path, out, mystran: bool = False) -> Path:
    """Write the deck at ``path`` as one large-field file ``out`` (module docstring; edits 4
    and 5 only with ``mystran``); returns ``out``."""
    deck = read_deck(path)
    head = []
    for line in Path(deck.files[0]).read_text(errors="replace").splitlines():
        head.append(line.expandtabs(8))
        if line.strip().upper().startswith("BEGIN BULK"):
            break
    cards = _bars(deck, list(deck.cards))
    if mystran:
        cards = [c for c in _ground_grids(deck, cards) if c.name not in ("SUPORT", "SUPORT1")]
    cards = [large_field_text(c) for c in cards]
    out = Path(out)
    out.write_text("\n".join(head) + "\n" + "".join(cards) + "ENDDATA\n")
    return out


def _ground_grids(deck, cards: list) -> list:
    """``cards`` with each grounded CBUSH given a GB of its own (module docstring, edit 4): a
    new GRID at GA's place held by PS 123456 (ids after the deck's largest)."""
    grids = read_grids(deck, Refusals(deck.path))
    next_grid = int(grids.ids.max()) + 1 if len(grids.ids) else 1
    out = []
    for c in cards:
        if c.name == "CBUSH" and not c["GB"]:
            row = int(grids.index([c.int("GA", positive=True)], c)[0])
            xyz = [real16(float(v)) for v in grids.xyz[row]]
            out.append(Card("GRID", (str(next_grid), "", *xyz, "", "123456"), c.file, c.line,
                            c.end))  # fmt: skip
            c = with_fields(c, {c.position("GB"): next_grid})
            next_grid += 1
        out.append(c)
    return out


def _bars(deck, cards: list) -> list:
    """``cards`` with each PBEAM of one section (no station after end A, or end B = end A) and
    no warping, shear-relief, NSI or neutral-axis terms written as the PBAR of the same beam
    (A, I1, I2, J, NSM, stress points, K1, K2, I12), and each CBEAM on one as a CBAR (the same
    orientation, OFFT, pin flags and offsets W1A-W3B) plus, with lumped mass, the twist inertia
    a CBEAM has and a CBAR has not (``_twist``); the other PBEAMs and CBEAMs stay."""
    bars = {}
    for c in cards:
        if c.name == "PBEAM":
            bar = _pbar(c)
            if bar is not None:
                bars[c.id()] = (c, bar)
    lumped = deck_settings(deck)["coupmass"] < 1
    grids = read_grids(deck, Refusals(deck.path))
    next_id = max((c.id() for c in cards if c.name.startswith(("C", "R"))), default=0) + 1
    out = []
    for c in cards:
        if c.name == "PBEAM" and c.id() in bars:
            c = bars[c.id()][1]
        elif c.name == "CBEAM" and c["PID"] in bars and not any(c.values(16, 18)):
            if lumped:
                twist = _twist(deck, grids, c, bars[c["PID"]][0], next_id)
                out += twist
                next_id += len(twist)
            c = Card("CBAR", tuple(c.raw[:16]), c.file, c.line, c.end)
        out.append(c)
    return out


def _twist(deck, grids, beam: Card, prop: Card, first_id: int) -> list:
    """Two CONM2 (M = 0) at a CBEAM's grids with half its lumped twist inertia each, rho (I1 +
    I2) L n n^T / 2 (n the axis GA-GB, basic), as ``cards.beams`` lumps a CBEAM's and not a
    CBAR's: an inertia with no mass is the same at the grid as at an offset end."""
    mat = deck.table("MAT1").get(prop["MID"])
    rho = 0.0 if mat is None else float(mat["RHO"])
    inertia = rho * (float(prop["I1"]) + float(prop["I2"]))
    if inertia == 0:
        return []
    ends = [beam.int(g, positive=True) for g in ("GA", "GB")]
    x = grids.xyz[grids.index(ends, beam)]
    length = float(np.linalg.norm(x[1] - x[0]))
    n = (x[1] - x[0]) / length
    J = 0.5 * inertia * length * np.outer(n, n)
    fields = [J[0, 0], -J[1, 0], J[1, 1], -J[2, 0], -J[2, 1], J[2, 2]]
    return [Card("CONM2", (str(first_id + k), str(g), "0", "0.", "", "", "", "",
                           *(real16(float(v)) for v in fields)), beam.file, beam.line, beam.end)
            for k, g in enumerate(ends)]  # fmt: skip


def _pbar(card: Card) -> Card | None:
    """The PBAR of a one-section PBEAM without beam-only terms (``_bars``), or None."""
    stations, tail = pbeam_layout(card)
    ends = [[card.value(start + k) for k in range(6)] for start, _, _ in stations]
    if any(row != ends[0] and any(v is not None for v in row) for row in ends[1:]):
        return None  # tapered: a CBEAM's own
    if any(tail[k] for k in tail if k not in ("K1", "K2")):
        return None
    raw = list(card.raw) + [""] * max(0, 16 - len(card.raw))
    a, i1, i2, i12, j, nsm = raw[2:8]
    stress = raw[8:16] if stations[0] and card.value(8) not in ("YES", "YESA", "NO") else [""] * 8
    k = [real16(float(tail["K1"])), real16(float(tail["K2"])), i12]
    return Card("PBAR", (*raw[:2], a, i1, i2, j, nsm, "", *stress, *k), card.file, card.line,
                card.end)  # fmt: skip
