"""RBE2, RBAR and RBE3 as the structure's rigid and interpolation elements (MSC Nastran QRG)."""

from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran.cards.common import Context, _builder_message, components, id_list

#: the cards this file converts (``cards.FAMILIES``)
CARDS = ("RBE2", "RBAR", "RBE3")


def add(ctx: Context) -> None:
    """RBE2, RBE3 (no UM set) and RBAR (CNA = CMB = 123456)."""
    ctx.each(("RBE2",), _add_rbe2)
    ctx.each(("RBAR",), _add_rbar)
    ctx.each(("RBE3",), _add_rbe3)


def _add_rbe2(ctx: Context, r) -> None:
    deps = id_list(r, 3)
    rows = ctx.grids.index(deps, r)
    comps = components(ctx, r["CM"], rows, r)
    gn = ctx.rows(r, ("GN",))[0]
    try:
        ctx.builder.add_rbe2(ctx.node[gn], ctx.node[rows], comps)
    except BayesUpdateError as exc:
        r.fail(_builder_message(exc))


def _add_rbar(ctx: Context, r) -> None:
    if str(r["CNA"]) != "123456" or str(r["CMB"]) != "123456" or r["CNB"] or r["CMA"]:
        r.fail("only CNA = 123456, CMB = 123456 is supported")
    ga, gb = ctx.node[ctx.rows(r, ("GA", "GB"))]
    ctx.builder.add_rbe2(ga, [gb], "123456")


def rbe3_groups(r) -> list[tuple[float, str, list[int]]]:
    """[(WTi, Ci, grids)] of an RBE3 (refused with a UM set)."""
    values = r.values(4)
    groups, k = [], 0
    while k < len(values):
        v = values[k]
        if v is None:
            k += 1
            continue
        if v in ("UM", "ALPHA", "TREF"):
            if v == "UM":
                r.fail("UM (user-chosen dependent DOFs) is not supported")
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


def _add_rbe3(ctx: Context, r) -> None:
    """RBE3: REFGRID's REFC is the weighted mean motion of the groups (WTi, Ci, Gi,j)."""
    groups = rbe3_groups(r)
    comps = {c for _, c, _ in groups}
    if len(comps) != 1:
        r.fail("all weight groups need the same components")
    nodes = [g for _, _, gs in groups for g in gs]
    weights = [float(w) for w, _, gs in groups for _ in gs]
    rows = ctx.grids.index(nodes, r)
    ref = ctx.rows(r, ("REFGRID",))
    node_c = components(ctx, comps.pop(), rows, r)
    ref_c = components(ctx, r["REFC"], ref, r)
    ctx.builder.add_rbe3(ctx.node[ref[0]], ctx.node[rows], weights, ref_c, node_c)
