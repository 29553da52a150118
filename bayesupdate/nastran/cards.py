"""Nastran line, point, spring and rigid cards -> ``StructureBuilder`` calls.

Each ``add_*`` takes the reading context (``Context``) and adds one card family.  Beams, rods,
masses and springs are few in a shell deck (hundreds), so they are added card by card; the shells
(thousands) are converted as arrays in ``reader``.  Conventions (MSC Nastran Quick Reference
Guide): components are digits 1-6 in the grid's CD frame; a CBAR/CBEAM orientation vector v lies
in the element's x-y plane; CONM2 inertia is [[I11, -I21, -I31], [-I21, I22, -I32], [-I31, -I32,
I33]]; PARAM COUPMASS < 1 (the default) gives line elements lumped translational mass, half at
each end (the beam then carries stiffness only).
"""

from dataclasses import dataclass, field

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.constraints import parse_components
from bayesupdate.fe.sections import circular_tube, solid_round
from bayesupdate.fe.structure import Material
from bayesupdate.nastran.deck import card_location
from bayesupdate.nastran.frames import Grids, axes_at


@dataclass
class Context:
    """What the card converters share: the pyNastran model, its grids, the structure node of
    each grid row (-1: not in the structure), WTMASS, lumped line mass, notes for the user."""

    model: object
    path: str
    grids: Grids
    node: np.ndarray
    wtmass: float
    lumped: bool
    builder: object
    notes: list = field(default_factory=list)
    beam_shear: list = field(default_factory=list)

    def nodes_of(self, ids, what):
        return self.node[self.grids.index(ids, what)]

    def fail(self, card: str, eid, message: str):
        where = card_location(self.path, card, str(eid))
        raise BayesUpdateError(f"{where}: {card} {eid}: {message}")


def _invariant(mask) -> bool:
    """A component set that is the same in every frame: none or all of 123, none or all of 456."""
    m = np.asarray(mask, bool)
    return bool((m[:3].all() or not m[:3].any()) and (m[3:].all() or not m[3:].any()))


def material(ctx: Context, mid: int, card: str, eid) -> Material:
    """MAT1 ``mid`` as a ``Material`` with density x WTMASS."""
    mat = ctx.model.materials.get(int(mid)) if mid else None
    if mat is None or mat.type != "MAT1":
        ctx.fail(card, eid, f"material {mid} is not a MAT1 (only MAT1 is supported)")
    if not (mat.e and mat.e > 0):
        ctx.fail("MAT1", mid, "needs E > 0")
    # Material needs a density > 0; a massless MAT1 gets a negligible one
    rho = max(float(mat.rho or 0.0) * ctx.wtmass, 1e-300)
    return Material(float(mat.e), float(mat.nu or 0.0), rho, f"MAT1 {mid}")


def density(ctx: Context, mid: int) -> float:
    return float(ctx.model.materials[int(mid)].rho or 0.0) * ctx.wtmass


def _lumped_mass(ctx: Context, nodes, mass_per_length, length, part, inertia=None):
    """Half the line mass (and of the ``inertia`` (3, 3) tensor) at each end node."""
    if mass_per_length > 0:
        J = None if inertia is None else 0.5 * inertia
        for n in nodes:
            ctx.builder.add_point_mass(n, 0.5 * mass_per_length * length, part, J)


def _section(ctx: Context, prop, eid, card):
    """(beam ``Section``, extra mass per length, shear area factor or 0 for the section's own)
    of a PBARL/PBEAML ROD or TUBE.  MSC's ROD uses the shear factor 0.9 (with it the beam_modes
    deck matches MSC to 2e-4 %; Cowper's 0.886 is 0.3 % low on the 4th bending pair)."""
    if prop.type in ("PBAR", "PBEAM"):
        ctx.fail(card, eid, f"{prop.type} {prop.pid} gives a general section (A, I1, I2, J); the "
                 "beam element takes PBARL/PBEAML ROD or TUBE sections only")  # fmt: skip
    dims = np.atleast_2d(np.asarray(prop.dim, dtype=float))
    nsm = float(np.max(np.atleast_1d(prop.nsm))) if prop.nsm is not None else 0.0
    if np.ptp(dims, axis=0).max() > 0:
        ctx.fail(card, eid, f"{prop.type} {prop.pid} is tapered; only constant sections")
    d = dims[0]
    if prop.Type == "ROD":
        return solid_round(2 * d[0]), nsm, 0.9
    if prop.Type == "TUBE":
        return circular_tube(2 * d[0], d[0] - d[1]), nsm, 0.0
    ctx.fail(card, eid, f"{prop.type} {prop.pid} type {prop.Type}: only ROD and TUBE sections")


def _orientation(ctx: Context, elem, ga_row):
    """Orientation vector v (3,) in basic coordinates of a CBAR/CBEAM/CBUSH."""
    g = ctx.grids
    if elem.g0:
        return g.xyz[g.index([elem.g0], f"{elem.type} {elem.eid}")[0]] - g.xyz[ga_row]
    v = np.asarray(elem.x, dtype=float)
    offt = getattr(elem, "offt", "GGG") or "GGG"
    return v if offt[0] == "B" else g.frame[ga_row].T @ v


def add_beams(ctx: Context) -> None:
    """CBAR and CBEAM with PBARL/PBEAML ROD or TUBE sections (no offsets, no pin flags).
    Lumped mass (COUPMASS < 1): rho A L / 2 at each end, and for CBEAM also half the torsional
    inertia rho J L about the axis (MSC lumps none for CBAR; the beam_modes torsion mode shows
    it, 3554.909 Hz with against MSC's 3554.923)."""
    for eid, e in sorted(ctx.model.elements.items()):
        if e.type not in ("CBAR", "CBEAM"):
            continue
        if np.any(np.asarray(e.wa, float)) or np.any(np.asarray(e.wb, float)) or e.pa or e.pb:
            ctx.fail(e.type, eid, "offsets (WA, WB) and pin flags (PA, PB) are not supported")
        rows = ctx.grids.index(e.node_ids, f"{e.type} {eid}")
        prop = ctx.model.properties[e.pid]
        section, nsm, shear = _section(ctx, prop, eid, e.type)
        mat = material(ctx, prop.mid, e.type, eid)
        x = ctx.grids.xyz[rows]
        length = np.linalg.norm(x[1] - x[0])
        axis = (x[1] - x[0]) / length
        up = np.cross(axis, _orientation(ctx, e, rows[0]))  # local z = x cross v
        a, b = ctx.node[rows]
        part = f"{prop.type} {prop.pid}"
        ctx.builder.add_beam(a, b, section, mat, part, up=up)
        ctx.beam_shear.append(shear)
        sec = section.properties(mat.poisson)
        line_nsm = nsm * ctx.wtmass
        if not ctx.lumped:
            _lumped_mass(ctx, (a, b), line_nsm, length, part)
            continue
        torsion = None
        if e.type == "CBEAM":
            torsion = mat.density * (sec["Iy"] + sec["Iz"]) * length * np.outer(axis, axis)
        _lumped_mass(ctx, (a, b), mat.density * sec["A"] + line_nsm, length, part, torsion)


def add_rods(ctx: Context) -> None:
    """CROD/CONROD as axial + torsion springs along the element axis, mass lumped at the ends."""
    for eid, e in sorted(ctx.model.elements.items()):
        if e.type not in ("CROD", "CONROD"):
            continue
        p = e if e.type == "CONROD" else ctx.model.properties[e.pid]
        mat = material(ctx, p.mid, e.type, eid)
        rows = ctx.grids.index(e.node_ids, f"{e.type} {eid}")
        x = ctx.grids.xyz[rows]
        length = np.linalg.norm(x[1] - x[0])
        frame = _frame_from_axis((x[1] - x[0]) / length)
        G = mat.youngs_modulus / (2 * (1 + mat.poisson))
        k = np.array([mat.youngs_modulus * p.A, 0, 0, G * (p.j or 0.0), 0, 0]) / length
        a, b = ctx.node[rows]
        part = f"{e.type} {eid}" if e.type == "CONROD" else f"PROD {p.pid}"
        ctx.builder.add_spring(a, b, k, part, frame=frame)
        _lumped_mass(ctx, (a, b), density(ctx, p.mid) * p.A + (p.nsm or 0.0) * ctx.wtmass,
                     length, part)  # fmt: skip


def _frame_from_axis(axis):
    """(3, 3) rows: axis and two unit vectors normal to it."""
    helper = np.eye(3)[np.argmin(np.abs(axis))]
    y = np.cross(axis, helper)
    y /= np.linalg.norm(y)
    return np.stack([axis, y, np.cross(axis, y)])


def add_masses(ctx: Context) -> None:
    """CONM2 (offset and inertia; CID -1, 0 or rectangular) and CONM1 (a rigid-body 6x6)."""
    for eid, m in sorted(ctx.model.masses.items()):
        row = ctx.grids.index([m.nid], f"{m.type} {eid}")[0]
        node = ctx.node[row]
        if m.type == "CONM2":
            R = _mass_frame(ctx, m, eid)
            offset = np.asarray(m.X, float)
            offset = offset - ctx.grids.xyz[row] if m.cid == -1 else R.T @ offset
            i11, i21, i22, i31, i32, i33 = np.asarray(m.I, float)
            J = np.array([[i11, -i21, -i31], [-i21, i22, -i32], [-i31, -i32, i33]])
            J = R.T @ J @ R * ctx.wtmass
            ctx.builder.add_point_mass(node, m.mass * ctx.wtmass, f"CONM2 {eid}", J, offset)
        elif m.type == "CONM1":
            _add_conm1(ctx, m, eid, node, _mass_frame(ctx, m, eid))
        else:
            ctx.fail(m.type, eid, "mass card not supported (CONM2, CONM1 only)")


def _mass_frame(ctx: Context, m, eid):
    if m.cid in (-1, 0, None):
        return np.eye(3)
    coord = ctx.model.coords[m.cid]
    if coord.Type != "R":
        ctx.fail(m.type, eid, f"CID {m.cid} is not rectangular")
    return np.asarray(coord.beta(), float)


def _add_conm1(ctx: Context, m, eid, node, R):
    """CONM1 as a point mass: needs M_tt = m I; offset c from M_tr = -m skew(c)... (module doc)."""
    M = np.asarray(m.mass_matrix, float) * ctx.wtmass
    T = np.kron(np.eye(2), R)
    M = T.T @ M @ T
    mass = M[0, 0]
    if mass <= 0 or not np.allclose(M[:3, :3], mass * np.eye(3), rtol=1e-6, atol=0):
        ctx.fail("CONM1", eid, "only a rigid-body mass (M11 = M22 = M33, no coupling) is supported")
    S = -M[:3, 3:] / mass  # = skew(c)
    c = np.array([S[2, 1], S[0, 2], S[1, 0]])
    from bayesupdate.fe.rotations import skew

    J = M[3:, 3:] - mass * skew(c[None])[0].T @ skew(c[None])[0]
    ctx.builder.add_point_mass(node, mass, f"CONM1 {eid}", J, c)


def add_springs(ctx: Context) -> None:
    """CELAS1/CELAS2 (one component each, in the grids' CD frames) and CBUSH + PBUSH."""
    for eid, e in sorted(ctx.model.elements.items()):
        if e.type in ("CELAS1", "CELAS2"):
            k = ctx.model.properties[e.pid].k if e.type == "CELAS1" else e.k
            _add_celas(ctx, e, eid, float(k))
        elif e.type == "CBUSH":
            _add_cbush(ctx, e, eid)


def _add_celas(ctx: Context, e, eid, k):
    ids = [n for n in e.node_ids if n]
    if len(ids) == 0 or k < 0:
        ctx.fail(e.type, eid, "needs a grid and K >= 0 (scalar points are not supported)")
    rows = ctx.grids.index(ids, f"{e.type} {eid}")
    comps = [int(c or 0) for c in (e.c1, e.c2)][: len(ids)]
    if min(comps) < 1:
        ctx.fail(e.type, eid, "components must be 1-6 (scalar points are not supported)")
    frame = ctx.grids.frame[rows[0]]
    if len(ids) == 2 and (comps[0] != comps[1] or not np.allclose(frame, ctx.grids.frame[rows[1]])):
        ctx.fail(e.type, eid, "the two ends need the same component in the same CD frame")
    stiff = np.zeros(6)
    stiff[comps[0] - 1] = k
    b = ctx.node[rows[1]] if len(ids) == 2 else None
    ctx.builder.add_spring(ctx.node[rows[0]], b, stiff, f"{e.type} {eid}", frame=frame)


def _add_cbush(ctx: Context, e, eid):
    prop = ctx.model.properties[e.pid]
    ids = [n for n in e.node_ids if n]
    rows = ctx.grids.index(ids, f"CBUSH {eid}")
    x = ctx.grids.xyz[rows]
    if e.cid is not None and e.cid >= 0:
        coord = ctx.model.coords[e.cid]
        frame = axes_at(coord, x[:1])[0]
    elif len(ids) == 2 and np.linalg.norm(x[1] - x[0]) > 0:
        axis = (x[1] - x[0]) / np.linalg.norm(x[1] - x[0])
        v = _orientation(ctx, e, rows[0])
        z = np.cross(axis, v)
        z /= np.linalg.norm(z)
        frame = np.stack([axis, np.cross(z, axis), z])
    else:
        ctx.fail("CBUSH", eid, "coincident or grounded CBUSH needs a CID")
    k = np.array([float(v or 0.0) for v in (list(prop.Ki) + [0.0] * 6)[:6]])
    if len(ids) == 2 and np.linalg.norm(x[1] - x[0]) > 0 and np.any(k[[1, 2, 4, 5]] > 0):
        # a lateral or bending spring between separate points needs CBUSH's rigid offsets
        # (moment equilibrium), which the structure's springs do not have
        ctx.fail("CBUSH", eid, "ends apart with lateral or bending stiffness (K2, K3, K5, K6) "
                 "are not supported; make GA and GB coincident")  # fmt: skip
    b = ctx.node[rows[1]] if len(ids) == 2 else None
    ctx.builder.add_spring(ctx.node[rows[0]], b, k, f"PBUSH {e.pid}", frame=frame)


def components(ctx: Context, text, rows, card, eid):
    """Component digits (sorted str) of ``text`` at grids ``rows``; a partial set (not all of
    123 or 456) needs basic CD frames, as the structure's DOFs are in basic axes."""
    mask = parse_components(str(text), f"{card} {eid}")
    if not _invariant(mask) and not np.all(ctx.grids.is_basic(np.atleast_1d(rows))):
        ctx.fail(card, eid, f"components {text} on a grid with a rotated CD frame are not "
                 "supported (use 123, 456 or 123456)")  # fmt: skip
    return "".join(str(i + 1) for i in np.flatnonzero(mask))


def add_rigid(ctx: Context) -> None:
    """RBE2, RBE3 (no UM set) and RBAR (CNA = CMB = 123456)."""
    b = ctx.builder
    for eid, r in sorted(ctx.model.rigid_elements.items()):
        if r.type == "RBE2":
            rows = ctx.grids.index(r.Gmi, f"RBE2 {eid}")
            comps = components(ctx, r.cm, rows, "RBE2", eid)
            b.add_rbe2(ctx.nodes_of([r.gn], f"RBE2 {eid}")[0], ctx.node[rows], comps)
        elif r.type == "RBAR":
            if str(r.cna) != "123456" or str(r.cmb) != "123456" or r.cnb or r.cma:
                ctx.fail("RBAR", eid, "only CNA = 123456, CMB = 123456 is supported")
            ga, gb = ctx.nodes_of([r.ga, r.gb], f"RBAR {eid}")
            b.add_rbe2(ga, [gb], "123456")
        elif r.type == "RBE3":
            _add_rbe3(ctx, r, eid)
        else:
            ctx.fail(r.type, eid, "rigid element not supported (RBE2, RBE3, RBAR only)")


def _add_rbe3(ctx: Context, r, eid):
    if r.Gmi:
        ctx.fail("RBE3", eid, "UM (user-chosen dependent DOFs) is not supported")
    comps = {str(c) for c in r.comps}
    if len(comps) != 1:
        ctx.fail("RBE3", eid, "all weight groups need the same components")
    nodes, weights = [], []
    for w, group in zip(r.weights, r.Gijs, strict=True):
        nodes += list(group)
        weights += [float(w)] * len(group)
    rows = ctx.grids.index(nodes, f"RBE3 {eid}")
    ref = ctx.grids.index([r.refgrid], f"RBE3 {eid}")
    node_c = components(ctx, comps.pop(), rows, "RBE3", eid)
    ref_c = components(ctx, r.refc, ref, "RBE3", eid)
    ctx.builder.add_rbe3(ctx.node[ref[0]], ctx.node[rows], weights, ref_c, node_c)
