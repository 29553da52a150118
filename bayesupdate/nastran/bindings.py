"""Parameters bound to fields of a Nastran deck: ``binds = "PSHELL 3,5 T"`` in a study file.

A binding is ``"CARD ids FIELD"`` (the parameter is the field's value, in the deck's units) or
``"CARD ids FIELD scale"`` (the parameter is a factor on the deck's values, 1 = the deck).
Several ids share one parameter.  Each binding becomes an ``fe.model`` property on element masks
(``DeckBinding``) with a factor ``c``: the FE model's value = c x the parameter (WTMASS, or
the nominal value of an absolute spring / mass bound as a factor).

==============  =====================  ==========================================
card field      FE property             acts on
==============  =====================  ==========================================
PSHELL T        thickness              its shells (exact powers of t: reduced basis)
MAT1 E          youngs_modulus /       the shells of every PSHELL with that MID1
                modulus_factor (scale)
MAT1 RHO        density                the same shells
CONM2 M         mass_factor            that point mass
CELAS2/4 K      stiffness_factor       that spring
PELAS K         stiffness_factor       the CELAS1 and CELAS3 springs of that property
PBUSH K1-K6     stiffness_factor       the CBUSH springs of that property (its only K)
PBUSH K scale   stiffness_factor       the CBUSH springs of that property (all six)
PBAR A I1 I2 J  line (re-built)        the CBARs of that property (``lines``), also NSM
PBEAM A I1 I2 J line (re-built)        the CBEAMs of that property (every station), NSM
PBARL DIMk      line (re-built)        the CBARs of that property, also NSM
PBEAML DIMk     line (re-built)        the CBEAMs of that property (every station), NSM
PROD A J NSM    line (re-built)        the CRODs of that property
MAT1 E / RHO    (re-built)             also every line element (CONROD too) with that MID
MAT1 G          line (re-built)        the line elements with that MID (not shells)
CBAR/CBEAM      line (card re-built)   those elements: the offsets W1A..W3B
W1A..W3B
CONM2 X1-X3,    line (card re-built)   that mass: offset, inertia (and M with them)
I11..I33
CMASS2 M        line (card re-built)   that scalar mass
==============  =====================  ==========================================

A MAT1 that PSOLIDs use binds their tetrahedra too: E as ``solid_modulus_factor`` (K linear),
RHO as ``solid_density_factor`` (M linear), a value as the factor value / the deck's; on CHEXA
bricks ``hexa_modulus_factor`` and ``hexa_density_factor`` alike.  One MAT1 over several
families (shells, line elements, tetrahedra, bricks) is one parameter: its main property acts
on the shells (or is re-built on the lines, or is the first solid family's), and the solid
factors follow the same value (``DeckBinding.companions``).  Refused: a solid's MAT1 G (a solid
takes E and NU), and a MAT1 that a PTUBE or PSHEAR uses or a PCOMP/PCOMPG takes as a ply
(tubes, shear panels and laminates take no parameter).

Line-element fields act on the bound elements as the reading of the edited deck does
(``lines``): their records (area, I, J, E, G, rho, NSM, lumped end masses), affine in each of
these card fields, are written at each solve and only their matrices are computed again, so
the result is exact whatever the field (A, I, J, E, RHO enter the Euler-Bernoulli matrices
linearly, but the Timoshenko shear parameter 12 EI / (k G A L^2) does not); a field whose
records are not affine (a PBARL's dimensions: A, I are powers of them) re-converts the bound
cards from copies with the value written in.

Fields of the element cards themselves (``FIELDS`` family "card": a CBAR/CBEAM offset, a CONM2
offset or inertia, a CMASS2 M) are written into copies of those cards
(``DeckBinding.relations``: each card, field, C0 and COEF of a DESVAR's DVCREL1 relations, or C0
= 0, COEF = 1 for a study's binding), which are converted again at each solve
(``lines.LineRebuild``): exact, whatever the field does (a CONM2 offset x enters M as m x and m
x^2; a beam offset through the rigid link of its ends, MSC QRG CBEAM). A CONM2 M bound beside
another field of the same CONM2 is written the same way (its mass factor alone would miss the m
x terms).

An absolute binding over several cards sets them all to one value.  When the deck's values of
those cards differ (seven PBEAM I1 of 0.0099-0.0563 in^4 bound as one section), the parameter's
default would be the deck and every other value one section: K would jump at the default, and
an optimizer or a sampler near it would see a discontinuous model.  Such a binding is refused
(``refuse_differing``) with the fix: a ``scale`` (1 = the deck, continuous, the distribution
kept) or one card.  Reading the deck with their mean instead would move the model at the
default off the deck, and with it every command's reference design (the pairing).  A DESVAR's
relations (``nastran.desvar``) are per-id by design and left to their own defaults.
"""

import dataclasses
import re
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran.bulk import CardError, with_fields
from bayesupdate.nastran.cards.laminates import ply_materials

_BAR = ("A", "I1", "I2", "J", "NSM")
_W = ("W1A", "W2A", "W3A", "W1B", "W2B", "W3B")
_DIMS = {f"DIM{k}": ("line", "line") for k in range(1, 11)}
#: card -> {field: (FE property, structure family)}
FIELDS = {
    "PSHELL": {"T": ("thickness", "shell")},
    "MAT1": {
        "E": ("youngs_modulus", "shell"),
        "RHO": ("density", "shell"),
        "G": ("line", "line"),
    },
    "CONM2": {
        "M": ("mass_factor", "mass"),
        **{
            f: ("line", "card")
            for f in ("X1", "X2", "X3", "I11", "I21", "I22", "I31", "I32", "I33")
        },
    },
    "CMASS2": {"M": ("line", "card")},
    "CBAR": {f: ("line", "card") for f in _W},
    "CBEAM": {f: ("line", "card") for f in _W},
    "CELAS2": {"K": ("stiffness_factor", "spring")},
    "CELAS4": {"K": ("stiffness_factor", "spring")},
    "PELAS": {"K": ("stiffness_factor", "spring")},
    "PBUSH": {
        **{f"K{i}": ("stiffness_factor", "spring") for i in range(1, 7)},
        "K": ("stiffness_factor", "spring"),
    },
    "PBAR": {f: ("line", "line") for f in _BAR},
    "PBEAM": {f: ("line", "line") for f in _BAR},
    "PROD": {f: ("line", "line") for f in ("A", "J", "NSM")},
    "PBARL": {**_DIMS, "NSM": ("line", "line")},
    "PBEAML": {**_DIMS, "NSM": ("line", "line")},
}
#: element-card fields (``FIELDS`` family "card": written into the cards themselves,
#: ``relations``, and converted again, ``lines.LineRebuild``) that take any sign: offsets
SIGNED_FIELDS = {"X1", "X2", "X3", "I21", "I31", "I32", *_W}
#: the cards whose own fields are re-built with the point masses (the others: line elements)
MASS_CARDS = ("CONM2", "CMASS2")
#: line properties (their elements are re-built: ``lines``)
LINE_PROPERTIES = ("PBAR", "PBARL", "PBEAM", "PBEAML", "PROD")
#: line elements and the property cards they take
LINE_ELEMENTS = {"CBAR": ("PBAR", "PBARL"), "CBEAM": ("PBEAM", "PBEAML"), "CROD": ("PROD",)}
_SYNTAX = re.compile(r"^\s*([A-Za-z0-9]+)\s+([0-9][0-9,\s]*?)\s+([A-Za-z0-9]+)(\s+scale)?\s*$")


@dataclass(frozen=True)
class DeckField:
    """A parsed binding: card, ids, field (upper case) and whether it is a scale factor."""

    spec: str
    card: str
    ids: tuple[int, ...]
    field: str
    scale: bool


@dataclass(frozen=True)
class DeckBinding:
    """A deck field as an ``fe.model`` binding (the ``Binding`` interface: target, property).

    target : the spec text.  property : the FE property (module table).
    shell, mass, spring : boolean masks over the structure's shells, point masses and springs;
    solid : over its solids, each family's in turn (``solid_families``: tetrahedra, then
    bricks; a MAT1's E or RHO as a factor).  companions : ((property, factor), ...) the solid
    factors a MAT1 that solids share with other elements (or tetrahedra with bricks) sets
    beside ``property``, each to factor x its FE value (``nastran.model``).
    factor : FE value = factor x parameter.  nominal : (n_ids,) the deck's values.
    default : the parameter at the deck's values (nominal, or 1 for a scale).
    coefficient, desvar : a DESVAR's parameter (``desvar``): field = coefficient x parameter.
    lines : ids of the CBAR/CBEAM/CROD elements re-built with the field (``lines``).
    coefficients, offsets : per id (a DESVAR on line-element fields whose relations differ):
    field_i = offsets_i + coefficients_i x parameter (``value_of``); empty: ``coefficient``, 0.
    relations : ((card, id, field, C0, COEF), ...) of an element-card binding (family "card",
    module docstring): each field = C0 + COEF x parameter, written into the card itself.
    """

    target: str
    property: str
    field: DeckField
    shell: np.ndarray
    mass: np.ndarray
    spring: np.ndarray
    factor: float
    nominal: tuple[float, ...]
    default: float
    coefficient: float = 1.0
    desvar: int | None = None
    lines: tuple[int, ...] = ()
    coefficients: tuple[float, ...] = ()
    offsets: tuple[float, ...] = ()
    relations: tuple[tuple[str, int, str, float, float], ...] = ()
    solid: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, bool))
    companions: tuple[tuple[str, float], ...] = ()

    def value_of(self, k: int, value: float) -> float:
        """The card value of id ``field.ids[k]`` at the parameter ``value``: C0_k + COEF_k x
        value for a DESVAR with per-id relations, else coefficient x value."""
        if self.coefficients:
            return self.offsets[k] + self.coefficients[k] * value
        return self.coefficient * value


def parse_binding(text, name: str) -> DeckField:
    """``"PSHELL 3,5 T"`` / ``"MAT1 2 E scale"`` -> ``DeckField``; a one-line error otherwise."""
    m = _SYNTAX.match(str(text))
    where = f"parameter {name}: binds = {text!r}"
    if not m:
        raise BayesUpdateError(f"{where}: give 'CARD ids FIELD' or 'CARD ids FIELD scale'")
    card, field = m.group(1).upper(), m.group(3).upper()
    ids = tuple(int(x) for x in re.split(r"[,\s]+", m.group(2).strip()) if x)
    if card not in FIELDS or field not in FIELDS[card]:
        raise BayesUpdateError(f"{where}: no bindable field {card} {field}; use {_bindable()}")
    if field == "K" and card == "PBUSH" and not m.group(4):
        raise BayesUpdateError(f"{where}: PBUSH K (all six) is a factor: add 'scale'")
    return DeckField(str(text).strip(), card, ids, field, bool(m.group(4)))


def _bindable() -> str:
    return (
        "PSHELL T, MAT1 E/RHO (G: line elements), CONM2 M, CELAS2/CELAS4 K, PELAS K, "
        "PBUSH K1-K6 (or K scale), PBAR/PBEAM A I1 I2 J NSM, PROD A J NSM, "
        "PBARL/PBEAML DIM1-DIM10 NSM, CONM2 X1-X3 I11-I33, CMASS2 M, CBAR/CBEAM W1A-W3B"
    )


def _card(deck, f: DeckField, i: int):
    """The deck's card ``f.card`` with id ``i``; a one-line error when there is none."""
    card = deck.table(f.card).get(i)
    if card is None or card.name != f.card:
        raise BayesUpdateError(f"parameter binds {f.spec!r}: the deck has no {f.card} {i}")
    return card


def _where(card, f: DeckField) -> list[int]:
    """Raw field indices of field ``f`` on ``card`` (a PBEAM(L): end A and every station)."""
    from bayesupdate.nastran.cards import L_DIMS, pbeam_layout

    if f.field.startswith("DIM") or (f.card in ("PBARL", "PBEAML") and f.field == "NSM"):
        kind = str(card["TYPE"])
        n = L_DIMS.get(kind, 0)
        k = n if f.field == "NSM" else int(f.field[3:]) - 1
        if f.field != "NSM" and k >= n:
            raise BayesUpdateError(
                f"parameter binds {f.spec!r}: {f.card} {card.id()} ({kind}) has {n} dimensions"
            )
        out, i = [8 + k], 9 + n
        while f.card == "PBEAML" and i < len(card.raw):  # stations: SO, X/XB, DIMs, NSM
            out.append(i + 2 + k)
            i += 3 + n
        return out
    if f.card == "PBEAM":
        k = ("A", "I1", "I2", "I12", "J", "NSM").index(f.field)
        stations, _ = pbeam_layout(card)
        return [start + k for start, _, _ in stations]
    return [card.position(f.field)]


def field_value(card, f: DeckField) -> float:
    """The deck's value of field ``f`` on ``card`` (PBUSH K scale: the largest K; a PBEAM(L):
    end A)."""
    from bayesupdate.nastran.cards import pbush_k

    try:
        if f.card == "PBUSH":
            k = pbush_k(card)
            return float(k.max() if f.field == "K" else k[int(f.field[1:]) - 1])
        i = _where(card, f)[0]
        v = card.value(i)
        if v is None:
            v = dict(card_defaults(card)).get(i, 0.0)
        return float(v)
    except CardError as exc:
        raise BayesUpdateError(f"parameter binds {f.spec!r}: {exc}") from None


def card_defaults(card) -> dict[int, object]:
    from bayesupdate.nastran.bulk import FIELDS as TABLE

    return {i: d for i, (_, d) in enumerate(TABLE.get(card.name, ())) if d is not None}


def set_field(card, f: DeckField, value: float, nominal: float):
    """``card`` with ``value`` written in (an absolute value, or a factor on ``nominal`` for a
    scale; a PBEAM(L): at every station where it is given; a MAT1 E whose G was blank: G stays
    blank and follows E, as Nastran derives it)."""
    if f.card == "PBUSH":
        starts = [s for s in range(0, len(card.raw), 8) if card.value(s + 1) == "K"]
        if not starts:
            return card
        s = starts[0] + 2
        if f.field == "K":
            given = [k for k in range(6) if card.value(s + k) is not None]
            return with_fields(card, {s + k: float(card.value(s + k)) * value for k in given})
        new = value * nominal if f.scale else value
        return with_fields(card, {s + int(f.field[1:]) - 1: float(new)})
    new = value * nominal if f.scale else value
    where = _where(card, f)
    changes = {where[0]: float(new)}
    # a later PBEAM(L) station given explicitly gets the value too (blank: end A's, QRG)
    changes.update({i: float(new) for i in where[1:] if card.value(i) is not None})
    out = with_fields(card, changes)
    if f.card == "PSHELL" and f.field == "T":
        # Z1/Z2 written as -+T/2 follow the new T (blank ones do so by themselves)
        for z, sign in (("Z1", -0.5), ("Z2", 0.5)):
            old = card[z]
            if isinstance(old, float) and abs(old - sign * nominal) < 1e-12 * abs(nominal):
                out = with_fields(out, {card.position(z): sign * float(new)})
    return out


def resolve(f: DeckField, deck, structure, name: str) -> DeckBinding:
    """The masks, factor and default of field ``f`` on the structure built from ``deck``."""
    cards = [_card(deck, f, i) for i in f.ids]
    nominal = np.array([field_value(c, f) for c in cards])
    prop, family = FIELDS[f.card][f.field]
    masks = _masks(f, deck, structure, cards)
    if family == "card":
        return _card_binding(f, deck, masks, nominal, name)
    lines = line_elements(deck, f)
    if not any(m.any() for m in masks.values()) and not lines:
        raise BayesUpdateError(f"parameter {name}: binds {f.spec!r}: no element uses it")
    wtmass = float(structure.metadata["nastran"]["wtmass"])
    solids = _solid_properties(f, masks["solid"], structure)
    if solids and not masks["shell"].any() and not lines:  # a MAT1 of solids alone
        prop, solids = solids[0], solids[1:]
    relative = prop in ("mass_factor", "stiffness_factor") or _is_solid_factor(prop)
    if prop == "line":  # re-built from the value itself (``lines``)
        factor = 1.0
    elif f.card == "MAT1" and f.field == "E" and f.scale and not relative:
        prop, factor = "modulus_factor", 1.0
    elif relative == f.scale:  # a factor as a factor, or a value as a value
        factor = wtmass if f.field == "RHO" and not relative else 1.0
    else:
        if np.ptp(nominal) > 1e-12 * np.abs(nominal).max() or not nominal[0] > 0:
            raise BayesUpdateError(
                f"parameter {name}: binds {f.spec!r}: the ids' values differ or are 0 "
                f"({nominal.tolist()}); bind them separately"
                + ("" if f.scale else " or as a 'scale'")
            )
        factor = 1.0 / nominal[0] if relative else nominal[0] * (wtmass if f.field == "RHO" else 1)
    # several ids with different values set to one value: the default is their mean
    default = 1.0 if f.scale else float(nominal.mean())
    companions = _solid_companions(f, solids, nominal, factor, name)
    return DeckBinding(
        f.spec, prop, f, masks["shell"], masks["mass"], masks["spring"], float(factor),
        tuple(nominal.tolist()), default, lines=lines, solid=masks["solid"],
        companions=companions,
    )  # fmt: skip


def _is_solid_factor(prop: str) -> bool:
    """Whether ``prop`` is a solid family's factor (``fe.elements.solid.factors``): its FE
    value is a factor, as a point mass's or a spring's."""
    return any(prop in (p.name for p in cls.properties) for cls in solid_families())


def _solid_companions(f: DeckField, props, nominal, factor: float, name: str) -> tuple:
    """((property, factor), ...) of the solid families a MAT1 binding sets beside its main
    property: each solid factor is the parameter (a ``scale``) or the parameter / the deck's
    value, i.e. this factor x the main property's FE value (the parameter x ``factor``)."""
    if not props:
        return ()
    if not f.scale and (np.ptp(nominal) > 1e-12 * np.abs(nominal).max() or not nominal[0] > 0):
        raise BayesUpdateError(
            f"parameter {name}: binds {f.spec!r}: the ids' values differ or are 0 "
            f"({nominal.tolist()}), which the solids' factor cannot follow; bind them "
            "separately or as a 'scale'"
        )
    target = 1.0 if f.scale else 1.0 / nominal[0]
    return tuple((p, float(target / factor)) for p in props)


def _card_binding(f: DeckField, deck, masks, nominal, name: str) -> DeckBinding:
    """An element-card field (``FIELDS`` family "card") as relations C0 = 0, COEF = 1 (a ``scale``:
    COEF = the card's value) on each id; a CMASS2 on a scalar point is refused (its ends are
    not re-built)."""
    if f.card == "CMASS2":
        grids = deck.table("GRID")
        for i in f.ids:
            c = deck.table("CMASS2")[i]
            ends = [c[g] for g in ("G1", "G2") if c.value(c.position(g)) is not None]
            if any(g not in grids for g in ends):
                raise BayesUpdateError(
                    f"parameter {name}: binds {f.spec!r}: CMASS2 {i} ({c.where}) is on a scalar "
                    "point, whose mass cannot be a parameter; bind a CMASS2 between GRIDs"
                )
    relations = tuple((f.card, i, f.field, 0.0, float(n) if f.scale else 1.0)
                      for i, n in zip(f.ids, nominal, strict=True))  # fmt: skip
    lines = f.ids if f.card in LINE_ELEMENTS else ()
    return DeckBinding(
        f.spec, "line", f, masks["shell"], masks["mass"], masks["spring"], 1.0,
        tuple(nominal.tolist()), 1.0 if f.scale else float(nominal.mean()), lines=lines,
        relations=relations,
    )  # fmt: skip


def relation_default(deck, relations) -> float:
    """The parameter x at which ``relations`` ((card, id, field, C0, COEF), ...) give the
    cards' own values: the mean of (value - C0) / COEF (one x when the cards agree)."""
    fields = [(DeckField(f"{c} {i} {f}", c, (i,), f, False), c0, k) for c, i, f, c0, k in relations]
    x = [(field_value(_card(deck, f, f.ids[0]), f) - c0) / k for f, c0, k in fields]
    return float(np.mean(x))


def write_relations(deck, b: DeckBinding, value: float, changed: dict) -> dict:
    """``changed`` ({(card, id): card}) with the element cards of ``b.relations`` given
    C0 + COEF x ``value`` in their fields (copies of the deck's cards where not yet changed)."""
    for card, i, field, c0, coef in b.relations:
        f = DeckField(b.target, card, (i,), field, False)
        old = changed.get((card, i)) or _card(deck, f, i)
        changed[(card, i)] = with_fields(old, {old.position(field): float(c0 + coef * value)})
    return changed


#: the field of a line property's own modulus (``modulus_binding``): not a card field, so not
#: in ``FIELDS`` (a study cannot bind it); discovery's ``stiffness_change`` on a deck's part
OWN_MODULUS = "E"


def is_own_modulus(f: DeckField) -> bool:
    """Whether ``f`` is a line property's own modulus (``modulus_binding``)."""
    return f.card in LINE_PROPERTIES and f.field == OWN_MODULUS


def modulus_binding(part: str, deck, structure) -> DeckBinding:
    """A factor on E and G of the line elements of a property part (``"PBEAM 1003"``: the
    CBEAMs of PBEAM 1003), those elements alone: re-built with their own copy of the property's
    MAT1, E and G (where given) times the factor (``lines.LineRebuild``), so every stiffness of
    theirs (EA, EI, GJ and the shear stiffness k G A) scales by it and their mass does not: the
    ``modulus_factor`` of a built-in model's beams.  K is linear in the factor (the Timoshenko
    shear parameter 12 EI / (k G A L^2) stays), M does not move."""
    card_name, _, pid = part.partition(" ")
    if card_name not in LINE_PROPERTIES or not pid.strip().isdigit():
        raise BayesUpdateError(
            f"stiffness of {part!r}: not a line property part (e.g. 'PBEAM 1003'); the parts with "
            f"line elements are named '<PBAR|PBARL|PBEAM|PBEAML|PROD> <PID>'"
        )
    f = DeckField(f"{part} E scale", card_name, (int(pid),), OWN_MODULUS, True)
    _card(deck, f, int(pid))
    lines = line_elements(deck, f)
    if not lines:
        raise BayesUpdateError(f"stiffness of {part!r}: no element uses it")
    n_shell = 0 if structure.shells is None else structure.shells.n_elements
    zeros = (np.zeros(n_shell, bool), np.zeros(len(structure.mass_part), bool),
             np.zeros(len(structure.spring_part), bool))  # fmt: skip
    return DeckBinding(f.spec, "line", f, *zeros, 1.0, (1.0,), 1.0, lines=lines)


def with_own_material(prop, mats: dict, factor: float) -> tuple:
    """(property card, materials): ``prop`` pointing at its own copy of its MAT1 in ``mats``
    ({MID: card}, completed), that copy's E and G (where given) times ``factor``.  The copy's
    MID is ``_OWN_BASE`` + PID: above any MID a deck can hold (8 digits), one per property."""
    mid = prop.int("MID", positive=True)
    mat = mats.get(mid)
    if mat is None:
        prop.fail(f"material {mid} is not a MAT1 (only MAT1 is supported)")
    own = _OWN_BASE + prop.id()
    # the full repr, not a card's 16 characters: the copy is never written, and its records
    # stay exactly affine in the factor (``lines.line_fields`` checks them to 1e-12)
    changes = {mat.position(k): repr(float(mat.real(k)) * factor)
               for k in ("E", "G") if not mat.is_blank(k)}  # fmt: skip
    mats = dict(mats)
    mats[own] = with_fields(mat, {**changes, 0: own})
    return with_fields(prop, {prop.position("MID"): own}), mats


#: offset of the private MAT1 ids of ``with_own_material`` (beyond any deck's: 8 digits)
_OWN_BASE = 10**8


def line_elements(deck, f: DeckField) -> tuple[int, ...]:
    """Ids of the CBAR/CBEAM/CROD/CONROD elements a binding re-builds: those of its line
    properties, or (MAT1) of every line property or CONROD with that MID."""
    if f.card in LINE_PROPERTIES:
        pids = set(f.ids)
    elif f.card == "MAT1":
        pids = {i for i, p in deck.table(*LINE_PROPERTIES).items() if p["MID"] in f.ids}
    else:
        return ()
    return tuple(sorted(
        e.id() for e in deck.of(*LINE_ELEMENTS, "CONROD")
        if (e.name in LINE_ELEMENTS and e["PID"] in pids)
        or (f.card == "MAT1" and e.name == "CONROD" and e["MID"] in f.ids)
    ))  # fmt: skip


def _masks(f: DeckField, deck, structure, cards) -> dict:
    s = structure
    parts = list(s.parts)
    n_shell = 0 if s.shells is None else s.shells.n_elements
    out = dict(
        shell=np.zeros(n_shell, bool),
        mass=np.zeros(len(s.mass_part), bool),
        spring=np.zeros(len(s.spring_part), bool),
        solid=np.zeros(n_solids(s), bool),
    )
    if f.card in LINE_PROPERTIES or FIELDS[f.card][f.field][1] == "card":
        return out
    if f.card == "MAT1":
        _refuse_unbound_users(f, deck)
        out["solid"] = _solid_mask(f, deck, s)
    if f.card == "MAT1" and f.field == "G":
        _refuse_shell_g(f, deck)
        return out
    if f.card == "MAT1" and f.field == "E":
        _refuse_mixed_shells(f, deck)
    if f.card in ("PSHELL", "MAT1"):
        pids = f.ids if f.card == "PSHELL" else _pshells_of(deck, f)
        names = [parts.index(f"PSHELL {p}") for p in pids if f"PSHELL {p}" in parts]
        if n_shell:
            out["shell"] = np.isin(s.shells.part, names)
        if f.card == "PSHELL":
            _check_uniform_thickness(f, s, out["shell"], cards)
    elif f.card == "CONM2":
        out["mass"] = _part_mask(s.mass_part, parts, [f"CONM2 {i}" for i in f.ids])
    else:
        if f.card in ("CELAS2", "CELAS4"):
            names = [f"{f.card} {i}" for i in f.ids]
        elif f.card == "PELAS":
            names = [f"{e.name} {e.id()}" for e in deck.of("CELAS1", "CELAS3")
                     if e["PID"] in f.ids]  # fmt: skip
        else:
            names = [f"PBUSH {i}" for i in f.ids]
            _check_pbush(f, cards)
        _refuse_scalar_springs(f, s, names)
        out["spring"] = _part_mask(s.spring_part, parts, names)
    return out


def _refuse_scalar_springs(f: DeckField, structure, names) -> None:
    """A CELAS between unlike DOFs is a scalar spring (``fe.elements.scalar_spring``), which no
    binding acts on: refused by name rather than silently left at the deck's K."""
    from bayesupdate.fe.elements.scalar_spring import ScalarSprings

    springs = ScalarSprings.of(structure)
    if springs is None:
        return
    scalar = {structure.parts[p] for p in springs.part}
    hit = [n for n in names if n in scalar]
    if hit:
        raise BayesUpdateError(
            f"parameter binds {f.spec!r}: {', '.join(hit)} join(s) unlike DOFs (a scalar "
            "spring), whose K cannot be a parameter; bind the springs along one axis only"
        )


def _refuse_unbound_users(f: DeckField, deck) -> None:
    """A MAT1 that a PTUBE or PSHEAR uses (no binding re-builds a CTUBE's rod or a CSHEAR),
    that a PCOMP or PCOMPG takes as a ply (a laminate's section is fixed when the deck is read)
    or that a PSOLID uses with G bound (a solid takes E and NU): refused, naming the properties,
    rather than leaving them at the deck's values while the rest changes."""
    unbuilt = [f"{p.name} {i}" for i, p in deck.table("PTUBE", "PSHEAR").items()
             if p["MID"] in f.ids]  # fmt: skip
    laminates = [f"{p.name} {i}" for i, p in deck.table("PCOMP", "PCOMPG").items()
                 if set(ply_materials(p)) & set(f.ids)]  # fmt: skip
    solids = _psolids_of(deck, f)
    why = ""
    if laminates:
        why = (f"{', '.join(laminates)} take(s) that MAT1 as a ply, and a laminate's plies "
               "cannot be parameters; give the other elements a MAT1 of their own")  # fmt: skip
    elif unbuilt:
        why = (f"{', '.join(unbuilt)} use(s) that MAT1, whose tubes and shear panels cannot take "
               "a parameter; give them a MAT1 of their own")  # fmt: skip
    elif solids and f.field == "G":
        why = f"{', '.join(solids)} use(s) that MAT1, and a solid takes E and NU: bind E instead"
    if why:
        raise BayesUpdateError(f"parameter binds {f.spec!r}: {why}")


def solid_families() -> tuple[type, ...]:
    """The registered solid families (``fe.elements.solid.Solids``: tetrahedra, bricks), in
    their registration order, which is the order of a binding's ``solid`` mask."""
    from bayesupdate.fe.elements.base import PARAMETRIC
    from bayesupdate.fe.elements.solid import Solids

    return tuple(cls for cls in PARAMETRIC.values() if issubclass(cls, Solids))


def solid_counts(structure) -> tuple[int, ...]:
    """The number of the structure's elements of each solid family (``solid_families``; 0:
    none)."""
    return tuple(0 if f is None else f.n_elements
                 for f in (cls.of(structure) for cls in solid_families()))  # fmt: skip


def n_solids(structure) -> int:
    """The number of the structure's solids (all families, ``solid_counts``)."""
    return sum(solid_counts(structure))


def solid_part(structure, family: str) -> slice:
    """The part of a ``solid`` mask over the registry ``family``'s elements."""
    names = [cls.family for cls in solid_families()]
    counts = solid_counts(structure)
    start = sum(counts[: names.index(family)])
    return slice(start, start + counts[names.index(family)])


def _solid_mask(f: DeckField, deck, structure) -> np.ndarray:
    """(n_solids,) each solid family's elements in turn (``solid_families``): those of the
    PSOLIDs whose MAT1 is one of ``f.ids``."""
    names = _psolids_of(deck, f)
    parts = list(structure.parts)
    found = (cls.of(structure) for cls in solid_families())
    masks = [_part_mask(e.part, parts, names) for e in found if e is not None]
    return np.concatenate(masks) if masks else np.zeros(0, bool)


def _solid_properties(f: DeckField, solid: np.ndarray, structure) -> list[str]:
    """The factors a MAT1's E or RHO sets on solids (``solid`` their mask): each solid family's
    own (``fe.elements.solid.factors``) where it has elements in the mask (empty: on none)."""
    which = {"E": 0, "RHO": 1}.get(f.field)
    if which is None:
        return []
    return [cls.properties[which].name for cls in solid_families()
            if solid[solid_part(structure, cls.family)].any()]  # fmt: skip


def _psolids_of(deck, f: DeckField) -> list[str]:
    """The part names ("PSOLID pid") of the PSOLIDs whose MAT1 is one of ``f.ids``."""
    return [f"PSOLID {i}" for i, p in deck.table("PSOLID").items() if p["MID"] in f.ids]


def _refuse_shell_g(f: DeckField, deck) -> None:
    """MAT1 G acts on line elements only (beams and rods use E and G; a shell takes E and NU
    here, and its MAT1 G would be left at the deck's value): refused on a shell material."""
    shells = _pshells_of(deck, f)
    if shells:
        raise BayesUpdateError(
            f"parameter binds {f.spec!r}: PSHELL {', '.join(map(str, shells))} use(s) that MAT1, "
            "whose G the shells do not take (they use E and NU); bind MAT1 E instead"
        )


def _refuse_mixed_shells(f: DeckField, deck) -> None:
    """A MAT1 E binding on a PSHELL whose MID2, MID3 or MID4 is another MAT1 (a sandwich, a
    coupled shell): its shells take the bending and shear moduli as ratios to MID1's and the
    coupling as part of their section (``nastran.reader._pshell``), so one E would scale them
    all: refused, naming the PSHELLs."""
    mixed = []
    for i, p in deck.table("PSHELL").items():
        mids = {p["MID1"], p["MID2"], p["MID3"], p["MID4"]} - {None}
        if len(mids) > 1 and mids & set(f.ids):
            mixed.append(i)
    if mixed:
        raise BayesUpdateError(
            f"parameter binds {f.spec!r}: PSHELL {', '.join(map(str, mixed))} take(s) bending or "
            "transverse shear or coupling from another MAT1 than MID1 (MID2/MID3/MID4), which "
            "one E cannot scale"
        )


def _part_mask(part_of, parts, names) -> np.ndarray:
    idx = [parts.index(n) for n in names if n in parts]
    return np.isin(part_of, idx)


def _pshells_of(deck, f: DeckField) -> list[int]:
    """PSHELL ids whose shells' material (``cards.common.pshell_material``) is one of ``f.ids``
    (line properties: ``line_elements``)."""
    from bayesupdate.nastran.cards.common import pshell_material

    return [i for i, p in deck.table("PSHELL").items() if pshell_material(p) in f.ids]


def _check_uniform_thickness(f: DeckField, s, mask, cards) -> None:
    blank = [c.id() for c in cards if c.is_blank("T")]
    if blank:
        raise BayesUpdateError(
            f"parameter binds {f.spec!r}: PSHELL {', '.join(map(str, blank))} has T blank (its "
            "shells' thicknesses are their corners', T1-T4); T cannot be bound"
        )
    t = np.array([c.real("T") for c in cards], float)
    pid_t = dict(zip(f.ids, t, strict=True))
    parts = np.array([pid_t.get(int(s.parts[p].split()[1]), np.nan) for p in s.shells.part[mask]])
    if not np.allclose(s.shells.thickness[mask], parts, rtol=1e-9):
        raise BayesUpdateError(
            f"parameter binds {f.spec!r}: some of its shells have corner thicknesses (T1-T4) "
            "other than T; T cannot be bound"
        )


def _check_pbush(f: DeckField, cards) -> None:
    if f.field == "K":
        return
    j = int(f.field[1:]) - 1
    from bayesupdate.nastran.cards import pbush_k

    for c in cards:
        k = pbush_k(c)
        if any(v != 0 for i, v in enumerate(k) if i != j):
            raise BayesUpdateError(
                f"parameter binds {f.spec!r}: PBUSH {c.id()} has other non-zero K; "
                f"bind 'PBUSH {c.id()} K scale' (all six)"
            )


#: study-table keys of a DESVAR's relations (``nastran.desvar``): not a study's own binding
_DESIGN_KEYS = ("relations", "coefficients", "desvar")


def refuse_differing(parameters: Mapping, deck) -> None:
    """Refuse each absolute binding (no ``scale``) of the study's ``{name: {binds, ...}}``
    tables over several cards whose deck values differ (module docstring), with a one-line
    ``BayesUpdateError`` naming the cards, their spread and the fix.  A DESVAR's relations
    (``_DESIGN_KEYS``) are left as they are."""
    for name, entry in parameters.items():
        if "binds" not in entry or any(k in entry for k in _DESIGN_KEYS):
            continue
        f = parse_binding(entry["binds"], name)
        if f.scale or len(f.ids) < 2:
            continue
        values = np.array([field_value(_card(deck, f, i), f) for i in f.ids])
        if not np.ptp(values) > 1e-12 * np.abs(values).max():
            continue
        ids = ",".join(map(str, f.ids))
        raise BayesUpdateError(
            f"parameter {name}: binds {f.spec!r}: the {len(f.ids)} cards' {f.field} differ "
            f"({values.min():.4g}-{values.max():.4g}), and one value on all would make the model "
            f"jump at its default, the deck; bind '{f.card} {ids} {f.field} scale', or one card"
        )
