"""RBE2, RBAR and RBE3 as the structure's rigid and interpolation elements (MSC Nastran QRG)."""

from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran.cards.common import Context, _builder_message, components, id_list

#: the cards this file converts (``cards.FAMILIES``)
CARDS = ("RBE2", "RBAR", "RBE3")


def add(ctx: Context) -> None:
    """RBE2, RBE3 (weight groups with their own components; UM) and RBAR (six independent
    components at one end)."""
    ctx.each(("RBE2",), _add_rbe2)
    ctx.each(("RBAR",), _add_rbar)
    ctx.each(("RBE3",), _add_rbe3)


def _add_rbe2(ctx: Context, r) -> None:
    deps = id_list(r, 3)
    rows = ctx.grids.index(deps, r)
    comps = components(ctx, r["CM"], rows, r)
    gn = ctx.rows(r, ("GN",))[0]
    try:
        ctx.rigid[f"rbe2 {ctx.builder.add_rbe2(ctx.node[gn], ctx.node[rows], comps)}"] = r
    except BayesUpdateError as exc:
        r.fail(_builder_message(exc))


def _add_rbar(ctx: Context, r) -> None:
    """RBAR with all six independent components at one end (CNA = 123456 and CNB blank, or
    CNB = 123456 and CNA blank): the other end's dependent components (CMB, or CMA; both
    blank: all six) follow it rigidly, an RBE2 from that end (MSC QRG RBAR; the other end's
    remaining components are not tied).  Independent components split over both ends are
    refused."""
    cna, cnb, cma, cmb = (str(r[f]) if r[f] else "" for f in ("CNA", "CNB", "CMA", "CMB"))
    if not cma and not cmb:  # every component not in CNA and CNB is dependent (QRG RBAR)
        cma, cmb = ("123456" if not cna else "", "123456" if not cnb else "")
    rows = ctx.rows(r, ("GA", "GB"))
    if cna == "123456" and not cnb and not cma and cmb:
        independent, dependent, comps = rows[0], rows[1], cmb
    elif cnb == "123456" and not cna and not cmb and cma:
        independent, dependent, comps = rows[1], rows[0], cma
    else:
        r.fail("only all six independent components at one end (CNA or CNB = 123456, the "
               "other end's CMB or CMA dependent) is supported")  # fmt: skip
    comps = components(ctx, comps, [dependent], r)
    rbe2 = ctx.builder.add_rbe2(ctx.node[independent], [ctx.node[dependent]], comps)
    ctx.rigid[f"rbe2 {rbe2}"] = r


def rbe3_groups(r) -> list[tuple[float, str, list[int]]]:
    """[(WTi, Ci, grids)] of an RBE3's weight groups (up to its UM, ALPHA or TREF)."""
    values = r.values(4)
    groups, k = [], 0
    while k < len(values):
        v = values[k]
        if v is None:
            k += 1
            continue
        if v in ("UM", "ALPHA", "TREF"):
            break
        if not isinstance(v, float) or k + 1 >= len(values):
            r.fail(f"field {v!r}: give WTi (a real), Ci, then grids")
        comp, grids, k = values[k + 1], [], k + 2
        while k < len(values) and (values[k] is None or isinstance(values[k], int)):
            grids += [values[k]] if values[k] is not None else []
            k += 1
        groups.append((v, str(comp), grids))
    if not groups:
        r.fail("no weight groups")
    return groups


def rbe3_um(r) -> list[tuple[int, str]]:
    """[(GMi, CMi)] of an RBE3's UM set (empty without one)."""
    values = r.values(4)
    if "UM" not in values:
        return []
    out, k = [], values.index("UM") + 1
    while k < len(values) and values[k] not in ("ALPHA", "TREF"):
        if values[k] is None:
            k += 1
            continue
        if not isinstance(values[k], int) or k + 1 >= len(values) or values[k + 1] is None:
            r.fail(f"UM field {values[k]!r}: give GMi, CMi pairs")
        out.append((values[k], str(values[k + 1])))
        k += 2
    return out


def _add_rbe3(ctx: Context, r) -> None:
    """RBE3: REFGRID's REFC is the weighted mean motion of the groups (WTi, Ci, Gi,j), each grid
    with its own group's weight and components (a grid in several groups: one leg each).  A UM
    set (MSC QRG RBE3: GMi, CMi) makes those DOFs dependent instead of REFC: the same equations,
    solved for them (``fe.constraints``), so REFC may be fixed or dependent elsewhere."""
    groups = rbe3_groups(r)
    nodes = [g for _, _, gs in groups for g in gs]
    weights = [float(w) for w, _, gs in groups for _ in gs]
    rows = ctx.grids.index(nodes, r)
    ref = ctx.rows(r, ("REFGRID",))
    node_c = []
    for w, comp, gs in groups:
        if not w > 0:
            r.fail(f"weight {w}: give WTi > 0")
        node_c += [components(ctx, comp, ctx.grids.index(gs, r), r)] * len(gs)
    ref_c = components(ctx, r["REFC"], ref, r)
    um = rbe3_um(r)
    _check_um(r, um, ref_c, set(nodes) | {r.int("REFGRID")})
    um_rows = [ctx.grids.index([g], r)[0] for g, _ in um]
    um = [(ctx.node[k], components(ctx, c, [k], r)) for k, (_, c) in zip(um_rows, um, strict=True)]
    try:
        i = ctx.builder.add_rbe3(ctx.node[ref[0]], ctx.node[rows], weights, ref_c, node_c, um)
        ctx.rigid[f"rbe3 {i}"] = r
    except BayesUpdateError as exc:
        r.fail(_builder_message(exc))


def _check_um(r, um, ref_c: str, grids: set) -> None:
    n = 0
    for g, comp in um:
        if g not in grids:
            r.fail(f"UM grid {g} is not one of the element's grids")
        if not comp.isdigit() or set(comp) - set("123456"):
            r.fail(f"UM components {comp!r}: give digits 1-6")
        n += len(set(comp))
    if um and n != len(ref_c):
        r.fail(f"UM has {n} DOFs; REFC {ref_c} has {len(ref_c)} (MSC QRG RBE3: as many)")
