"""CELAS1/CELAS2 and CBUSH + PBUSH as springs (MSC Nastran QRG).

A CBUSH whose ends are apart acts at its location (S along GA-GB, or S1-S3 in OCID) through
rigid arms from both grids (``StructureBuilder.add_spring(location=...)``, ``fe.bush``), so
moments balance as in MSC's CBUSH.
"""

import numpy as np

from bayesupdate.nastran.cards.beams import _orientation
from bayesupdate.nastran.cards.common import Context
from bayesupdate.nastran.frames import coordinate

#: the cards this file converts (``cards.FAMILIES``)
CARDS = ("CELAS1", "CELAS2", "CBUSH")


def add(ctx: Context) -> None:
    """CELAS1/CELAS2 (one component each, in the grids' CD frames) and CBUSH + PBUSH."""
    ctx.each(("CELAS1", "CELAS2"), _add_celas)
    ctx.each(("CBUSH",), _add_cbush)


def _add_celas(ctx: Context, e) -> None:
    k = ctx.prop(e, ("PELAS",)).real("K") if e.name == "CELAS1" else e.real("K")
    ids = [g for g in (e["G1"], e["G2"]) if g]
    if len(ids) == 0 or k < 0:
        e.fail("needs a grid and K >= 0 (scalar points are not supported)")
    rows = ctx.grids.index(ids, e)
    comps = [int(e["C1"] or 0), int(e["C2"] or 0)][: len(ids)]
    if min(comps) < 1:
        e.fail("components must be 1-6 (scalar points are not supported)")
    frame = ctx.grids.frame[rows[0]]
    if len(ids) == 2 and (comps[0] != comps[1] or not np.allclose(frame, ctx.grids.frame[rows[1]])):
        e.fail("the two ends need the same component in the same CD frame")
    stiff = np.zeros(6)
    stiff[comps[0] - 1] = k
    b = ctx.node[rows[1]] if len(ids) == 2 else None
    ctx.builder.add_spring(ctx.node[rows[0]], b, stiff, f"{e.name} {e.id()}", frame=frame)


def pbush_lines(p) -> dict[str, list]:
    """{keyword: its six values (None where blank)} of a PBUSH (K, B, GE, RCV, M, ...)."""
    out = {}
    for start in range(0, len(p.raw), 8):
        key = p.value(start + 1)
        if isinstance(key, str):
            out[key] = [p.value(start + 2 + k) for k in range(6)]
    return out


def pbush_k(p) -> np.ndarray:
    """(6,) K1-K6 of a PBUSH (blank = 0); refuses a mass (M) it cannot place."""
    lines = pbush_lines(p)
    if any(v for v in lines.get("M", [])):
        p.fail("PBUSH M (mass) is not supported")
    return np.array([float(v or 0.0) for v in lines.get("K", [None] * 6)])


def _add_cbush(ctx: Context, e) -> None:
    """A CBUSH: K1-K6 along its element axes (CID's axes; else x from GA to GB and y in the plane
    of x and v), at its location P; ends apart act at P through rigid arms from GA and GB."""
    prop = ctx.prop(e, ("PBUSH",))
    k = pbush_k(prop)
    gb = e["GB"]
    ids = [e.int("GA", positive=True)] + ([int(gb)] if gb else [])
    rows = ctx.grids.index(ids, e)
    x = ctx.grids.xyz[rows]
    apart = len(ids) == 2 and np.linalg.norm(x[1] - x[0]) > 1e-4
    cid = e["CID"]
    if cid is not None and int(cid) >= 0:
        frame = coordinate(ctx.grids, int(cid), e).axes_at(x[:1])[0]
    elif apart:
        axis = (x[1] - x[0]) / np.linalg.norm(x[1] - x[0])
        z = np.cross(axis, _orientation(ctx, e, rows[0]))
        if np.linalg.norm(z) < 1e-12:
            e.fail("the orientation vector is parallel to GA-GB")
        z /= np.linalg.norm(z)
        frame = np.stack([axis, np.cross(z, axis), z])
    else:
        e.fail("coincident or grounded CBUSH needs a CID")
    part = f"PBUSH {prop.id()}"
    a = ctx.node[rows[0]]
    b = ctx.node[rows[1]] if len(ids) == 2 else None
    p = None
    if len(ids) == 2 and np.linalg.norm(x[1] - x[0]) > 0:
        p = _cbush_point(ctx, e, x)
    ctx.builder.add_spring(a, b, k, part, frame=frame, location=p)


def _cbush_point(ctx: Context, e, x) -> np.ndarray:
    """The spring's location: GA + S (GB - GA) (OCID -1, the default), or S1-S3 in OCID."""
    ocid = e.int("OCID")
    if ocid == -1:
        s = e.real("S")
        if not 0 <= s <= 1:
            e.fail(f"S = {s}: give 0 <= S <= 1")
        return x[0] + s * (x[1] - x[0])
    offset = np.array([e.real(k) if not e.is_blank(k) else 0.0 for k in ("S1", "S2", "S3")])
    coord = coordinate(ctx.grids, ocid, e)
    if coord.kind != "rectangular":
        e.fail(f"OCID {ocid} is not rectangular")
    return x[0] + offset @ coord.axes
