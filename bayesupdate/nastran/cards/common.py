"""What the card converters share: the reading context, MAT1, component sets and id lists.

MSC Nastran Quick Reference Guide conventions: components are digits 1-6 in the grid's CD frame
(a grid whose CD frame turns a partial component set gets that frame in the structure,
``fe.frames``); MAT1 is completed from any two of E, G, NU as the QRG's MAT1 remark does
(``mat1``); PARAM COUPMASS < 1 (the default) gives line elements lumped translational mass, half
at each end (``lumped_mass``).  A card that cannot be converted raises ``bulk.CardError``;
``Context.each`` records it and converts the next card, so one read names every refusal.
"""

import re
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.constraints import parse_components
from bayesupdate.fe.frames import CoordinateFrame
from bayesupdate.fe.structure import Material
from bayesupdate.nastran.bulk import CardError
from bayesupdate.nastran.frames import Grids

#: element, property and material cards by family (``Context`` tables)
ELEMENTS = ("CBAR", "CBEAM", "CROD", "CONROD", "CONM2", "CONM1", "CMASS1", "CMASS2", "CMASS3",
            "CMASS4", "CELAS1", "CELAS2", "CELAS3", "CELAS4", "CBUSH", "RBE2", "RBE3", "RBAR",
            "CQUAD4", "CTRIA3", "CTETRA", "CHEXA", "CTUBE", "CSHEAR")  # fmt: skip
PROPERTIES = ("PSHELL", "PCOMP", "PCOMPG", "PBAR", "PBARL", "PBEAM", "PBEAML", "PROD", "PBUSH",
              "PELAS", "PMASS", "PSOLID", "PTUBE", "PSHEAR")  # fmt: skip


@dataclass
class Context:
    """What the card converters share: elements {(card name, id): Card} (elements, masses and
    rigid elements have id spaces of their own), property and material tables ({id: Card}),
    the grids, the structure node of each grid row (-1: not in the structure), WTMASS, lumped
    line mass, the builder, the deck's refusals, notes for the user, the rigid elements' cards;
    the deck's SPOINT cards, its scalar points as element ends ({id: ``scalar.End``}) and the
    scalar masses on them ([(mass, ends)]: ``scalar.rigid_share``); the scalar springs between
    unlike DOFs."""

    elements: dict
    props: dict
    mats: dict
    grids: Grids
    node: np.ndarray
    wtmass: float
    lumped: bool
    builder: object
    refusals: object
    notes: list = field(default_factory=list)
    framed: set = field(default_factory=set)
    #: {"rbe2 i" / "rbe3 i" (the builder's names): the card}, to name cards in its errors
    rigid: dict = field(default_factory=dict)
    spoint_cards: tuple = ()
    spoints: dict = field(default_factory=dict)
    unused_spoints: set = field(default_factory=set)
    spoint_masses: list = field(default_factory=list)
    #: CELAS between unlike DOFs: [(part name, k, End, End or None)] (``springs``,
    #: ``fe.elements.scalar_spring``), added to the built structure (``reader``)
    scalar_springs: list = field(default_factory=list)
    #: functions parts -> (element family or None, parts extended with its part names) that
    #: add what the builder has no call for (the families held in ``Structure.elements``:
    #: scalar springs, solids), run in order on the built structure (``reader``)
    finishers: list = field(default_factory=list)

    @cached_property
    def grids_set(self) -> set:
        """The GRID ids (scalar element ends that are not scalar points)."""
        return set(self.grids.ids.tolist())

    @cached_property
    def in_id_order(self) -> list:
        """The element cards in id order (``_by_id``), sorted once for every family's ``each``."""
        return [card for _, card in sorted(self.elements.items(), key=_by_id)]

    def each(self, names, convert) -> None:
        """``convert(self, card)`` for each element named ``names``, in id order; a refused
        card is recorded and the next one converted."""
        for card in self.in_id_order:
            if card.name in names:
                try:
                    convert(self, card)
                except CardError as exc:
                    self.refusals.add(str(exc))

    def rows(self, card, names) -> np.ndarray:
        return self.grids.index([card.int(n, positive=True) for n in names], card)

    def prop(self, card, kinds) -> object:
        pid = card.int("PID", positive=True)
        p = self.props.get(pid)
        if p is None or p.name not in kinds:
            card.fail(f"property {pid} is not a {' / '.join(kinds)}")
        return p


def _by_id(item) -> tuple:
    """Sort key of an ``elements`` item: its id (a bad id first), then its card name."""
    (name, i), _ = item
    return (i if isinstance(i, int) else -1, name)


def _invariant(mask) -> bool:
    """A component set that is the same in every frame: none or all of 123, none or all of 456."""
    m = np.asarray(mask, bool)
    return bool((m[:3].all() or not m[:3].any()) and (m[3:].all() or not m[3:].any()))


@dataclass(frozen=True)
class Mat1:
    """A completed MAT1: E, G, NU (any two given; QRG MAT1 remark), RHO [deck units]."""

    E: float
    G: float
    NU: float
    RHO: float


def mat1(ctx: Context, mid: int, user) -> Mat1:
    """MAT1 ``mid`` completed from any two of E, G, NU (QRG MAT1: NU = E / 2G - 1, G = E / 2(1 +
    NU), E = 2(1 + NU) G; E alone: G = NU = 0).  A NU outside (-1, 0.5) is kept (beams use E and
    G only) with a note; ``user`` is the card refused when ``mid`` is no MAT1."""
    card = ctx.mats.get(int(mid)) if mid else None
    if card is None:
        user.fail(f"material {mid} is not a MAT1 (only MAT1 is supported)")
    if card.name != "MAT1":
        user.fail(f"material {mid} is a {card.name}, read only as a PCOMP/PCOMPG ply (this "
                  "card needs a MAT1)")  # fmt: skip
    E, G, nu = (None if card.is_blank(k) else card.real(k) for k in ("E", "G", "NU"))
    if E is None and G is not None and nu is not None:
        E = 2 * (1 + nu) * G
    if E is None or not E > 0:
        card.fail("needs E > 0 (or G and NU)")
    if G is None:
        G = 0.0 if nu is None else E / (2 * (1 + nu))
    if nu is None:
        nu = E / (2 * G) - 1 if G else 0.0
    if not -1 < nu < 0.5:
        note = (f"MAT1 {mid} ({card.where}): NU = {nu:.4g} from E and G is outside (-1, 0.5); "
                "kept for beams and rods, which use E and G only")  # fmt: skip
        if note not in ctx.notes:
            ctx.notes.append(note)
    return Mat1(E, G, nu, card.real("RHO"))


def material(ctx: Context, mid: int, user) -> Material:
    """MAT1 ``mid`` as a ``Material`` with density x WTMASS (a NU outside (-1, 0.5) is given as
    0 there: callers pass G itself, ``shear_modulus``)."""
    m = mat1(ctx, mid, user)
    # Material needs a density > 0; a massless MAT1 gets a negligible one
    rho = max(m.RHO * ctx.wtmass, 1e-300)
    nu = m.NU if -1 < m.NU < 0.5 else 0.0
    return Material(m.E, nu, rho, f"MAT1 {mid}")


def _lumped_mass(
    ctx: Context, nodes, mass_per_length, length, part, inertia=None, offsets=None, split=None
):
    """The line mass at each end (node + offset), half each or the fractions ``split`` (2,)
    (a tapered line's first moments), and half the ``inertia`` (3, 3) tensor at each."""
    if mass_per_length > 0:
        J = None if inertia is None else 0.5 * inertia
        off = np.zeros((2, 3)) if offsets is None else offsets
        split = (0.5, 0.5) if split is None else split
        for n, w, share in zip(nodes, off, split, strict=True):
            ctx.builder.add_point_mass(n, share * mass_per_length * length, part, J, w)


def _builder_message(exc) -> str:
    """A builder error without its 'add_beams (part ...): element k' prefix (the card is named
    instead)."""
    return re.sub(r"^element \d+:? ", "", str(exc).split(": ", 1)[-1])


def _pins(e):
    return tuple("" if not e[p] else str(e.int(p)) for p in ("PA", "PB"))


def components(ctx: Context, text, rows, card):
    """Component digits (sorted str) of ``text`` at grids ``rows``.  A partial set (not all of
    123 or of 456) on a grid with a rotated CD frame gives that grid its frame
    (``StructureBuilder.set_frame``): the components then act in the CD axes, exactly."""
    try:
        mask = parse_components(str(text), card.label)
    except BayesUpdateError as exc:
        card.fail(str(exc).split(": ", 1)[-1])
    frame_partial(ctx, mask, rows)
    return "".join(str(i + 1) for i in np.flatnonzero(mask))


def pshell_material(p):
    """The MAT1 id whose E, NU and RHO a PSHELL's shells take: MID1, or MID2 where MID1 is
    blank (a bending panel; MSC QRG PSHELL remark 2)."""
    return p["MID2"] if p["MID1"] is None else p["MID1"]


def frame_partial(ctx: Context, mask, rows) -> None:
    """Give each grid of ``rows`` with a rotated CD frame that frame in the structure
    (``StructureBuilder.set_frame``) where the component ``mask`` (6,) is a partial set, so
    that the components act in the CD axes."""
    if _invariant(mask):
        return
    for row in np.atleast_1d(rows):
        if not ctx.grids.is_basic([row])[0] and row not in ctx.framed:
            xyz = ctx.grids.xyz[row]
            frame = CoordinateFrame.from_axes("rectangular", xyz, ctx.grids.frame[row])
            ctx.builder.set_frame(int(ctx.node[row]), frame)
            ctx.framed.add(int(row))


def id_list(card, start: int) -> list[int]:
    """Integers of ``card`` from raw field ``start`` on, 'THRU' ranges expanded (blank fields
    skipped; a real, e.g. RBE2's ALPHA, ends the list)."""
    out, values, k = [], card.values(start), 0
    while k < len(values):
        v = values[k]
        if v == "THRU" and out and k + 1 < len(values) and isinstance(values[k + 1], int):
            out += range(out[-1] + 1, values[k + 1] + 1)
            k += 2
            continue
        if isinstance(v, float):
            break
        if isinstance(v, int):
            out.append(v)
        elif v is not None:
            card.fail(f"field {v!r}: give grid ids (THRU allowed)")
        k += 1
    return out
