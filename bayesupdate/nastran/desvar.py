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


def desvar_parameters(bdf) -> dict:
    """{label: {"binds", "bounds" (optional), "coefficient", "desvar"}} from DESVAR/DVPREL1."""
    by_desvar = {}
    for oid, rel in sorted(bdf.dvprels.items()):
        if rel.type != "DVPREL1":
            raise BayesUpdateError(f"{rel.type} {oid}: only DVPREL1 design relations are read")
        dvids = [int(d) for d in rel.desvar_ids]
        if len(dvids) != 1 or abs(float(rel.c0 or 0.0)) > 0:
            raise BayesUpdateError(
                f"DVPREL1 {oid}: only one DESVAR with C0 = 0 is supported (field = COEF x)"
            )
        field = rel.pname_fid
        if not isinstance(field, str):
            field = _FIELD_NUMBER.get((rel.prop_type, int(field)))
            if field is None:
                raise BayesUpdateError(
                    f"DVPREL1 {oid}: {rel.prop_type} field {rel.pname_fid} cannot be bound"
                )
        key = (rel.prop_type, field.upper(), float(rel.coeffs[0]))
        entry = by_desvar.setdefault(dvids[0], [key, []])
        if entry[0] != key:
            raise BayesUpdateError(
                f"DVPREL1 {oid}: DESVAR {dvids[0]} sets {entry[0][:2]} with COEF {entry[0][2]} "
                "elsewhere; one DESVAR must set one field type with one COEF"
            )
        entry[1].append(int(rel.pid))
    return {_name(bdf, d, by_desvar): _entry(bdf, d, *v) for d, v in sorted(by_desvar.items())}


def _name(bdf, desvar_id, taken) -> str:
    label = str(bdf.desvars[desvar_id].label).strip() or f"desvar_{desvar_id}"
    labels = [str(bdf.desvars[d].label).strip() for d in taken]
    return label if labels.count(label) == 1 else f"{label}_{desvar_id}"


def _entry(bdf, desvar_id, key, pids) -> dict:
    card, field, coefficient = key
    dv = bdf.desvars.get(desvar_id)
    if dv is None:
        raise BayesUpdateError(f"DVPREL1 on {card} {pids[0]}: no DESVAR {desvar_id}")
    out = {
        "binds": f"{card} {','.join(str(p) for p in pids)} {field}",
        "coefficient": coefficient,
        "desvar": desvar_id,
    }
    low, high = float(dv.xlb), float(dv.xub)
    if low > 0 and high < _NO_BOUND and low < high:
        out["bounds"] = [low, high]
    return out
