"""CTETRA (four GRIDs) with PSOLID and an isotropic MAT1 as ``fe.elements.tetra`` elements (MSC
Nastran QRG CTETRA, PSOLID).

A four-node CTETRA is the constant-strain tetrahedron in every code: its stiffness has no
integration or formulation option (PSOLID IN, ISOP and STRESS change nothing for it) and its
lumped mass is a quarter at each corner.  Refused, each naming its card: a CTETRA with
mid-side GRIDs (G5-G10, the ten-node element), a PSOLID whose FCTN is not SMECH (a fluid), a
MAT1 whose NU (given, or from E and G) is outside (-1, 0.5) or that has no E, a corner
repeated or four corners in one plane.  PSOLID CORDM (the material frame) is read and has no
effect on an isotropic material.
"""

import numpy as np

from bayesupdate.fe.elements.tetra import Tetrahedra, volumes
from bayesupdate.nastran.cards.common import Context, mat1

#: the cards this file converts (``cards.FAMILIES``)
CARDS = ("CTETRA", "PSOLID")
#: a corner volume below this fraction of the cube of the longest edge is a flat element
FLAT = 1e-10


def add(ctx: Context) -> None:
    """The CTETRA cards as records (nodes, E, NU, RHO x WTMASS, part "PSOLID pid"); the
    ``fe.elements.tetra.Tetrahedra`` of all of them joins the built structure
    (``Context.finishers``).  Each card's fields are read once; its GRIDs, volume and material
    are then found for all cards together (a material once per PSOLID), and a card with a
    missing GRID or no volume is refused by name."""
    cards, grid_ids, materials = [], [], {}
    ctx.each(("CTETRA",), lambda ctx, e: _fields(ctx, e, cards, grid_ids, materials))
    if not cards:
        return
    ids = np.array(grid_ids, dtype=np.int64)
    rows, found = _rows(ctx, cards, ids)
    corners = ctx.grids.xyz[rows]
    edges = corners[:, :, None] - corners[:, None]
    longest = np.sqrt(np.einsum("eabi,eabi->eab", edges, edges).max(axis=(1, 2)))
    volume = volumes(corners)
    repeated = np.sort(ids, axis=1)
    flat = (volume <= FLAT * longest**3) | np.any(repeated[:, 1:] == repeated[:, :-1], axis=1)
    for i in np.flatnonzero(flat & found):
        ctx.refusals.guard(lambda i=i: cards[i][0].fail(
            f"its four corners span no volume ({volume[i]:.3g} for edges up to {longest[i]:.3g})"
        ))  # fmt: skip
    keep = np.flatnonzero(found & ~flat)
    records = [(ctx.node[rows[i]], corners[i], *materials[cards[i][1]]) for i in keep]
    if records:
        ctx.finishers.append(lambda parts: tetrahedra(records, parts, ctx.lumped))


def _fields(ctx: Context, e, cards: list, grid_ids: list, materials: dict) -> None:
    """A CTETRA's corner GRID ids and PSOLID, its material completed once per PSOLID
    ((E, NU, RHO x WTMASS, part name) in ``materials``); refused with its card where the card
    or its PSOLID or MAT1 cannot be used."""
    p = ctx.prop(e, ("PSOLID",))
    if any(not e.is_blank(f"G{i}") for i in range(5, 11)):
        e.fail("a CTETRA with mid-side GRIDs (G5-G10, ten nodes) is not supported; give the "
               "four corners only")  # fmt: skip
    pid = p.id()
    if pid not in materials:
        materials[pid] = _material(ctx, p)
    if materials[pid] is None:
        return
    grid_ids.append([e.int(f"G{i}", positive=True) for i in range(1, 5)])
    cards.append((e, pid))


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


def tetrahedra(records: list, parts: tuple, lumped: bool):
    """(``Tetrahedra``, the parts extended with their names) of (nodes (4,), corners (4, 3),
    E, NU, RHO, part name) records; ``lumped``: mass a quarter at each corner (PARAM COUPMASS
    < 1)."""
    names = list(parts)
    for *_, name in records:
        if name not in names:
            names.append(name)
    n = len(records)
    solids = Tetrahedra(
        nodes=np.array([r[0] for r in records], dtype=np.int64),
        corners=np.array([r[1] for r in records], dtype=float),
        E=np.array([r[2] for r in records], dtype=float),
        nu=np.array([r[3] for r in records], dtype=float),
        rho=np.array([r[4] for r in records], dtype=float),
        lumped=np.full(n, bool(lumped)),
        part=np.array([names.index(r[5]) for r in records], dtype=np.int64),
    )
    return solids, tuple(names)
