"""CTETRA (four GRIDs) and CHEXA (eight GRIDs) with PSOLID and an isotropic MAT1 as
``fe.elements.tetra`` and ``fe.elements.hexa`` elements (MSC Nastran QRG CTETRA, CHEXA, PSOLID).

A four-node CTETRA is the constant-strain tetrahedron in every code: its stiffness has no
integration or formulation option (PSOLID IN, ISOP and STRESS change nothing for it) and its
lumped mass is a quarter at each corner.  An eight-node CHEXA is Nastran's default brick
(``fe.elements.hexa``: checked on MSC's and NX's own solutions), so a PSOLID that its CHEXAs
use must leave IN and ISOP blank (the default integration).  Refused, each naming
its card: a solid with mid-side GRIDs (CTETRA G5-G10, CHEXA G9-G20), a PSOLID whose FCTN is
not SMECH (a fluid), a CHEXA's PSOLID with IN or ISOP given, a MAT1 whose NU (given, or
from E and G) is outside (-1, 0.5) or that has no E, a corner repeated, a tetrahedron's four
corners in one plane, a brick whose volume vanishes or turns inside out within it.  A brick
numbered inside out (G1-G4 clockwise seen from G5-G8) is read with its faces' order reversed,
as Nastran reads it.  PSOLID CORDM (the material frame) is read and has no effect on an
isotropic material.
"""

import numpy as np

from bayesupdate.fe.elements import hexa
from bayesupdate.fe.elements.hexa import Hexahedra
from bayesupdate.fe.elements.tetra import Tetrahedra, volumes
from bayesupdate.nastran.cards.common import Context, mat1

#: the cards this file converts (``cards.FAMILIES``)
CARDS = ("CTETRA", "CHEXA", "PSOLID")
#: per element card: its corner GRIDs, its last mid-side GRID field, the family it builds
SHAPES = {"CTETRA": (4, 10, Tetrahedra), "CHEXA": (8, 20, Hexahedra)}
#: a brick's corners with its faces' order reversed (an inside-out numbering made right)
MIRROR = (0, 3, 2, 1, 4, 7, 6, 5)
#: a corner volume below this fraction of the cube of the longest edge is a flat element
FLAT = 1e-10


def add(ctx: Context) -> None:
    """The CTETRA and CHEXA cards as records (nodes, corners, E, NU, RHO x WTMASS, part
    "PSOLID pid"); the ``Tetrahedra`` and the ``Hexahedra`` of all of them join the built
    structure (``Context.finishers``).  Each card's fields are read once; its GRIDs, volume
    and material are then found for all cards of its kind together (a material once per
    PSOLID), and a card with a missing GRID or no volume is refused by name."""
    materials, integration = {}, {}
    for name in SHAPES:
        out = ([], [])  # the cards kept, their corner GRID ids
        ctx.each((name,), lambda ctx, e, out=out: _fields(ctx, e, out, materials, integration))
        if out[0]:
            _finish(ctx, out[0], np.array(out[1], dtype=np.int64), materials)


def _finish(ctx: Context, cards: list, ids: np.ndarray, materials: dict) -> None:
    """Locate the corners of one kind's cards (n, k GRID ids), refuse the degenerate ones by
    name, and hand the rest to the structure (``Context.finishers``)."""
    name = cards[0][0].name
    rows, found = _rows(ctx, cards, ids)
    corners = ctx.grids.xyz[rows]
    edges = corners[:, :, None] - corners[:, None]
    longest = np.sqrt(np.einsum("eabi,eabi->eab", edges, edges).max(axis=(1, 2)))
    repeated = np.sort(ids, axis=1)
    repeated = np.any(repeated[:, 1:] == repeated[:, :-1], axis=1)
    if name == "CTETRA":
        low = high = volumes(corners)
        what = "its four corners span no volume ({:.3g} for edges up to {:.3g})"
    else:
        det = np.linalg.det(hexa.jacobians(corners, np.vstack([hexa.GAUSS, hexa.CORNERS])))
        inside_out = np.all(det < 0, axis=1)
        rows[inside_out] = rows[inside_out][:, MIRROR]
        corners[inside_out] = corners[inside_out][:, MIRROR]
        det[inside_out] = -det[inside_out]
        low, high = det.min(axis=1), det.max(axis=1)
        what = ("its volume vanishes or turns inside out within it (det J from {:.3g} to "
                "{:.3g}, edges up to {:.3g}): a folded or collapsed brick")  # fmt: skip
    flat = (low <= FLAT * longest**3) | repeated
    for i in np.flatnonzero(flat & found):
        values = (low[i], longest[i]) if name == "CTETRA" else (low[i], high[i], longest[i])
        reason = "a corner is repeated" if repeated[i] else what.format(*values)
        ctx.refusals.guard(lambda reason=reason, i=i: cards[i][0].fail(reason))
    keep = np.flatnonzero(found & ~flat)
    if not keep.size:
        return
    pids = np.array([cards[i][1] for i in keep])
    # the PSOLIDs in the order their first element comes (the parts' order), each element's one
    first, which = np.unique(pids, return_index=True, return_inverse=True)[1:]
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    table = [materials[pid] for pid in np.unique(pids)[order]]  # (E, NU, RHO, part name)
    elements = (ctx.node[rows[keep]], corners[keep], np.array([m[:3] for m in table]),
                [m[3] for m in table], rank[which])  # fmt: skip
    family = SHAPES[name][2]
    ctx.finishers.append(lambda parts: solids(family, elements, parts, ctx.lumped))


def _fields(ctx: Context, e, out: tuple, materials: dict, integration: dict) -> None:
    """A solid card's corner GRID ids and PSOLID (appended to ``out`` = (cards, grid ids)),
    its material completed once per PSOLID ((E, NU, RHO x WTMASS, part name) in
    ``materials``) and, for a CHEXA, its PSOLID's integration checked once
    (``integration``); refused with its card where the card or its PSOLID or MAT1 cannot be
    used."""
    p = ctx.prop(e, ("PSOLID",))
    n, last, _ = SHAPES[e.name]
    if any(not e.is_blank(f"G{i}") for i in range(n + 1, last + 1)):
        e.fail(f"a {e.name} with mid-side GRIDs (G{n + 1}-G{last}, {last} nodes) is not "
               f"supported; give the {n} corners only")  # fmt: skip
    pid = p.id()
    if pid not in materials:
        materials[pid] = _material(ctx, p)
    if e.name == "CHEXA" and pid not in integration:
        integration[pid] = ctx.refusals.guard(lambda: _default_integration(p))
    if materials[pid] is None or integration.get(pid, True) is None:
        return
    out[1].append([e.int(f"G{i}", positive=True) for i in range(1, n + 1)])
    out[0].append((e, pid))


def _default_integration(p) -> bool:
    """True when a CHEXA's PSOLID leaves IN and ISOP blank, Nastran's default brick, the one
    ``fe.elements.hexa`` forms (checked on MSC's and NX's solutions with both blank); else its
    card is refused.  IN names an integration network (0 BUBBLE, 1 GAUSS, 2 TWO, 3 THREE: a
    given one may drop the bubble functions), ISOP a scheme, neither checked here."""
    given = [f"{f} {p[f]}" for f in ("IN", "ISOP") if not p.is_blank(f)]
    if given:
        p.fail(f"{', '.join(given)}: a CHEXA is read with the default integration only (IN and "
               "ISOP blank)")  # fmt: skip
    return True


def _material(ctx: Context, p):
    """(E, NU, RHO x WTMASS, part name) of a PSOLID, or None when it is refused (recorded once,
    with the PSOLID's or the MAT1's card)."""

    def read():
        if str(p["FCTN"]).strip().upper() != "SMECH":
            p.fail(f"FCTN {p['FCTN']}: only a structural solid (SMECH) is supported")
        mid = p.int("MID", positive=True)
        m = mat1(ctx, mid, p)
        if not -1 < m.NU < 0.5:
            p.fail(f"MAT1 {mid}: NU = {m.NU:.4g} (given, or from E and G) is outside (-1, 0.5), "
                   "which a solid cannot take")  # fmt: skip
        return m.E, m.NU, m.RHO * ctx.wtmass, f"PSOLID {p.id()}"

    return ctx.refusals.guard(read)


def _rows(ctx: Context, cards: list, ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """((n, 4) grid rows of the cards' corners, (n,) True where all four GRIDs exist); a card
    naming a missing GRID is refused by name (``Grids.index``)."""
    known = ctx.grids.ids
    rows = np.clip(np.searchsorted(known, ids), 0, max(len(known) - 1, 0))
    found = known[rows] == ids if len(known) else np.zeros(ids.shape, bool)
    for i in np.flatnonzero(~found.all(axis=1)):
        ctx.refusals.guard(ctx.grids.index, ids[i], cards[i][0])
    return rows, found.all(axis=1)


def solids(family: type, elements: tuple, parts: tuple, lumped: bool):
    """(the ``family`` (``Tetrahedra`` or ``Hexahedra``) of ``elements``, the parts extended
    with their names): ``elements`` = (nodes (n, k), corners (n, k, 3), the PSOLIDs' E, NU,
    RHO (p, 3), their part names (p,), each element's PSOLID (n,)); ``lumped``: PARAM COUPMASS
    < 1 (each family's lumping rule)."""
    nodes, corners, values, part_names, which = elements
    names = list(parts) + [n for n in part_names if n not in parts]
    part = np.array([names.index(n) for n in part_names], dtype=np.int64)[which]
    solid = family(nodes=nodes.astype(np.int64), corners=corners.astype(float),
                   E=values[which, 0], nu=values[which, 1], rho=values[which, 2],
                   lumped=np.full(len(which), bool(lumped)), part=part)  # fmt: skip
    return solid, tuple(names)
