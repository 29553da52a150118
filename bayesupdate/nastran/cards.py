"""Nastran line, point, spring and rigid cards -> ``StructureBuilder`` calls.

Each ``add_*`` takes the reading context (``Context``) and adds one card family.  Beams, rods,
masses and springs are few in a shell deck (hundreds), so they are added card by card; the shells
(thousands) are converted as arrays in ``reader``.  Conventions (MSC Nastran Quick Reference
Guide): components are digits 1-6 in the grid's CD frame (a grid whose CD frame turns a partial
component set gets that frame in the structure, ``fe.frames``); a CBAR/CBEAM orientation vector
v lies in the element's x-y plane, its section has I1 about z (plane 1, x-y) and I2 about y, and
its offsets WA, WB run from the grids to the element's ends; CONM2 inertia is [[I11, -I21, -I31],
[-I21, I22, -I32], [-I31, -I32, I33]]; PARAM COUPMASS < 1 (the default) gives line elements
lumped translational mass, half at each end (the element then carries stiffness only);
COUPMASS 1 their consistent mass.  CBAR/CBEAM are ``fe.general_beam`` elements, CROD/CONROD
``fe.rod`` elements.
"""

import re
from dataclasses import dataclass, field, replace

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import standard_sections as ss
from bayesupdate.fe.constraints import parse_components
from bayesupdate.fe.frames import CoordinateFrame
from bayesupdate.fe.standard_sections import general_section
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
    framed: set = field(default_factory=set)

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


def _lumped_mass(ctx: Context, nodes, mass_per_length, length, part, inertia=None, offsets=None):
    """Half the line mass (and of the ``inertia`` (3, 3) tensor) at each end (node + offset)."""
    if mass_per_length > 0:
        J = None if inertia is None else 0.5 * inertia
        off = np.zeros((2, 3)) if offsets is None else offsets
        for n, w in zip(nodes, off, strict=True):
            ctx.builder.add_point_mass(n, 0.5 * mass_per_length * length, part, J, w)


#: PBAR K1/K2 at or above this (pyNastran's stand-in for a blank field) mean rigid in shear
_RIGID_SHEAR = 1e8
#: PBARL/PBEAML shapes read (Nastran DIM order; ``standard_sections`` for the formulas)
L_SECTIONS = ("ROD", "TUBE", "TUBE2", "BAR", "BOX", "I")


def shear_modulus(ctx: Context, mid: int) -> float:
    """MAT1 G (pyNastran fills a blank G with E / 2(1 + nu), as Nastran does)."""
    mat = ctx.model.materials[int(mid)]
    g = mat.g if mat.g else mat.e / (2 * (1 + (mat.nu or 0.0)))
    return float(g)


def _general_section(ctx: Context, prop, eid, card):
    """(``BeamSection``, nsm) of a PBAR or a single-station PBEAM (I1 -> iz, I2 -> iy)."""
    if prop.type == "PBAR":
        a, i1, i2, i12, j, nsm = (
            float(v or 0.0) for v in (prop.A, prop.i1, prop.i2, prop.i12, prop.j, prop.nsm)
        )
        # K1, K2 blank (or ignored because I12 != 0) mean rigid in shear (MSC QRG, PBAR)
        k = [
            0.0 if (v is None or v >= _RIGID_SHEAR or i12) else float(v) for v in (prop.k1, prop.k2)
        ]
    else:
        values = [
            np.atleast_1d(np.asarray(v, float))
            for v in (prop.A, prop.i1, prop.i2, prop.i12, prop.j, prop.nsm)
        ]
        if any(np.ptp(v) > 0 for v in values):
            ctx.fail(card, eid, f"PBEAM {prop.pid} is tapered; only constant sections")
        extras = dict(
            S1=prop.s1,
            S2=prop.s2,
            NSIA=prop.nsia,
            NSIB=prop.nsib,
            CWA=prop.cwa,
            CWB=prop.cwb,
            M1A=prop.m1a,
            M2A=prop.m2a,
            M1B=prop.m1b,
            M2B=prop.m2b,
            N1A=prop.n1a,
            N2A=prop.n2a,
            N1B=prop.n1b,
            N2B=prop.n2b,
        )
        used = [k for k, v in extras.items() if v]
        if used:
            ctx.fail(
                card,
                eid,
                f"PBEAM {prop.pid}: {', '.join(used)} not supported (shear "
                "relief, warping, mass and neutral-axis offsets)",
            )
        a, i1, i2, i12, j, nsm = (float(v[0]) for v in values)
        # PBEAM K1, K2 default 1.0; 0.0 means rigid in shear (MSC QRG, PBEAM)
        k = [float(v or 0.0) for v in (prop.k1, prop.k2)]
    try:
        sec = general_section(a, i2, i1, j, i12, k[0], k[1], name=f"{prop.type} {prop.pid}")
    except BayesUpdateError as exc:
        ctx.fail(card, eid, str(exc))
    return sec, nsm


def _library_section(ctx: Context, prop, eid, card, nu):
    """(``BeamSection``, nsm) of a PBARL/PBEAML of a shape in ``L_SECTIONS``.  Nastran's
    figures have y_elem vertical: the shapes are built with their height along z and turned.
    MSC's ROD uses the shear factor 0.9 (with it the beam_modes deck matches MSC to 2e-4 %;
    Cowper's 0.886 is 0.3 % low on the 4th bending pair); the others use Cowper's (a note)."""
    dims = np.atleast_2d(np.asarray(prop.dim, dtype=float))
    nsm = float(np.max(np.atleast_1d(prop.nsm))) if prop.nsm is not None else 0.0
    if np.ptp(dims, axis=0).max() > 0:
        ctx.fail(card, eid, f"{prop.type} {prop.pid} is tapered; only constant sections")
    d, kind = dims[0], prop.Type
    if kind not in L_SECTIONS:
        ctx.fail(card, eid, f"{prop.type} {prop.pid} type {kind}: only {', '.join(L_SECTIONS)}")
    if kind == "I" and (d[1] != d[2] or d[4] != d[5]):
        ctx.fail(card, eid, f"{prop.type} {prop.pid}: an I with unequal flanges is not supported")
    try:
        if kind == "ROD":
            return replace(ss.rod_section(2 * d[0], nu), shear_y=0.9, shear_z=0.9), nsm
        if kind in ("TUBE", "TUBE2"):
            wall = d[0] - d[1] if kind == "TUBE" else d[1]
            return ss.tube_section(2 * d[0], wall, nu), nsm
        ctx.notes.append(
            f"{prop.type} {prop.pid} {kind}: shear factors of Cowper (1966); "
            "Nastran's own may differ"
        )
        if kind == "BAR":
            return ss.bar_section(d[0], d[1], nu).swap_yz(), nsm
        if kind == "BOX":
            return ss.box_section(d[0], d[1], d[3], d[2], nu).swap_yz(), nsm
        return ss.i_section(d[0], d[1], d[3], d[4], nu).swap_yz(), nsm
    except BayesUpdateError as exc:
        ctx.fail(card, eid, f"{prop.type} {prop.pid}: {exc}")


def _orientation(ctx: Context, elem, ga_row):
    """Orientation vector v (3,) in basic coordinates of a CBAR/CBEAM/CBUSH."""
    g = ctx.grids
    if elem.g0:
        return g.xyz[g.index([elem.g0], f"{elem.type} {elem.eid}")[0]] - g.xyz[ga_row]
    v = np.asarray(elem.x, dtype=float)
    offt = getattr(elem, "offt", "GGG") or "GGG"
    return v if offt[0] == "B" else g.frame[ga_row].T @ v


def _offsets(ctx: Context, e, rows) -> np.ndarray:
    """(2, 3) end offsets WA, WB in basic axes: OFFT 'G' = the end grid's CD frame, 'B' =
    basic (MSC QRG, CBAR/CBEAM); 'O' (element axes) and CBEAM's BIT are not supported."""
    w = np.stack([np.asarray(e.wa, float), np.asarray(e.wb, float)])
    offt = getattr(e, "offt", "GGG")
    if getattr(e, "bit", None) is not None or not isinstance(offt, str):
        ctx.fail(e.type, e.eid, "BIT / a numeric OFFT is not supported (OFFT GGG, BGG, ... only)")
    if not np.any(w):
        return w
    for end in (0, 1):
        if offt[1 + end] == "G":
            w[end] = ctx.grids.frame[rows[end]].T @ w[end]
        elif offt[1 + end] != "B":
            ctx.fail(e.type, e.eid, f"OFFT {offt}: offsets in element axes ('O') are not supported")
    return w


def _builder_message(exc) -> str:
    """A builder error without its 'add_beams (part ...): element k' prefix (the card is named
    instead)."""
    return re.sub(r"^element \d+:? ", "", str(exc).split(": ", 1)[-1])


def _pins(e):
    return tuple("" if not p else str(int(p)) for p in (e.pa, e.pb))


def add_beams(ctx: Context) -> None:
    """CBAR and CBEAM (``fe.general_beam``) with PBAR, PBEAM (one station), PBARL or PBEAML
    (``L_SECTIONS``), offsets WA/WB and pin flags PA/PB.  G from MAT1.  Lumped mass
    (COUPMASS < 1): point masses at the element's ends (rigidly offset), (rho A + NSM) L / 2 each,
    and for CBEAM also half the torsional inertia rho (I1 + I2) L about the axis (MSC lumps none
    for CBAR; the beam_modes torsion mode shows it, 3554.909 Hz with against MSC's 3554.923)."""
    for eid, e in sorted(ctx.model.elements.items()):
        if e.type not in ("CBAR", "CBEAM"):
            continue
        if e.type == "CBEAM" and (e.sa or e.sb):
            ctx.fail(e.type, eid, "warping scalar points SA, SB are not supported")
        rows = ctx.grids.index(e.node_ids, f"{e.type} {eid}")
        prop = ctx.model.properties[e.pid]
        mat = material(ctx, prop.mid, e.type, eid)
        if prop.type in ("PBAR", "PBEAM"):
            section, nsm = _general_section(ctx, prop, eid, e.type)
        else:
            section, nsm = _library_section(ctx, prop, eid, e.type, mat.poisson)
        off = _offsets(ctx, e, rows)
        x = ctx.grids.xyz[rows] + off
        length = np.linalg.norm(x[1] - x[0])
        axis = (x[1] - x[0]) / max(length, 1e-300)
        up = np.cross(axis, _orientation(ctx, e, rows[0]))  # local z = x cross v
        a, b = ctx.node[rows]
        part = f"{prop.type} {prop.pid}"
        try:
            ctx.builder.add_beams(
                [[a, b]],
                section,
                mat,
                part,
                up=up,
                offsets=off,
                pins=_pins(e),
                mass="none" if ctx.lumped else "consistent",
                nsm=nsm * ctx.wtmass,
                shear_modulus=shear_modulus(ctx, prop.mid),
            )
        except BayesUpdateError as exc:
            ctx.fail(e.type, eid, _builder_message(exc))
        if ctx.lumped:
            line = mat.density * section.area + nsm * ctx.wtmass
            twist = None
            if e.type == "CBEAM":
                twist = mat.density * (section.iy + section.iz) * length * np.outer(axis, axis)
            _lumped_mass(ctx, (a, b), line, length, part, twist, off)


def add_rods(ctx: Context) -> None:
    """CROD (with PROD) and CONROD as rods (``fe.rod``): axial EA / L and torsion GJ / L (G from
    MAT1), consistent mass (COUPMASS 1) or mass lumped at the ends."""
    for eid, e in sorted(ctx.model.elements.items()):
        if e.type not in ("CROD", "CONROD"):
            continue
        p = e if e.type == "CONROD" else ctx.model.properties[e.pid]
        mat = material(ctx, p.mid, e.type, eid)
        rows = ctx.grids.index(e.node_ids, f"{e.type} {eid}")
        x = ctx.grids.xyz[rows]
        length = np.linalg.norm(x[1] - x[0])
        a, b = ctx.node[rows]
        part = f"{e.type} {eid}" if e.type == "CONROD" else f"PROD {p.pid}"
        nsm = (p.nsm or 0.0) * ctx.wtmass
        try:
            ctx.builder.add_rods(
                [[a, b]],
                p.A,
                mat,
                part,
                torsion=p.j or 0.0,
                nsm=nsm,
                mass="none" if ctx.lumped else "consistent",
                shear_modulus=shear_modulus(ctx, p.mid),
            )
        except BayesUpdateError as exc:
            ctx.fail(e.type, eid, _builder_message(exc))
        if ctx.lumped:
            _lumped_mass(ctx, (a, b), density(ctx, p.mid) * p.A + nsm, length, part)


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
    """Component digits (sorted str) of ``text`` at grids ``rows``.  A partial set (not all of
    123 or of 456) on a grid with a rotated CD frame gives that grid its frame
    (``StructureBuilder.set_frame``): the components then act in the CD axes, exactly."""
    mask = parse_components(str(text), f"{card} {eid}")
    if not _invariant(mask):
        for row in np.atleast_1d(rows):
            if not ctx.grids.is_basic([row])[0] and row not in ctx.framed:
                xyz = ctx.grids.xyz[row]
                frame = CoordinateFrame.from_axes("rectangular", xyz, ctx.grids.frame[row])
                ctx.builder.set_frame(int(ctx.node[row]), frame)
                ctx.framed.add(int(row))
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
