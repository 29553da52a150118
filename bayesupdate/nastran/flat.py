"""A deck written as one file of large-field cards, for readers stricter than MSC Nastran
(MYSTRAN): the same model, in the subset of the format every reader takes.

MYSTRAN 18 refuses the mAEWing1 decks as published (``benchmarks/deck_solve.py``): first for
format (tab characters inside fields: its reader takes a tab as a character, "TOO LONG AN
ENTRY", an integer with 15 digits; a PBEAM with no end-B station: "MUST BE YES, YESA OR NO",
and a one-line PBEAM "REQUIRED CONTINUATION ... MISSING"), then, with those fixed, for the
model: a grounded CBUSH stops it (ELMGM1_BUSH), and it has no CBEAM element ("CODE NOT WRITTEN
FOR BEAM ELEMENT MATRICES AS YET").  The flat deck makes these edits.  Edits 1-3 leave the
model as MSC reads it (to the 16-character rounding); edits 4-9 (``mystran=True``) write the
deck so that MYSTRAN computes the model MSC reads from the original, and MSC (or this
package) would read the CONM2 of edit 6 differently:

1. the executive and case control are copied (tabs expanded); ``INCLUDE``d files are read in
   (``deck.read_deck``: case-insensitive names);
2. every bulk card is written from its parsed fields as large-field lines
   (``bulk.large_field_text``: 16-character fields, no tabs, no continuation markers); a real
   this module computes is written with a decimal point ("5.e-06": MYSTRAN refuses "5e-06",
   "NO DECIMAL POINT WAS FOUND");
3. a PBEAM of one section (no end-B station: end B is end A, QRG PBEAM) without warping, NSI,
   shear-relief or neutral-axis terms is the PBAR of the same beam (A, I1, I2, I12, J, NSM,
   and K1, K2, whose PBEAM default 1.0 is written: a PBAR's blank K is shear-rigid), and a
   CBEAM on it the CBAR with the same orientation, OFFT, pin flags and offsets (QRG CBAR,
   CBEAM: the same fields 2-17); with lumped mass (COUPMASS < 1) a CBEAM's lumped twist
   inertia rho (I1 + I2) L / 2 about its axis at each end, which a CBAR has not
   (``cards.beams``), is written as two massless CONM2 (3.4 % on v3.3's mode 3 without them;
   ``_twist``: the diagonal raised where rounding leaves it indefinite, ``_rounded_psd``);
4. (``mystran=True``) a grounded CBUSH (GB blank: MYSTRAN 18 stops in
   ELMGM1_BUSH, "Index '0' of dimension 1 of array 'grid'"; it refuses a grounded CELAS2 too,
   "INVALID COMPONENT NUMBER = 0 IN FIELD 7") gets a GB of its own, a new GRID at GA's place
   held by its PS field 123456 (QRG CBUSH remark 6: a grounded terminal is a point constrained
   to zero, so MSC reads the same model).  This reader takes a fully held GRID as a support, so
   that with SUPORT it finds no free rigid motion: it reads the deck written with
   ``mystran=False`` (edits 4 to 9 left out) instead;
5. (``mystran=True``) SUPORT is dropped: MYSTRAN computes the elastic modes of the structure
   held at the SUPORT DOFs (its L-set with the R-set removed: on mAEWing1 v3.3 the two wings
   then vibrate apart, in pairs from 3.70 Hz), where MSC gives those of the free structure
   and SUPORT only names its rigid modes; without it the soft suspension springs give six
   modes near 0 Hz, and the elastic modes follow;
6. (``mystran=True``) every CONM2 is written with CID 0, its offset in basic axes, and inertia
   fields that give MSC's rotary inertia in MYSTRAN (``mystran_conm2_fields``).  MYSTRAN 18
   negates the product fields when it assembles the 6x6 (``MGGC_MASS_MATRIX``, as MSC, QRG
   CONM2: [[I11, -I21, -I31], [-I21, I22, -I32], [-I31, -I32, I33]]), but before that it
   rotates the fields from CID to basic (``CONM2_PROC_1``), moves them from the centre of
   gravity to the grid (``CONM2_PROC_2``: I21 - m dy dx) and rotates them to the grid's CD
   axes as if they were the tensor's own off-diagonal terms.  A CONM2 with principal inertias
   in a rotated CID then gets products of the wrong sign, and an offset with two non-zero
   components a parallel-axis product of the wrong sign: one grid, translations held, springs
   k on its rotations, a CONM2 with principal inertias (1, 2, 3) in a CID whose z axis is
   (1, 1, 1)/sqrt 3 gives omega^2 = k (1, 1/2, 1/3) (MSC, this package), MYSTRAN k (1.142,
   0.4286, 0.3583); M = 2 at offset (.5, .5, .5), J = I: k (1, 0.4, 0.4), MYSTRAN k (0.667,
   0.667, 0.333) (``tests/test_flat_mystran.py``).  On mAEWing1 v3.3 (control-surface and
   flap masses in the hinge-line CORD2Rs 101-202) this is MYSTRAN's -32 % to +21 % on modes
   7-11: the CID rotation nearly all of it, the offset products up to 0.08 %;
7. (``mystran=True``, before edit 6) a grounded CMASS2 (G2 blank) on a GRID's rotation 4, 5
   or 6 is a massless CONM2 with that inertia about the CD axis (MSC QRG CMASS2: a scalar
   mass on that DOF): MYSTRAN 18 stops on v4.2's twelve in its mass assembly, "Index '949' of
   dimension 1 of array 'j_mgg' above upper bound of 948";
8. (``mystran=True``, a deck with SUPORT: a free structure) EIGR is written as EIGRL (V1 = F1
   where positive, V2 = F2, ND): MYSTRAN's GIV factors KLL by Cholesky (LAPACK DPBSTF), which
   a free structure without suspension springs (v4.2, v4.2.1) stops once SUPORT is dropped
   ("*ERROR 989: THE FACTORIZATION OF THE MATRIX KLL COULD NOT BE COMPLETED"); its Lanczos
   takes it, with the same modes (v3.3: GIV and Lanczos within 3e-7 of the f06).  A deck
   without SUPORT keeps its EIGR (MYSTRAN's Lanczos wants more DOFs than modes);
9. (``mystran=True``) a CBAR whose OFFT is not GGG (v in basic, an offset in basic or in the
   element's axes, QRG CBAR) is written as GGG with the same v and offsets in the grids' CD
   frames: MYSTRAN 18 reads no OFFT (its BD_CBAR takes field 9 as blank) and so took a GOO
   bar's element-axis offsets as CD-frame ones (0.24-0.91 % on a skew tip-mass cantilever's
   modes, ``tests/test_flat_mystran.py``);
10. ``ENDDATA`` closes the file.
"""

from pathlib import Path

import numpy as np

from bayesupdate.nastran.bulk import Card, large_field_text, parse_number, real16, with_fields
from bayesupdate.nastran.cards.beams import in_grid_frames, pbeam_layout
from bayesupdate.nastran.cards.masses import conm2_inertia
from bayesupdate.nastran.deck import Refusals, read_deck
from bayesupdate.nastran.frames import coordinate, read_grids
from bayesupdate.nastran.reader import deck_settings

#: the edits ``write_flat_deck`` makes (module docstring), for reports
EDITS = (
    "INCLUDE files read in, one file",
    "every bulk card in large-field format (no tabs, no continuation markers)",
    "PBEAM of one section -> PBAR (K1, K2 written), CBEAM on it -> CBAR + 2 CONM2 (twist)",
    "grounded CBUSH: GB a new GRID at GA's place with PS 123456 (for MYSTRAN)",
    "SUPORT dropped (for MYSTRAN: it solves the elastic modes held at the SUPORT DOFs)",
    "CONM2 in CID 0, basic offset, inertia fields for MYSTRAN's product convention (for MYSTRAN)",
    "grounded CMASS2 on a rotation -> massless CONM2 (for MYSTRAN)",
    "EIGR -> EIGRL where the deck has SUPORT (for MYSTRAN: its GIV needs a held structure)",
    "CBAR OFFT other than GGG -> GGG, v and offsets in the grids' CD frames (for MYSTRAN)",
    "ENDDATA appended",
)


def write_flat_deck(path, out, mystran: bool = False) -> Path:
    """Write the deck at ``path`` as one large-field file ``out`` (module docstring; edits 4
    to 9 only with ``mystran``); returns ``out``."""
    deck = read_deck(path)
    head = []
    for line in Path(deck.files[0]).read_text(errors="replace").splitlines():
        head.append(line.expandtabs(8))
        if line.strip().upper().startswith("BEGIN BULK"):
            break
    cards = _bars(deck, list(deck.cards))
    if mystran:
        cards = [c for c in _ground_grids(deck, cards) if c.name not in ("SUPORT", "SUPORT1")]
        grids = read_grids(deck, Refusals(deck.path))
        free = any(c.name in ("SUPORT", "SUPORT1") for c in deck.cards)
        cards = [_rotary_cmass2(grids, _eigrl(c) if free else c) for c in cards]
        cards = [_conm2_basic(grids, c) if c.name == "CONM2" else c for c in cards]
        cards = [_bar_ggg(grids, c) if c.name == "CBAR" else c for c in cards]
    cards = [large_field_text(c) for c in cards]
    out = Path(out)
    out.write_text("\n".join(head) + "\n" + "".join(cards) + "ENDDATA\n")
    return out


def mystran_conm2_fields(mass: float, offset, inertia, frame) -> np.ndarray:
    """The CONM2 inertia fields (3, 3) that make MYSTRAN 18 build a given rotary inertia at a
    grid, for a CONM2 written with CID 0 and X1-X3 = ``offset`` (module docstring, edit 6).

    MYSTRAN assembles a CONM2 with its product fields negated, as MSC does (M(4,5) = -I21,
    M(4,6) = -I31, M(5,6) = -I32: MYSTRAN source ``Source/LK1/L1E/MGGC_MASS_MATRIX.f90`` line
    233), but first rotates the fields from CID to basic (``Source/LK1/L1C/CONM2_PROC_1.f90``
    lines 173-248), moves them to the grid (``CONM2_PROC_2.f90`` line 132: I21 - m dy dx) and
    rotates them to the grid's CD frame (lines 216-220) as if they were the tensor's own
    off-diagonal terms (unchanged from release 17.0.0 to the 2026 source; MYSTRAN 18 computes
    what they say, ``tests/test_flat_mystran.py``).  With N(X) = 2 diag(X) - X (the
    off-diagonal terms negated) its rotation block is N(R (A + S) R^T) for fields A (CID 0),
    S = m (|d|^2 I - d d^T); the fields that give J_G = R (J + S) R^T are A = R^T N(J_G) R - S.

    Parameters
    ----------
    mass : the CONM2's M [deck mass units] (WTMASS applies to every term alike: not here)
    offset : (3,) d, from the grid to the centre of gravity, basic axes [deck length]
    inertia : (3, 3) J, the inertia tensor about the centre of gravity, basic axes (MSC QRG
        CONM2: [[I11, -I21, -I31], [-I21, I22, -I32], [-I31, -I32, I33]] in CID, rotated)
    frame : (3, 3) R, rows = the grid's CD axes in basic

    Returns
    -------
    (3, 3) A, symmetric: write I11 = A[0, 0], I21 = A[1, 0], I22 = A[1, 1], I31 = A[2, 0],
    I32 = A[2, 1], I33 = A[2, 2]
    """
    d = np.asarray(offset, dtype=float)
    R = np.asarray(frame, dtype=float)
    S = mass * (d @ d * np.eye(3) - np.outer(d, d))
    J_G = R @ (np.asarray(inertia, dtype=float) + S) @ R.T
    N = 2 * np.diag(np.diag(J_G)) - J_G
    return R.T @ N @ R - S


def _real(value: float) -> str:
    """``real16`` with a decimal point always ('5e-06' -> '5.e-06'; module docstring, edit 2)."""
    text = real16(value)
    if "." in text:
        return text
    mantissa, e, exponent = text.partition("e")
    return f"{mantissa}.{e}{exponent}"


def _rotary_cmass2(grids, card: Card) -> Card:
    """A grounded CMASS2 on a GRID rotation as the massless CONM2 (CID 0, basic axes) with its
    inertia M e e^T about that CD axis e (module docstring, edit 7); any other card as it is."""
    if card.name != "CMASS2" or card["G2"] not in (None, 0) or card["C1"] not in (4, 5, 6):
        return card
    if not np.any(grids.ids == card.int("G1")):
        return card  # a scalar point: no rotation
    row = int(grids.index([card.int("G1")], card)[0])
    e = grids.frame[row][card.int("C1") - 4]
    J = card.real("M") * np.outer(e, e)
    fields = [_real(float(v)) for v in (J[0, 0], -J[1, 0], J[1, 1], -J[2, 0], -J[2, 1], J[2, 2])]
    raw = (card.raw[0], str(card.int("G1")), "0", "0.", "", "", "", "", *fields)
    return Card("CONM2", raw, card.file, card.line, card.end)


def _eigrl(card: Card) -> Card:
    """An EIGR as the EIGRL of the same range and number of modes (module docstring, edit 8)."""
    if card.name != "EIGR":
        return card
    f1, f2, nd = card["F1"], card["F2"], card["ND"]
    v1 = _real(float(f1)) if f1 is not None and float(f1) > 0 else ""
    v2 = "" if f2 is None else _real(float(f2))
    return Card("EIGRL", (card.raw[0], v1, v2, "" if nd is None else str(nd)), card.file,
                card.line, card.end)  # fmt: skip


def _conm2_basic(grids, card: Card) -> Card:
    """One CONM2 written with CID 0, its offset in basic axes and the inertia fields
    ``mystran_conm2_fields`` gives (module docstring, edit 6); MSC QRG CONM2: X1-X3 offsets and
    Iij in CID, or with CID -1 the centre's basic coordinates and basic axes."""
    row = int(grids.index([card.int("G", positive=True)], card)[0])
    cid = card.int("CID")
    axes = np.eye(3)
    if cid > 0:
        coord = coordinate(grids, cid, card)
        if coord.kind != "rectangular":
            card.fail(f"CID {cid} is not rectangular")
        axes = coord.axes
    x = np.array([card.real(k) for k in ("X1", "X2", "X3")])
    offset = x - grids.xyz[row] if cid == -1 else axes.T @ x
    J = conm2_inertia([card.real(k) for k in ("I11", "I21", "I22", "I31", "I32", "I33")])
    A = mystran_conm2_fields(card.real("M"), offset, axes.T @ J @ axes, grids.frame[row])
    fields = [_real(float(v)) for v in (A[0, 0], A[1, 0], A[1, 1], A[2, 0], A[2, 1], A[2, 2])]
    head = (card.raw[0], str(card.int("G")), "0", _real(card.real("M")))
    raw = (*head, *(_real(float(v)) for v in offset), "", *fields)
    return Card("CONM2", raw, card.file, card.line, card.end)


def _bar_ggg(grids, card: Card) -> Card:
    """A CBAR with an OFFT other than GGG written as GGG: X1-X3 in GA's CD frame, each offset
    in its grid's CD frame (``cards.beams.in_grid_frames``), field 9 blank (edit 9: MYSTRAN 18
    reads no OFFT and takes every offset in its grid's CD frame)."""
    if card["OFFT"] in (None, "GGG"):
        return card
    v, w = in_grid_frames(grids, card)
    changes = {7: None} | {10 + k: float(x) for k, x in enumerate(w.ravel())}
    if v is not None:
        changes |= {4 + k: float(x) for k, x in enumerate(v)}
    return with_fields(card, changes)


def _ground_grids(deck, cards: list) -> list:
    """``cards`` with each grounded CBUSH given a GB of its own (module docstring, edit 4): a
    new GRID at GA's place held by PS 123456 (ids after the deck's largest)."""
    grids = read_grids(deck, Refusals(deck.path))
    next_grid = int(grids.ids.max()) + 1 if len(grids.ids) else 1
    out = []
    for c in cards:
        if c.name == "CBUSH" and not c["GB"]:
            row = int(grids.index([c.int("GA", positive=True)], c)[0])
            xyz = [_real(float(v)) for v in grids.xyz[row]]
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
    orientation, OFFT (blank for a BIT, which an ordinary CBEAM ignores), pin flags and offsets
    W1A-W3B) plus, with lumped mass, the twist inertia a CBEAM has and a CBAR has not
    (``_twist``); the other PBEAMs and CBEAMs stay."""
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
            raw = list(c.raw[:16])
            if isinstance(c["OFFT"], float):  # a CBEAM's BIT, which a CBAR has no field for
                raw[7] = ""
            c = Card("CBAR", tuple(raw), c.file, c.line, c.end)
        out.append(c)
    return out


def _twist(deck, grids, beam: Card, prop: Card, first_id: int) -> list:
    """Two CONM2 (M = 0) at a CBEAM's grids with half its lumped twist inertia each, rho (I1 +
    I2) L n n^T / 2 (n the axis GA-GB, basic), as ``cards.beams`` lumps a CBEAM's and not a
    CBAR's: an inertia with no mass is the same at the grid as at an offset end.  A 16-character
    field rounds a term by up to 5e-13 of it, which can leave the rank-one n n^T with a negative
    eigenvalue (v4.2's CBEAMs 2000055, 2000056: -7.8e-16 of 7.8e-4, refused by
    ``cards.masses``): only there is twice that eigenvalue added on the diagonal
    (``_rounded_psd``), so a deck whose fields round harmlessly is written exactly."""
    mat = deck.table("MAT1").get(prop["MID"])
    rho = 0.0 if mat is None else float(mat["RHO"])
    inertia = rho * (float(prop["I1"]) + float(prop["I2"]))
    if inertia == 0:
        return []
    ends = [beam.int(g, positive=True) for g in ("GA", "GB")]
    x = grids.xyz[grids.index(ends, beam)]
    length = float(np.linalg.norm(x[1] - x[0]))
    n = (x[1] - x[0]) / length
    fields = _rounded_psd(0.5 * inertia * length * np.outer(n, n))
    return [Card("CONM2", (str(first_id + k), str(g), "0", "0.", "", "", "", "", *fields),
                 beam.file, beam.line, beam.end)
            for k, g in enumerate(ends)]  # fmt: skip


def _conm2_inertia_fields(J: np.ndarray) -> list[str]:
    """The six CONM2 inertia fields (I11, I21, I22, I31, I32, I33) of the (3, 3) inertia J
    (MSC QRG CONM2: products entered negated), each as a 16-character real."""
    return [_real(float(v)) for v in (J[0, 0], -J[1, 0], J[1, 1], -J[2, 0], -J[2, 1], J[2, 2])]


def _rounded_psd(J: np.ndarray) -> list[str]:
    """CONM2 inertia fields of the PSD (3, 3) J that read back PSD: where the rounded fields
    have a negative eigenvalue, twice its size is added on J's diagonal and they are rounded
    again."""
    fields = _conm2_inertia_fields(J)
    low = np.linalg.eigvalsh(conm2_inertia(parse_number(f) for f in fields))[0]
    if low >= 0:
        return fields
    return _conm2_inertia_fields(J - 2 * low * np.eye(3))


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
    k = [_real(float(tail["K1"])), _real(float(tail["K2"])), i12]
    return Card("PBAR", (*raw[:2], a, i1, i2, j, nsm, "", *stress, *k), card.file, card.line,
                card.end)  # fmt: skip
