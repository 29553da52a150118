"""The seed's exhaust as the paper built it: closed shell bodies joined by beam pipes.

The catalyst and both mufflers are closed shells (MITC4 quads, ``fe.elements.shell``): an oval
mantle, two
oval end caps (flat or conical, fitted) and, in the main muffler, two internal baffles
(``exhaust_shell_mesh``); the pre-silencer's straight-through pipe is a beam from cap to cap.
The pipes are the beam pipes of ``exhaust`` (same routing, lengths, bend radii, B31.3 elbow
flexibility).

Pipe-to-shell connection (choice): each pipe end sits at the centre of a cap, in a hole of the
pipe's radius, and is joined to every node of the hole's ring by an RBE2 spider (all six
components). A closed tube welded into the hole is far stiffer in its own section plane than the
cap sheet, so a rigid ring is the welded pipe; the cap around it flexes with its own thickness, and
that is the joint stiffness the beam model lumps into springs. (An RBE3 would add no stiffness and
leave the ring free to ovalize, which a welded pipe does not allow.)  The spider's centre follows
the pipe end through a connection spring (``_connection``: bending ``connection_k_rot``, rigid
by default) in parts named as the beam model's joints, which discovery scans
(``connection_flexibility``) and the uncertainty study floats.  At the main muffler's
inlet the ring is an oval collar (fitted width and height: the pipe's welded footprint, a formed
neck or doubler), which makes that joint stiffer in vertical than in horizontal bending, as seed
Table 1's modes 9/10 (H5 71.0, V5 88.6 Hz) need. The sensors on the shell
bodies read an RBE3 reference node on the body axis (the weighted rigid motion of the mantle ring
there, no stiffness added), so they measure the body's cross-section motion at the beam model's
points.

Docs: docs/guide/exhaust-shell.md (choices, mesh convergence, Table 1, fit).

The rear hanger bar is a beam from the main muffler's side (a mantle node at mid-length) outwards,
welded over a patch of the mantle (RBE2 from that node to the mantle nodes within
``rear_bar_weld`` of it).  The main muffler's internals (packing, perforated tubes) are
non-structural mass spread over its sheets; their amount closes the 12.29 kg budget.

Design variables (seed Table 3): ``t_hot_pipe``/``t_cold_pipe`` -> the pipes' beam walls;
``t_main_muffler`` -> every sheet of the main muffler (mantle and baffles at it, the caps at a
fixed fitted ratio of it: ``fe``'s per-element ``thickness_factor``);
``rho_catalyst``/``rho_intermediate_muffler`` -> the density of those bodies' shells (mantle and
caps).  Shell thickness and density enter K and M as exact sums of powers (``fe.assembly``).
"""

from dataclasses import replace

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import STEEL, FEModel, Material, StructureBuilder, circular_tube
from bayesupdate.fe.assembly import element_mass
from bayesupdate.models import exhaust
from bayesupdate.models.exhaust_paper import MEASURED_MASS_KG
from bayesupdate.models.exhaust_shell_geometry import (
    MESH_DENSITY_DEFAULT,
    check_mesh_density,
    inlet_collar,
    shell_geometry,
)
from bayesupdate.models.exhaust_shell_mesh import oval_body

N_SENSORS = exhaust.N_SENSORS
DESIGN_BINDINGS = exhaust.DESIGN_BINDINGS
DESIGN_DEFAULTS = exhaust.DESIGN_DEFAULTS
DESIGN_BOUNDS = exhaust.DESIGN_BOUNDS

#: default bending stiffness [N m/rad] of each pipe-to-body connection spring (``_connection``):
#: effectively rigid (against RBE2-rigid connections the 12 modes move by at most 0.004 % at
#: mesh density 16, 1e6 would move them by 0.4 %: docs/guide/exhaust-shell.md, "Connection
#: springs"), and the null of discovery's ``connection_flexibility``, whose range ends at it
CONNECTION_K_ROT = 1.0e8
#: the option's range [N m/rad], discovery's range too: from rigid down to a connection as soft
#: as 5 m of the 40 mm pipe (EI / L, about 1e3), where all six at it lower the modes by 40-60 %
CONNECTION_K_RANGE = (1.0e3, 1.0e8)
_SHELL_10K = Material(STEEL.youngs_modulus, STEEL.poisson, 10.0e3, "steel, altered density")
_SPIDER = "123456"


def _shell_body(b: StructureBuilder, g: dict, key: str, inlet: int, material, n_c, baffles=()):
    """A closed oval body (``key`` in cat, im, mm) from the pipe end node ``inlet`` along x,
    joined to the pipes at both caps by ``_connection`` springs (``g["connection_k_rot"]``).

    Walls: mantle and baffles ``{key}_wall``, caps at ``_thickness_factor`` of it; the caps are
    cones of depth ``{key}_cone``; internal tubes (``_TUBES``) join hole rings; both caps' holes
    sit at (``{key}_pipe_dy``, ``{key}_pipe_dz``) [m] from the body's axis (0 if absent), the
    main muffler's inlet hole is its oval collar (``_collar``).  Returns
    (outlet pipe node at the outlet cap centre, axis nodes (RBE3) at the interior mantle rings on
    the pipe line, the body mesh and its structure node numbers)."""
    length, width, height = g[f"{key}_length"], g[f"{key}_width"], g[f"{key}_height"]
    depth = g[f"{key}_cone"]
    x0 = b.node_xyz(inlet)
    # off-centre pipes: the body's axis sits at -offset from the pipe line (both caps' holes at
    # +offset, so the tail keeps the beam model's line and sensor points)
    offset = np.array([g.get(f"{key}_pipe_dy", 0.0), g.get(f"{key}_pipe_dz", 0.0)])
    fixed = [0.5 * length] + [length * k / 3 for k in (1, 2)] * (key == "mm")
    body = oval_body(
        width,
        height,
        length - 2 * depth,
        0.5 * g["pipe_od"],
        n_c,
        [x - depth for x in baffles],
        x0 + (depth, -offset[0], -offset[1]),
        [x - depth for x in fixed],
        cone=depth,
        offset=offset,
        collar=_collar(g, key),
    )
    factor = _thickness_factor(g, key, body)
    thickness = g[f"{key}_wall"] * factor
    part = _PART[key]
    ids = b.add_shells(body.nodes, body.quads, thickness=thickness, material=material, part=part)
    outlet = b.add_node(x0 + (length, 0.0, 0.0))
    hole_centre = [b.add_node(x0), b.add_node(x0 + (length, 0.0, 0.0))]
    upstream, downstream = CONNECTIONS[key]
    _connection(b, inlet, hole_centre[0], g["connection_k_rot"][upstream], upstream)
    _connection(b, outlet, hole_centre[1], g["connection_k_rot"][downstream], downstream)
    for xb in baffles:  # tube nodes at the baffles (a few per body: not a hot path)
        hole_centre.append(b.add_node(x0 + (xb, -offset[0], -offset[1])))
    for disc, centre in enumerate(hole_centre):
        b.add_rbe2(centre, ids[body.holes[disc]], _SPIDER)
    tube = circular_tube(g["pipe_od"], g["pipe_wall"])
    for d1, d2 in _TUBES[key]:
        b.add_beam(hole_centre[d1], hole_centre[d2], tube, STEEL, "internal_tubes")
    axis = []
    for j in range(1, len(body.stations) - 1):
        node = b.add_node((body.stations[j], x0[1], x0[2]))
        b.add_rbe3(node, ids[body.rings[j]])
        axis.append(node)
    return outlet, axis, body, ids


#: the pipe-to-body connections of each body (inlet, outlet), named as the beam model's joints
CONNECTIONS = {
    "cat": ("hot_pipe/catalyst", "catalyst/cold_pipe"),
    "im": ("cold_pipe/intermediate_muffler", "intermediate_muffler/cold_pipe"),
    "mm": ("cold_pipe/main_muffler", "main_muffler/tail_pipe"),
}
CONNECTION_NAMES = tuple(name for pair in CONNECTIONS.values() for name in pair)


def _connection(b: StructureBuilder, pipe: int, spider: int, k_rot: float, name: str) -> None:
    """The pipe end ``pipe`` joined to its spider's centre ``spider`` (same point): translations
    and torsion rigid (RBE2 ``"1234"``, the pipe axis is x), bending in both planes through a
    spring of ``k_rot`` [N m/rad] in part ``name`` (``"pipe/body"``), in series with the cap's own
    flexibility.  The spring is what discovery's ``connection_flexibility`` scales and what the
    uncertainty study floats; at the default (``CONNECTION_K_ROT``) it is effectively rigid."""
    b.add_rbe2(pipe, [spider], "1234")
    b.add_spring(pipe, spider, [0.0, 0.0, 0.0, 0.0, k_rot, k_rot], name)


def _collar(g: dict, key: str):
    """Semi-axes (y, z) [m] of the inlet cap's collar (the main muffler's only), or None."""
    return inlet_collar(g) if key == "mm" else None


def _thickness_factor(g: dict, key: str, body) -> np.ndarray:
    """(n_quads,) each sheet's thickness over the body's mantle wall: 1 on the mantle and the
    baffles, the caps' gauge ratio on the caps (``{key}_cap_wall`` / ``{key}_wall``, for the main
    muffler ``mm_cap_ratio``), times ``mm_bead_factor`` on the main muffler's inlet cap within
    ``mm_bead_width`` / 2 of the vertical line through its hole (a vertical bead band)."""
    ratio = g[f"{key}_cap_wall"] / g[f"{key}_wall"] if key != "mm" else g["mm_cap_ratio"]
    factor = np.where(body.surface == 1, ratio, 1.0)
    if key == "mm":
        centre = body.nodes[body.quads].mean(axis=1)
        inlet = (body.surface == 1) & (centre[:, 0] < body.stations.mean())
        hole_y = body.nodes[body.holes[0], 1].mean()
        band = inlet & (np.abs(centre[:, 1] - hole_y) < 0.5 * g["mm_bead_width"])
        factor = np.where(band, factor * g["mm_bead_factor"], factor)
    return factor


#: internal tubes as (disc, disc) pairs (0 inlet cap, 1 outlet cap, 2.. baffles): the
#: pre-silencer's straight-through perforated pipe.  The main muffler has none: its pipes end in
#: its domed caps (a main muffler with an inlet tube through the first baffle or a tube through
#: every baffle was 2-3 % RMS worse against seed Table 1 before the fit, see docs/guide)
_TUBES = {"cat": (), "im": ((0, 1),), "mm": ()}


_PART = {"cat": "catalyst", "im": "intermediate_muffler", "mm": "main_muffler"}


def _rear_hanger_bar(b: StructureBuilder, g: dict, body, ids) -> None:
    """Solid bar welded to both sides of the main muffler at mid-length (RBE2 weld patches)."""
    bar = exhaust._solid_bar(g["rear_bar_diameter"])  # noqa: SLF001 - same bar as the beam model
    xyz = body.nodes
    j = int(np.argmin(np.abs(body.stations - (body.stations[0] + 0.5 * g["mm_length"]))))
    ring = body.rings[j]
    for side in (1.0, -1.0):
        root_local = ring[int(np.argmax(side * xyz[ring, 1]))]
        root = int(ids[root_local])
        near = np.linalg.norm(xyz[body.rings.ravel()] - xyz[root_local], axis=1)
        patch = ids[body.rings.ravel()[(near < g["rear_bar_weld"]) & (near > 0)]]
        b.add_rbe2(root, np.unique(patch))
        tip = b.add_node(b.node_xyz(root) + (0, side * g["rear_bar_overhang"], 0))
        b.add_beam(root, tip, bar, STEEL, "rear_hanger_bar", up=(0, 0, 1))


def _pipe(b, g, points, part, start, wall_key="pipe_wall", **kw):
    sec = circular_tube(g["pipe_od"], g[wall_key])
    opts = dict(element_length=g["element_length"], max_bend_angle_deg=30.0, start_node=start)
    return b.add_pipe_run(points, sec, STEEL, part, **opts, **kw)


def _upstream(b: StructureBuilder, g: dict, n_c: int):
    """Flange, hot pipe with its front hanger, catalyst, first cold pipe, intermediate muffler.
    Returns the gas path nodes so far and the intermediate muffler's outlet node."""
    z1, x1 = -g["hot_drop"], g["hot_drop_run"] + g["hot_length"]
    hot = _pipe(
        b,
        g,
        [(0, 0, 0), (0.0, 0, z1 * 0.5), (g["hot_drop_run"], 0, z1), (x1, 0, z1)],
        "hot_pipe",
        None,
        bend_radii=[g["hot_bend_radius"], g["hot_bend_radius"]],
        bend_names=["hot_bend1", "hot_bend2"],
    )
    flange = g["flange_mass"]
    inertia = exhaust._box_inertia(flange, 0.006, 0.12, 0.08)  # noqa: SLF001 - same flange
    b.add_point_mass(hot[0], flange, "hot_pipe", inertia=inertia)
    top = b.add_node(b.node_xyz(hot[-2]) + (0, 0, g["front_hanger_length"]))
    rod = exhaust._solid_bar(g["front_hanger_diameter"])  # noqa: SLF001
    b.add_beam(hot[-2], top, rod, STEEL, "front_hanger")
    out, axis, *_ = _shell_body(b, g, "cat", hot[-1], _SHELL_10K, n_c)
    path = [*hot, *axis, out]
    xc = b.node_xyz(out)
    cold1 = _pipe(b, g, [xc, xc + (g["cold1_length"], 0, 0)], "cold_pipe", out)
    out, axis, *_ = _shell_body(b, g, "im", cold1[-1], _SHELL_10K, n_c)
    return [*path, *cold1[1:], *axis, out]


def _downstream(b: StructureBuilder, g: dict, n_c: int, path: list):
    """Cold pipe with the S-jog, main muffler (baffles, rear hanger bar), tail pipe; extends
    ``path``; returns the main muffler's body mesh and its node numbers."""
    a = b.node_xyz(path[-1])
    bpt = a + (g["cold2_length"], 0, 0)
    cpt = bpt + (g["jog_dx"], g["jog_dy"], g["jog_dz"])
    cold2 = _pipe(
        b,
        g,
        [a, bpt, cpt, cpt + (g["cold3_length"], 0, 0)],
        "cold_pipe",
        path[-1],
        bend_radii=[g["elbow_radius"], g["elbow_radius"]],
        bend_names=["elbow", "elbow2"],
    )
    sheet = Material(STEEL.youngs_modulus, STEEL.poisson, STEEL.density, "main muffler sheet")
    baffles = [g["mm_length"] * k / 3 for k in (1, 2)]
    out, axis, body, ids = _shell_body(b, g, "mm", cold2[-1], sheet, n_c, baffles)
    _rear_hanger_bar(b, g, body, ids)
    xt = b.node_xyz(out)
    tail = _pipe(b, g, [xt, xt + (g["tail_length"], 0, 0)], "tail_pipe", out, "tail_wall")
    path += [*cold2[1:], *axis, *tail]
    return body, ids


def connection_stiffnesses(k_rot: float | dict | None = None) -> dict:
    """{connection name: bending stiffness [N m/rad]} of the six pipe-to-body connections from
    one value, a partial dict (the rest at ``CONNECTION_K_ROT``) or None (all at it); each must
    lie in ``CONNECTION_K_RANGE``, else a one-line error with the range."""
    if k_rot is None or isinstance(k_rot, dict):
        given = dict(k_rot or {})
    else:
        given = dict.fromkeys(CONNECTION_NAMES, k_rot)
    unknown = sorted(set(given) - set(CONNECTION_NAMES))
    if unknown:
        raise BayesUpdateError(
            f"exhaust_shell connection_k_rot: unknown connections {unknown}; "
            f"they are {list(CONNECTION_NAMES)}"
        )
    out = dict.fromkeys(CONNECTION_NAMES, CONNECTION_K_ROT)
    lo, hi = CONNECTION_K_RANGE
    for name, value in given.items():
        try:
            v = float(value)
        except (TypeError, ValueError):
            v = float("nan")
        if not lo <= v <= hi:
            shown = f"{v:g}" if np.isfinite(v) else repr(value)
            raise BayesUpdateError(
                f"exhaust_shell connection_k_rot: {name} = {shown} N m/rad is outside its range "
                f"[{lo:g}, {hi:g}] N m/rad"
            )
        out[name] = v
    return out


def build_exhaust_shell_structure(g: dict, mesh_density: float = MESH_DENSITY_DEFAULT):
    """The shell exhaust ``Structure`` at the initial design for a full geometry
    (``exhaust_shell_geometry.shell_geometry``; ``g["connection_k_rot"]`` as
    ``connection_stiffnesses`` gives, all at ``CONNECTION_K_ROT`` when absent) and
    ``mesh_density`` elements around each oval body.

    ``metadata``: path_nodes (gas path from the manifold to the tail, pipe nodes and body axis
    nodes: ``models.exhaust.mode_character`` reads the modes' plane and node count on them, as
    on the beam exhaust), path_s (their arc length [m]), mm_internal_mass_kg (the internals'
    mass closing the 12.29 kg budget), n_shells, connections (the connection springs' parts,
    which discovery's ``connection_flexibility`` scans), mesh_density."""
    g = {"connection_k_rot": connection_stiffnesses(), **g}
    b = StructureBuilder()
    path = _upstream(b, g, mesh_density)
    _downstream(b, g, mesh_density, path)
    s_path = _place_sensors(b, g, path)
    structure = b.build()
    # t_main_muffler binds the main muffler's sheets: each at its own fixed fraction of it
    sh = structure.shells
    mm = sh.part == structure.part_index("main_muffler")
    factor = np.where(mm, sh.thickness / g["mm_wall"], 1.0)
    structure = replace(structure, shells=replace(sh, thickness_factor=factor))
    m_int = _internal_mass(structure)
    structure = _with_internal_mass(structure, m_int)
    structure.metadata.update(
        path_nodes=np.array(path),
        path_s=s_path,
        mm_internal_mass_kg=float(m_int),
        n_shells=int(structure.shells.n_elements),
        connections=CONNECTION_NAMES,
        mesh_density=int(mesh_density),
    )
    return structure


def _shell_areas(structure) -> np.ndarray:
    """(n_shell,) element areas [m^2] (quads split along a diagonal; quads first)."""
    sh, x = structure.shells, structure.nodes
    q = x[sh.quads]
    aq = 0.5 * np.linalg.norm(np.cross(q[:, 2] - q[:, 0], q[:, 3] - q[:, 1]), axis=1)
    t = x[sh.trias]
    at = 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)
    return np.concatenate([aq, at])


def _internal_mass(structure) -> float:
    """12.29 kg minus the beams, point masses and shells at the initial design [kg]."""
    sh = structure.shells
    m_beams, _ = element_mass(structure)
    m_shells = float(np.sum(_shell_areas(structure) * (sh.rho * sh.thickness + sh.nsm)))
    return MEASURED_MASS_KG - m_beams - m_shells


def _with_internal_mass(structure, m_int: float):
    """The main muffler's internals as non-structural mass [kg/m^2] on all its sheets."""
    if m_int < 0:
        raise BayesUpdateError(
            f"exhaust_shell geometry: the structure alone weighs {MEASURED_MASS_KG - m_int:.2f} kg"
            f", more than {MEASURED_MASS_KG} kg; reduce the walls or body sizes"
        )
    sh = structure.shells
    mm = sh.part == structure.part_index("main_muffler")
    area = _shell_areas(structure)
    nsm = sh.nsm.copy()
    nsm[mm] += m_int / area[mm].sum()
    return replace(structure, shells=replace(sh, nsm=nsm))


def _place_sensors(b: StructureBuilder, g: dict, path: list) -> np.ndarray:
    """The beam exhaust's 20 sensor points (same coordinates, V and H): each must be a node of
    the shell model's gas path.  Returns the path's arc length [m]."""
    beam = exhaust.build_exhaust_structure(g)
    pts = beam.nodes[beam.sensor_node[::2]]
    nodes = np.array([b.node_xyz(n) for n in path])
    d = np.linalg.norm(nodes[None] - pts[:, None], axis=2)
    pick = np.argmin(d, axis=1)
    if d[np.arange(len(pts)), pick].max() > 1e-6:
        raise BayesUpdateError("exhaust_shell: a beam-model sensor point is not on the gas path")
    for k, i in enumerate(pick, start=1):
        b.add_sensor(f"{k}V", path[i], "V")
        b.add_sensor(f"{k}H", path[i], "H")
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(nodes, axis=0), axis=1))])


def build_exhaust_shell_model(
    geometry: str | int | dict = "best",
    mesh_density: float = MESH_DENSITY_DEFAULT,
    connection_k_rot: float | dict | None = None,
) -> FEModel:
    """The shell exhaust ``FEModel`` with the five design variables of seed Table 3.

    geometry : "best", an index (0 = best, 1.. = runner-ups) or a dict of shell quantities
    overriding the stored fit (``exhaust_shell_geometry.SHELL_QUANTITIES``; each checked against
    its plausible range).  mesh_density : elements around each oval body (a multiple of 4 in
    ``MESH_DENSITY_RANGE``; axial and radial sizes follow, ``exhaust_shell_mesh``).
    connection_k_rot : bending stiffness [N m/rad] of the pipe-to-body connection springs
    (``_connection``): one value for all six, or {connection name: value} for some
    (``CONNECTION_NAMES``; the rest at ``CONNECTION_K_ROT``), each in ``CONNECTION_K_RANGE``."""
    mesh_density = check_mesh_density(mesh_density)
    g = shell_geometry(geometry)
    g["connection_k_rot"] = connection_stiffnesses(connection_k_rot)
    structure = build_exhaust_shell_structure(g, mesh_density)
    return FEModel(
        structure,
        dict(DESIGN_BINDINGS),
        dict(DESIGN_DEFAULTS),
        dict(DESIGN_BOUNDS),
        name="exhaust_shell",
    )
