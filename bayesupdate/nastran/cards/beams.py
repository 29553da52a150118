"""CBAR and CBEAM with PBAR, PBARL, PBEAM and PBEAML (constant or tapered; MSC Nastran QRG).

A CBAR/CBEAM orientation vector v lies in the element's x-y plane, its section has I1 about z
(plane 1, x-y) and I2 about y, and its offsets WA, WB run from the grids to the element's ends
(OFFT G: the end grid's CD frame, B: basic, O: the element's axes); pin flags PA/PB release
element-axis components.
The elements are ``fe.elements.general_beam`` elements; lumped mass (COUPMASS < 1) at their ends.
"""

from dataclasses import replace

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import standard_sections as ss
from bayesupdate.fe.elements.beam import element_frames
from bayesupdate.fe.standard_sections import general_section
from bayesupdate.nastran.cards.common import (
    Context,
    _builder_message,
    _lumped_mass,
    mat1,
    material,
)

#: the cards this file converts (``cards.FAMILIES``)
CARDS = ("CBAR", "CBEAM")

#: PBARL/PBEAML shapes read (Nastran DIM order; ``standard_sections`` for the formulas) and
#: their number of dimensions
L_SECTIONS = {"ROD": 1, "TUBE": 2, "TUBE2": 2, "BAR": 2, "BOX": 4, "I": 6, "T": 4, "T2": 4,
              "CHAN": 4}  # fmt: skip
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
    {K1: value, ...} with the QRG defaults (K1 = K2 = 1, others 0).  End A's stress points
    (C1(A) ... F2(A)) may be left out: a first continuation that starts with SO is a station."""
    n = len(p.raw)
    stations, i = [(2, None, 0.0)], 8 if p.value(8) in ("YES", "YESA", "NO") else 16
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


def pbeam_stations(p, card) -> tuple[np.ndarray, np.ndarray]:
    """(x (k,), values (k, 6)) of a PBEAM: x / L of end A, each intermediate station and end B
    (0 ... 1), values A, I1, I2, I12, J, NSM there.  Blank fields as the QRG's PBEAM remark
    gives them: at end B (X/XB = 1) end A's value, at an intermediate station the linear
    interpolation between end A and end B; no end B station: end B is end A."""
    stations, _ = pbeam_layout(p)
    rows = [[p.value(start + k) for k in range(6)] for start, _, _ in stations]
    x = [0.0]
    a = np.array([p.real(k) for k in _STATION])
    for _, _, xb in stations[1:]:
        if not isinstance(xb, int | float) or not 0 < xb <= 1 or xb <= x[-1]:
            card.fail(f"PBEAM {p.id()}: station X/XB = {xb!r}; give increasing values in (0, 1]")
        x.append(float(xb))
    end_b = next((r for xb, r in zip(x, rows, strict=True) if xb == 1.0), None)
    b = a if end_b is None else np.array([a[k] if v is None else float(v)
                                          for k, v in enumerate(end_b)])  # fmt: skip
    vals = [
        np.array([a[k] + xb * (b[k] - a[k]) if v is None else float(v) for k, v in enumerate(r)])
        for xb, r in zip(x, rows, strict=True)
    ]
    if x[-1] < 1.0:
        x.append(1.0)
        vals.append(b)
    return np.array(x), np.array(vals)


def _varies(v: np.ndarray) -> bool:
    """True if the station values v (k, n) differ from the first row beyond rounding."""
    return bool(np.any(np.abs(v - v[0]) > 1e-12 * np.maximum(np.abs(v[0]), 1e-300)))


def is_tapered(p) -> bool:
    """True if the PBEAM ``p``'s A, I1, I2, I12, J or NSM vary along it (``pbeam_stations``)."""
    return _varies(pbeam_stations(p, p)[1])


def _pbeam_values(ctx: Context, p, card) -> tuple[np.ndarray, np.ndarray | None]:
    """((6,) A, I1, I2, I12, J, NSM of a PBEAM's element, (2, 6) its values at end A and end B
    or None): ``station_values`` of its stations (``pbeam_stations``)."""
    x, v = pbeam_stations(p, card)
    return station_values(ctx, x, v, f"PBEAM {p.id()}", card)


def station_values(ctx: Context, x, v, label: str, card) -> tuple[np.ndarray, np.ndarray | None]:
    """((6,) A, I1, I2, I12, J, NSM of a beam element, (2, 6) its values at end A and end B or
    None) from its stations: x (k,) from 0 (end A) to 1 (end B), v (k, 6) the values there.
    Constant: its own values, None.  Tapered with every station on the line from end A to end
    B, no I12: the mean and both ends (NX's tapered CBEAM, linear along the element:
    ``studies/nx_tapered_cbeam.py``).  Another tapered one (an intermediate station off that
    line, an I12, or an A, I1, I2 or J of 0 somewhere): the mean over the length of the
    piecewise-linear variation through its stations (trapezoid rule, exact for that
    variation), None, with a note: the mean section keeps the element's mass and is exact as
    the taper goes to 0, so a member meshed in several tapered CBEAMs converges to the tapered
    beam (Kirchhoff's wedge, ``tests/test_nastran_cards``)."""
    if not _varies(v):
        return v[0], None
    if np.any(v[:, :3] < 0) or np.any(v[:, 4] < 0):
        card.fail(f"{label}: a station has A, I1, I2 or J < 0")
    mean = np.trapezoid(v, x, axis=0)
    line = v[0] + np.outer(x, v[-1] - v[0])
    linear = np.all(np.abs(v - line) <= 1e-12 * np.maximum(np.abs(v).max(axis=0), 1e-300))
    if linear and not np.any(v[:, 3]) and np.all(v[:, [0, 1, 2, 4]] > 0):
        return mean, v[[0, -1]]
    note = (f"{label} is tapered with stations off the line from end A to end B, an "
            "I12, or an A, I1, I2 or J of 0: each of its CBEAMs uses the section averaged over "
            "its length (mesh a tapered member in several elements)")  # fmt: skip
    if note not in ctx.notes:
        ctx.notes.append(note)
    return mean, None


def _general_section(ctx: Context, prop, card):
    """(``BeamSection``, nsm, ends) of a PBAR or a PBEAM (tapered: its mean section; I1 -> iz,
    I2 -> iy); ends (2, 6) a linearly tapered PBEAM's A, I1, I2, I12, J, NSM at end A and end B
    (``_pbeam_values``), else None."""
    pid = prop.id()
    ends = None
    if prop.name == "PBAR":
        a, i1, i2, i12, j, nsm = (prop.real(k) for k in ("A", "I1", "I2", "I12", "J", "NSM"))
        # K1, K2 blank (or ignored because I12 != 0) mean rigid in shear (MSC QRG, PBAR)
        k = [0.0 if (prop.is_blank(n) or i12) else prop.real(n) for n in ("K1", "K2")]
    else:
        (a, i1, i2, i12, j, nsm), ends = _pbeam_values(ctx, prop, card)
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
    return sec, nsm, ends


def library_dims(prop, card) -> tuple[str, np.ndarray, float]:
    """(TYPE, DIM (n,), NSM) of a PBARL or of a PBEAML's end A (its stations:
    ``library_stations``)."""
    kind = str(prop["TYPE"])
    if kind not in L_DIMS:
        card.fail(f"{prop.name} {prop.id()} type {kind}: only {', '.join(L_SECTIONS)}")
    n = L_DIMS[kind]
    dims = np.array([float(prop.value(8 + k) or 0.0) for k in range(n)])
    nsm = float(prop.value(8 + n) or 0.0)
    return kind, dims, nsm


def library_stations(prop, card) -> tuple[np.ndarray, np.ndarray]:
    """(x (k,), values (k, n + 1)) of a PBEAML: x / L of end A, each station and end B (0 ... 1),
    and DIM1..DIMn, NSM there (a PBARL: end A alone, x = [0]).  Blank fields as for PBEAM
    (``pbeam_stations``): at end B (X/XB = 1) end A's, at an intermediate station the linear
    interpolation between end A and end B; no end B station: end B is end A."""
    _, dims, nsm = library_dims(prop, card)
    n = dims.size
    a = np.append(dims, nsm)
    x, rows, i = [0.0], [], 9 + n  # stations: SO, X/XB, DIMs, NSM (3 + n fields each)
    while prop.name == "PBEAML" and i < len(prop.raw):
        xb = prop.value(i + 1)
        if not isinstance(xb, int | float) or not 0 < xb <= 1 or xb <= x[-1]:
            card.fail(f"PBEAML {prop.id()}: station X/XB = {xb!r}; give increasing values in "
                      "(0, 1]")  # fmt: skip
        x.append(float(xb))
        rows.append([prop.value(i + 2 + k) for k in range(n + 1)])
        i += 3 + n
    end_b = next((r for xb, r in zip(x[1:], rows, strict=True) if xb == 1.0), None)
    b = a if end_b is None else np.array([a[k] if v is None else float(v)
                                          for k, v in enumerate(end_b)])  # fmt: skip
    vals = [a] + [np.array([a[k] + xb * (b[k] - a[k]) if v is None else float(v)
                            for k, v in enumerate(r)])
                  for xb, r in zip(x[1:], rows, strict=True)]  # fmt: skip
    if x[-1] < 1.0 and len(x) > 1:
        x.append(1.0)
        vals.append(b)
    return np.array(x), np.array(vals)


def library_is_tapered(prop) -> bool:
    """True if a PBEAML's dimensions or NSM vary along it (``library_stations``)."""
    return _varies(library_stations(prop, prop)[1])


def _library_section(ctx: Context, prop, card, nu):
    """(``BeamSection``, nsm, ends) of a PBARL/PBEAML of a shape in ``L_SECTIONS``, ends as
    ``station_values``'.  A tapered PBEAML is read as MSC reads it: MSC replaces it by the
    PBEAM of its stations' sections (its f06 prints them: "the user supplied PBEAML bulk data
    entries are replaced by the following PBEAM entries"), whose properties vary linearly
    between the stations; the shear factors are end A's.  MSC's own modes of pyNastran's
    ``aero/fmondsp`` (tapered TUBEs): ``tests/test_nastran_fmondsp.py``."""
    kind, _, _ = library_dims(prop, card)
    x, v = library_stations(prop, card)
    if not _varies(v):
        return _shape_section(ctx, prop, card, kind, v[0, :-1], nu), v[0, -1], None
    sections = [_shape_section(ctx, prop, card, kind, row[:-1], nu) for row in v]
    values = np.array([[s.area, s.iz, s.iy, s.iyz, s.torsion, row[-1]]
                       for s, row in zip(sections, v, strict=True)])  # fmt: skip
    (a, i1, i2, i12, j, nsm), ends = station_values(ctx, x, values, f"PBEAML {prop.id()}", card)
    first = sections[0]
    name = f"PBEAML {prop.id()}" + (" (tapered)" if ends is not None else " (mean)")
    try:
        section = general_section(a, i2, i1, j, i12, first.shear_y, first.shear_z, name=name)
    except BayesUpdateError as exc:
        card.fail(str(exc))
    return section, nsm, ends


def _shape_section(ctx: Context, prop, card, kind, d, nu):
    """``BeamSection`` of a library shape with dimensions ``d``.  Nastran's figures have y_elem
    vertical: the shapes are built with their height along z and turned.  MSC's ROD uses the
    shear factor 0.9 (with it the beam_modes deck matches MSC to 2e-4 %; Cowper's 0.886 is 0.3 %
    low on the 4th bending pair) and its BAR 5/6 whatever NU (MYSTRAN's PBARL writes the same;
    with it the mAEWing1 decks' 20 modes match their f06 to 1.2e-6, with Cowper's
    10 (1 + nu) / (12 + 11 nu) at their NU = E / 2G - 1 = 1.66 to 8.5e-6:
    ``tests/test_nastran_maewing1.py``).  A TUBE (or TUBE2) has 0.5 and a BOX the area of the
    walls along each shear direction over its area, as MSC's own conversion to PBEAM prints
    them in its f06 (pyNastran's ``aero/fmondsp``, MSC 2005: TUBE K1 = K2 = 0.5, BOX 0.6 x 0.2
    x 0.0025 K1 = 0.24528 = 2 DIM4 (DIM2 - 2 DIM3) / A, the sides, K2 = 0.74843 = 2 DIM3
    (DIM1 - 2 DIM4) / A, top and bottom; NX's ``aero/aerobeam`` prints the same); with them
    that deck's 12 elastic modes match MSC's to 6e-6 (Cowper's put them up to 3.7 % low:
    ``tests/test_nastran_fmondsp.py``).  The I uses Cowper's (a note: no vendor's value here)."""
    pid = prop.id()
    if kind not in L_SECTIONS:
        card.fail(f"{prop.name} {pid} type {kind}: only {', '.join(L_SECTIONS)}")
    if kind == "I" and (d[1] != d[2] or d[4] != d[5]):
        card.fail(f"{prop.name} {pid}: an I with unequal flanges is not supported")
    try:
        if kind == "ROD":
            return replace(ss.rod_section(2 * d[0], nu), shear_y=0.9, shear_z=0.9)
        if kind in ("TUBE", "TUBE2"):
            wall = d[0] - d[1] if kind == "TUBE" else d[1]
            return replace(ss.tube_section(2 * d[0], wall, nu), shear_y=0.5, shear_z=0.5)
        if kind == "BAR":
            return replace(ss.bar_section(d[0], d[1], nu), shear_y=5 / 6, shear_z=5 / 6).swap_yz()
        if kind == "BOX":  # DIM1 width (z), DIM2 height (y), DIM3 top and bottom, DIM4 sides
            box = ss.box_section(d[0], d[1], d[3], d[2], nu).swap_yz()
            walls = (2 * d[3] * (d[1] - 2 * d[2]), 2 * d[2] * (d[0] - 2 * d[3]))
            return replace(box, shear_y=walls[0] / box.area, shear_z=walls[1] / box.area)
        if kind in ("T", "T2", "CHAN"):
            return _open_section(ctx, prop, kind, d)
        note = f"{prop.name} {pid} {kind}: shear factors of Cowper (1966); Nastran's own may differ"
        if note not in ctx.notes:
            ctx.notes.append(note)
        return ss.i_section(d[0], d[1], d[3], d[4], nu).swap_yz()
    except BayesUpdateError as exc:
        card.fail(f"{prop.name} {pid}: {exc}")


def _open_section(ctx: Context, prop, kind: str, d):
    """``BeamSection`` of a T, T2 (DIM1 flange width, DIM2 height, DIM3 flange, DIM4 web; the
    flange at the top or the bottom: one section about the centroid) or CHAN (DIM1 flange width,
    DIM2 height, DIM3 web, DIM4 flanges): exact A and I about the centroid, the element's axis
    through the centroid (a CBEAM's shear-centre offset is not modelled), J and shear areas of
    thin walls (``standard_sections``), with a note: no vendor's value of these checks them."""
    note = (f"{prop.name} {prop.id()} {kind}: J and the shear factors of thin walls; Nastran's "
            "own may differ" + ("; the shear centre's offset from the centroid is not "
            "modelled" if prop.name == "PBEAML" else ""))  # fmt: skip
    if note not in ctx.notes:
        ctx.notes.append(note)
    if kind == "CHAN":
        return ss.channel_section(d[1], d[0], d[2], d[3]).swap_yz()
    return ss.tee_section(d[1], d[0], d[3], d[2]).swap_yz()


def _orientation(grids, e, ga_row, offt: str = "GGG"):
    """Orientation vector v (3,) in basic coordinates of a CBAR/CBEAM/CBUSH (X1-X3 in GA's CD
    frame, or in basic for OFFT 'B..'; or from GA to G0); ``grids`` the deck's ``Grids``."""
    g = grids
    x1 = e["X1"]
    if isinstance(x1, int):
        return g.xyz[g.index([x1], e)[0]] - g.xyz[ga_row]
    v = np.array([e.real(k) for k in ("X1", "X2", "X3")])
    return v if offt[0] == "B" else g.frame[ga_row].T @ v


def _offt(ctx: Context, e) -> str:
    """OFFT of a CBAR/CBEAM ('GGG' when blank).  A CBEAM's field 9 may be BIT instead (a real),
    the built-in twist of a beam p-element only (MSC QRG CBEAM), which an ordinary CBEAM
    ignores: the offsets then take OFFT's default GGG, and a BIT other than 0 gets a note.  An
    integer 1 or 2 there is NASTRAN's old flag F (how X1-X3 give the orientation, which the
    fields show anyway): OFFT GGG, with a note."""
    offt = e["OFFT"]
    if isinstance(offt, str):
        return offt
    if isinstance(offt, int) and offt in (1, 2):  # the old orientation flag F
        note = ("CBAR/CBEAM field 9 = 1 or 2: NASTRAN's old orientation flag (1: X1-X3 a "
                "vector, 2: X1 the grid G0), read as OFFT GGG")  # fmt: skip
        if note not in ctx.notes:
            ctx.notes.append(note)
        return "GGG"
    if e.name != "CBEAM" or not isinstance(offt, float):
        e.fail(f"OFFT = {offt}: give a code such as GGG or BOO")
    if offt != 0.0:
        note = ("CBEAM BIT (built-in twist) is for beam p-elements only (MSC QRG CBEAM) and "
                "is ignored, as MSC ignores it on an ordinary CBEAM")  # fmt: skip
        if note not in ctx.notes:
            ctx.notes.append(note)
    return "GGG"


def offsets_in_basic(grids, e, rows, offt: str) -> np.ndarray:
    """(2, 3) end offsets WA, WB of a CBAR/CBEAM ``e`` in basic axes: OFFT 'G' = the end grid's
    CD frame, 'B' = basic, 'O' = the element's axes before its offsets (``_grid_axes``) (MSC
    QRG, CBAR/CBEAM OFFT); ``grids`` the deck's ``Grids``, ``rows`` GA's and GB's rows."""
    w = np.array([[e.real(f"W{k}{end}") for k in (1, 2, 3)] for end in "AB"])
    if len(offt) != 3 or offt[0] not in "GB" or any(c not in "GBO" for c in offt[1:]):
        e.fail(f"OFFT {offt}: give three letters, G or B for the orientation vector and G, B or "
               "O for each end's offset")  # fmt: skip
    if not np.any(w):
        return w
    axes = _grid_axes(grids, e, rows, offt) if "O" in offt[1:] else None
    for end in (0, 1):
        if offt[1 + end] == "G":
            w[end] = grids.frame[rows[end]].T @ w[end]
        elif offt[1 + end] == "O":
            w[end] = axes.T @ w[end]
    return w


def orientation_vector(grids, e) -> tuple[np.ndarray, np.ndarray]:
    """(GA's and GB's rows (2,), the orientation vector v (3,) in basic) of a CBAR/CBEAM ``e``
    as ``add`` reads them (``_orientation``; a BIT in the OFFT field reads as GGG)."""
    rows = grids.index([e.int(g, positive=True) for g in ("GA", "GB")], e)
    offt = e["OFFT"] if isinstance(e["OFFT"], str) else "GGG"
    return rows, _orientation(grids, e, rows[0], offt)


def in_grid_frames(grids, e) -> tuple[np.ndarray | None, np.ndarray]:
    """A CBAR's (or CBEAM's, with an OFFT) orientation vector and offsets as OFFT GGG gives
    them: (v (3,) in GA's CD frame, or None where G0 gives it; (2, 3) WA, WB in GA's and GB's
    CD frames), the same element for any reader of the fields (``nastran.flat``)."""
    rows = grids.index([e.int(g, positive=True) for g in ("GA", "GB")], e)
    offt = e["OFFT"] if isinstance(e["OFFT"], str) else "GGG"
    w = offsets_in_basic(grids, e, rows, offt)
    w = np.stack([grids.frame[r] @ wi for r, wi in zip(rows, w, strict=True)])
    if isinstance(e["X1"], int):
        return None, w
    return grids.frame[rows[0]] @ _orientation(grids, e, rows[0], offt), w


def _grid_axes(grids, e, rows, offt: str) -> np.ndarray:
    """(3, 3) rows x, y, z in basic of the frame that OFFT 'O' offsets are given in: the
    element's frame (``fe.elements.beam.element_frames``, z along x cross v, v the orientation
    vector) with x from GA to GB, the grids, not the offset ends: the offsets cannot define the
    frame they are given in (as pyNastran's ``rotate_v_wa_wb`` reads the QRG)."""
    a, b = grids.xyz[rows]
    z = np.cross(b - a, _orientation(grids, e, rows[0], offt))
    with np.errstate(invalid="ignore", divide="ignore"):  # degenerate: refused below
        R, _ = element_frames(a[None], b[None], z[None])
    if not np.all(np.isfinite(R)):
        e.fail("OFFT 'O': GA and GB coincide, or the orientation vector is along GA-GB")
    return R[0]


def _pins(e):
    return tuple("" if not e[p] else str(e.int(p)) for p in ("PA", "PB"))


def add(ctx: Context) -> None:
    """CBAR and CBEAM (``fe.elements.general_beam``) with PBAR, PBEAM, PBARL or PBEAML
    (``L_SECTIONS``; a PBEAM tapered linearly from end A to end B: NX's tapered element, its
    flexibility with the section linear along it; another tapered PBEAM or a tapered PBEAML:
    its mean section), offsets WA/WB and pin flags PA/PB.  G from MAT1.  Lumped mass (COUPMASS
    < 1): point masses at the element's ends (rigidly offset), (rho A + NSM) L / 2 each (a
    linearly tapered PBEAM: each end the first moment of the linear line mass, L (m_a / 3 +
    m_b / 6) at end A, NX's: ``studies/nx_tapered_cbeam.py``), and for CBEAM also half the
    torsional inertia rho (I1 + I2) L about the axis (MSC lumps none for CBAR; the beam_modes
    torsion mode shows it, 3554.909 Hz with against MSC's 3554.923).  Coupled mass (COUPMASS
    1): ``_coupled``."""
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
        section, nsm, ends = _general_section(ctx, prop, e)
    else:
        section, nsm, ends = _library_section(ctx, prop, e, mat1(ctx, mid, e).NU)
    offt = _offt(ctx, e)
    off = offsets_in_basic(ctx.grids, e, rows, offt)
    v = _orientation(ctx.grids, e, rows[0], offt)
    length, axis, up = (x[0] for x in end_geometry(ctx.grids.xyz[rows][None], off[None], v[None]))
    a, b = ctx.node[rows]
    part = f"{prop.name} {prop.id()}"
    # a linearly tapered PBEAM's or PBEAML's (A, I2 -> iy, I1 -> iz, J) at each end
    taper = None if ends is None else ends[:, [0, 2, 1, 4]]
    try:
        ctx.builder.add_beams(
            [[a, b]], section, mat, part, up=up, offsets=off, pins=_pins(e),
            mass="none" if ctx.lumped else _coupled(e), nsm=nsm * ctx.wtmass,
            shear_modulus=mat1(ctx, mid, e).G, taper=taper,
        )  # fmt: skip
    except BayesUpdateError as exc:
        e.fail(_builder_message(exc))
    if ctx.lumped:
        line = mat.density * section.area + nsm * ctx.wtmass
        twist = None
        if e.name == "CBEAM":
            twist = mat.density * (section.iy + section.iz)
            twist = lumped_twist(np.array([twist]), length[None], axis[None])[0]
        split = None
        if ends is not None and line > 0:  # m(s) linear: each end its first moment
            m_a, m_b = mat.density * ends[:, 0] + ends[:, 5] * ctx.wtmass  # L (m_a / 3 + m_b / 6)
            split = np.array([2 * m_a + m_b, m_a + 2 * m_b]) / (3 * (m_a + m_b))
        _lumped_mass(ctx, (a, b), line, length, part, twist, off, split)


def _coupled(e) -> str:
    """The coupled mass (PARAM COUPMASS 1) of a CBAR: its translations' consistent mass alone,
    no rotary or torsional inertia, as MSC's (pyNastran's ``models/aero/pt145``: every mode of
    MSC's f06 to its printed digits, where the rotary and torsional inertia moved bending by up
    to 0.05 % and torsion by 0.03 %); of a CBEAM: the consistent mass with both (MSC's CBEAM
    convention not checked)."""
    return "translational" if e.name == "CBAR" else "consistent"


def end_geometry(ends, offsets, v) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(length (n,), axis (n, 3), up (n, 3)) of CBAR/CBEAM elements whose grids sit at ``ends``
    (n, 2, 3) with end ``offsets`` (n, 2, 3) in basic axes and orientation vectors ``v`` (n, 3)
    in basic (``_orientation``) [deck length units]: the element spans the offset ends (MSC QRG
    CBAR, CBEAM), ``up`` = axis x v is its local z, the reference ``fe.elements.general_beam``
    takes (its local y is then v's part normal to the axis, v in plane 1)."""
    x = ends + offsets
    d = x[:, 1] - x[:, 0]
    length = np.linalg.norm(d, axis=1)
    axis = d / np.maximum(length, 1e-300)[:, None]
    return length, axis, np.cross(axis, v)


def lumped_twist(per_length, length, axis) -> np.ndarray:
    """(n, 3, 3) a lumped CBEAM's torsional inertia tensor, rho (I1 + I2) L about its axis
    (``per_length`` (n,) rho (I1 + I2), ``length`` (n,), ``axis`` (n, 3) unit); half of it goes to
    each end (``add``)."""
    return (per_length * length)[:, None, None] * axis[:, :, None] * axis[:, None, :]
