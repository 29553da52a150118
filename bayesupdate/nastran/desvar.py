"""A deck's design variables as parameters: DESVAR + DVPREL1 / DVMREL1 / DVCREL1 (``x`` -> field).

Used when the study names no parameters.  A relation sets ``field = C0 + sum(COEF_i x_i)`` (MSC
QRG DVPREL1, DVMREL1, DVCREL1); a DESVAR becomes a parameter named by its label, in its own
units, when every relation using it is the linear form (one DESVAR, C0 = 0) on a field
``bindings`` can bind and all set the same card type and field with the same COEF (several ids
are one binding, ``"PSHELL 3,5 T"``), or when all its relations (one DESVAR each) set the same
line-element field of distinct cards with any C0_i and COEF_i (PBAR/PBEAM/PROD/PBARL/PBEAML
fields, MAT1 G: re-built from the cards, ``lines``; ``DeckBinding.value_of``); the other
DESVARs are listed in a note.  Bounds are XLB,
XUB (a bound at Nastran's +-1e20 default, or a lower bound <= 0, takes ``model.DEFAULT_RANGE``
of the deck's value instead).  The parameter's default is the card's value / COEF, which may
differ from XINIT (``xinit_values``).

Every relation, bindable or not (CBEAM offsets W1A-W3B, CONM2 X1-X3 and I11-I33, CMASS2 M,
several COEFs for one DESVAR), is evaluated by ``design_cards``: the deck's cards with
``C0 + sum(COEF_i x_i)`` written into each related field (bounded by the relation's PMIN / PMAX
where the card gives them), which ``writer.write_design_deck`` writes as a deck: the model at
any DESVAR values as SOL 200 builds it, by reading the cards again (no fast path).
"""

import re

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran.bulk import CardError, with_fields

#: DVPREL1 field numbers of the bindable fields (MSC QRG: PSHELL T is field 4, PELAS K 3,
#: PBAR A I1 I2 J NSM 4-8, PROD A J 4-5); names (PNAME) are read as they are
_FIELD_NUMBER = {
    ("PSHELL", 4): "T", ("PELAS", 3): "K", ("CONM2", 4): "M",
    **{("PBAR", 4 + k): f for k, f in enumerate(("A", "I1", "I2", "J", "NSM"))},
    ("PROD", 4): "A", ("PROD", 5): "J",
}  # fmt: skip
_NO_BOUND = 1e19
#: a PBEAM / PBEAML property name of one station: "A(A)", "I1(B)", "DIM2(B)" (MSC QRG DVPREL1)
_STATION = re.compile(r"^([A-Z0-9]+)\((A|B|\d+)\)$")


def _station(ptype, name) -> tuple[object, str | None]:
    """(field name, station "A" / "B" / "1".. or None) of a relation's PNAME: a PBEAM(L)'s name
    with its station in parentheses; a bare name is end A's field (MSC QRG DVPREL1)."""
    m = _STATION.match(name.upper()) if isinstance(name, str) else None
    if m and ptype in ("PBEAM", "PBEAML"):
        return m.group(1), m.group(2)
    return name, None


def _relation(rel) -> tuple[str, object, float, list[tuple[int, float]]]:
    """(TYPE, field name or number, C0, [(DVID, COEF)]) of a DVPREL1 / DVMREL1 / DVCREL1 (one
    layout: ID TYPE id NAME MIN MAX C0, then DVIDi COEFi pairs from the first continuation)."""
    pairs, values = [], rel.values(8)
    for k in range(0, len(values) - 1, 2):
        if values[k] is not None:
            pairs.append((int(values[k]), float(values[k + 1] or 0.0)))
    return str(rel.value(1)), rel.value(3), float(rel.value(6) or 0.0), pairs


def _field(rel, ptype, name):
    """The bindable field name of a relation, or None (a DVPREL1 field number: QRG table)."""
    from bayesupdate.nastran.bindings import FIELDS

    if not isinstance(name, str):
        name = _FIELD_NUMBER.get((ptype, int(name or 0))) if rel.name == "DVPREL1" else None
    if _station(ptype, name)[1] is not None:  # one station: a binding sets every station
        return None
    return name.upper() if name and name.upper() in FIELDS.get(ptype, {}) else None


def design_refusals(deck) -> list[str]:
    """'file:line DVPREL1 id: ...' of each DVPREL1 to a field that cannot be bound (the reader
    adds them to the deck's other refusals when the DESVARs are to be the parameters); one
    station of a PBEAM(L) field ("A(B)") is not refused (its DESVAR stays out, with a note)."""
    from bayesupdate.nastran.bindings import FIELDS

    out = []
    for rel in deck.of("DVPREL1"):
        ptype, name, _, _ = _relation(rel)
        base, station = _station(ptype, name)
        if station is not None and str(base) in FIELDS.get(ptype, {}):
            continue  # one station of a PBEAM(L): read and written, not a parameter
        if _field(rel, ptype, name) is None:
            out.append(f"{rel.where} DVPREL1 {rel.value(0)}: {ptype} field {name} cannot be bound")
    return out


def desvar_parameters(deck, strict: bool = True) -> dict:
    """{label: {"binds", "bounds" (optional), "coefficient" or "coefficients" and "offsets",
    "desvar"}} of the DESVARs that are one binding: every relation (DVPREL1, DVMREL1, DVCREL1)
    sets one bindable field as COEF x (C0 = 0, one DESVAR, one COEF), one binding over their
    ids; or every relation sets the same line-element field (PBAR/PBEAM/PROD/... fields, MAT1
    G: re-built, ``lines``) of distinct cards as C0_i + COEF_i x.  With ``strict`` a DVPREL1 to
    a field that cannot be bound is refused (all of them in one message); without, its DESVAR
    is left out like the other DESVARs, which ``unbound_note`` lists."""
    refused = design_refusals(deck) if strict else []
    if refused:
        raise BayesUpdateError(f"{len(refused)} design relation(s) refused: " + "; ".join(refused))
    relations = {}
    for rel in deck.of("DVPREL1", "DVMREL1", "DVCREL1"):
        ptype, name, c0, pairs = _relation(rel)
        field = _field(rel, ptype, name)
        if field is not None and _stations_given(deck, ptype, rel.value(2), field):
            field = None  # the relation sets end A alone; a binding sets every station
        for dvid, coef in pairs:
            one = field is not None and len(pairs) == 1
            relations.setdefault(dvid, []).append(
                ((ptype, field) if one else None, coef, c0, int(rel.value(2)))
            )
    desvars = deck.table("DESVAR")
    shape = _shape_variables(deck)
    out = {}
    for dvid, rels in sorted(relations.items()):
        if dvid in shape:
            continue  # it moves GRIDs too (DVGRID), which no binding does
        if any(k is not None and _family(k) == "card" for k, *_ in rels):
            entry = _card_relations(rels)
        else:
            entry = _one_binding(rels) or _line_combination(rels) or _card_relations(rels)
        if entry is not None and dvid in desvars:
            out[dvid] = entry
    return {_name(desvars, d, out): _entry(desvars, d, e) for d, e in out.items()}


def _stations_given(deck, ptype, pid, field) -> bool:
    """True if PBEAM(L) ``pid`` gives ``field`` explicitly at a station after end A (a bare
    PNAME sets end A alone there, MSC QRG DVPREL1; a binding writes every station)."""
    from bayesupdate.nastran.bindings import DeckField, _where

    card = deck.table(ptype).get(pid) if ptype in ("PBEAM", "PBEAML") else None
    if card is None or card.name != ptype:
        return False
    where = _where(card, DeckField(f"{ptype} {pid} {field}", ptype, (pid,), field, False))
    return any(card.value(i) is not None for i in where[1:])


def _one_binding(rels) -> dict | None:
    """{"binds", "coefficient"} when every relation is one bindable field x one COEF, C0 = 0."""
    keys = {(k, coef) for k, coef, c0, _ in rels if k is not None and c0 == 0}
    if len(keys) != 1 or len(keys) != len({(k, coef, c0) for k, coef, c0, _ in rels}):
        return None
    (card, field), coef = keys.pop()
    ids = sorted({i for *_, i in rels})
    return {"binds": f"{card} {','.join(map(str, ids))} {field}", "coefficient": coef}


def _line_combination(rels) -> dict | None:
    """{"binds", "coefficients", "offsets"} when every relation sets the same line-element
    field (re-built from the cards: any C0 and COEF) of distinct cards."""
    from bayesupdate.nastran.bindings import FIELDS

    keys = {k for k, *_ in rels}
    ids = [i for *_, i in rels]
    if len(keys) != 1 or None in keys or len(set(ids)) != len(ids):
        return None
    card, field = keys.pop()
    if FIELDS[card][field] != ("line", "line") or any(coef == 0 for _, coef, _, _ in rels):
        return None
    rels = sorted(rels, key=lambda r: r[3])
    return {
        "binds": f"{card} {','.join(str(r[3]) for r in rels)} {field}",
        "coefficients": [r[1] for r in rels],
        "offsets": [r[2] for r in rels],
    }


def _family(key) -> str:
    from bayesupdate.nastran.bindings import FIELDS

    return FIELDS[key[0]][key[1]][1]


def _card_relations(rels) -> dict | None:
    """{"binds", "relations"} when every relation sets a field of the element cards
    themselves (``bindings.FIELDS`` family "card": CBAR/CBEAM offsets, CONM2 offset, inertia and M,
    CMASS2 M), one DESVAR each, of one card type, each (card, field) once: C0_i + COEF_i x is
    written into each card, which is converted again (``lines.LineRebuild``)."""
    keys = {k for k, *_ in rels}
    if None in keys or len({c for c, _ in keys}) != 1:
        return None
    card = next(iter(keys))[0]
    if any(_family(k) != "card" and k != ("CONM2", "M") for k in keys):
        return None
    targets = [(i, k[1]) for k, _, _, i in rels]
    if len(set(targets)) != len(targets) or any(coef == 0 for _, coef, _, _ in rels):
        return None
    rels = sorted(rels, key=lambda r: (r[3], r[0][1]))
    ids = list(dict.fromkeys(r[3] for r in rels))
    return {
        "binds": f"{card} {','.join(map(str, ids))} {rels[0][0][1]}",
        "relations": [[card, r[3], r[0][1], r[2], r[1]] for r in rels],
    }


def _label(desvars, d) -> str:
    card = desvars.get(d)
    label = "" if card is None else str(card["LABEL"] or "").strip()
    return label or f"desvar_{d}"


def _name(desvars, desvar_id, taken) -> str:
    label = _label(desvars, desvar_id)
    labels = [_label(desvars, d) for d in taken]
    return label if labels.count(label) == 1 else f"{label}_{desvar_id}"


def _entry(desvars, desvar_id, entry: dict) -> dict:
    """The parameter's table: the DESVAR's XLB, XUB as its bounds where they are finite and
    fit the field (> 0; an element card's inertia or mass >= 0, its offset any sign)."""
    from bayesupdate.nastran.bindings import SIGNED_FIELDS

    dv = desvars[desvar_id]
    out = {**entry, "desvar": desvar_id}
    low, high = dv.real("XLB"), dv.real("XUB")
    rel = entry.get("relations", ())
    signed = bool(rel) and all(r[2] in SIGNED_FIELDS for r in rel)
    fits = low > -_NO_BOUND if signed else (low >= 0 if rel else low > 0)
    if fits and high < _NO_BOUND and low < high:
        out["bounds"] = [low, high]
    return out


def unbound_note(deck, parameters: dict) -> str | None:
    """One note naming each DESVAR that did not become a parameter, with its XINIT, bounds and
    why, at the file:line of the relation that keeps it out (``unbound_reasons``); None when
    all did.  Such a DESVAR stays at the cards' values; ``writer.write_design_deck`` writes the
    deck with every relation evaluated at any DESVAR values."""
    used = {int(e["desvar"]) for e in parameters.values() if "desvar" in e}
    rest = [c for i, c in sorted(deck.table("DESVAR").items()) if i not in used]
    if not rest:
        return None
    why = unbound_reasons(deck)
    items = "; ".join(
        f"{c['LABEL']} ({c.id()}: {c.real('XINIT'):g} in [{c.real('XLB'):g}, {c.real('XUB'):g}]"
        f"): {why.get(c.id(), _unused(deck, c.id()))}"
        for c in rest
    )
    return f"{len(rest)} DESVAR(s) not made parameters (they stay at the cards' values): {items}"


def _unused(deck, dvid: int) -> str:
    """Why a DESVAR with no ``unbound_reasons`` entry is out: unused, or relations that mix
    kinds of fields (a factor and a re-built field) or set one field twice."""
    used = any(d == dvid for rel in deck.of("DVPREL1", "DVMREL1", "DVCREL1")
               for d, _ in _relation(rel)[3])  # fmt: skip
    if not used:
        return "no relation uses it"
    return "its relations mix kinds of fields or set one field twice"


def _shape_variables(deck) -> dict[int, str]:
    """{DESVAR id: 'file:line DVGRID id: why'} of the DESVARs a DVGRID moves GRIDs with (shape
    design variables, MSC QRG DVGRID): not parameters, the deck's GRIDs are at their XINIT."""
    out = {}
    for c in deck.of("DVGRID"):
        dvid = int(c.value(0))
        out.setdefault(dvid, f"{c.where} DVGRID {dvid}: it moves GRID {c.value(1)} (a shape "
                             "variable, which no binding is)")  # fmt: skip
    return out


def unbound_reasons(deck) -> dict[int, str]:
    """{DESVAR id: 'file:line CARD id: why'} of the first relation that keeps each DESVAR from
    being a parameter (``desvar_parameters``): one PBEAM(L) station, a field no binding acts
    on, several DESVARs in one relation, C0 != 0 or COEFs / fields that differ between its
    relations on a field that is a factor (PSHELL T, MAT1 E/RHO of shells, springs), relations
    on several card types (one parameter re-builds one kind of card), a DVGRID (shape)."""
    out, first = dict(_shape_variables(deck)), {}
    for rel in deck.of("DVPREL1", "DVMREL1", "DVCREL1"):
        ptype, name, c0, pairs = _relation(rel)
        where = f"{rel.where} {rel.name} {rel.value(0)}"
        field = _field(rel, ptype, name)
        for dvid, coef in pairs:
            if dvid not in out:
                why = _reason(deck, rel, (ptype, name, field, c0, coef, len(pairs)), first, dvid)
                if why:
                    out[dvid] = f"{where}: {why}"
    return out


def _reason(deck, rel, what, first: dict, dvid: int) -> str:
    """Why relation ``rel`` keeps DESVAR ``dvid`` out ("" when it does not by itself)."""
    ptype, name, field, c0, coef, n_pairs = what
    if _station(ptype, name)[1] is not None or (
        field is not None and _stations_given(deck, ptype, rel.value(2), field)
    ):
        return f"sets one station of {ptype} {rel.value(2)} (a binding sets every station)"
    if field is None:
        return f"{ptype} {name} is a field no binding acts on"
    if n_pairs > 1:
        return f"{n_pairs} DESVARs in one relation"
    rebuilt = _family((ptype, field)) in ("line", "card")
    t, n, c, w = first.setdefault(dvid, (ptype, field, coef, f"{rel.where} {rel.name}"))
    if rebuilt and (t in ("CBAR", "CBEAM")) != (ptype in ("CBAR", "CBEAM")):
        return f"{ptype} {field} beside {t} {n} at {w} (one parameter re-builds one card type)"
    if rebuilt:
        return ""
    if c0 != 0:
        return f"C0 = {c0:g} (a binding of {ptype} {field} is COEF x)"
    if (t, n, c) != (ptype, field, coef):
        return (f"{ptype} {field} x {coef:g} beside {t} {n} x {c:g} at {w} (one binding has one "
                "field and one COEF)")  # fmt: skip
    return ""


def design_values(deck, values=None) -> dict[int, float]:
    """{DESVAR id: value}: ``values`` ({DESVAR id or label: value}) over the DESVARs' XINIT."""
    out = {i: c.real("XINIT") for i, c in deck.table("DESVAR").items()}
    labels = {_label(deck.table("DESVAR"), i).upper(): i for i in out}
    for key, v in (values or {}).items():
        i = key if isinstance(key, int) else labels.get(str(key).upper())
        if i not in out:
            raise BayesUpdateError(f"DESVAR {key!r}: the deck has no such design variable")
        out[i] = float(v)
    return out


def design_cards(deck, values=None) -> dict:
    """{(card name, id): the card with every DVPREL1 / DVMREL1 / DVCREL1 relation's field set to
    C0 + sum(COEF_i x_i)} at the DESVAR values ``values`` (``design_values``: XINIT where not
    given); the relation's PMIN / PMAX bound it where written on the card.  A PBEAM(L) field is
    written at every station that gives it (``bindings.set_field``).  Relations whose card,
    field or DESVAR does not exist are refused together, each with its file:line."""
    x = design_values(deck, values)
    changed, refused = {}, []
    for rel in deck.of("DVPREL1", "DVMREL1", "DVCREL1"):
        try:
            key, card = _apply(deck, rel, x, changed)
        except (BayesUpdateError, CardError) as exc:
            refused.append(f"{rel.where} {rel.name} {rel.value(0)}: {str(exc).split(': ')[-1]}")
            continue
        changed[key] = card
    if refused:
        raise BayesUpdateError(f"{len(refused)} design relation(s) refused: " + "; ".join(refused))
    return changed


def _apply(deck, rel, x: dict, changed: dict):
    """((card name, id), the card with the relation's field written)."""
    from bayesupdate.nastran.bindings import FIELDS, DeckField, set_field

    ctype, name, c0, pairs = _relation(rel)
    cid = rel.value(2)
    card = changed.get((ctype, cid)) or deck.table(ctype).get(cid)
    if card is None or card.name != ctype:
        raise BayesUpdateError(f"no {ctype} {cid}")
    missing = [d for d, _ in pairs if d not in x]
    if missing or not pairs:
        raise BayesUpdateError(f"no DESVAR {missing or '(no DVIDi)'}")
    value = c0 + sum(coef * x[d] for d, coef in pairs)
    low, high = (rel.value(k) for k in (4, 5))
    value = float(np.clip(value, -np.inf if low is None else low, np.inf if high is None else high))
    if not isinstance(name, str):  # a DVPREL1 field number: raw index number - 2
        field = _FIELD_NUMBER.get((ctype, int(name or 0)))
        if field is None:
            return (ctype, cid), with_fields(card, {int(name) - 2: float(value)})
        name = field
    name, station = _station(ctype, name.upper())
    if ctype in ("PBEAM", "PBEAML") and name in FIELDS[ctype]:
        return (ctype, cid), with_fields(card, {_station_index(card, name, station): value})
    if name in FIELDS.get(ctype, {}):
        f = DeckField(f"{ctype} {cid} {name}", ctype, (cid,), name, False)
        return (ctype, cid), set_field(card, f, float(value), 0.0)
    return (ctype, cid), with_fields(card, {card.position(name): float(value)})


def _station_index(card, name: str, station: str | None) -> int:
    """Raw index of PBEAM(L) field ``name`` at ``station`` ("A" or None: end A, "B": end B, "k":
    the k-th intermediate station; MSC QRG DVPREL1); a station the card does not give is
    refused."""
    from bayesupdate.nastran.bindings import DeckField, _where

    where = _where(card, DeckField(f"{card.name} {card.id()} {name}", card.name, (card.id(),),
                                   name, False))  # fmt: skip
    k = {None: 0, "A": 0, "B": len(where) - 1}.get(station)
    k = int(station) if k is None else k
    if station == "B" and len(where) == 1 or not 0 <= k < len(where):
        raise BayesUpdateError(f"{card.name} {card.id()} has no station {station} for {name}")
    return where[k]


def xinit_values(deck, model) -> dict[str, float]:
    """{parameter: its DESVAR's XINIT} of the model's DESVAR parameters (Nastran's start)."""
    desvars = deck.table("DESVAR")
    return {
        name: desvars[b.desvar].real("XINIT")
        for name, b in model.bindings.items()
        if getattr(b, "desvar", None) is not None
    }
