"""Structured quad meshes of the exhaust's closed shell bodies (catalyst, mufflers): an oval
(elliptic) mantle along x with flat or conical oval end caps and flat internal baffles, each cap or
baffle pierced by a circular hole of the pipe's radius (centred; the caps' may be off-centre).
Arrays only, no FE objects.

Coordinates: body axis along +x from ``x0``, centre line at (y0, z0); the oval has semi-axes
a = width / 2 along y and b = height / 2 along z.  Node (k, i) of a disc (cap or baffle) sits at
parametric angle phi_k = 2 pi k / n_circ on ring i, interpolated between the hole circle (i = 0,
radius r0 about c) and the oval (i = n_ring): p = (1 - s_i) (c + r0 (cos, sin)) + s_i (a cos,
b sin), c the hole's offset (0 for baffles and centred caps), with the
rings graded geometrically so the elements near the hole are not needle-thin.  The mantle uses the
same angles, so a disc's outer ring and the mantle's ring at that station coincide and the FE
builder merges them (shared DOFs, a welded seam).
"""

from dataclasses import dataclass

import numpy as np

#: axial and radial element size over the circumferential one: the fields along the body are
#: smoother than around it (measured: 2 changes the 12 modes by < 0.1 % against 1)
ASPECT = 2.0


@dataclass(frozen=True)
class OvalBodyMesh:
    """One closed shell body.  nodes (N, 3) [m]; quads (nq, 4) node numbers; surface (nq,) int:
    0 = mantle, 1 = end cap, 2 = baffle; ``holes`` (n_disc, n_circ) node numbers of each disc's
    hole ring (caps first: inlet cap, outlet cap, then baffles in x order); ``stations`` (n_st,)
    x of the mantle rings [m]; ``rings`` (n_st, n_circ) node numbers of the mantle rings."""

    nodes: np.ndarray
    quads: np.ndarray
    surface: np.ndarray
    holes: np.ndarray
    stations: np.ndarray
    rings: np.ndarray


def oval_perimeter(width: float, height: float) -> float:
    """Perimeter of the oval [m] (Ramanujan's approximation, 1e-5 relative here)."""
    a, b = 0.5 * width, 0.5 * height
    return float(np.pi * (3 * (a + b) - np.sqrt((3 * a + b) * (a + 3 * b))))


def _grid(n1: int, n2: int, index: np.ndarray) -> np.ndarray:
    """(n1 n2, 4) quads on node numbers index (n1 + 1, n2 + 1)."""
    i, j = np.meshgrid(np.arange(n1), np.arange(n2), indexing="ij")
    i, j = i.ravel(), j.ravel()
    return np.stack([index[i, j], index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]], axis=1)


def axial_stations(length: float, size: float, fixed, discs=(), layer: float = 0.0) -> np.ndarray:
    """Mantle ring positions in [0, length] [m]: every ``fixed`` position (baffles, sensors),
    uniform subdivisions of at most ``size`` between consecutive fixed positions, and near each
    position of ``discs`` (caps, baffles) extra rings at ``layer`` x (1, 2, 4, ...) below
    ``size / 2`` (the mantle's bending boundary layer at a welded disc, ~ sqrt(R t) wide)."""
    knots = np.unique(np.concatenate([[0.0, length], np.asarray(fixed, dtype=float)]))
    parts = [
        np.linspace(lo, hi, int(np.ceil((hi - lo) / size - 1e-9)) + 1)[:-1]
        for lo, hi in zip(knots[:-1], knots[1:], strict=True)
    ]
    st = np.concatenate([*parts, [length]])
    for d in discs if layer > 0 else ():
        for step in (layer, -layer):
            st = _add_layer(st, d, step, size, knots)
    return st


def ring_fractions(r0, width, height, n_circ, size, layer=0.0) -> np.ndarray:
    """(n_ring + 1,) interpolation fractions s from the hole (0) to the oval (1), geometrically
    graded: mean ring radius grows by a constant factor, with n_ring chosen so the radial element
    size is at most ``size`` and at most the circumferential size; with ``layer`` > 0 extra
    rings at ``layer`` x (1, 2, 4, ...) inside the oval (the weld to the mantle)."""
    rm = 0.25 * (width + height)
    by_size = np.ceil((rm - r0) / size)
    by_aspect = np.ceil(np.log(rm / r0) / np.log1p(2 * np.pi / n_circ))
    n_ring = int(max(2, by_size, by_aspect))
    radius = r0 * (rm / r0) ** (np.arange(n_ring + 1) / n_ring)
    s = (radius - r0) / (rm - r0)
    if layer > 0:
        s = _add_layer(s, 1.0, -layer / (rm - r0), s[-1] - s[-2])
    return s


def _add_layer(x, at, step, spacing, protected=()) -> np.ndarray:
    """``x`` (sorted) with points at ``at + step * (1, 2, 4, ...)`` while |offset| < spacing / 2,
    dropping the old points that come closer than |step| / 2 to a new one; a new point that
    close to a ``protected`` one (baffles, sensor rings) is dropped instead."""
    k = np.arange(max(0, int(np.floor(np.log2(0.5 * spacing / abs(step)))) + 1))
    new = at + step * 2.0**k
    new = new[(new > min(x[0], x[-1])) & (new < max(x[0], x[-1]))]
    prot = np.asarray(protected, dtype=float)
    if prot.size:
        new = new[np.min(np.abs(new[:, None] - prot[None]), axis=1) >= 0.5 * abs(step)]
    keep = np.min(np.abs(x[:, None] - new[None]), axis=1, initial=np.inf) >= 0.5 * abs(step)
    return np.sort(np.concatenate([x[keep], new]))


def _disc_points(s, phi, semi_axes, hole, centre, x) -> np.ndarray:
    """(n_ring n_c, 3) nodes of a cap or baffle [m] inside its mantle ring: rings at fractions
    ``s`` (n_ring + 1,) from the hole (semi-axes ``hole`` (2,), centred at ``centre`` (2,)) to the
    mantle (semi-axes ``semi_axes``), at angles ``phi`` (n_c,), axial positions ``x`` (n_ring,)
    (the outermost ring, the mantle's own, is left out)."""
    (a, b), (ry, rz), (oy, oz) = semi_axes, hole, centre
    cos, sin = np.cos(phi), np.sin(phi)
    disc_y = (1 - s)[:, None] * (ry * cos + oy) + s[:, None] * a * cos  # (n_ring + 1, n_c)
    disc_z = (1 - s)[:, None] * (rz * sin + oz) + s[:, None] * b * sin
    xs = np.repeat(x, phi.size)
    return np.stack([xs, disc_y[:-1].ravel(), disc_z[:-1].ravel()]).T


def oval_body(
    width,
    height,
    length,
    r0,
    n_c,
    baffles=(),
    x0=(0.0, 0.0, 0.0),
    fixed=(),
    cone=0.0,
    offset=None,
    collar=None,
):
    """``OvalBodyMesh`` of a closed oval body: mantle from x0 to x0 + length, two end caps and
    baffles at the axial positions ``baffles`` [m from x0], all with a hole of radius ``r0`` [m];
    element size about ``size`` [m]; ``fixed`` extra mantle ring positions [m from x0].
    ``cone`` [m]: the caps' hole rings stand that far out of the mantle's ends (conical caps, as
    on a catalyst can; 0 = flat caps).  ``offset`` (2,) [m]: (y, z) of both caps' hole centres
    from the body axis (off-centre pipes; None = centred); the baffles' holes stay centred.
    ``collar`` (2,) [m]: semi-axes (y, z) of the inlet cap's hole ring (an oval collar welded
    around the pipe; None = the circle of radius ``r0``)."""
    x0 = np.asarray(x0, dtype=float)
    size = ASPECT * oval_perimeter(width, height) / n_c
    layer = size / (4 * ASPECT)
    phi = 2 * np.pi * np.arange(n_c) / n_c
    cos, sin = np.cos(phi), np.sin(phi)
    a, b = 0.5 * width, 0.5 * height
    st = axial_stations(length, size, [*baffles, *fixed], [0.0, length, *baffles], layer)
    # mantle: ring j at station st[j], node number j * n_c + k
    mantle = np.stack(
        [np.repeat(st, n_c), np.tile(a * cos, len(st)), np.tile(b * sin, len(st))], axis=1
    )
    rings = np.arange(len(st) * n_c).reshape(len(st), n_c)
    wrap = np.concatenate([rings, rings[:, :1]], axis=1)  # (n_st, n_c + 1), closed around
    quads = [_grid(len(st) - 1, n_c, wrap)]
    surface = [np.zeros(len(quads[0]), int)]
    s = ring_fractions(r0, width, height, n_c, size, layer)
    cy, cz = (0.0, 0.0) if offset is None else offset
    nodes, holes = [mantle], []
    n_next = len(mantle)
    disc_x = [0.0, length, *sorted(baffles)]
    for d, xd in enumerate(disc_x):
        j = int(np.argmin(np.abs(st - xd)))
        inner = n_next + np.arange((len(s) - 1) * n_c).reshape(len(s) - 1, n_c)
        index = np.concatenate([inner, rings[j][None]], axis=0)  # outer ring = mantle ring
        index = np.concatenate([index, index[:, :1]], axis=1)
        q = _grid(len(s) - 1, n_c, index)
        quads.append(q[:, ::-1] if d == 0 else q)  # inlet cap faces -x
        surface.append(np.full(len(q), 1 if d < 2 else 2))
        rise = {0: -cone, 1: cone}.get(d, 0.0) * (1 - s[:-1])  # conical caps
        oy, oz = (cy, cz) if d < 2 else (0.0, 0.0)
        hole = collar if (d == 0 and collar is not None) else (r0, r0)
        nodes.append(_disc_points(s, phi, (a, b), hole, (oy, oz), xd + rise))
        holes.append(inner[0])
        n_next += inner.size
    xyz = np.concatenate(nodes) + x0
    return OvalBodyMesh(
        xyz, np.concatenate(quads), np.concatenate(surface), np.array(holes), st + x0[0], rings
    )
