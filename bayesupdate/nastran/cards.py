"""Nastran line, point, spring and rigid cards -> ``StructureBuilder`` calls.

Each ``add_*`` takes the reading context (``Context``) and adds one card family, card by card;
a card that cannot be converted is refused (``bulk.CardError``, collected by ``Context.each``)
and the others go on, so one read names every refusal.  Conventions (MSC Nastran Quick
Reference Guide): components are digits 1-6 in the grid's CD frame (a grid whose CD frame turns
a partial component set gets that frame in the structure, ``fe.frames``); a CBAR/CBEAM
orientation vector v lies in the element's x-y plane, its section has I1 about z (plane 1, x-y)
and I2 about y, and its offsets WA, WB run from the grids to the element's ends; CONM2 inertia
is [[I11, -I21, -I31], [-I21, I22, -I32], [-I31, -I32, I33]]; PARAM COUPMASS < 1 (the default)
gives line elements lumped translational mass, half at each end (the element then carries
stiffness only); COUPMASS 1 their consistent mass.  CBAR/CBEAM are ``fe.general_beam``
elements, CROD/CONROD ``fe.rod`` elements.  MAT1 is completed from any two of E, G, NU as the
QRG's MAT1 remark does (``mat1``).  A CBUSH whose ends are apart acts at its location (S along
GA-GB, or S1-S3 in OCID) through rigid arms from both grids (``add_springs``).
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
from bayesupdate.nastran.bulk import CardError
from bayesupdate.nastran.frames import Grids, coordinate

#: element, property and material cards by family (``Context`` tables)
ELEMENTS = ("CBAR", "CBEAM", "CROD", "CONROD", "CONM2", "CONM1", "CMASS1", "CMASS2", "CELAS1",
            "CELAS2", "CBUSH", "RBE2", "RBE3", "RBAR", "CQUAD4", "CTRIA3")  # fmt: skip
PROPERTIES = ("PSHELL", "PBAR", "PBARL", "PBEAM", "PBEAML", "PROD", "PBUSH", "PELAS", "PMASS")


@dataclass
class Context:
    """What the card converters share: elements {(card name, id): Card} (elements, masses and
    rigid elements have id spaces of their own), property and material tables ({id: Card}),
    the grids, the structure node of each grid row (-1: not in the structure), WTMASS, lumped
    line mass, the builder, the deck's refusals, notes for the user."""

    elements: dict
    props: dict
    mats: dict
    grids: Grids
    node: np.ndarray
    wtmass: float
    lumped: bool
    builder: object
    refusals: object
    notes: list = field(default_factory=list)
    framed: set = field(default_factory=set)

    def each(self, names, convert) -> None:
        """``convert(self, card)`` for each element named ``names``, in id order; a refused
        card is recorded and the next one converted."""
        for _, card in sorted(self.elements.items(), key=_by_id):
            if card.name in names:
                try:
                    convert(self, card)
                except CardError as exc:
                    self.refusals.add(str(exc))

    def rows(self, card, names) -> np.ndarray:
        return self.grids.index([card.int(n, positive=True) for n in names], card)

    def prop(self, card, kinds) -> object:
        pid = card.int("PID", positive=True)
        p = self.props.get(pid)
        if p is None or p.name not in kinds:
            card.fail(f"property {pid} is not a {' / '.join(kinds)}")
        return p


def _by_id(item) -> tuple:
    """Sort key of an ``elements`` item: its id (a bad id first), then its card name."""
    (name, i), _ = item
    return (i if isinstance(i, int) else -1, name)


def _invariant(mask) -> bool:
    """A component set that is the same in every frame: none or all of 123, none or all of 456."""
    m = np.asarray(mask, bool)
    return bool((m[:3].all() or not m[:3].any()) and (m[3:].all() or not m[3:].any()))


@dataclass(frozen=True)
class Mat1:
    """A completed MAT1: E, G, NU (any two given; QRG MAT1 remark), RHO [deck units]."""

    E: float
    G: float
    NU: float
    RHO: float


def mat1(ctx: Context, mid: int, user) -> Mat1:
    """MAT1 ``mid`` completed from any two of E, G, NU (QRG MAT1: NU = E / 2G - 1, G = E / 2(1 +
    NU), E = 2(1 + NU) G; E alone: G = NU = 0).  A NU outside (-1, 0.5) is kept (beams use E and
    G only) with a note; ``user`` is the card refused when ``mid`` is no MAT1."""
    card = ctx.mats.get(int(mid)) if mid else None
    if card is None:
        user.fail(f"material {mid} is not a MAT1 (only MAT1 is supported)")
    E, G, nu = (None if card.is_blank(k) else card.real(k) for k in ("E", "G", "NU"))
    if E is None and G is not None and nu is not None:
        E = 2 * (1 + nu) * G
    if E is None or not E > 0:
        card.fail("needs E > 0 (or G and NU)")
    if G is None:
        G = 0.0 if nu is None else E / (2 * (1 + nu))
    if nu is None:
        nu = E / (2 * G) - 1 if G else 0.0
    if not -1 < nu < 0.5:
        note = (f"MAT1 {mid} ({card.where}): NU = {nu:.4g} from E and G is outside (-1, 0.5); "
                "kept for beams and rods, which use E and G only")  # fmt: skip
        if note not in ctx.notes:
            ctx.notes.append(note)
    return Mat1(E, G, nu, card.real("RHO"))


def material(ctx: Context, mid: int, user) -> Material:
    """MAT1 ``mid`` as a ``Material`` with density x WTMASS (a NU outside (-1, 0.5) is given as
    0 there: callers pass G itself, ``shear_modulus``)."""
    m = mat1(ctx, mid, user)
    # Material needs a density > 0; a massless MAT1 gets a negligible one
    rho = max(m.RHO * ctx.wtmass, 1e-300)
    nu = m.NU if -1 < m.NU < 0.5 else 0.0
    return Material(m.E, nu, rho, f"MAT1 {mid}")


def _lumped_mass(ctx: Context, nodes, mass_per_length, length, part, inertia=None, offsets=None):
    """Half the line mass (and of the ``inertia`` (3, 3) tensor) at each end (node + offset)."""
    if mass_per_length > 0:
        J = None if inertia is None else 0.5 * inertia
        off = np.zeros((2, 3)) if offsets is None else offsets
        for n, w in zip(nodes, off, strict=True):
            ctx.builder.add_point_mass(n, 0.5 * mass_per_length * length, part, J, w)


#: PBARL/PBEAML shapes read (Nastran DIM order; ``standard_sections`` for the formulas) and
#: their number of dimensions
L_SECTIONS = {"ROD": 1, "TUBE": 2, "TUBE2": 2, "BAR": 2, "BOX": 4, "I": 6}
#: number of dimensions of the other PBARL shapes (to find NSM after them)
L_DIMS = {**L_SECTIONS, "CHAN": 4, "T": 4, "L": 4, "H": 4, "T1": 4, "I1": 4, "CHAN1": 4,
          "Z": 4, "CHAN2": 4, "T2": 4, "BOX1": 6, "HEXA": 3, "HAT": 4, "HAT1": 5, "DBOX": 10,
          "CROSS": 4}  # fmt: skip
#: PBEAM fields of one station (after SO, X/XB) and of end A
_STATION = ("A", "I1", "I2", "I12", "J", "NSM")
#: PBEAM's last two lines: shear factors, shear relief, warping, mass and neutral-axis offsets
_PBEAM_TAIL = ("K1", "K2", "S1", "S2", "NSIA", "NSIB", "CWA", "CWB", "M1A", "M2A", "M1B", "M2B",
               "N1A", "N2A", "N1B", "N2B")  # fmt: skip
_TAIL_DEFAULT = dict(K1=1.0, K2=1.0)


def pbeam_layout(p) -> tuple[list, dict]:
    """(stations, tail) of a PBEAM: stations = [(raw index of A, SO, X/XB)] (end A first), tail =
    {K1: value, ...} with the QRG defaults (K1 = K2 = 1, others 0)."""
    stations, i, n = [(2, None, 0.0)], 16, len(p.raw)
    while i < n:
        so = p.value(i)
        if so not in ("YES", "YESA", "NO"):
            break
        stations.append((i + 2, so, p.value(i + 1)))
        i += 16 if so == "YES" else 8
    tail = {}
    for k, name in enumerate(_PBEAM_TAIL):
        v = p.value(i + k)
        tail[name] = _TAIL_DEFAULT.get(name, 0.0) if v is None else v
    return stations, tail


def _pbeam_values(p, card) -> np.ndarray:
    """(6,) A, I1, I2, I12, J, NSM of a constant PBEAM; refuses a tapered one (a station whose
    fields differ from end A's; a blank station field is end A's, QRG PBEAM)."""
    stations, _ = pbeam_layout(p)
    a = np.array([p.real(k) for k in _STATION])
    for start, _, _ in stations[1:]:
        vals = [p.value(start + k) for k in range(6)]
        v = np.array([a[k] if x is None else float(x) for k, x in enumerate(vals)])
        if np.any(np.abs(v - a) > 1e-12 * np.maximum(np.abs(a), 1e-300)):
            card.fail(f"PBEAM {p.id()} is tapered; only constant sections")
    return a


def _general_section(ctx: Context, prop, card):
    """(``BeamSection``, nsm) of a PBAR or a single-station PBEAM (I1 -> iz, I2 -> iy)."""
    pid = prop.id()
    if prop.name == "PBAR":
        a, i1, i2, i12, j, nsm = (prop.real(k) for k in ("A", "I1", "I2", "I12", "J", "NSM"))
        # K1, K2 blank (or ignored because I12 != 0) mean rigid in shear (MSC QRG, PBAR)
        k = [0.0 if (prop.is_blank(n) or i12) else prop.real(n) for n in ("K1", "K2")]
    else:
        a, i1, i2, i12, j, nsm = _pbeam_values(prop, card)
        _, tail = pbeam_layout(prop)
        used = [n for n in _PBEAM_TAIL[2:] if tail[n]]
        if used:
            card.fail(f"PBEAM {pid}: {', '.join(used)} not supported (shear relief, warping, "
                      "mass and neutral-axis offsets)")  # fmt: skip
        # PBEAM K1, K2 default 1.0; 0.0 means rigid in shear (MSC QRG, PBEAM)
        k = [float(tail["K1"]), float(tail["K2"])]
    try:
        sec = general_section(a, i2, i1, j, i12, k[0], k[1], name=f"{prop.name} {pid}")
    except BayesUpdateError as exc:
        card.fail(str(exc))
    return sec, nsm


def library_dims(prop, card) -> tuple[str, np.ndarray, float]:
    """(TYPE, DIM (n,), NSM) of a PBARL or a constant PBEAML (refused when tapered)."""
    kind = str(prop["TYPE"])
    if kind not in L_DIMS:
        card.fail(f"{prop.name} {prop.id()} type {kind}: only {', '.join(L_SECTIONS)}")
    n = L_DIMS[kind]
    dims = np.array([float(prop.value(8 + k) or 0.0) for k in range(n)])
    nsm = float(prop.value(8 + n) or 0.0)
    if prop.name == "PBEAML":  # stations: SO, X/XB, DIMs, NSM each; blank = end A's
        i = 9 + n
        while i < len(prop.raw):
            vals = [prop.value(i + 2 + k) for k in range(n)]
            other = np.array(
                [d if v is None else float(v) for d, v in zip(dims, vals, strict=True)]
            )
            if np.any(other != dims):
                card.fail(f"PBEAML {prop.id()} is tapered; only constant sections")
            i += 3 + n
    return kind, dims, nsm


def _library_section(ctx: Context, prop, card, nu):
    """(``BeamSection``, nsm) of a PBARL/PBEAML of a shape in ``L_SECTIONS``.  Nastran's
    figures have y_elem vertical: the shapes are built with their height along z and turned.
    MSC's ROD uses the shear factor 0.9 (with it the beam_modes deck matches MSC to 2e-4 %;
    Cowper's 0.886 is 0.3 % low on the 4th bending pair); the others use Cowper's (a note)."""
    kind, d, nsm = library_dims(prop, card)
    pid = prop.id()
    if kind not in L_SECTIONS:
        card.fail(f"{prop.name} {pid} type {kind}: only {', '.join(L_SECTIONS)}")
    if kind == "I" and (d[1] != d[2] or d[4] != d[5]):
        card.fail(f"{prop.name} {pid}: an I with unequal flanges is not supported")
    try:
        if kind == "ROD":
            return replace(ss.rod_section(2 * d[0], nu), shear_y=0.9, shear_z=0.9), nsm
        if kind in ("TUBE", "TUBE2"):
            wall = d[0] - d[1] if kind == "TUBE" else d[1]
            return ss.tube_section(2 * d[0], wall, nu), nsm
        note = f"{prop.name} {pid} {kind}: shear factors of Cowper (1966); Nastran's own may differ"
        if note not in ctx.notes:
            ctx.notes.append(note)
        if kind == "BAR":
            return ss.bar_section(d[0], d[1], nu).swap_yz(), nsm
        if kind == "BOX":
            return ss.box_section(d[0], d[1], d[3], d[2], nu).swap_yz(), nsm
        return ss.i_section(d[0], d[1], d[3], d[4], nu).swap_yz(), nsm
    except BayesUpdateError as exc:
        card.fail(f"{prop.name} {pid}: {exc}")


def _orientation(ctx: Context, e, ga_row, offt: str = "GGG"):
    """Orientation vector v (3,) in basic coordinates of a CBAR/CBEAM/CBUSH (X1-X3 in GA's CD
    frame, or in basic for OFFT 'B..'; or from GA to G0)."""
    g = ctx.grids
    x1 = e["X1"]
    if isinstance(x1, int):
        return g.xyz[g.index([x1], e)[0]] - g.xyz[ga_row]
    v = np.array([e.real(k) for k in ("X1", "X2", "X3")])
    return v if offt[0] == "B" else g.frame[ga_row].T @ v


def _offt(e) -> str:
    """OFFT of a CBAR/CBEAM ('GGG' when blank); refuses CBEAM's BIT (a real) and bad flags."""
    offt = e["OFFT"]
    if not isinstance(offt, str):
        e.fail("BIT / a numeric OFFT is not supported (OFFT GGG, BGG, ... only)")
    return offt


def _offsets(ctx: Context, e, rows, offt: str) -> np.ndarray:
    """(2, 3) end offsets WA, WB in basic axes: OFFT 'G' = the end grid's CD frame, 'B' =
    basic (MSC QRG, CBAR/CBEAM); 'O' (element axes) is not supported."""
    w = np.array([[e.real(f"W{k}{end}") for k in (1, 2, 3)] for end in "AB"])
    if not np.any(w):
        return w
    for end in (0, 1):
        if len(offt) != 3 or offt[1 + end] not in "GB":
            e.fail(f"OFFT {offt}: offsets in element axes ('O') are not supported")
        if offt[1 + end] == "G":
            w[end] = ctx.grids.frame[rows[end]].T @ w[end]
    return w


def _builder_message(exc) -> str:
    """A builder error without its 'add_beams (part ...): element k' prefix (the card is named
    instead)."""
    return re.sub(r"^element \d+:? ", "", str(exc).split(": ", 1)[-1])


def _pins(e):
    return tuple("" if not e[p] else str(e.int(p)) for p in ("PA", "PB"))


def add_beams(ctx: Context) -> None:
    """CBAR and CBEAM (``fe.general_beam``) with PBAR, PBEAM (one station), PBARL or PBEAML
    (``L_SECTIONS``), offsets WA/WB and pin flags PA/PB.  G from MAT1.  Lumped mass
    (COUPMASS < 1): point masses at the element's ends (rigidly offset), (rho A + NSM) L / 2 each,
    and for CBEAM also half the torsional inertia rho (I1 + I2) L about the axis (MSC lumps none
    for CBAR; the beam_modes torsion mode shows it, 3554.909 Hz with against MSC's 3554.923)."""
    ctx.each(("CBAR", "CBEAM"), _add_beam)


def _add_beam(ctx: Context, e) -> None:
    if e.name == "CBEAM" and (e["SA"] or e["SB"]):
        e.fail("warping scalar points SA, SB are not supported")
    rows = ctx.rows(e, ("GA", "GB"))
    kinds = ("PBAR", "PBARL") if e.name == "CBAR" else ("PBEAM", "PBEAML")
    prop = ctx.prop(e, kinds)
    mid = prop.int("MID", positive=True)
    mat = material(ctx, mid, e)
    if prop.name in ("PBAR", "PBEAM"):
        section, nsm = _general_section(ctx, prop, e)
    else:
        section, nsm = _library_section(ctx, prop, e, mat1(ctx, mid, e).NU)
    offt = _offt(e)
    off = _offsets(ctx, e, rows, offt)
    x = ctx.grids.xyz[rows] + off
    length = np.linalg.norm(x[1] - x[0])
    axis = (x[1] - x[0]) / max(length, 1e-300)
    up = np.cross(axis, _orientation(ctx, e, rows[0], offt))  # local z = x cross v
    a, b = ctx.node[rows]
    part = f"{prop.name} {prop.id()}"
    try:
        ctx.builder.add_beams(
            [[a, b]], section, mat, part, up=up, offsets=off, pins=_pins(e),
            mass="none" if ctx.lumped else "consistent", nsm=nsm * ctx.wtmass,
            shear_modulus=mat1(ctx, mid, e).G,
        )  # fmt: skip
    except BayesUpdateError as exc:
        e.fail(_builder_message(exc))
    if ctx.lumped:
        line = mat.density * section.area + nsm * ctx.wtmass
        twist = None
        if e.name == "CBEAM":
            twist = mat.density * (section.iy + section.iz) * length * np.outer(axis, axis)
        _lumped_mass(ctx, (a, b), line, length, part, twist, off)


def rod_values(e, p) -> tuple[int, float, float, float]:
    """(MID, A, J, NSM) of a CROD's PROD or a CONROD."""
    return p.int("MID", positive=True), p.real("A"), p.real("J"), p.real("NSM")


def add_rods(ctx: Context) -> None:
    """CROD (with PROD) and CONROD as rods (``fe.rod``): axial EA / L and torsion GJ / L (G from
    MAT1), consistent mass (COUPMASS 1) or mass lumped at the ends."""
    ctx.each(("CROD", "CONROD"), _add_rod)


def _add_rod(ctx: Context, e) -> None:
    p = e if e.name == "CONROD" else ctx.prop(e, ("PROD",))
    mid, area, j, nsm = rod_values(e, p)
    mat = material(ctx, mid, e)
    rows = ctx.rows(e, ("G1", "G2"))
    x = ctx.grids.xyz[rows]
    length = np.linalg.norm(x[1] - x[0])
    a, b = ctx.node[rows]
    part = f"CONROD {e.id()}" if e.name == "CONROD" else f"PROD {p.id()}"
    nsm = nsm * ctx.wtmass
    try:
        ctx.builder.add_rods(
            [[a, b]], area, mat, part, torsion=j, nsm=nsm,
            mass="none" if ctx.lumped else "consistent", shear_modulus=mat1(ctx, mid, e).G,
        )  # fmt: skip
    except BayesUpdateError as exc:
        e.fail(_builder_message(exc))
    if ctx.lumped:
        _lumped_mass(ctx, (a, b), mat.density * area + nsm, length, part)


def add_masses(ctx: Context) -> None:
    """CONM2 (offset and inertia; CID -1, 0 or rectangular), CONM1 (a rigid-body 6x6) and
    CMASS1/CMASS2 on one grid's rotation (4, 5, 6: an inertia about that CD axis)."""
    ctx.each(("CONM2",), _add_conm2)
    ctx.each(("CONM1",), _add_conm1)
    ctx.each(("CMASS1", "CMASS2"), _add_cmass)


def _mass_frame(ctx: Context, m):
    cid = m.int("CID")
    if cid in (-1, 0):
        return np.eye(3)
    coord = coordinate(ctx.grids, cid, m)
    if coord.kind != "rectangular":
        m.fail(f"CID {cid} is not rectangular")
    return coord.axes


def _add_conm2(ctx: Context, m) -> None:
    row = ctx.rows(m, ("G",))[0]
    R = _mass_frame(ctx, m)
    offset = np.array([m.real(k) for k in ("X1", "X2", "X3")])
    offset = offset - ctx.grids.xyz[row] if m.int("CID") == -1 else R.T @ offset
    i11, i21, i22, i31, i32, i33 = (m.real(k) for k in ("I11", "I21", "I22", "I31", "I32", "I33"))
    J = np.array([[i11, -i21, -i31], [-i21, i22, -i32], [-i31, -i32, i33]])
    J = R.T @ J @ R * ctx.wtmass
    try:
        ctx.builder.add_point_mass(ctx.node[row], m.real("M") * ctx.wtmass, f"CONM2 {m.id()}",
                                   J, offset)  # fmt: skip
    except BayesUpdateError as exc:
        m.fail(_builder_message(exc))


def _add_conm1(ctx: Context, m) -> None:
    """CONM1 as a point mass: needs M_tt = m I; its offset c from M_tr = -m skew(c)."""
    from bayesupdate.fe.rotations import skew

    row = ctx.rows(m, ("G",))[0]
    R = _mass_frame(ctx, m)
    lower = [m.real(f"M{i}{j}") for i in range(1, 7) for j in range(1, i + 1)]
    M = np.zeros((6, 6))
    M[np.tril_indices(6)] = lower
    M = (M + np.tril(M, -1).T) * ctx.wtmass
    T = np.kron(np.eye(2), R)
    M = T.T @ M @ T
    mass = M[0, 0]
    if mass <= 0 or not np.allclose(M[:3, :3], mass * np.eye(3), rtol=1e-6, atol=0):
        m.fail("only a rigid-body mass (M11 = M22 = M33, no coupling) is supported")
    S = -M[:3, 3:] / mass  # = skew(c)
    c = np.array([S[2, 1], S[0, 2], S[1, 0]])
    J = M[3:, 3:] - mass * skew(c[None])[0].T @ skew(c[None])[0]
    ctx.builder.add_point_mass(ctx.node[row], mass, f"CONM1 {m.id()}", J, c)


def _add_cmass(ctx: Context, m) -> None:
    """A scalar mass on one grid's rotation component: the inertia m e e^T about the CD axis e
    (a point inertia; a translation component or two grids are refused)."""
    if m.name == "CMASS1":
        value = ctx.prop(m, ("PMASS",)).real("M")
    else:
        value = m.real("M")
    if m["G2"] or m["C2"]:
        m.fail("a scalar mass between two grids is not supported (one grid only)")
    comp = m.int("C1")
    if comp not in (4, 5, 6):
        m.fail(f"component {comp}: only a rotation (4, 5, 6) of one grid is supported")
    row = ctx.rows(m, ("G1",))[0]
    e = ctx.grids.frame[row][comp - 4]
    J = value * ctx.wtmass * np.outer(e, e)
    if value < 0:
        m.fail("a negative mass is not supported")
    ctx.builder.add_point_mass(ctx.node[row], 0.0, f"{m.name} {m.id()}", J)


def add_springs(ctx: Context) -> None:
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
    of x and v), at its location P; ends apart get rigid arms from GA and GB to P (two nodes at
    P tied by RBE2s, the spring between them), so moments balance as in MSC's CBUSH."""
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
    if len(ids) == 2 and np.linalg.norm(x[1] - x[0]) > 0:
        p = _cbush_point(ctx, e, x)
        arms = [ctx.builder.add_node(p) for _ in range(2)]
        ctx.builder.add_rbe2(a, [arms[0]], "123456")
        ctx.builder.add_rbe2(b, [arms[1]], "123456")
        a, b = arms
    ctx.builder.add_spring(a, b, k, part, frame=frame)


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


def components(ctx: Context, text, rows, card):
    """Component digits (sorted str) of ``text`` at grids ``rows``.  A partial set (not all of
    123 or of 456) on a grid with a rotated CD frame gives that grid its frame
    (``StructureBuilder.set_frame``): the components then act in the CD axes, exactly."""
    try:
        mask = parse_components(str(text), card.label)
    except BayesUpdateError as exc:
        card.fail(str(exc).split(": ", 1)[-1])
    if not _invariant(mask):
        for row in np.atleast_1d(rows):
            if not ctx.grids.is_basic([row])[0] and row not in ctx.framed:
                xyz = ctx.grids.xyz[row]
                frame = CoordinateFrame.from_axes("rectangular", xyz, ctx.grids.frame[row])
                ctx.builder.set_frame(int(ctx.node[row]), frame)
                ctx.framed.add(int(row))
    return "".join(str(i + 1) for i in np.flatnonzero(mask))


def id_list(card, start: int) -> list[int]:
    """Integers of ``card`` from raw field ``start`` on, 'THRU' ranges expanded (blank fields
    skipped; a real, e.g. RBE2's ALPHA, ends the list)."""
    out, values, k = [], card.values(start), 0
    while k < len(values):
        v = values[k]
        if v == "THRU" and out and k + 1 < len(values) and isinstance(values[k + 1], int):
            out += range(out[-1] + 1, values[k + 1] + 1)
            k += 2
            continue
        if isinstance(v, float):
            break
        if isinstance(v, int):
            out.append(v)
        elif v is not None:
            card.fail(f"field {v!r}: give grid ids (THRU allowed)")
        k += 1
    return out


def add_rigid(ctx: Context) -> None:
    """RBE2, RBE3 (no UM set) and RBAR (CNA = CMB = 123456)."""
    ctx.each(("RBE2",), _add_rbe2)
    ctx.each(("RBAR",), _add_rbar)
    ctx.each(("RBE3",), _add_rbe3)


def _add_rbe2(ctx: Context, r) -> None:
    deps = id_list(r, 3)
    rows = ctx.grids.index(deps, r)
    comps = components(ctx, r["CM"], rows, r)
    gn = ctx.rows(r, ("GN",))[0]
    try:
        ctx.builder.add_rbe2(ctx.node[gn], ctx.node[rows], comps)
    except BayesUpdateError as exc:
        r.fail(_builder_message(exc))


def _add_rbar(ctx: Context, r) -> None:
    if str(r["CNA"]) != "123456" or str(r["CMB"]) != "123456" or r["CNB"] or r["CMA"]:
        r.fail("only CNA = 123456, CMB = 123456 is supported")
    ga, gb = ctx.node[ctx.rows(r, ("GA", "GB"))]
    ctx.builder.add_rbe2(ga, [gb], "123456")


def rbe3_groups(r) -> list[tuple[float, str, list[int]]]:
    """[(WTi, Ci, grids)] of an RBE3 (refused with a UM set)."""
    values = r.values(4)
    groups, k = [], 0
    while k < len(values):
        v = values[k]
        if v is None:
            k += 1
            continue
        if v in ("UM", "ALPHA", "TREF"):
            if v == "UM":
                r.fail("UM (user-chosen dependent DOFs) is not supported")
            break
        if not isinstance(v, float) or k + 1 >= len(values):
            r.fail(f"field {v!r}: give WTi (a real), Ci, then grids")
        comp, grids, k = values[k + 1], [], k + 2
        while k < len(values) and (values[k] is None or isinstance(values[k], int)):
            grids += [values[k]] if values[k] is not None else []
            k += 1
        groups.append((v, str(comp), grids))
    if not groups:
        r.fail("no weight groups")
    return groups


def _add_rbe3(ctx: Context, r) -> None:
    """RBE3: REFGRID's REFC is the weighted mean motion of the groups (WTi, Ci, Gi,j)."""
    groups = rbe3_groups(r)
    comps = {c for _, c, _ in groups}
    if len(comps) != 1:
        r.fail("all weight groups need the same components")
    nodes = [g for _, _, gs in groups for g in gs]
    weights = [float(w) for w, _, gs in groups for _ in gs]
    rows = ctx.grids.index(nodes, r)
    ref = ctx.rows(r, ("REFGRID",))
    node_c = components(ctx, comps.pop(), rows, r)
    ref_c = components(ctx, r["REFC"], ref, r)
    ctx.builder.add_rbe3(ctx.node[ref[0]], ctx.node[rows], weights, ref_c, node_c)


#: the grid fields of each element card (RBE2 / RBE3 lists: ``element_grids``)
GRID_FIELDS = {
    "CBAR": ("GA", "GB"), "CBEAM": ("GA", "GB"), "CROD": ("G1", "G2"), "CONROD": ("G1", "G2"),
    "CBUSH": ("GA", "GB"), "CELAS1": ("G1", "G2"), "CELAS2": ("G1", "G2"), "CONM2": ("G",),
    "CONM1": ("G",), "CMASS1": ("G1", "G2"), "CMASS2": ("G1", "G2"), "RBAR": ("GA", "GB"),
    "RBE2": ("GN",), "RBE3": ("REFGRID",), "CQUAD4": ("G1", "G2", "G3", "G4"),
    "CTRIA3": ("G1", "G2", "G3"),
}  # fmt: skip


def element_grids(card) -> list[int]:
    """GRID ids an element card connects (blank fields skipped)."""
    ids = [card[f] for f in GRID_FIELDS[card.name]]
    if card.name == "RBE2":
        ids += id_list(card, 3)
    elif card.name == "RBE3":
        ids += [g for _, _, gs in rbe3_groups(card) for g in gs]
    return [int(i) for i in ids if isinstance(i, int) and i > 0]
