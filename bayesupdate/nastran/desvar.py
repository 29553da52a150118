"""A deck's design variables as parameters: DESVAR + DVPREL1 / DVMREL1 / DVCREL1 (``x`` -> field).

Used when the study names no parameters.  A relation sets ``field = C0 + sum(COEF_i x_i)`` (MSC
QRG DVPREL1, DVMREL1, DVCREL1); a DESVAR becomes a parameter named by its label, in its own
units, when every relation using it is the linear form (one DESVAR, C0 = 0) on a field
``bindings`` can bind and all set the same card type and field with the same COEF (several ids
are one binding, ``"PSHELL 3,5 T"``); the other DESVARs are listed in a note.  Bounds are XLB,
XUB (a bound at Nastran's +-1e20 default, or a lower bound <= 0, takes ``model.DEFAULT_RANGE``
of the deck's value instead).  The parameter's default is the card's value / COEF, which may
differ from XINIT (``xinit_values``).
"""

from bayesupdate.errors import BayesUpdateError

#: DVPREL1 field numbers of the bindable fields (MSC QRG: PSHELL T is field 4, PELAS K 3,
#: PBAR A I1 I2 J NSM 4-8, PROD A J 4-5); names (PNAME) are read as they are
_FIELD_NUMBER = {
    ("PSHELL", 4): "T", ("PELAS", 3): "K", ("CONM2", 4): "M",
    **{("PBAR", 4 + k): f for k, f in enumerate(("A", "I1", "I2", "J", "NSM"))},
    ("PROD", 4): "A", ("PROD", 5): "J",
}  # fmt: skip
_NO_BOUND = 1e19


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
    return name.upper() if name and name.upper() in FIELDS.get(ptype, {}) else None


def design_refusals(deck) -> list[str]:
    """'file:line DVPREL1 id: ...' of each DVPREL1 to a field that cannot be bound (the reader
    adds them to the deck's other refusals when the DESVARs are to be the parameters)."""
    out = []
    for rel in deck.of("DVPREL1"):
        ptype, name, _, _ = _relation(rel)
        if _field(rel, ptype, name) is None:
            out.append(f"{rel.where} DVPREL1 {rel.value(0)}: {ptype} field {name} cannot be bound")
    return out


def desvar_parameters(deck) -> dict:
    """{label: {"binds", "bounds" (optional), "coefficient", "desvar"}} of the DESVARs whose every
    relation (DVPREL1, DVMREL1, DVCREL1) sets one bindable field as COEF x (C0 = 0, one DESVAR):
    one binding over their ids.  A DVPREL1 to a field that cannot be bound is refused (all of
    them in one message); the other DESVARs are listed by ``unbound_note``."""
    refused = design_refusals(deck)
    if refused:
        raise BayesUpdateError(f"{len(refused)} design relation(s) refused: " + "; ".join(refused))
    relations = {}
    for rel in deck.of("DVPREL1", "DVMREL1", "DVCREL1"):
        ptype, name, c0, pairs = _relation(rel)
        field = _field(rel, ptype, name)
        for dvid, _ in pairs:
            ok = field is not None and len(pairs) == 1 and c0 == 0
            key = (ptype, field, pairs[0][1]) if ok else None
            relations.setdefault(dvid, []).append((key, int(rel.value(2))))
    by_desvar = {}
    for dvid, rels in sorted(relations.items()):
        keys = {k for k, _ in rels}
        if len(keys) == 1 and None not in keys:
            by_desvar[dvid] = [keys.pop(), sorted({i for _, i in rels})]
    desvars = deck.table("DESVAR")
    return {_name(desvars, d, by_desvar): _entry(desvars, d, *v)
            for d, v in sorted(by_desvar.items())}  # fmt: skip


def _label(desvars, d) -> str:
    card = desvars.get(d)
    label = "" if card is None else str(card["LABEL"] or "").strip()
    return label or f"desvar_{d}"


def _name(desvars, desvar_id, taken) -> str:
    label = _label(desvars, desvar_id)
    labels = [_label(desvars, d) for d in taken]
    return label if labels.count(label) == 1 else f"{label}_{desvar_id}"


def _entry(desvars, desvar_id, key, pids) -> dict:
    card, field, coefficient = key
    dv = desvars.get(desvar_id)
    if dv is None:
        raise BayesUpdateError(f"DVPREL1 on {card} {pids[0]}: no DESVAR {desvar_id}")
    out = {
        "binds": f"{card} {','.join(str(p) for p in pids)} {field}",
        "coefficient": coefficient,
        "desvar": desvar_id,
    }
    low, high = dv.real("XLB"), dv.real("XUB")
    if low > 0 and high < _NO_BOUND and low < high:
        out["bounds"] = [low, high]
    return out


def unbound_note(deck, parameters: dict) -> str | None:
    """A note naming the DESVARs that did not become parameters (those acting through DVMREL1 /
    DVCREL1 only, or through no relation), with their XINIT and bounds; None when all did."""
    used = {int(e["desvar"]) for e in parameters.values() if "desvar" in e}
    rest = [c for i, c in sorted(deck.table("DESVAR").items()) if i not in used]
    if not rest:
        return None
    items = ", ".join(
        f"{c['LABEL']} ({c.id()}: {c.real('XINIT'):g} in [{c.real('XLB'):g}, {c.real('XUB'):g}])"
        for c in rest
    )
    return (
        f"{len(rest)} DESVAR(s) not made parameters (a relation with C0, several DESVARs, or a "
        f"field that cannot be bound: CBEAM offsets, CONM2 X/I, CMASS2 M): {items}"
    )


def xinit_values(deck, model) -> dict[str, float]:
    """{parameter: its DESVAR's XINIT} of the model's DESVAR parameters (Nastran's start)."""
    desvars = deck.table("DESVAR")
    return {
        name: desvars[b.desvar].real("XINIT")
        for name, b in model.bindings.items()
        if getattr(b, "desvar", None) is not None
    }
