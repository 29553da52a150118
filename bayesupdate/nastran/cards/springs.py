"""CELAS1-4 and CBUSH + PBUSH as springs (MSC Nastran QRG); scalar points: ``scalar``.

A CELAS whose two ends are one axis is a spring on the nodes' own DOFs; one between two unlike
DOFs (different components, or directions of different frames) is a scalar spring
(``fe.elements.scalar_spring``), which the reader adds to the built structure.

A PBUSH's K line gives the six stiffnesses along the element axes (CID's, or x from GA to GB);
its M line (MSC: one MASS, the lumped mass of the CBUSH) is translational mass, (1 - S) MASS
at GA and S MASS at GB (QRG PBUSH remark 13; a grounded CBUSH's GB is a grounded terminal, so
only (1 - S) MASS moves); its B and GE lines (damping) do not change real normal
modes and are listed once as ignored.

A CBUSH whose ends are apart acts at its location (S along GA-GB, or S1-S3 in OCID) through
rigid arms from both grids (``StructureBuilder.add_spring(location=...)``, ``fe.elements.spring``),
so
moments balance as in MSC's CBUSH.
"""

import numpy as np

from bayesupdate.nastran.cards import scalar
from bayesupdate.nastran.cards.beams import _orientation
from bayesupdate.nastran.cards.common import Context
from bayesupdate.nastran.frames import coordinate

#: the cards this file converts (``cards.FAMILIES``)
CARDS = ("CELAS1", "CELAS2", "CELAS3", "CELAS4", "CBUSH")


def add(ctx: Context) -> None:
    """CELAS1-4 (a GRID component in its CD frame or a scalar point at each end) and CBUSH +
    PBUSH."""
    ctx.each(("CELAS1", "CELAS2", "CELAS3", "CELAS4"), _add_celas)
    ctx.each(("CBUSH",), _add_cbush)
    ctx.finishers.append(lambda parts: scalar_springs(ctx.scalar_springs, parts))


def _add_celas(ctx: Context, e) -> None:
    """CELAS1-4: k on the two ends' DOFs (``scalar.ends``).  Two ends on one axis (the same
    component in the same CD frame, or two frames' components along one axis), or one end, give
    a spring along it on the nodes' own DOFs, k (e . u_A - e . u_B)^2; two unlike DOFs (C1 = 1
    of one grid, C2 = 5 of another) give a scalar spring k (d_A . u_A - d_B . u_B)^2
    (``fe.elements.scalar_spring``, collected in ``ctx.scalar_springs``)."""
    k = ctx.prop(e, ("PELAS",)).real("K") if e.name in ("CELAS1", "CELAS3") else e.real("K")
    if k < 0:
        e.fail(f"K = {k:g}: a negative spring is not supported")
    points = scalar.ends(ctx, e)
    if not points:
        e.fail("both ends are grounded: give a GRID or SPOINT at one end at least")
    a = points[0]
    b = points[1] if len(points) == 2 else None
    if b is not None and a.node == b.node and np.allclose(a.direction, b.direction):
        e.fail(f"both ends are {a.label} (MSC QRG: the two connection points must be distinct)")
    if b is not None and not np.allclose(a.direction, b.direction):
        ctx.scalar_springs.append((f"{e.name} {e.id()}", k, a, b))
        return
    stiff = np.zeros(6)
    stiff[a.comp - 1] = k
    ctx.builder.add_spring(a.node, None if b is None else b.node, stiff, f"{e.name} {e.id()}",
                           frame=a.frame)  # fmt: skip


def scalar_springs(records: list, parts: tuple):
    """(``ScalarSprings``, the parts extended with their names) of ``ctx.scalar_springs``
    records [(part name, k x 1, End A, End B)]; (None, parts) when there are none."""
    from bayesupdate.fe.elements.scalar_spring import ScalarSprings

    if not records:
        return None, parts
    names = list(parts)
    for name, *_ in records:
        if name not in names:
            names.append(name)
    springs = ScalarSprings(
        nodes=np.array([(a.node, b.node) for _, _, a, b in records], dtype=np.int64),
        direction=np.array([(a.direction, b.direction) for _, _, a, b in records]),
        stiffness=np.array([k for _, k, _, _ in records], dtype=float),
        part=np.array([names.index(name) for name, *_ in records], dtype=np.int64),
    )
    return springs, tuple(names)


def pbush_lines(p) -> dict[str, list]:
    """{keyword: its six values (None where blank)} of a PBUSH (K, B, GE, RCV, M, ...)."""
    out = {}
    for start in range(0, len(p.raw), 8):
        key = p.value(start + 1)
        if isinstance(key, str):
            out[key] = [p.value(start + 2 + k) for k in range(6)]
    return out


def pbush_k(p) -> np.ndarray:
    """(6,) K1-K6 of a PBUSH (blank = 0)."""
    return np.array([float(v or 0.0) for v in pbush_lines(p).get("K", [None] * 6)])


def pbush_mass(p) -> float:
    """MASS of a PBUSH's M line (MSC QRG PBUSH: one value, the lumped mass of the CBUSH; blank
    or no M line: 0).  Six directional masses (another code's PBUSH) are refused."""
    values = pbush_lines(p).get("M", [None] * 6)
    if any(values[1:]):
        p.fail("M line with more than one mass: MSC's PBUSH M has one MASS field")
    mass = float(values[0] or 0.0)
    if mass < 0:
        p.fail(f"MASS = {mass}: give a mass >= 0")
    return mass


def _pbush_note(ctx: Context, p) -> None:
    """A note for the PBUSH lines that do not change real normal modes (B: viscous damping,
    GE: structural damping, RCV: stress recovery)."""
    lines = pbush_lines(p)
    unused = [k for k in ("B", "GE") if any(lines.get(k, []))]
    if unused:
        note = (f"PBUSH {p.id()}: {' and '.join(unused)} (damping) ignored: no effect on real "
                "normal modes")  # fmt: skip
        if note not in ctx.notes:
            ctx.notes.append(note)


def _add_cbush(ctx: Context, e) -> None:
    """A CBUSH: K1-K6 along its element axes (CID's axes; else x from GA to GB and y in the plane
    of x and v), at its location P; ends apart act at P through rigid arms from GA and GB."""
    prop = ctx.prop(e, ("PBUSH",))
    k, mass = pbush_k(prop), pbush_mass(prop)
    _pbush_note(ctx, prop)
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
        z = np.cross(axis, _orientation(ctx.grids, e, rows[0]))
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
    if mass > 0:
        _add_bush_mass(ctx, e, mass * ctx.wtmass, a, b, part)


def _add_bush_mass(ctx: Context, e, mass: float, a, b, part: str) -> None:
    """PBUSH MASS as MSC places it (QRG PBUSH remark 13): translational, the same in the three
    element directions, (1 - S) MASS at GA and S MASS at GB.  A grounded CBUSH's GB is a
    grounded terminal (QRG CBUSH remark 6: a point whose displacement is constrained to zero),
    so only (1 - S) MASS moves, at GA (a note says so).  An OCID offset (MSC splits by
    distances given as formulas we have not checked) is refused rather than guessed."""
    if e.int("OCID") != -1:
        e.fail("PBUSH M with an OCID offset is not supported (give the mass as a CONM2)")
    s = e.real("S")
    if not 0 <= s <= 1:
        e.fail(f"S = {s}: give 0 <= S <= 1")
    ctx.builder.add_point_mass(a, (1 - s) * mass, part)
    if b is not None:
        ctx.builder.add_point_mass(b, s * mass, part)
        return
    ctx.notes.append(
        f"{e.where} CBUSH {e.id()} is grounded: (1 - S) = {1 - s:g} of its PBUSH MASS is at GA, "
        "the rest on the grounded terminal (QRG PBUSH remark 13, CBUSH remark 6)"
    )


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
