"""A Nastran deck -> ``Structure`` (through ``StructureBuilder``) and a parameter-free ``FEModel``.

Shells are converted as arrays: one ``add_shells`` call with per-element thickness (PSHELL T, or
the mean of the corner thicknesses T1-T4), ZOFFS offset and NSM, then each element's MAT1 E, nu
and density are set on the built structure (``add_shells`` takes one material per call, and one
call keeps coincident but distinct GRIDs apart: nothing is merged by distance).  Line, point,
spring and rigid cards go through ``cards``.  Units are the deck's own (``units``); PARAM WTMASS
multiplies every mass and density.  GRIDs that no element uses are dropped and DOFs with no
stiffness are held, as Nastran's AUTOSPC does.
"""

import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.shell import SHEAR_FACTOR
from bayesupdate.fe.structure import Material, StructureBuilder
from bayesupdate.nastran import cards
from bayesupdate.nastran.deck import read_deck
from bayesupdate.nastran.frames import read_grids
from bayesupdate.nastran.units import unit_system

SHELL_TYPES = ("CQUAD4", "CTRIA3")


def _param(model, name, default):
    card = model.params.get(name)
    if card is None:
        return default
    value = card.values[0]
    return value if value is not None else default


def _case_value(subcase, name):
    """An integer case-control selection, or None (pyNastran's has_parameter can say yes for a
    name its get_parameter then refuses: the global subcase 0 of a deck without subcases)."""
    if subcase is None or not subcase.has_parameter(name):
        return None
    try:
        return int(subcase.get_parameter(name)[0])
    except KeyError:
        return None


def deck_settings(model) -> dict:
    """PARAMs and case-control selections that shape the model (module docstring)."""
    cc = model.case_control_deck
    spc_id = method_id = None
    if cc is not None:
        sub = cc.subcases.get(1) or cc.subcases.get(0)
        spc_id, method_id = _case_value(sub, "SPC"), _case_value(sub, "METHOD")
    n_modes = None
    if method_id is not None and method_id in model.methods:
        n_modes = model.methods[method_id].nd
    autospc = str(_param(model, "AUTOSPC", "YES")).upper().startswith("Y")
    return dict(
        wtmass=float(_param(model, "WTMASS", 1.0)),
        k6rot=float(_param(model, "K6ROT", 100.0)),
        coupmass=int(_param(model, "COUPMASS", -1)),
        autospc=autospc,
        spc_id=spc_id,
        method_id=method_id,
        n_modes=None if n_modes is None else int(n_modes),
    )


def _shell_cards(model):
    """(eids, pids, node ids (n, 4) with -1 for triangles, zoffs, corner thickness (n, 4) nan
    where blank, tflag) of all CQUAD4/CTRIA3, quads first (pyNastran objects -> arrays)."""
    shells = [e for _, e in sorted(model.elements.items()) if e.type in SHELL_TYPES]
    shells.sort(key=lambda e: e.type != "CQUAD4")
    n = len(shells)
    nodes = -np.ones((n, 4), np.int64)
    corner = np.full((n, 4), np.nan)
    for i, e in enumerate(shells):  # reading pyNastran's objects; the maths below is vectorised
        ids = e.node_ids
        nodes[i, : len(ids)] = ids
        corner[i, : len(ids)] = [
            np.nan if t is None else t for t in (e.T1, e.T2, e.T3, getattr(e, "T4", None))
        ][: len(ids)]
    eids = np.array([e.eid for e in shells], np.int64)
    pids = np.array([e.pid for e in shells], np.int64)
    zoffs = np.array([e.zoffset or 0.0 for e in shells], float)
    tflag = np.array([e.tflag for e in shells], np.int64)
    return eids, pids, nodes, zoffs, corner, tflag


def _pshell_table(ctx, pids):
    """Per property id: (T, MAT1 id, NSM); errors for features the shell element lacks."""
    table = {}
    for pid in np.unique(pids):
        p = ctx.model.properties.get(int(pid))
        if p is None or p.type != "PSHELL":
            raise BayesUpdateError(f"shell property {pid}: not a PSHELL (only PSHELL is supported)")
        if p.mid2 not in (None, p.mid1) or p.mid3 not in (None, p.mid1) or p.mid4:
            ctx.fail("PSHELL", pid, "MID2/MID3 must equal MID1 (or be blank) and MID4 blank")
        if p.mid2 is None:
            ctx.fail("PSHELL", pid, "a membrane-only shell (MID2 blank) is not supported")
        if abs((p.twelveIt3 or 1.0) - 1.0) > 1e-6:
            ctx.fail("PSHELL", pid, f"12I/T**3 = {p.twelveIt3} is not supported (only 1.0)")
        if p.mid3 is not None and abs((p.tst or SHEAR_FACTOR) - SHEAR_FACTOR) > 1e-4:
            ctx.fail("PSHELL", pid, f"TS/T = {p.tst} is not supported (only 5/6)")
        if p.mid3 is None:
            ctx.notes.append(f"PSHELL {pid}: MID3 blank (no shear flexibility) is modelled as a "
                             "Mindlin shell with TS/T = 5/6")  # fmt: skip
        table[int(pid)] = (float(p.t), int(p.mid1), float(p.nsm or 0.0))
    return table


def _shell_arrays(ctx, pids, nodes, corner, tflag, zoffs):
    """Per-element thickness (mean of the corner thicknesses; blank corners take PSHELL T,
    TFLAG 1 makes them factors of T), E, nu, rho, nsm (WTMASS applied) and offset arrays."""
    table = _pshell_table(ctx, pids)
    uniq, inv = np.unique(pids, return_inverse=True)
    t_p, mid, nsm = (np.array([table[int(p)][k] for p in uniq]) for k in range(3))
    mats = {
        int(m): cards.material(ctx, int(m), "PSHELL", int(p))
        for p, m in zip(uniq, mid, strict=True)
    }
    E, nu, rho = (np.array([getattr(mats[int(m)], a) for m in mid]) for a in
                  ("youngs_modulus", "poisson", "density"))  # fmt: skip
    t = t_p[inv][:, None]
    corner_t = np.where(np.isnan(corner), t, np.where(tflag[:, None] == 1, corner * t, corner))
    n_nodes = np.where(nodes[:, 3] >= 0, 4, 3)
    valid = np.arange(4)[None, :] < n_nodes[:, None]
    thickness = np.where(valid, corner_t, 0.0).sum(axis=1) / n_nodes
    return dict(thickness=thickness, E=E[inv], nu=nu[inv], rho=rho[inv],
                nsm=nsm[inv] * ctx.wtmass, offset=zoffs)  # fmt: skip


def _used_rows(ctx, shell_nodes):
    """Grid rows of shell nodes (sorted) and of the other GRIDs some element uses."""
    g = ctx.grids
    shell_rows = np.unique(g.index(shell_nodes[shell_nodes >= 0], "shell element"))
    other = []
    for e in ctx.model.elements.values():
        if e.type not in SHELL_TYPES:
            other += [n for n in e.node_ids if n]
    other += [m.nid for m in ctx.model.masses.values()]
    for r in ctx.model.rigid_elements.values():
        other += list(r.independent_nodes) + list(r.dependent_nodes)
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


def _patch_shells(structure, pids, props):
    """Per-element material and part (PSHELL id) on the built structure's shells."""
    names = [f"PSHELL {p}" for p in np.unique(pids)]
    parts = tuple(structure.parts) + tuple(n for n in names if n not in structure.parts)
    part = np.array([parts.index(f"PSHELL {p}") for p in pids])
    rho = np.maximum(props["rho"], 0.0)
    shells = replace(structure.shells, E=props["E"], nu=props["nu"], rho=rho, part=part)
    return replace(structure, shells=shells, parts=parts)


def _add_spcs(ctx, settings):
    """SPC/SPC1 of the case control's SPC set (SPCADD resolved) and GRID PS fields."""
    items = []
    if settings["spc_id"] is not None:
        try:
            spcs = ctx.model.get_reduced_spcs(settings["spc_id"], consider_spcadd=True)
        except Exception:  # a missing set: pyNastran raises KeyError/RuntimeError
            raise BayesUpdateError(
                f"case control SPC = {settings['spc_id']}: no SPC/SPC1/SPCADD with that id"
            ) from None
        for spc in spcs:
            if spc.type == "SPC1":
                items += [(n, str(spc.components), "SPC1", spc.conid) for n in spc.node_ids]
            else:
                items += [
                    (n, str(c), "SPC", spc.conid)
                    for n, c in zip(spc.node_ids, spc.components, strict=True)
                ]
    for gid, ps in zip(ctx.grids.ids, ctx.grids.ps, strict=True):
        if ps:
            items.append((int(gid), ps, "GRID", int(gid)))
    for gid, comps, card, sid in items:
        row = ctx.grids.index([gid], f"{card} {sid}")[0]
        if ctx.node[row] >= 0:
            digits = cards.components(ctx, comps, [row], card, sid)
            ctx.builder.add_support(int(ctx.node[row]), digits)


def _autospc(ctx, structure):
    """Hold the independent DOFs with no stiffness at all (Nastran's AUTOSPC): shell and beam
    nodes have all six; springs and rods are checked on their assembled diagonal."""
    from bayesupdate.fe.assembly import Assembler
    from bayesupdate.fe.constraints import Constraints, constraint_transform
    from bayesupdate.fe.general import line_matrices

    a = Assembler(structure)
    K, _, _ = a.assemble(a.default_properties())
    diag = np.abs(K.diagonal())
    for dofs, Ke, _ in line_matrices(structure):
        np.add.at(diag, dofs.ravel(), np.abs(np.diagonal(Ke, axis1=1, axis2=2)).ravel())
    if structure.shells is not None:
        sh = structure.shells
        for conn in (sh.quads, sh.trias):
            diag[(6 * conn.ravel()[:, None] + np.arange(6)).ravel()] += 1.0
    c = structure.constraints if structure.constraints is not None else Constraints()
    tr = constraint_transform(structure.nodes, c)
    reduced = tr.reduce(sp.diags(diag)).diagonal()
    zero = tr.independent[reduced <= 1e-12 * max(diag.max(), 1.0)]
    for node in np.unique(zero // 6):
        comps = "".join(str(int(d % 6) + 1) for d in zero[zero // 6 == node])
        ctx.builder.add_support(int(node), comps)
    return zero.size


def read_structure(path) -> tuple:
    """(Structure, info, pyNastran BDF) of the Nastran deck at ``path``; info records units,
    PARAMs, counts and notes (also in ``structure.metadata["nastran"]``)."""
    model = read_deck(path)
    settings = deck_settings(model)
    grids = read_grids(model)
    lumped = settings["coupmass"] < 1
    ctx = cards.Context(model, str(path), grids, -np.ones(len(grids.ids), np.int64),
                        settings["wtmass"], lumped, StructureBuilder())  # fmt: skip
    eids, pids, nodes, zoffs, corner, tflag = _shell_cards(model)
    shell_rows, other_rows = _used_rows(ctx, nodes)
    ctx.node[shell_rows] = np.arange(shell_rows.size)
    if eids.size:
        props = _shell_arrays(ctx, pids, nodes, corner, tflag, zoffs)
        _add_shells(ctx, shell_rows, pids, nodes, props)
    for row in other_rows:
        ctx.node[row] = ctx.builder.add_node(grids.xyz[row])
    for add in (cards.add_beams, cards.add_rods, cards.add_masses, cards.add_springs,
                cards.add_rigid):  # fmt: skip
        add(ctx)
    _add_spcs(ctx, settings)
    structure = _finish(ctx, eids, pids, props if eids.size else None)
    n_auto = 0
    if settings["autospc"]:
        n_auto = _autospc(ctx, structure)
        if n_auto:
            structure = _finish(ctx, eids, pids, props if eids.size else None)
    info = _info(ctx, settings, model, grids, structure, n_auto)
    return replace(structure, metadata={**structure.metadata, "nastran": info}), info, model


def _finish(ctx, eids, pids, props):
    structure = ctx.builder.build()
    if props is not None:
        structure = _patch_shells(structure, pids, props)
    return structure


def _info(ctx, settings, model, grids, structure, n_auto) -> dict:
    moduli = [m.e for m in model.materials.values() if m.type == "MAT1"]
    dropped = int(np.sum(ctx.node < 0))
    notes = list(ctx.notes)
    if dropped:
        notes.append(f"{dropped} GRID(s) used by no element were dropped (AUTOSPC)")
    if n_auto:
        notes.append(f"{n_auto} DOF(s) with no stiffness were held (AUTOSPC)")
    if structure.shells is not None:
        notes.append(f"PARAM K6ROT {settings['k6rot']:g} not applied: the shell's drilling "
                     "penalty is fixed (fe.shell.DRILL_ALPHA)")  # fmt: skip
        notes.append("shell mass is consistent (Nastran's default is lumped, COUPMASS -1)")
    used = ctx.node >= 0
    grid_of_node = np.zeros(structure.n_nodes, np.int64)
    grid_of_node[ctx.node[used]] = grids.ids[used]
    # each node's output (CD) frame, rows = its axes in basic: test directions given in it
    frame_of_node = np.broadcast_to(np.eye(3), (structure.n_nodes, 3, 3)).copy()
    frame_of_node[ctx.node[used]] = grids.frame[used]
    return dict(
        deck=str(Path(ctx.path).name),
        units=unit_system(moduli, settings["wtmass"]),
        **settings,
        card_count={k: int(v) for k, v in sorted(model.card_count.items())},
        grid_ids=grid_of_node,
        grid_frames=frame_of_node,
        grid_sets=_grid_sets(model),
        notes=notes,
    )


def _grid_sets(model) -> dict[int, tuple[int, ...]]:
    """{set id: GRID ids} of the bulk SET1 cards and the case control's SET lines (test points
    'all GRIDs of a set', ``test_points``)."""
    sets = {int(sid): tuple(int(i) for i in s.ids) for sid, s in model.sets.items()}
    deck = getattr(model, "case_control_deck", None)
    for subcase in deck.subcases.values() if deck is not None else ():
        for key, value in subcase.params.items():
            if key.startswith("SET ") and isinstance(value[0], list):
                ids = [i for i in value[0] if isinstance(i, int)]
                sets.setdefault(int(key.split()[1]), tuple(ids))
    return sets
