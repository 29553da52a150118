"""A deck's design variables as parameters: DESVAR + DVPREL1 (``x`` -> property field).

Used when the study names no parameters.  Each DESVAR that DVPREL1 cards use becomes a parameter
named by its label, in its own units: a DVPREL1 sets ``field = C0 + sum(COEF_i x_i)``; only the
linear form (one DESVAR, C0 = 0) with fields ``bindings`` can bind is read, and every DVPREL1 of
one DESVAR must set the same card type and field with the same COEF (several PIDs are one
binding, ``"PSHELL 3,5 T"``).  Bounds are XLB, XUB (a bound at Nastran's +-1e20 default, or a
lower bound <= 0, takes ``model.DEFAULT_RANGE`` of the deck's value instead).
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
    """(TYPE, PNAME or field number, C0, [(DVID, COEF)]) of a DVPREL1."""
    pairs, values = [], rel.values(8)
    for k in range(0, len(values) - 1, 2):
        if values[k] is not None:
            pairs.append((int(values[k]), float(values[k + 1] or 0.0)))
    return str(rel["TYPE"]), rel["PNAME"], rel.real("C0"), pairs


def desvar_parameters(deck) -> dict:
    """{label: {"binds", "bounds" (optional), "coefficient", "desvar"}} from DESVAR/DVPREL1."""
    by_desvar = {}
    for rel in deck.of("DVPREL1"):
        oid = rel.id()
        ptype, pname, c0, pairs = _relation(rel)
        if len(pairs) != 1 or abs(c0) > 0:
            raise BayesUpdateError(
                f"{rel.where} DVPREL1 {oid}: only one DESVAR with C0 = 0 is supported "
                "(field = COEF x)"
            )
        field = pname
        if not isinstance(field, str):
            field = _FIELD_NUMBER.get((ptype, int(field or 0)))
            if field is None:
                raise BayesUpdateError(
                    f"{rel.where} DVPREL1 {oid}: {ptype} field {pname} cannot be bound"
                )
        dvid, coef = pairs[0]
        key = (ptype, field.upper(), coef)
        entry = by_desvar.setdefault(dvid, [key, []])
        if entry[0] != key:
            raise BayesUpdateError(
                f"{rel.where} DVPREL1 {oid}: DESVAR {dvid} sets {entry[0][:2]} with COEF "
                f"{entry[0][2]} elsewhere; one DESVAR must set one field type with one COEF"
            )
        entry[1].append(int(rel["PID"]))
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
    via = sorted({c.name for c in deck.of("DVMREL1", "DVCREL1")})
    items = ", ".join(
        f"{c['LABEL']} ({c.id()}: {c.real('XINIT'):g} in [{c.real('XLB'):g}, {c.real('XUB'):g}])"
        for c in rest
    )
    return (
        f"{len(rest)} DESVAR(s) not made parameters (only DVPREL1 relations are bound"
        + (f"; the deck relates them through {', '.join(via)}" if via else "")
        + f"): {items}"
    )
