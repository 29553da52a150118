"""Scalar points (SPOINT) and the ends of scalar elements (CELAS1-4, CMASS1-4), MSC Nastran QRG.

An SPOINT is one degree of freedom with no geometry; CELASi / CMASSi join two "points" (a GRID
with a component 1-6 in its CD frame, or a scalar point with component 0 or blank), or one point
and ground (id 0 or blank), with k [[1, -1], [-1, 1]] (or m) on the two scalar coordinates.

Representation (``StructureBuilder`` public methods only).  The structure's DOFs are the six of
a node, and its rigid-body modes are the zero-energy combinations of the node motions a rigid
body allows (``fe.sparse_modal``), so a scalar point is a node whose single free DOF takes, in
every rigid-body motion, the value the springs ask of it in a zero-energy mode:

* a cluster of scalar points (joined by springs among themselves) with springs to a GRID
  component (G, c) is placed at G, with G's CD frame, its free DOF component c; its other five
  components follow G rigidly (one RBE2: dependent DOFs do not restrict the rigid motions, as a
  held DOF would).  A zero-energy mode has every spring unstretched, so the points equal G's
  component c: the very value the embedding gives them.
* a cluster with no spring to a GRID (a scalar-only system) is placed at the origin with its
  free DOF along x and its other five components held: the only rigid motion left is "all
  points equal", the cluster's own zero-energy mode when no spring grounds it.

A spring between two points on one physical DOF direction e (same component in the same CD
frame, or components of two frames that name the same axis) acts on the structure's axis of both
(``StructureBuilder.add_spring`` on the nodes' own DOFs: k (e . u_A - e . u_B)^2).  Two unlike
DOFs (C1 = 1 of one grid, C2 = 5 of another, or a scalar point placed along another direction)
make a scalar spring k (d_A . u_A - d_B . u_B)^2 (``fe.elements.scalar_spring``, ``springs``);
a cluster sprung to several GRID components is placed at the first (by element id), and its
springs to the others are scalar springs.  Masses likewise take a direction at each end
(``add_scalar_mass``).

A scalar point carries no rigid-body mass (MSC's grid point weight generator uses grids only):
``scalar_point_rigid_mass`` is the share the embedding gives the scalar masses on scalar points
in R^T M R, which ``NastranModel`` removes from its mass properties.

Ids: scalar points and GRIDs share one id space (an SPOINT with a GRID's id is refused).  MSC
also creates a scalar point for any CELAS/CMASS id that is no GRID; here such an id is refused
("GRID or SPOINT k does not exist"): a mistyped GRID id would otherwise become a silent,
disconnected scalar point.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.fe.frames import CoordinateFrame
from bayesupdate.nastran.bulk import CardError
from bayesupdate.nastran.cards.common import Context, _by_id, id_list

#: the cards this file converts (``cards.FAMILIES``): scalar points, made before any element
CARDS = ("SPOINT",)
#: the scalar elements: (name, their point fields: (id field, component field or None))
SCALAR_ENDS = {
    "CELAS1": (("G1", "C1"), ("G2", "C2")), "CELAS2": (("G1", "C1"), ("G2", "C2")),
    "CMASS1": (("G1", "C1"), ("G2", "C2")), "CMASS2": (("G1", "C1"), ("G2", "C2")),
    "CELAS3": (("S1", None), ("S2", None)), "CELAS4": (("S1", None), ("S2", None)),
    "CMASS3": (("S1", None), ("S2", None)), "CMASS4": (("S1", None), ("S2", None)),
}  # fmt: skip
SPRINGS = ("CELAS1", "CELAS2", "CELAS3", "CELAS4")


@dataclass(frozen=True)
class End:
    """One end of a scalar element: structure ``node``, ``comp`` 1-6 in ``frame`` (3, 3) (rows:
    the axes in basic), ``spoint`` id (None on a GRID), ``label`` for messages."""

    node: int
    comp: int
    frame: np.ndarray
    spoint: int | None
    label: str

    @property
    def direction(self) -> np.ndarray:
        """(6,) the DOF's unit vector on the node's six global DOFs."""
        d = np.zeros(6)
        block = 3 * ((self.comp - 1) // 3)
        d[block : block + 3] = self.frame[(self.comp - 1) % 3]
        return d


def add(ctx: Context) -> None:
    """The scalar points the scalar elements use, as nodes (module docstring): ``ctx.spoints``
    {SPOINT id: ``End``}."""
    declared = _declared(ctx)
    used = {}
    for card in _scalar_cards(ctx):
        for gid, _ in _raw_ends(card):
            if gid in declared:
                used.setdefault(gid, card)
    parent = {s: s for s in used}
    anchors: dict[int, list] = {}
    for card in _scalar_cards(ctx, SPRINGS):
        if not _positive(ctx, card):
            continue
        points = [(g, c) for g, c in _raw_ends(card) if g in used]
        grids = [(g, int(c)) for g, c in _raw_ends(card)
                 if g not in declared and g in ctx.grids_set and c in range(1, 7)]  # fmt: skip
        if len(points) == 2:
            parent[_root(parent, points[0][0])] = _root(parent, points[1][0])
        elif len(points) == 1 and grids:
            anchors.setdefault(points[0][0], []).append(grids[0])
    clusters: dict[int, list] = {}
    for s in sorted(used):
        clusters.setdefault(_root(parent, s), []).append(s)
    for members in clusters.values():
        tied = [a for s in members for a in anchors.get(s, [])]
        _embed(ctx, members, tied[0] if tied else None, used)
    unused = sorted(set(declared) - set(used))
    ctx.unused_spoints = set(unused)
    if unused:
        ctx.notes.append(f"{len(unused)} SPOINT(s) used by no element were dropped (AUTOSPC)")


def _declared(ctx: Context) -> dict[int, object]:
    """{SPOINT id: its card} of the deck's SPOINT cards (THRU lists expanded); an id that is
    also a GRID's is refused."""
    out = {}
    for card in ctx.spoint_cards:
        for sid in ctx.refusals.guard(id_list, card, 0) or []:
            if sid <= 0:
                ctx.refusals.card(card, f"SPOINT id {sid}: give ids > 0")
            elif sid in ctx.grids_set:
                ctx.refusals.card(card, f"SPOINT {sid} is also a GRID id (GRID and SPOINT ids "
                                  "are one id space)")  # fmt: skip
            else:
                out.setdefault(sid, card)
    return out


def _scalar_cards(ctx: Context, names=tuple(SCALAR_ENDS)) -> list:
    return [c for _, c in sorted(ctx.elements.items(), key=_by_id) if c.name in names]


def _raw_ends(card) -> list[tuple[int, object]]:
    """[(id, component or None)] of a scalar element's non-grounded ends, as written (fields
    that cannot be read are left to the element's converter to refuse)."""
    out = []
    for gfield, cfield in SCALAR_ENDS[card.name]:
        try:
            gid = card[gfield]
            comp = card[cfield] if cfield else None
        except CardError:
            continue
        if isinstance(gid, int) and gid > 0:
            out.append((gid, comp))
    return out


def _positive(ctx: Context, card) -> bool:
    """True if a CELAS's K is > 0 (a zero or unreadable spring ties nothing)."""
    try:
        k = ctx.prop(card, ("PELAS",)).real("K") if card.name in ("CELAS1", "CELAS3") \
            else card.real("K")  # fmt: skip
    except CardError:
        return False
    return k > 0


def _root(parent: dict, s: int) -> int:
    while parent[s] != s:
        parent[s] = parent[parent[s]]
        s = parent[s]
    return s


def _embed(ctx: Context, members: list[int], anchor, used: dict) -> None:
    """Nodes of one cluster of scalar points (module docstring): at the GRID ``anchor`` (id,
    component), its other five components tied to it by one RBE2, or, without one, at the
    origin with the other five held."""
    b = ctx.builder
    if anchor is None:
        for s in members:
            node = b.add_node((0.0, 0.0, 0.0))
            b.add_support(node, "23456")
            ctx.spoints[s] = End(node, 1, np.eye(3), s, f"SPOINT {s}")
        return
    gid, comp = anchor
    row = int(ctx.grids.index([gid], used[members[0]])[0])
    xyz, frame = ctx.grids.xyz[row], ctx.grids.frame[row]
    nodes = [b.add_node(xyz) for _ in members]
    if not ctx.grids.is_basic([row])[0]:
        b.set_frame(nodes, CoordinateFrame.from_axes("rectangular", xyz, frame))
    others = "".join(str(k) for k in range(1, 7) if k != comp)
    i = b.add_rbe2(int(ctx.node[row]), nodes, others)
    ctx.rigid[f"rbe2 {i}"] = used[members[0]]
    for s, node in zip(members, nodes, strict=True):
        label = f"SPOINT {s} (component {comp} of GRID {gid}, the GRID it is sprung to)"
        ctx.spoints[s] = End(node, comp, frame, s, label)


def ends(ctx: Context, card) -> list[End]:
    """The non-grounded ends of a scalar element (``SCALAR_ENDS``): GRID components 1-6 in
    their CD frames, scalar points (component 0 or blank); refuses ids that are neither."""
    out = []
    for gfield, cfield in SCALAR_ENDS[card.name]:
        gid = card[gfield]
        if gid is None or gid == 0:
            continue
        if not isinstance(gid, int) or gid < 0:
            card.fail(f"{gfield} = {gid!r}: give a GRID or SPOINT id (0 or blank: ground)")
        comp = card[cfield] if cfield else None
        if gid in ctx.spoints:
            if comp not in (None, 0):
                card.fail(f"{cfield} = {comp!r}: SPOINT {gid} has one DOF (give 0 or blank)")
            out.append(ctx.spoints[gid])
        elif cfield is None:
            what = "is a GRID (CELAS1/2, CMASS1/2 join GRIDs)" if gid in ctx.grids_set \
                else "does not exist"  # fmt: skip
            card.fail(f"{gfield}: SPOINT {gid} {what}")
        elif gid not in ctx.grids_set:
            card.fail(f"{gfield}: GRID or SPOINT {gid} does not exist")
        else:
            out.append(_grid_end(ctx, card, gid, comp, cfield))
    return out


def _grid_end(ctx: Context, card, gid: int, comp, cfield: str) -> End:
    if not isinstance(comp, int) or not 1 <= comp <= 6:
        card.fail(f"{cfield} = {comp!r}: give a component 1-6 of GRID {gid}")
    row = int(ctx.grids.index([gid], card)[0])
    return End(int(ctx.node[row]), comp, ctx.grids.frame[row], None,
               f"component {comp} of GRID {gid}")  # fmt: skip


def rigid_share(structure_nodes: np.ndarray, records) -> np.ndarray:
    """(6, 6) share of the scalar masses on scalar points in R^T M R (R: rigid-body motions
    about the origin, ``fe.mass_properties``) that the embedding gives them and MSC's weight
    generator does not.  records : [(mass, [End, End?])] (mass x WTMASS); an element's rigid
    vector is rho = R^T v, v = (d_A, -d_B) (``add_scalar_mass``), and only its GRID ends
    count in MSC's: the share is m (rho rho^T - rho_g rho_g^T)."""
    out = np.zeros((6, 6))
    for mass, element_ends in records:
        rho, rho_g = np.zeros(6), np.zeros(6)
        for sign, end in zip((1.0, -1.0), element_ends, strict=False):
            r = sign * _rigid_vector(structure_nodes[end.node], end.direction)
            rho += r
            rho_g += 0.0 if end.spoint is not None else r
        out += mass * (np.outer(rho, rho) - np.outer(rho_g, rho_g))
    return out


def _rigid_vector(x: np.ndarray, d: np.ndarray) -> np.ndarray:
    """(6,) R_node^T d: the DOF d's value under the unit rigid motions about the origin, u =
    t + theta x x (3 translations, then 3 rotations)."""
    t, r = d[:3], d[3:]
    return np.concatenate([t, np.cross(x, t) + r])
