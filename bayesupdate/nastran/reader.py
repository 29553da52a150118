"""A Nastran deck -> ``Structure`` (through ``StructureBuilder``) and a parameter-free ``FEModel``.

Shells are converted as arrays: one ``add_shells`` call with per-element thickness (PSHELL T, or
the mean of the corner thicknesses T1-T4), ZOFFS offset and NSM, then each element's MAT1 E, nu
and density are set on the built structure (``add_shells`` takes one material per call, and one
call keeps coincident but distinct GRIDs apart: nothing is merged by distance).  Line, point,
spring and rigid cards go through ``cards``.  Units are the deck's own (``units``); PARAM WTMASS
multiplies every mass and density.  GRIDs that no element uses are dropped and DOFs with no
stiffness are held, as Nastran's AUTOSPC does.
"""

import re
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.elements import shell
from bayesupdate.fe.elements.shell import SHEAR_FACTOR, plane_stress
from bayesupdate.fe.laminate import SectionMatrices
from bayesupdate.fe.structure import Material, StructureBuilder, check_connected
from bayesupdate.nastran import cards
from bayesupdate.nastran.bulk import CardError
from bayesupdate.nastran.deck import Refusals, check_cards, read_deck
from bayesupdate.nastran.frames import BASIC, read_grids
from bayesupdate.nastran.units import unit_system

SHELL_TYPES = ("CQUAD4", "CTRIA3")


def deck_settings(deck) -> dict:
    """PARAMs and case-control selections that shape the model (module docstring)."""
    method_id = deck.case.get("METHOD")
    n_modes = None
    if method_id is not None:
        method = deck.table("EIGRL", "EIGR").get(method_id)
        if method is not None:
            n_modes = method.value(3 if method.name == "EIGRL" else 5)
    autospc = str(deck.param("AUTOSPC", "YES")).upper().startswith("Y")
    return dict(
        wtmass=float(deck.param("WTMASS", 1.0)),
        k6rot=float(deck.param("K6ROT", 100.0)),
        coupmass=int(deck.param("COUPMASS", -1)),
        autospc=autospc,
        spc_id=deck.case.get("SPC"),
        mpc_id=deck.case.get("MPC"),
        method_id=method_id,
        n_modes=int(n_modes) if isinstance(n_modes, int) else None,
    )


def _shell_cards(ctx):
    """(eids, pids, node ids (n, 4) with -1 for triangles, zoffs, corner thickness (n, 4) nan
    where blank, tflag) of all CQUAD4/CTRIA3, quads first."""
    shells = [c for _, c in sorted(ctx.elements.items(), key=cards._by_id)
              if c.name in SHELL_TYPES]  # fmt: skip
    shells.sort(key=lambda e: e.name != "CQUAD4")
    n = len(shells)
    nodes = -np.ones((n, 4), np.int64)
    corner = np.full((n, 4), np.nan)
    zoffs, tflag = np.zeros(n), np.zeros(n, np.int64)
    for i, e in enumerate(shells):  # reading the cards; the maths below is vectorized
        k = 4 if e.name == "CQUAD4" else 3
        try:
            nodes[i, :k] = [e.int(f"G{j + 1}", positive=True) for j in range(k)]
            corner[i, :k] = [np.nan if e.is_blank(f"T{j + 1}") else e.real(f"T{j + 1}")
                             for j in range(k)]  # fmt: skip
            zoffs[i], tflag[i] = e.real("ZOFFS"), e.int("TFLAG")
        except CardError as exc:
            ctx.refusals.add(str(exc))
            nodes[i, :k] = nodes[0, :k] if i else -1
    eids = np.array([e.id() for e in shells], np.int64)
    pids = np.array([int(e["PID"] or 0) for e in shells], np.int64)
    return eids, pids, nodes, zoffs, corner, tflag, shells


def _pshell_table(ctx, pids, shells):
    """Per property id: (T, MID1, NSM, 12I/T**3, TS/T, bending NU, membrane ratio) of a PSHELL,
    or the ``LaminateSection`` of a PCOMP/PCOMPG; refusals for features the shell element lacks
    (named at the property, or at the first shell whose PID is neither)."""
    table = {}
    for pid in np.unique(pids):
        p = ctx.props.get(int(pid))
        try:
            if p is None or p.name not in ("PSHELL", *cards.laminates.CARDS):
                user = next(e for e in shells if e["PID"] == pid)
                user.fail(f"shell property {pid}: not a PSHELL, PCOMP or PCOMPG")
            if p.name == "PSHELL":
                table[int(pid)] = _pshell(ctx, p)
            else:
                table[int(pid)] = cards.laminates.laminate_section(ctx, p)
        except CardError as exc:
            ctx.refusals.add(str(exc))
    return table


def _pshell(ctx, p):
    """(T, base MID, NSM, bending ratio, shear ratio, bending NU, membrane ratio, coupling) of a
    PSHELL.

    The base material is MID1 (MID2 where MID1 is blank): its E, NU and RHO are the shell's
    (the mass is MID1's RHO, MID2's where MID1 is blank: MSC Nastran QRG PSHELL remark 2).
    Bending: 12I/T**3 times E2 / E1 when MID2 is another MAT1 (a sandwich's faces), with MID2's
    NU in the bending matrix (``shell.local_pieces``); shear: TS/T times G3 / G of the base
    (G = E / 2 (1 + NU)) for a transverse shear material MID3 (its core).  MID3 blank: no
    transverse shear flexibility, the shear ratio inf (the quads are discrete Kirchhoff
    quadrilaterals, ``shell.quad_operators``; the triangles are Kirchhoff anyway).  A blank
    MID leaves its part out (remark 3): MID1 blank, no membrane (membrane ratio 0, and no
    drilling stiffness); MID2 blank, no bending and no transverse shear (bending and shear
    ratios 0: a membrane).  MID4 (a MAT1, with MID1 and MID2 given): the membrane-bending
    coupling T^2 G4 (QRG PSHELL), as the coupling (3, 3) per unit t^2 E4 D(NU4) of the shell's
    section (``fe.laminate.SectionMatrices``); None without MID4."""
    mid1, mid2, mid3 = p["MID1"], p["MID2"], p["MID3"]
    coupling = None
    if p["MID4"]:
        if mid1 is None or mid2 is None:
            p.fail("MID4 (membrane-bending coupling) needs both MID1 and MID2")
        m4 = _shell_mat1(ctx, p["MID4"], p, "MID4")
        coupling = m4.E * plane_stress(np.array([m4.NU]))[0]
    if mid2 == -1:
        p.fail("MID2 = -1 (plane strain) is not supported")
    if mid1 is None and mid2 is None:
        p.fail("MID1 and MID2 are both blank: the shell has no stiffness")
    if mid2 is None:
        if mid3 is not None:
            p.fail("MID3 must be blank when MID2 is blank (QRG PSHELL)")
        m = _shell_mat1(ctx, mid1, p, "MID1")
        return _pshell_t(p), int(mid1), p.real("NSM"), 0.0, 0.0, m.NU, 1.0, None
    bending, shear = p.real("12IT3"), p.real("TST")
    for name, v in (("12I/T**3", bending), ("TS/T", shear)):
        if not v > 0:
            p.fail(f"{name} = {v:g}: it must be > 0")
    if abs(shear - SHEAR_FACTOR) < 1e-5:  # 5/6 as an 8-character field writes it (.8333333)
        shear = SHEAR_FACTOR
    if mid3 is None:  # no transverse shear flexibility: the discrete Kirchhoff quadrilateral
        shear = np.inf
    base = cards.common.pshell_material(p)
    m = _shell_mat1(ctx, base, p, "MID1" if mid1 is not None else "MID2")
    bending_nu = m.NU
    if mid2 != base:
        m2 = _shell_mat1(ctx, mid2, p, "MID2")
        bending *= m2.E / m.E
        bending_nu = m2.NU
    if mid3 is not None and mid3 != base:
        m3 = cards.mat1(ctx, mid3, p)
        if not m3.G > 0:
            p.fail(f"MID3 {mid3}: the transverse shear material needs G > 0")
        shear *= m3.G / (m.E / (2 * (1 + m.NU)))
    membrane = 0.0 if mid1 is None else 1.0
    return _pshell_t(p), int(base), p.real("NSM"), bending, shear, bending_nu, membrane, coupling


def _pshell_t(p) -> float:
    """PSHELL T; NaN where blank (the shells then give every corner thickness, QRG PSHELL)."""
    return np.nan if p.is_blank("T") else p.real("T")


def _shell_mat1(ctx, mid, p, field):
    """The MAT1 ``mid`` of PSHELL ``p``'s ``field``, refused where its NU (given or from E and G)
    is outside (-1, 0.5)."""
    m = cards.mat1(ctx, mid, p)
    if not -1 < m.NU < 0.5:
        p.fail(f"{field} {mid}: NU = {m.NU:.4g} (from E and G) is outside (-1, 0.5)")
    return m


def _shell_arrays(ctx, pids, nodes, corner, tflag, zoffs, shells):
    """Per-element thickness (mean of the corner thicknesses; blank corners take PSHELL T,
    TFLAG 1 makes them factors of T), E, nu, rho, nsm (WTMASS applied) and offset arrays, and
    the laminates' sections (``_laminate_arrays``); None when a property is refused."""
    table = _pshell_table(ctx, pids, shells)
    uniq, inv = np.unique(pids, return_inverse=True)
    kinds = {int(p): getattr(ctx.props.get(int(p)), "name", None) for p in uniq}
    lam = np.isin(pids, [p for p, k in kinds.items() if k in cards.laminates.CARDS])
    angle = _material_angles(ctx, nodes, shells, lam)  # its refusals too where a PCOMP is
    laminates = {p: row for p, row in table.items() if not isinstance(row, tuple)}
    table = table | {p: _laminate_row(row) for p, row in laminates.items()}
    partial = {p for p, row in table.items() if row[3] == 0 or row[6] == 0}
    for i in np.flatnonzero(np.isin(pids, list(partial)) & (zoffs != 0)):  # QRG remark 3's note
        ctx.refusals.card(
            shells[i],
            "ZOFFS needs both MID1 and MID2 on its PSHELL (or a "
            "PCOMP's membrane and bending: LAM blank or SYM)",
        )
    if any(int(p) not in table for p in uniq):
        return None
    t_p, mid, nsm, bending, shear, bending_nu, membrane = (
        np.array([table[int(p)][k] for p in uniq]) for k in range(7))  # fmt: skip
    E, nu, rho = _shell_materials(ctx, uniq, mid, laminates)
    t = t_p[inv][:, None]
    corner_t = np.where(np.isnan(corner), t, np.where(tflag[:, None] == 1, corner * t, corner))
    n_nodes = np.where(nodes[:, 3] >= 0, 4, 3)
    valid = np.arange(4)[None, :] < n_nodes[:, None]
    for i in np.flatnonzero(np.any(np.isnan(corner_t) & valid, axis=1)):  # T blank
        why = "TFLAG 1 scales T" if tflag[i] == 1 else "a corner thickness (T1-T4) is blank"
        ctx.refusals.card(shells[i], f"{why}, and PSHELL {pids[i]} has no T")
    thickness = np.where(valid, corner_t, 0.0).sum(axis=1) / n_nodes
    props = dict(thickness=thickness, E=E[inv], nu=nu[inv], rho=rho[inv],
                 nsm=nsm[inv] * ctx.wtmass, offset=zoffs, bending_ratio=bending[inv],
                 shear_ratio=shear[inv], bending_nu=bending_nu[inv],
                 membrane_ratio=membrane[inv], section=None,
                 cards={p: ctx.props[p].name for p in laminates})  # fmt: skip
    couplings = {p: row[7] for p, row in table.items() if row[7] is not None}
    if laminates or couplings:
        _laminate_arrays(props, pids, angle, laminates, couplings)
    return props


def _laminate_row(lam) -> tuple:
    """A ``LaminateSection`` as a PSHELL table row (T, no MID, NSM, ratios, NU 0)."""
    bending, shear, membrane = lam.ratios
    return lam.thickness, 0, lam.nsm, bending, shear, 0.0, membrane, None


def _shell_materials(ctx, uniq, mid, laminates):
    """(E, nu, rho) per property id of ``uniq``: its MAT1's (WTMASS applied), or for a laminate
    its membrane's A11 / T (the shell's nominal E: the stiffness is the section's), 0 and the
    plies' mean density."""
    rows = []
    for p, m in zip(uniq, mid, strict=True):
        lam = laminates.get(int(p))
        if lam is not None:
            rows.append((lam.section.membrane[0, 0, 0] or lam.section.bending[0, 0, 0], 0.0,
                         lam.rho_t / lam.thickness))  # fmt: skip
        else:
            mat = cards.material(ctx, int(m), ctx.props[int(p)])
            rows.append((mat.youngs_modulus, mat.poisson, mat.density))
    return (np.array(col, dtype=float) for col in zip(*rows, strict=True))


def _laminate_arrays(props, pids, angle, laminates, couplings) -> None:
    """The laminates' entries of ``props``: each element's section in its local axes (``angle``
    (n,) [rad] their material axes from their local x-axes, ``_material_angles``), the offset
    of the stack's mid-plane added to ZOFFS, and for the other shells their isotropic sections
    (``fe.laminate.SectionMatrices``) with the coupling of a PSHELL's MID4 (``couplings``:
    PSHELL id -> (3, 3) per unit t^2)."""
    iso = _isotropic_sections(props)
    membrane, bending, shear = iso.membrane, iso.bending, iso.shear
    coupling = np.array([couplings.get(int(p), np.zeros((3, 3))) for p in pids])
    rotary = np.ones(len(pids))
    for pid, lam in laminates.items():  # each laminate's one section on all its shells
        rows, sec = pids == pid, lam.section
        membrane[rows], bending[rows], shear[rows] = sec.membrane, sec.bending, sec.shear
        coupling[rows] = 0.0 if sec.coupling is None else sec.coupling
        rotary[rows] = 1.0 if sec.rotary is None else sec.rotary
    coupled = bool(couplings) or any(lam.section.coupling is not None for lam in laminates.values())
    section = SectionMatrices(membrane, bending, shear, coupling if coupled else None,
                              None if np.all(rotary == 1.0) else rotary)  # fmt: skip
    props["section"] = section.rotated(angle)
    props["offset"] = props["offset"] + np.array([getattr(laminates.get(int(p)), "offset", 0.0)
                                                  for p in pids])  # fmt: skip


def _isotropic_sections(props) -> SectionMatrices:
    """The PSHELL shells' sections per unit thickness (``shell.local_pieces``'s isotropic
    pieces as a section): E D(nu) x membrane ratio, E D(bending nu) x bending ratio, kappa G
    (0 where shear rigid or absent)."""
    E, nu, bnu = props["E"], props["nu"], props["bending_nu"]
    G = E / (2 * (1 + nu))
    shear = np.where(np.isfinite(props["shear_ratio"]), props["shear_ratio"], 0.0)
    return SectionMatrices(
        (E * props["membrane_ratio"])[:, None, None] * plane_stress(nu),
        (E * props["bending_ratio"])[:, None, None] * plane_stress(bnu),
        (shear * G)[:, None, None] * np.eye(2),
    )


def _material_angles(ctx, nodes, shells, lam) -> np.ndarray:
    """(n,) angle [rad] of each laminate shell's material x-axis from its local x-axis
    (``shell.quad_frames`` / ``tria_frames``): THETA [deg] from the G1-G2 side, or MCID's
    x-axis projected on the element (a rectangular system); 0 for the other shells."""
    angle = np.zeros(len(nodes))
    axis, turn = np.zeros((len(nodes), 3)), np.zeros(len(nodes))
    for i in np.flatnonzero(lam):  # the cards' fields; the geometry below is vectorized
        e = shells[i]
        theta = e.value(e.position("THETA"))
        if isinstance(theta, int):  # MCID
            found = ctx.refusals.guard(_mcid_axis, ctx, e, theta)
            axis[i] = np.nan if found is None else found  # a refused deck: never built
        elif theta is not None:
            turn[i] = np.radians(theta)
    known = np.all(np.isin(np.where(nodes >= 0, nodes, nodes[:, :1]), ctx.grids.ids), axis=1)
    for k, frames in ((4, shell.quad_frames), (3, shell.tria_frames)):
        rows = np.flatnonzero(lam & known & ((nodes[:, 3] >= 0) == (k == 4)))
        if not rows.size:
            continue
        x = ctx.grids.xyz[ctx.grids.index(nodes[rows, :k], "shell")]
        R = frames(x).R
        side = np.where(np.any(axis[rows], axis=1)[:, None], axis[rows], x[:, 1] - x[:, 0])
        angle[rows] = np.arctan2(np.einsum("ni,ni->n", side, R[:, 1]),
                                 np.einsum("ni,ni->n", side, R[:, 0])) + turn[rows]  # fmt: skip
    return angle


def _mcid_axis(ctx, e, mcid: int) -> np.ndarray:
    """The x-axis (3,) in basic of the rectangular system ``mcid`` (0: basic)."""
    frame = ctx.grids.coords.get(mcid, BASIC if mcid == 0 else None)
    if frame is None:
        e.fail(f"MCID {mcid}: the deck has no coordinate system {mcid} it could read")
    if frame.kind != "rectangular":
        e.fail(f"MCID {mcid}: give a rectangular coordinate system (CORD1R/CORD2R) or THETA")
    return frame.axes[0]


def _used_rows(ctx, shell_nodes):
    """Grid rows of shell nodes (sorted) and of the other GRIDs some element uses (an element
    naming a missing GRID is refused here)."""
    g = ctx.grids
    ok = shell_nodes[shell_nodes >= 0]
    ok = ok[np.isin(ok, g.ids)] if len(g.ids) else ok[:0]
    for e in ctx.elements.values():  # shells naming a missing GRID
        if e.name in SHELL_TYPES:
            ctx.refusals.guard(lambda e=e: g.index(cards.element_grids(e), e))
    shell_rows = np.unique(g.index(ok, "shell element")) if ok.size else np.zeros(0, np.int64)
    other, known = [], set(g.ids.tolist())
    for e in ctx.elements.values():
        if e.name not in SHELL_TYPES:
            ids = ctx.refusals.guard(cards.element_grids, e) or []
            other += [i for i in ids if i in known]
    rows = np.unique(g.index(np.array(other, np.int64), "element")) if other else np.zeros(0, int)
    return shell_rows, np.setdiff1d(rows, shell_rows)


def _add_shells(ctx, shell_rows, pids, nodes, props):
    """One ``add_shells`` call on an empty builder (structure nodes 0..k-1 = ``shell_rows``)."""
    local = np.searchsorted(
        shell_rows, ctx.grids.index(np.where(nodes >= 0, nodes, nodes[:, :1]), "shell")
    )
    quad = nodes[:, 3] >= 0
    first = Material(props["E"][0], props["nu"][0], max(props["rho"][0], 1e-300))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ctx.builder.add_shells(
            ctx.grids.xyz[shell_rows], local[quad], local[~quad, :3],
            thickness=props["thickness"], material=first, part=f"PSHELL {pids[0]}",
            offset=props["offset"], nsm=props["nsm"], merge_tol=0.0,
        )  # fmt: skip
    ctx.notes += [str(w.message) for w in caught]


def _patch_shells(structure, pids, props, lumped: bool):
    """Per-element material, laminate sections and part ("PSHELL id", "PCOMP id") on the built
    structure's shells; ``lumped``: their mass lumped, translational only (PARAM COUPMASS < 1,
    Nastran's default)."""
    label = {int(p): f"{props['cards'].get(int(p), 'PSHELL')} {p}" for p in np.unique(pids)}
    parts = tuple(structure.parts) + tuple(n for n in label.values() if n not in structure.parts)
    part = np.array([parts.index(label[int(p)]) for p in pids])
    rho = np.maximum(props["rho"], 0.0)
    # None where every shell has the solid section's ratios: the arrays' products are then
    # left out, and decks without 12I/T**3 or TS/T keep their bits
    bending, shear, bending_nu = props["bending_ratio"], props["shear_ratio"], props["bending_nu"]
    membrane = props["membrane_ratio"]
    ratios = dict(
        bending_ratio=None if np.all(bending == 1.0) else bending,
        shear_ratio=None if np.all(shear == SHEAR_FACTOR) else shear,
        bending_nu=None if np.all(bending_nu == props["nu"]) else bending_nu,
        membrane_ratio=None if np.all(membrane == 1.0) else membrane,
    )
    shells = replace(structure.shells, E=props["E"], nu=props["nu"], rho=rho, part=part,
                     lumped=lumped, section=props["section"], **ratios)  # fmt: skip
    return replace(structure, shells=shells, parts=parts)


def _set_cards(deck, sid, kinds, add_card, seen=()) -> list:
    """The ``kinds`` cards of set ``sid``, its ``add_card`` unions resolved: ("SPC", "SPC1")
    with "SPCADD", ("MPC",) with "MPCADD"."""
    out = [c for c in deck.of(*kinds) if c.value(0) == sid]
    for add in deck.of(add_card):
        if add.value(0) == sid and sid not in seen:
            for s in cards.id_list(add, 1):
                out += _set_cards(deck, s, kinds, add_card, (*seen, sid))
    return out


def _add_mpcs(ctx, deck, settings) -> None:
    """The MPC equations of the case control's MPC set (MPCADD resolved; MSC QRG MPC: G1 C1 A1
    the dependent term, then Gi Ci Ai three to a half line); MPC sets the case control does not
    select are listed in a note and left out, as Nastran leaves them."""
    sid = settings["mpc_id"]
    chosen = _set_cards(deck, sid, ("MPC",), "MPCADD") if sid is not None else []
    if sid is not None and not chosen:
        ctx.refusals.add(f"case control MPC = {sid}: no MPC/MPCADD with that id")
    unused = sorted({c.value(0) for c in deck.of("MPC")} - {c.value(0) for c in chosen})
    if unused:
        ctx.notes.append(f"MPC set(s) {unused} not selected by the case control: left out")
    for c in chosen:
        ctx.refusals.guard(_add_mpc, ctx, c)


def _add_mpc(ctx, c) -> None:
    """One MPC card's equation (its terms' GRIDs with a rotated CD frame get that frame)."""
    n_lines = (len(c.raw) + 7) // 8
    starts = [1, 4] + [8 * k + s for k in range(1, n_lines) for s in (1, 4)]
    terms = []
    for i in starts:
        if c.value(i) is None:
            continue
        gid, comp, coef = c.value(i), c.value(i + 1), c.value(i + 2)
        if gid in ctx.spoints or not isinstance(comp, int) or not 1 <= comp <= 6:
            c.fail(f"term G {gid} C {comp}: give a GRID and one component 1-6")
        row = ctx.grids.index([gid], c)[0]
        mask = np.zeros(6, bool)
        mask[comp - 1] = True
        cards.common.frame_partial(ctx, mask, row)
        terms.append((int(ctx.node[row]), str(comp), float(coef or 0.0)))
    try:
        ctx.rigid[f"mpc {ctx.builder.add_mpc(terms)}"] = c
    except BayesUpdateError as exc:
        c.fail(str(exc).split(": ", 1)[-1])


def _add_spcs(ctx, deck, settings):
    """SPC/SPC1 of the case control's SPC set (SPCADD resolved) and GRID PS fields."""
    items = []  # (grid, components, card)
    sid = settings["spc_id"]
    if sid is not None:
        spcs = _set_cards(deck, sid, ("SPC", "SPC1"), "SPCADD")
        if not spcs:
            ctx.refusals.add(f"case control SPC = {sid}: no SPC/SPC1/SPCADD with that id")
        for c in spcs:
            if c.name == "SPC1":
                ids = ctx.refusals.guard(cards.id_list, c, 2) or []
                items += [(g, str(c["C"]), c) for g in ids]
            else:
                for k in (1, 4):
                    if c.value(k) is not None:
                        items.append((c.value(k), str(c.value(k + 1)), c))
                        if c.value(k + 2):
                            ctx.refusals.card(c, "an enforced displacement D is not supported")
    for gid, ps in zip(ctx.grids.ids, ctx.grids.ps, strict=True):
        if ps:
            items.append((int(gid), ps, deck.table("GRID")[int(gid)]))
    for gid, comps, card in items:
        if gid in ctx.spoints or gid in ctx.unused_spoints:
            _hold_spoint(ctx, gid, comps, card)
            continue
        try:
            row = ctx.grids.index([gid], card)[0]
            if ctx.node[row] >= 0:
                digits = cards.components(ctx, comps, [row], card)
                ctx.builder.add_support(int(ctx.node[row]), digits)
        except CardError as exc:
            ctx.refusals.add(str(exc))


def _hold_spoint(ctx, sid: int, comps: str, card) -> None:
    """SPC/SPC1 on a scalar point (component 0 or blank): its one DOF held."""
    if comps not in ("0", "None", ""):
        ctx.refusals.card(card, f"SPOINT {sid}: component {comps}; a scalar point has one DOF "
                          "(give 0 or blank)")  # fmt: skip
    elif sid in ctx.spoints:
        end = ctx.spoints[sid]
        ctx.builder.add_support(end.node, str(end.comp))


def _autospc(ctx, structure):
    """Hold the independent DOFs with no stiffness (Nastran's AUTOSPC), found per node in its
    CD axes on the constrained stiffness by ``fe.autospc.singular_dofs`` (a grid with a rotated
    CD frame held on a partial set gets that frame, ``cards.common.frame_partial``); a node
    whose singular direction off its axes carries mass is refused.  Returns the number held."""
    from bayesupdate.fe.assembly import Assembler
    from bayesupdate.fe.autospc import singular_dofs
    from bayesupdate.fe.constraints import Constraints, constraint_transform

    a = Assembler(structure)
    K, M, _ = a.assemble(a.default_properties())
    c = structure.constraints if structure.constraints is not None else Constraints()
    tr = constraint_transform(structure.nodes, c)
    # rows: the node's CD axes in the reduced DOFs' axes (basic, or the frame it already has)
    axes = np.broadcast_to(np.eye(3), (structure.n_nodes, 3, 3)).copy()
    rows = np.flatnonzero(ctx.node >= 0)
    rotated = rows[~ctx.grids.is_basic(rows) & ~np.isin(rows, list(ctx.framed))]
    axes[ctx.node[rotated]] = ctx.grids.frame[rotated]
    found = singular_dofs(tr.reduce(K), tr.reduce(M), tr.independent, axes)
    row_of_node = dict(zip(ctx.node[rows].tolist(), rows.tolist(), strict=True))
    # each node's held components, found in one pass (not one scan of them all per node)
    nodes, at = np.unique(found.held // 6, return_inverse=True)
    masks = np.zeros((nodes.size, 6), bool)
    masks[at, found.held % 6] = True
    for node, mask in zip(nodes.tolist(), masks, strict=True):
        if node in row_of_node:
            cards.common.frame_partial(ctx, mask, row_of_node[node])
        ctx.builder.add_support(node, "".join(str(i + 1) for i in np.flatnonzero(mask)))
    names = ctx.builder.node_names
    if found.off_axis.size:
        ctx.notes.append(
            f"{found.off_axis.size} GRID(s) have rotations with no stiffness and no "
            "mass off their axes (e.g. a membrane skewed to them), held through "
            f"chosen components (AUTOSPC; exact): {_few(names, found.off_axis)}"
        )
    if found.loose.size:
        raise BayesUpdateError(
            f"{found.loose.size} GRID(s) have a direction with mass but no stiffness that is not "
            "along their axes (e.g. the normal of a flat membrane skewed to them), which "
            "AUTOSPC cannot hold without changing the answer: hold it by an SPC in a CD frame "
            f"along it, or connect it: {_few(names, found.loose)}")  # fmt: skip
    return found.held.size


def _few(name, nodes, shown: int = 5) -> str:
    """The first ``shown`` of ``nodes`` by ``name`` (a node's label), and how many more."""
    text = ", ".join(name(int(n)) for n in nodes[:shown])
    return text + (f" and {nodes.size - shown} more" if nodes.size > shown else "")


def context(deck, grids, node, settings, builder, refusals) -> cards.Context:
    """The converters' ``cards.Context`` of a read deck."""
    elements = {(c.name, c.value(0)): c for c in deck.of(*cards.ELEMENTS)}
    return cards.Context(
        elements, deck.table(*cards.PROPERTIES), deck.table("MAT1", "MAT8"), grids,
        node, settings["wtmass"], settings["coupmass"] < 1, builder, refusals,
        spoint_cards=tuple(deck.of("SPOINT")),
    )  # fmt: skip


def read_structure(path, design: bool = False) -> tuple:
    """(Structure, info, Deck) of the Nastran deck at ``path``; info records units, PARAMs,
    counts and notes (also in ``structure.metadata["nastran"]``).  Every refusal of the deck is
    raised together, as one ``BayesUpdateError`` (``deck.Refusals``); with ``design`` (the
    DESVARs are to be the parameters) also each DVPREL1 to a field that cannot be bound."""
    from bayesupdate.nastran.desvar import design_refusals

    refusals = Refusals(str(path))
    deck = read_deck(path, refusals)
    notes = check_cards(deck, refusals)
    if design and deck.of("DESVAR"):
        for message in design_refusals(deck):
            refusals.add(message)
    settings = deck_settings(deck)
    grids = read_grids(deck, refusals)
    ctx = context(deck, grids, -np.ones(len(grids.ids), np.int64), settings, StructureBuilder(),
                  refusals)  # fmt: skip
    ctx.notes += list(deck.notes) + notes
    eids, pids, nodes, zoffs, corner, tflag, shells = _shell_cards(ctx)
    shell_rows, other_rows = _used_rows(ctx, nodes)
    ctx.node[shell_rows] = np.arange(shell_rows.size)
    props = None
    if eids.size:
        props = _shell_arrays(ctx, pids, nodes, corner, tflag, zoffs, shells)
        if props is not None and not refusals.items:
            _add_shells(ctx, shell_rows, pids, nodes, props)
        else:  # the shells' nodes alone, so that the cards after them still find theirs
            for row in shell_rows:  # and every refusal of the deck is collected
                ctx.builder.add_node(grids.xyz[row])
    scalar_only = any(c.name in cards.scalar.SCALAR_ENDS for c in ctx.elements.values())
    if not shell_rows.size and not other_rows.size and not scalar_only:
        refusals.add("the deck has no elements")
    for row in other_rows:
        ctx.node[row] = ctx.builder.add_node(grids.xyz[row])
    for family in cards.FAMILIES:
        family.add(ctx)
    _add_spcs(ctx, deck, settings)
    _add_mpcs(ctx, deck, settings)
    refusals.raise_all()
    try:
        structure = _finish(ctx, eids, pids, props)
        n_auto = 0
        if settings["autospc"]:
            n_auto = _autospc(ctx, structure)
            if n_auto:
                structure = _finish(ctx, eids, pids, props)
    except BayesUpdateError as exc:
        raise _named(ctx, exc) from None
    info = _info(ctx, settings, deck, grids, structure, n_auto)
    meta = {**structure.metadata, "nastran": info}
    if deck.of("SUPORT", "SUPORT1"):
        # MSC's SUPORT makes every allowed rigid motion a rigid mode, also where soft springs to
        # ground give them a little energy (``fe.sparse_modal``, ``ModalSettings.rigid_set``)
        meta["rigid_set"] = "rigid_motions"
    return replace(structure, metadata=meta), info, deck


def node_namer(grid_of_node: dict, spoint_of_node: dict):
    """node index -> its name in a deck's messages: "GRID 12", "SPOINT 7", or a CBUSH arm's
    end (a node of no GRID); grid_of_node, spoint_of_node : {node index: GRID / SPOINT id}."""

    def name(node: int) -> str:
        if node in grid_of_node:
            return f"GRID {grid_of_node[node]}"
        if node in spoint_of_node:
            return f"SPOINT {spoint_of_node[node]}"
        return f"(a CBUSH arm end, node {node})"

    return name


def _deck_names(ctx):
    """``node_namer`` of the deck being read."""
    rows = np.flatnonzero(ctx.node >= 0)
    grids = dict(zip(ctx.node[rows].tolist(), ctx.grids.ids[rows].tolist(), strict=True))
    return node_namer(grids, {end.node: s for s, end in ctx.spoints.items()})


def _named(ctx, exc) -> BayesUpdateError:
    """The structure's error with its rigid elements ('rbe3 0', the builder's index) named by
    their cards' file:line and label, and its DOFs ('node 2 uz', the builder's node index) by
    the deck's names ('GRID 103 uz', ``node_namer``)."""

    def card(m):
        c = ctx.rigid.get(m.group(0))
        return m.group(0) if c is None else f"{c.where} {c.label}"

    names = _deck_names(ctx)
    text = re.sub(r"\b(rbe[23]|mpc) \d+", card, str(exc))
    text = re.sub(r"\bnode (\d+)(?= [ur][xyz]\b)", lambda m: names(int(m.group(1))), text)
    return BayesUpdateError(f"Nastran model {ctx.refusals.path}: {text}")


def _finish(ctx, eids, pids, props):
    # the connectivity check runs on the whole deck and names its GRIDs, not node indices
    grid_name = _deck_names(ctx)
    ctx.builder.node_names = grid_name
    structure = ctx.builder.build(check=False)
    for finish in ctx.finishers:
        family, parts = finish(structure.parts)
        if family is not None:
            structure = replace(structure, elements=(*structure.elements, family), parts=parts)
    check_connected(structure, grid_name)
    if props is not None and eids.size:
        structure = _patch_shells(structure, pids, props, ctx.lumped)
    return structure


def _info(ctx, settings, deck, grids, structure, n_auto) -> dict:
    moduli = [cards.mat1(ctx, m, c).E for m, c in ctx.mats.items() if c.name == "MAT1"]
    dropped = int(np.sum(ctx.node < 0))
    notes = list(ctx.notes)
    if dropped:
        notes.append(f"{dropped} GRID(s) used by no element were dropped (AUTOSPC)")
    if n_auto:
        notes.append(f"{n_auto} DOF(s) with no stiffness were held (AUTOSPC)")
    if structure.shells is not None and np.any(structure.shells.offset):
        notes.append("shell ZOFFS: the mass moves with the mid-surface, as the stiffness does "
                     "(MSC's QRG PSHELL remark 6 says the mass is not offset; not checked "
                     "against MSC)")  # fmt: skip
    if structure.shells is not None:
        notes.append(f"PARAM K6ROT {settings['k6rot']:g} not applied: the shell's drilling "
                     "penalty is fixed (fe.elements.shell.DRILL_ALPHA)")  # fmt: skip
        notes.append("shell mass lumped at the GRIDs, translational only (PARAM COUPMASS -1, "
                     "Nastran's default)" if structure.shells.lumped else "shell mass "
                     "consistent, with rotary inertia (PARAM COUPMASS 1)")  # fmt: skip
    n_nodes = structure.n_nodes
    used = ctx.node >= 0
    grid_of_node = np.zeros(n_nodes, np.int64)  # 0: a node of no GRID (a CBUSH's arm ends)
    grid_of_node[ctx.node[used]] = grids.ids[used]
    # each node's output (CD) frame, rows = its axes in basic: test directions given in it
    frame_of_node = np.broadcast_to(np.eye(3), (n_nodes, 3, 3)).copy()
    frame_of_node[ctx.node[used]] = grids.frame[used]
    return dict(
        deck=str(Path(deck.path).name),
        units=unit_system(moduli, settings["wtmass"]),
        **settings,
        card_count=deck.count(),
        grid_ids=grid_of_node,
        grid_frames=frame_of_node,
        grid_sets=_grid_sets(deck),
        notes=notes,
        # {SPOINT id: (node, its DOF (6,) on the node's global DOFs)}: a scalar point's value
        # in a shape phi (n_dof,) is phi[6 node : 6 node + 6] @ direction
        spoint_dofs={s: (e.node, e.direction) for s, e in sorted(ctx.spoints.items())},
        spoint_rigid_mass=cards.scalar.rigid_share(structure.nodes, ctx.spoint_masses),
    )


def _grid_sets(deck) -> dict[int, tuple[int, ...]]:
    """{set id: GRID ids} of the bulk SET1 cards and the case control's SET lines (test points
    'all GRIDs of a set', ``test_points``)."""
    sets = {}
    for c in deck.of("SET1"):
        ids = [i for i in (cards.id_list(c, 1) if c.value(1) != "ALL" else [])]
        sets.setdefault(c.id(), tuple(ids))
    for sid, ids in deck.case_sets.items():
        sets.setdefault(int(sid), tuple(ids))
    return sets
