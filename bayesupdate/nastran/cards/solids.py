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

from bayesupdate.nastran.cards.common import Context, mat1

#: the cards this file converts (``cards.FAMILIES``)
CARDS = ("CTETRA", "PSOLID")
#: a corner volume below this fraction of the cube of the longest edge is a flat element
FLAT = 1e-10


def add(ctx: Context) -> None:
    """Each CTETRA as a record (nodes, E, NU, RHO x WTMASS, part "PSOLID pid"); the
    ``fe.elements.tetra.Tetrahedra`` of all of them joins the built structure
    (``Context.finishers``)."""
    records = []
    ctx.each(("CTETRA",), lambda ctx, e: records.append(_record(ctx, e)))
    if records:
        ctx.finishers.append(lambda parts: tetrahedra(records, parts, ctx.lumped))


def _record(ctx: Context, e) -> tuple:
    p = ctx.prop(e, ("PSOLID",))
    if any(not e.is_blank(f"G{i}") for i in range(5, 11)):
        e.fail("a CTETRA with mid-side GRIDs (G5-G10, ten nodes) is not supported; give the "
               "four corners only")  # fmt: skip
    if str(p["FCTN"]).strip().upper() != "SMECH":
        p.fail(f"FCTN {p['FCTN']}: only a structural solid (SMECH) is supported")
    mid = p.int("MID", positive=True)
    m = mat1(ctx, mid, p)
    if not -1 < m.NU < 0.5:
        e.fail(f"MAT1 {mid}: NU = {m.NU:.4g} (given, or from E and G) is outside (-1, 0.5), "
               "which a solid cannot take")  # fmt: skip
    rows = ctx.rows(e, ("G1", "G2", "G3", "G4"))
    corners = ctx.grids.xyz[rows]
    edges = corners[:, None] - corners[None]
    longest = np.sqrt(np.max(np.einsum("abi,abi->ab", edges, edges)))
    volume = abs(np.linalg.det(corners[1:] - corners[0])) / 6.0
    if len(set(rows.tolist())) < 4 or not volume > FLAT * longest**3:
        e.fail(f"its four corners span no volume ({volume:.3g} for edges up to {longest:.3g})")
    return ctx.node[rows], m.E, m.NU, m.RHO * ctx.wtmass, f"PSOLID {p.id()}"


def tetrahedra(records: list, parts: tuple, lumped: bool):
    """(``Tetrahedra``, the parts extended with their names) of (nodes (4,), E, NU, RHO, part
    name) records; ``lumped``: mass a quarter at each corner (PARAM COUPMASS < 1)."""
    from bayesupdate.fe.elements.tetra import Tetrahedra

    names = list(parts)
    for *_, name in records:
        if name not in names:
            names.append(name)
    n = len(records)
    solids = Tetrahedra(
        nodes=np.array([r[0] for r in records], dtype=np.int64),
        E=np.array([r[1] for r in records], dtype=float),
        nu=np.array([r[2] for r in records], dtype=float),
        rho=np.array([r[3] for r in records], dtype=float),
        lumped=np.full(n, bool(lumped)),
        part=np.array([names.index(r[4]) for r in records], dtype=np.int64),
    )
    return solids, tuple(names)
