"""Coordinate systems and GRID positions and displacement frames of a deck, in basic coordinates.

MSC Nastran Quick Reference Guide, CORD1R/C/S, CORD2R/C/S and GRID: a CORD2x is given by its
origin A, a point B on its z axis and a point C in its x-z plane, in the coordinates of its
reference system RID; a CORD1x by three GRIDs (the same roles), and a CORD1x card may define a
second system in fields 6-9 (CIDB, G1B, G2B, G3B).  A GRID's position is in its
CP system ((x, y, z), cylindrical (R, theta [deg], z) or spherical (R, theta [deg], phi [deg]),
theta of a sphere from its z axis) and its displacements in its CD system.  Systems and grids
that refer to one another are resolved in rounds until nothing changes; what is left refers to
a missing system or a cycle and is refused.  Each grid carries R (3, 3) whose rows are its CD
axes in basic coordinates (for a cylindrical or spherical CD, the local axes at the grid).
"""

from dataclasses import dataclass, replace

import numpy as np

from bayesupdate.fe import frames
from bayesupdate.fe.frames import CoordinateFrame

_KIND = {"R": "rectangular", "C": "cylindrical", "S": "spherical"}
CORDS = ("CORD2R", "CORD2C", "CORD2S", "CORD1R", "CORD1C", "CORD1S")


@dataclass(frozen=True)
class Coord:
    """A resolved coordinate system: kind ('rectangular', ...), origin (3,), axes (3, 3) rows =
    its x, y, z unit axes in basic."""

    cid: int
    kind: str
    origin: np.ndarray
    axes: np.ndarray

    def to_basic(self, x) -> np.ndarray:
        """Basic coordinates (n, 3) of points given in this system's own coordinates (n, 3)."""
        x = np.atleast_2d(np.asarray(x, dtype=float))
        if self.kind == "cylindrical":
            t = np.radians(x[:, 1])
            x = np.stack([x[:, 0] * np.cos(t), x[:, 0] * np.sin(t), x[:, 2]], 1)
        elif self.kind == "spherical":
            t, p = np.radians(x[:, 1]), np.radians(x[:, 2])
            r = x[:, 0]
            x = np.stack([r * np.sin(t) * np.cos(p), r * np.sin(t) * np.sin(p), r * np.cos(t)], 1)
        return self.origin + x @ self.axes

    def axes_at(self, xyz) -> np.ndarray:
        """(n, 3, 3) rows = the system's local axes at basic points xyz (n, 3) (``fe.frames``)."""
        return frames.axes_at(self.kind, self.origin, self.axes, xyz)


BASIC = Coord(0, "rectangular", np.zeros(3), np.eye(3))


def _from_points(card, cid, kind, a, b, c) -> Coord:
    try:
        f = CoordinateFrame.from_points(kind, a, b, c)
    except Exception as exc:  # the builder's own message: collinear points
        card.fail(str(exc).split(": ", 1)[-1])
    return Coord(cid, kind, np.asarray(f.origin, float), np.asarray(f.axes, float))


@dataclass(frozen=True)
class Grids:
    """ids (n,) GRID ids, sorted; xyz (n, 3) basic coordinates [deck length]; cd (n,) CD ids;
    frame (n, 3, 3) rows = CD axes in basic; ps (n,) permanent single-point constraints
    (component digits as str, '' for none); cards {GRID id: card} (for file:line)."""

    ids: np.ndarray
    xyz: np.ndarray
    cd: np.ndarray
    frame: np.ndarray
    ps: tuple[str, ...]
    coords: dict

    def index(self, ids, what) -> np.ndarray:
        """Row of each GRID id in ``ids`` (any shape); ``CardError`` naming ``what`` (a card or
        text) when one is missing."""
        from bayesupdate.errors import BayesUpdateError

        ids = np.asarray(ids, dtype=np.int64)
        if not len(self.ids):
            pos = np.zeros(ids.shape, np.int64)
            bad = np.ones(ids.shape, bool)
        else:
            pos = np.clip(np.searchsorted(self.ids, ids), 0, len(self.ids) - 1)
            bad = self.ids[pos] != ids
        if np.any(bad):
            missing = int(ids[bad].ravel()[0])
            if hasattr(what, "fail"):
                what.fail(f"GRID {missing} does not exist")
            raise BayesUpdateError(f"{what}: GRID {missing} does not exist")
        return pos

    def is_basic(self, rows) -> np.ndarray:
        """(k,) True where the grid's CD axes are the basic axes."""
        return np.all(np.abs(self.frame[rows] - np.eye(3)) < 1e-9, axis=(1, 2))


def read_grids(deck, refusals) -> Grids:
    """``Grids`` of the deck's GRID and CORDxx cards (module docstring); unresolvable ones go
    to ``refusals``."""
    grid_cards = {}
    for c in deck.of("GRID"):
        i = refusals.guard(c.id)
        if i is not None:
            grid_cards.setdefault(i, c)
    coords, xyz = {0: BASIC}, {}
    pending_c = _pending_systems(deck, refusals)
    pending_g = dict(grid_cards)
    progress = True
    while progress and (pending_c or pending_g):
        progress = False
        for cid, card in list(pending_c.items()):
            done = refusals.guard(_coord, card, cid, coords, xyz)
            if done is not False:
                pending_c.pop(cid)
                progress = True
                if done is not None:
                    coords[cid] = done
        for gid, card in list(pending_g.items()):
            cp = refusals.guard(card.int, "CP")
            if cp is None:
                pending_g.pop(gid)
            elif cp in coords:
                point = refusals.guard(lambda c=card: [c.real(k) for k in ("X1", "X2", "X3")])
                if point is not None:
                    xyz[gid] = coords[cp].to_basic(point)[0]
                pending_g.pop(gid)
                progress = True
    for card in list(pending_c.values()) + list(pending_g.values()):
        refusals.card(card, "refers to a coordinate system that is missing or refers back to it")
    return _grids(grid_cards, xyz, coords, refusals)


def _coord(card, cid, coords, xyz):
    """The ``Coord`` of a CORDxx card, or False while what it refers to is not yet resolved."""
    kind = _KIND[card.name[-1]]
    if card.name.startswith("CORD2"):
        rid = card.int("RID")
        if rid not in coords:
            return False
        pts = np.array([[card.real(f"{p}{k}") for k in (1, 2, 3)] for p in "ABC"])
        a, b, c = coords[rid].to_basic(pts)
        return _from_points(card, cid, kind, a, b, c)
    gids = [card.int(k, positive=True) for k in ("G1A", "G2A", "G3A")]
    if not all(g in xyz for g in gids):
        return False
    return _from_points(card, cid, kind, *(xyz[g] for g in gids))


def _pending_systems(deck, refusals) -> dict:
    """{cid: card} of every system the deck's CORDxx cards define (``_systems``).  Two cards
    with one id are refused by the deck's duplicate check; a CORD1x's second system sharing an
    id with any other system is refused here, at the card that repeats the id."""
    out, seconds = {}, set()
    for c in deck.of(*CORDS):
        for k, system in enumerate(refusals.guard(_systems, c) or ()):
            cid = refusals.guard(system.id)
            if cid is None:
                continue
            if cid in out and (k == 1 or cid in seconds):
                refusals.card(system, f"coordinate system {cid} is defined twice")
                continue
            out[cid] = system
            if k == 1:
                seconds.add(cid)
    return out


def _systems(card) -> tuple:
    """The systems a CORDxx card defines, each as a card of its own: a CORD2x one; a CORD1x one
    or two, the second read from fields 6-9 as the first from fields 2-5 (its CIDB as its id,
    the same file and line)."""
    if not card.name.startswith("CORD1") or card.value(4) is None:
        return (card,)
    second = replace(card, raw=card.raw[4:8])
    if second.id() == card.id():
        card.fail(f"CIDB = CIDA = {card.id()}: coordinate system {card.id()} is defined twice")
    return card, second


def _grids(grid_cards, xyz, coords, refusals) -> Grids:
    ids = np.array(sorted(xyz), np.int64)
    pts = np.array([xyz[i] for i in ids], float).reshape(-1, 3)
    cd = np.zeros(len(ids), np.int64)
    ps = []
    for k, gid in enumerate(ids):
        card = grid_cards[int(gid)]
        cd[k] = refusals.guard(card.int, "CD") or 0
        if cd[k] not in coords:
            refusals.card(card, f"CD {cd[k]} is not a coordinate system of the deck")
            cd[k] = 0
        p = card["PS"]
        ps.append("" if p is None else str(p))
    frame = np.broadcast_to(np.eye(3), (len(ids), 3, 3)).copy()
    for cid in np.unique(cd[cd > 0]):
        rows = np.flatnonzero(cd == cid)
        frame[rows] = coords[int(cid)].axes_at(pts[rows])
    return Grids(ids, pts, cd, frame, tuple(ps), coords)


def coordinate(grids: Grids, cid: int, card) -> Coord:
    """The resolved system ``cid`` (0 = basic); refuses ``card`` when there is none."""
    if cid not in grids.coords:
        card.fail(f"coordinate system {cid} does not exist")
    return grids.coords[cid]
