"""The seed's exhaust system (Lupea 2013, Dacia Logan) as a small 3D beam model.

Axes: x rearward along the car from the manifold flange (origin), y lateral (horizontal, "H"),
z vertical up ("V").  Flow order: hot_pipe -> catalyst -> cold_pipe -> intermediate_muffler ->
cold_pipe (with the large S-jog whose first bend is ``elbow``) -> main_muffler -> tail_pipe.
Welded hangers: ``front_hanger`` (short rod on the hot pipe, seed section 2) and
``rear_hanger_bar`` (solid bar across the main muffler, seed section 2).

Pipes are circular tubes, the catalyst and mufflers thin-walled oval tubes (their wall thickness or
density is a design variable of seed Table 3, so they are beams of the shell section); internals of
the main muffler and the manifold flange are point masses with inertia.  Where a pipe enters the
catalyst or a muffler, the end cap is not rigid in a shell model: each such connection is a joint
spring (part ``"partA/partB"`` in flow order) with separate bending stiffness in the vertical and
horizontal planes.

Every dimension is in ``GEOMETRY_QUANTITIES`` (name -> (value or None, unit, source)).  Quantities
the paper does not give and that the modes are sensitive to were fixed once by a documented fit
(``bayesupdate.models.exhaust_fit``, ``studies/reproduce_paper_fe.py``), stored with the
runner-up geometries as package data, one file per fit (``GEOMETRY_FILES``): "table1" (seed
Table 1, ``bayesupdate/data/exhaust_geometry.json``) and "two_design" (seed Tables 1 and 4, the
paper's FE model at both of its designs, with joints that follow the wall their compliance lies
in, ``JOINT_WALL_PART``; ``bayesupdate/data/exhaust_geometry_two_design.json``).

Design variables (seed Table 3, DESIGN.md names), initial values 1.0 mm and 10e-9 t/mm^3:

=========================  =================================  ==========  ==================
name                       binds                              initial     bounds
=========================  =================================  ==========  ==================
t_hot_pipe                 (hot_pipe, thickness)              1.0e-3 m    0.4e-3 .. 3.0e-3 m
t_cold_pipe                (cold_pipe, thickness)             1.0e-3 m    0.4e-3 .. 3.0e-3 m
t_main_muffler             (main_muffler, thickness)          1.0e-3 m    0.4e-3 .. 3.0e-3 m
rho_catalyst               (catalyst, density)                1.0e4       2.0e3 .. 3.0e4 kg/m^3
rho_intermediate_muffler   (intermediate_muffler, density)    1.0e4       2.0e3 .. 3.0e4 kg/m^3
=========================  =================================  ==========  ==================

Bounds: exhaust pipes and muffler shells are rolled from 0.5-2.5 mm sheet; 0.4-3.0 mm covers the
paper's optimum (2.08, 1.29, 0.577 mm) with margin and stays a thin wall (t/D < 0.07).  The
densities are "altered" to carry the substrate/internals mass (seed section 2): 2,000 kg/m^3 (an
almost empty shell, a quarter of steel) to 30,000 kg/m^3 (three times the initial mass) covers the
paper's optimum (8,900 and 17,600 kg/m^3).
"""

import json
from functools import lru_cache
from importlib import resources

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import (
    STEEL,
    Binding,
    FEModel,
    Material,
    StructureBuilder,
    circular_tube,
    oval_tube,
    solid_round,
)
from bayesupdate.models.exhaust_paper import MEASURED_MASS_KG

PARTS = (
    "hot_pipe",
    "catalyst",
    "intermediate_muffler",
    "cold_pipe",
    "main_muffler",
    "tail_pipe",
    "front_hanger",
    "rear_hanger_bar",
)
#: joint spring parts (flow order), the connections a shell model resolves and a beam model
#: lumps into springs: their stiffness is the model-form uncertainty of the connections
JOINTS = (
    "hot_pipe/catalyst",
    "catalyst/cold_pipe",
    "cold_pipe/intermediate_muffler",
    "intermediate_muffler/cold_pipe",
    "cold_pipe/main_muffler",
    "main_muffler/tail_pipe",
)
N_SENSORS = 20

DESIGN_BINDINGS = {
    "t_hot_pipe": Binding("hot_pipe", "thickness"),
    "t_cold_pipe": Binding("cold_pipe", "thickness"),
    "t_main_muffler": Binding("main_muffler", "thickness"),
    "rho_catalyst": Binding("catalyst", "density"),
    "rho_intermediate_muffler": Binding("intermediate_muffler", "density"),
}
DESIGN_DEFAULTS = {
    "t_hot_pipe": 1.0e-3,
    "t_cold_pipe": 1.0e-3,
    "t_main_muffler": 1.0e-3,
    "rho_catalyst": 10.0e3,
    "rho_intermediate_muffler": 10.0e3,
}
DESIGN_BOUNDS = {
    "t_hot_pipe": (0.4e-3, 3.0e-3),
    "t_cold_pipe": (0.4e-3, 3.0e-3),
    "t_main_muffler": (0.4e-3, 3.0e-3),
    "rho_catalyst": (2.0e3, 30.0e3),
    "rho_intermediate_muffler": (2.0e3, 30.0e3),
}

#: steel shells whose density was "altered" to carry the internals (seed section 2, Table 3 initial
#: value 10e-9 t/mm^3), so that the structure itself is at the initial design
_SHELL_10K = Material(STEEL.youngs_modulus, STEEL.poisson, 10.0e3, "steel, altered density")

#: stiff massless links (the main muffler shell between its axis and the hanger bar weld)
_MASSLESS_STEEL = Material(STEEL.youngs_modulus, STEEL.poisson, 1.0e-3, "massless link")

_A = "assumption"
_F = "fitted to seed Table 1 (exhaust_fit), within the range given"
#: name -> (value, unit, source).  Fitted quantities have value None here (taken from the JSON)
#: and their plausible range in the source text (also in exhaust_fit.FIT_BOUNDS).
GEOMETRY_QUANTITIES = {
    # pipes
    "pipe_od": (None, "m", _F + " [0.038, 0.051]: 1.4-1.6 L petrol engines use 38-50 mm pipes"),
    "pipe_wall": (1.0e-3, "m", "seed Table 3 initial thickness of hot and cold pipe"),
    "tail_wall": (1.2e-3, "m", _A + ": tail pipe is not a design variable; usual 1.2 mm"),
    "hot_drop": (0.20, "m", _A + ": manifold outlet above the floor tunnel"),
    "hot_drop_run": (0.12, "m", _A + ": x-run of the down-pipe"),
    "hot_bend_radius": (0.08, "m", _A + ": about 1.8 pipe diameters (mandrel bend)"),
    "hot_length": (None, "m", _F + " [0.35, 0.9]: horizontal hot pipe to the catalyst"),
    "cold1_length": (None, "m", _F + " [0.2, 0.8]: catalyst outlet to intermediate muffler"),
    "cold2_length": (None, "m", _F + " [0.3, 1.3]: intermediate muffler to the elbow"),
    "jog_dx": (None, "m", _F + " [0.05, 0.45]: x-run of the S-jog after the elbow"),
    "jog_dy": (None, "m", _F + " [0.05, 0.40]: lateral offset of the S-jog (width <= 0.9 m)"),
    "jog_dz": (None, "m", _F + " [0.0, 0.30]: rise of the S-jog (over the rear axle)"),
    "elbow_radius": (None, "m", _F + " [0.07, 0.25]: both bends of the S-jog"),
    "cold3_length": (None, "m", _F + " [0.1, 0.8]: after the jog to the main muffler"),
    "tail_length": (None, "m", _F + " [0.10, 0.5]: straight tail pipe"),
    # catalyst (mass carried by the shell, seed section 2: density altered to keep the mass)
    "cat_width": (0.16, "m", _A + ": oval can of a ~1 L substrate"),
    "cat_height": (0.11, "m", _A + ": oval can of a ~1 L substrate"),
    "cat_length": (0.30, "m", _A + ": including the cones"),
    "cat_wall": (1.5e-3, "m", _A + ": catalyst can, not a design variable"),
    # intermediate muffler (mass carried by the shell, seed section 2)
    "im_width": (0.20, "m", _A + ": pre-silencer of a small car"),
    "im_height": (0.13, "m", _A + ": pre-silencer of a small car"),
    "im_length": (0.35, "m", _A + ": pre-silencer of a small car"),
    "im_wall": (0.8e-3, "m", _A + ": pre-silencer wrapper sheet (shell mass 1.4 kg at 10,000)"),
    # main muffler
    "mm_width": (0.34, "m", _A + ": oval rear silencer, W along y"),
    "mm_height": (0.19, "m", _A + ": oval rear silencer, H along z"),
    "mm_length": (None, "m", _F + " [0.30, 0.60]"),
    "mm_sheet_factor": (
        None,
        "-",
        _F + " [1.0, 3.0]: all sheet metal of the main muffler (wall, end caps, baffles) per"
        " unit outer wall; it scales with t_main_muffler, so the Table 3 optimum mass 12.12 kg"
        " fixes it",
    ),
    "mm_internal_mass": (
        None,
        "kg",
        "non-design internals of the main muffler (packing, pipes): closes the 12.29 kg budget",
    ),
    # hangers and flange
    "front_hanger_diameter": (0.010, "m", _A + ": welded hanger rod"),
    "front_hanger_length": (0.08, "m", _A + ": 'a short hanger welded to the pipe'"),
    "rear_bar_diameter": (0.014, "m", _A + ": solid bar (seed: meshed with solid elements)"),
    "rear_bar_overhang": (0.15, "m", _A + ": bar length beyond each side of the muffler"),
    "flange_mass": (0.35, "kg", _A + ": 3-bolt manifold flange, 6 mm plate"),
    # joints where a pipe enters the catalyst or a muffler
    "joint_k_axial": (1.0e8, "N/m", _A + ": translations practically rigid"),
    "joint_k_torsion": (1.0e5, "N m/rad", _A + ": torsion stiff (weld around the pipe)"),
    "joint_log10_k_v": (None, "log10 N m/rad", _F + " [4, 6]: bending in the vertical plane"),
    "joint_log10_k_h": (None, "log10 N m/rad", _F + " [4, 6]: bending in the horizontal plane"),
    "joint_stub_length": (
        0.02,
        "m",
        _A + ": reach of the wall-following joint stub (half a pipe diameter into the cap)",
    ),
    # mesh
    "element_length": (0.15, "m", "mesh: 130 Hz bending wavelength of the pipe is ~2 m"),
}


#: quantities a geometry may leave out (value None: the feature is off).  joint_wall_log10_k:
#: bending stiffness EI/L [log10 N m/rad] at the initial 1.0 mm wall of the joint stub that follows
#: the wall (``JOINT_WALL_PART``); fitted to seed Tables 1 and 4 by the two-design fit [4, 6]
OPTIONAL_QUANTITIES = {
    "joint_wall_log10_k": (
        "log10 N m/rad",
        "fitted to seed Tables 1 and 4 (exhaust_fit, two-design) [4, 6]: the wall-following "
        "part of a joint's bending stiffness at the initial 1.0 mm wall",
    ),
}

#: Section rule of the two-design geometry: a joint's compliance lies in the more flexible of the
#: two walls it joins - the thinner sheet, and at equal sheet a muffler's end cap (a plate) rather
#: than the pipe (a tube) - so its stiffness scales with that wall's thickness.  A stub beam of
#: that part carries it (thin-walled tube: EI, GJ, EA proportional to t).  The catalyst can
#: (1.5 mm) is thicker than the pipes (1.0 mm): the pipe's wall; the intermediate muffler's
#: wrapper (0.8 mm) is thinner: its wall, not a design variable, so those joints keep a constant
#: spring; the main muffler's 1.0 mm end caps against the 1.0 mm pipes: the cap.
JOINT_WALL_PART = {
    "hot_pipe/catalyst": "hot_pipe",
    "catalyst/cold_pipe": "cold_pipe",
    "cold_pipe/intermediate_muffler": None,
    "intermediate_muffler/cold_pipe": None,
    "cold_pipe/main_muffler": "main_muffler",
    "main_muffler/tail_pipe": "main_muffler",
}

#: stored geometry sets: name -> package data file (``geometry=NAME`` or ``NAME:k``)
GEOMETRY_FILES = {
    "table1": "data/exhaust_geometry.json",
    "two_design": "data/exhaust_geometry_two_design.json",
}
#: the set ``geometry="best"`` (and an index alone) refers to
DEFAULT_GEOMETRY = "table1"


@lru_cache(maxsize=4)
def load_geometries(name: str = DEFAULT_GEOMETRY) -> dict:
    """The stored geometry fits of set ``name`` (``GEOMETRY_FILES``): {"best": {...},
    "runners_up": [{...}, ...], ...} (JSON data)."""
    if name not in GEOMETRY_FILES:
        raise BayesUpdateError(_unknown_geometry(name))
    text = resources.files("bayesupdate").joinpath(GEOMETRY_FILES[name]).read_text()
    return json.loads(text)


def _unknown_geometry(choice) -> str:
    return (
        f"exhaust geometry {choice!r}: known geometries are 'best' (= {DEFAULT_GEOMETRY!r}), "
        + ", ".join(repr(n) for n in GEOMETRY_FILES)
        + ", each with ':k' for its k-th runner-up (e.g. 'table1:2'), or an index k alone"
    )


def parse_geometry(choice: str | int) -> tuple[str, int]:
    """``choice`` -> (geometry set, index): "best" or an index k (default set), a set name
    ("two_design"), or "NAME:k" (its k-th runner-up).  Raises BayesUpdateError otherwise."""
    if isinstance(choice, int) and not isinstance(choice, bool):
        return DEFAULT_GEOMETRY, choice
    if not isinstance(choice, str):
        raise BayesUpdateError(_unknown_geometry(choice))
    name, _, index = choice.partition(":")
    if name.isdigit() and not index:
        return DEFAULT_GEOMETRY, int(name)
    name = DEFAULT_GEOMETRY if name == "best" else name
    if name not in GEOMETRY_FILES or not (index == "" or index.isdigit()):
        raise BayesUpdateError(_unknown_geometry(choice))
    return name, int(index or 0)


def fitted_geometry(choice: str | int = "best") -> dict:
    """Fitted quantities of geometry ``choice`` (``parse_geometry``): "best" or 0 = the default
    set's best fit, k >= 1 = its k-th runner-up; "two_design", "table1:2", ....  Returns
    name -> value (SI)."""
    name, k = parse_geometry(choice)
    data = load_geometries(name)
    fits = [data["best"], *data["runners_up"]]
    if not 0 <= k < len(fits):
        raise BayesUpdateError(
            f"exhaust geometry {choice!r}: set {name!r} has fits 0..{len(fits) - 1} "
            f"(0 = best fit, 1.. = runner-up fits in bayesupdate/{GEOMETRY_FILES[name]})"
        )
    return dict(fits[k]["values"])


def full_geometry(fitted: dict) -> dict:
    """All quantities: fixed ones from ``GEOMETRY_QUANTITIES`` overridden by ``fitted``, which may
    also set ``OPTIONAL_QUANTITIES`` (absent: that feature is off)."""
    g = {k: v[0] for k, v in GEOMETRY_QUANTITIES.items()}
    unknown = set(fitted) - set(g) - set(OPTIONAL_QUANTITIES)
    if unknown:
        raise BayesUpdateError(f"exhaust geometry: unknown quantities {sorted(unknown)}")
    g.update(fitted)
    g.pop("mm_internal_mass")  # derived from the mass budget, never an input
    missing = [k for k, v in g.items() if v is None]
    if missing:
        raise BayesUpdateError(f"exhaust geometry: quantities {missing} have no value")
    return g


def _solid_bar(diameter):
    """A solid round bar (hanger rods)."""
    return solid_round(diameter)


def _box_inertia(mass, lx, ly, lz):
    """Inertia tensor [kg m^2] of a uniform box of the given mass [kg] and sizes [m]."""
    return mass / 12.0 * np.diag([ly**2 + lz**2, lx**2 + lz**2, lx**2 + ly**2])


def _joint(b: StructureBuilder, node, axis, g, name):
    """A coincident node joined to ``node`` by the joint spring ``name``; returns the new node.

    Spring frame rows: pipe axis, horizontal normal, vertical normal, so rotation about the
    horizontal normal is bending in the vertical plane (k_v) and about the vertical normal is
    bending in the horizontal plane (k_h)."""
    axis = np.asarray(axis, dtype=float)
    axis /= np.linalg.norm(axis)
    n_h = np.cross((0.0, 0.0, 1.0), axis)
    n_h /= np.linalg.norm(n_h)
    n_v = np.cross(axis, n_h)
    new = b.add_node(b.node_xyz(node))
    ka, kt = g["joint_k_axial"], g["joint_k_torsion"]
    kv, kh = 10.0 ** g["joint_log10_k_v"], 10.0 ** g["joint_log10_k_h"]
    b.add_spring(node, new, [ka, ka, ka, kt, kv, kh], name, frame=np.array([axis, n_h, n_v]))
    wall_part = JOINT_WALL_PART[name]
    if g.get("joint_wall_log10_k") is None or wall_part is None:
        return new
    return _wall_stub(b, new, axis, g, wall_part)


def _wall_stub(b: StructureBuilder, node, axis, g: dict, part: str):
    """The wall-following part of a joint (``JOINT_WALL_PART``), in series with its spring: a
    massless stub of the pipe's tube section in ``part``, so the part's thickness binding reaches
    it; its modulus makes EI/L = 10**joint_wall_log10_k at the initial 1.0 mm wall.  Returns the
    stub's far node (``joint_stub_length`` along ``axis``)."""
    length = g["joint_stub_length"]
    section = circular_tube(g["pipe_od"], g["pipe_wall"])
    modulus = 10.0 ** g["joint_wall_log10_k"] * length / section.properties(STEEL.poisson)["Iy"]
    material = Material(modulus, STEEL.poisson, 1.0e-3, "joint wall (massless)")
    end = b.add_node(b.node_xyz(node) + length * axis)
    b.add_beam(node, end, section, material, part, up=(0, 0, 1))
    return end


def _component(b, start_node, length, section, part, n_el, material=STEEL):
    """A straight oval component from ``start_node`` along x: the nodes along it."""
    x0 = b.node_xyz(start_node)
    end = b.add_node(x0 + (length, 0.0, 0.0))
    return b.add_line(
        start_node, end, section, material, part, element_length=length / n_el * 1.0001
    )


def build_exhaust_structure(geometry: dict, elbow_flexibility: bool = True):
    """The exhaust ``Structure`` for a full geometry (``full_geometry``), at the initial design.

    Also returns the derived main-muffler internal mass [kg] (closes the 12.29 kg budget) in
    ``structure.metadata``; ``metadata["path_nodes"]`` lists the nodes along the gas path from
    the manifold to the tail (for mode classification), ``metadata["path_s"]`` their arc length.
    """
    g = geometry
    b = StructureBuilder()
    kw = dict(
        element_length=g["element_length"],
        max_bend_angle_deg=30.0,
        elbow_flexibility=elbow_flexibility,
    )
    hot, path = _upstream(b, g, kw)
    mid = _downstream(b, g, kw, path)
    m_int = _close_mass_budget(b, g, hot[0], mid)
    s_path = _place_sensors(b, path)
    b.metadata.update(path_nodes=np.array(path), path_s=s_path, mm_internal_mass_kg=float(m_int))
    return b.build()


def _upstream(b: StructureBuilder, g: dict, kw: dict) -> tuple[list[int], list[int]]:
    """Hot pipe with its front hanger, catalyst, first cold pipe, intermediate muffler; returns
    the hot pipe's nodes and the gas path so far."""
    pipe = circular_tube(g["pipe_od"], g["pipe_wall"])
    x_axis = (1.0, 0.0, 0.0)
    # hot pipe: down-pipe from the manifold flange, then horizontal to the catalyst
    z1 = -g["hot_drop"]
    x1 = g["hot_drop_run"] + g["hot_length"]
    hot = b.add_pipe_run(
        [(0, 0, 0), (0.0, 0, z1 * 0.5), (g["hot_drop_run"], 0, z1), (x1, 0, z1)],
        pipe,
        STEEL,
        "hot_pipe",
        bend_radii=[g["hot_bend_radius"], g["hot_bend_radius"]],
        bend_names=["hot_bend1", "hot_bend2"],
        **kw,
    )
    path = list(hot)
    # front hanger welded near the catalyst inlet (one element of the hot pipe before it)
    h_node = hot[-2]
    top = b.add_node(b.node_xyz(h_node) + (0, 0, g["front_hanger_length"]))
    b.add_beam(h_node, top, _solid_bar(g["front_hanger_diameter"]), STEEL, "front_hanger")

    # catalyst (shell mass at the design density carries the substrate, seed section 2)
    c0 = _joint(b, hot[-1], x_axis, g, "hot_pipe/catalyst")
    cat_sec = oval_tube(g["cat_width"], g["cat_height"], g["cat_wall"])
    cat = _component(b, c0, g["cat_length"], cat_sec, "catalyst", 2, material=_SHELL_10K)
    path += cat[1:]
    p0 = _joint(b, cat[-1], x_axis, g, "catalyst/cold_pipe")
    xc = b.node_xyz(p0)
    cold1 = b.add_pipe_run(
        [xc, xc + (g["cold1_length"], 0, 0)], pipe, STEEL, "cold_pipe", start_node=p0, **kw
    )
    path += cold1[1:]

    # intermediate muffler
    m0 = _joint(b, cold1[-1], x_axis, g, "cold_pipe/intermediate_muffler")
    im_sec = oval_tube(g["im_width"], g["im_height"], g["im_wall"])
    im = _component(b, m0, g["im_length"], im_sec, "intermediate_muffler", 2, material=_SHELL_10K)
    path += im[1:]
    return hot, path


def _downstream(b: StructureBuilder, g: dict, kw: dict, path: list[int]) -> int:
    """Cold pipe with the large elbow, main muffler with its rear hanger bar, tail pipe, from the
    end of ``path`` (extended in place); returns the main muffler's middle node."""
    pipe = circular_tube(g["pipe_od"], g["pipe_wall"])
    tail = circular_tube(g["pipe_od"], g["tail_wall"])
    x_axis = (1.0, 0.0, 0.0)
    # cold pipe with the large elbow: straight, S-jog (elbow + second bend), straight
    p1 = _joint(b, path[-1], x_axis, g, "intermediate_muffler/cold_pipe")
    a = b.node_xyz(p1)
    bpt = a + (g["cold2_length"], 0, 0)
    cpt = bpt + (g["jog_dx"], g["jog_dy"], g["jog_dz"])
    dpt = cpt + (g["cold3_length"], 0, 0)
    cold2 = b.add_pipe_run(
        [a, bpt, cpt, dpt],
        pipe,
        STEEL,
        "cold_pipe",
        bend_radii=[g["elbow_radius"], g["elbow_radius"]],
        bend_names=["elbow", "elbow2"],
        start_node=p1,
        **kw,
    )
    path += cold2[1:]

    # main muffler with its welded rear hanger bar and internals
    q0 = _joint(b, cold2[-1], x_axis, g, "cold_pipe/main_muffler")
    mm_sec = oval_tube(g["mm_width"], g["mm_height"], 1.0e-3)
    mm_sheet = Material(
        STEEL.youngs_modulus, STEEL.poisson, STEEL.density * g["mm_sheet_factor"], "mm sheet"
    )
    mm = _component(b, q0, g["mm_length"], mm_sec, "main_muffler", 3, material=mm_sheet)
    path += mm[1:]
    mid = mm[len(mm) // 2]
    _rear_hanger_bar(b, g, mid)

    t0 = _joint(b, mm[-1], x_axis, g, "main_muffler/tail_pipe")
    xt = b.node_xyz(t0)
    tl = b.add_pipe_run(
        [xt, xt + (g["tail_length"], 0, 0)], tail, STEEL, "tail_pipe", start_node=t0, **kw
    )
    path += tl[1:]
    return mid


def _rear_hanger_bar(b: StructureBuilder, g: dict, mid: int) -> None:
    """The bar is welded along the shell: from the muffler axis to the shell side it moves with
    the shell (a massless stiff link of the main muffler part), beyond it it is a free solid bar."""
    xm = b.node_xyz(mid)
    bar = _solid_bar(g["rear_bar_diameter"])
    link = circular_tube(0.5 * g["mm_height"], 1.0e-3)
    for side in (1.0, -1.0):
        weld = b.add_node(xm + (0, side * 0.5 * g["mm_width"], 0))
        tip = b.add_node(xm + (0, side * (0.5 * g["mm_width"] + g["rear_bar_overhang"]), 0))
        b.add_beam(mid, weld, link, _MASSLESS_STEEL, "main_muffler", up=(0, 0, 1))
        b.add_beam(weld, tip, bar, STEEL, "rear_hanger_bar", up=(0, 0, 1))


def _close_mass_budget(b: StructureBuilder, g: dict, flange_node: int, mid: int) -> float:
    """Non-design masses: the flange at the manifold; the main muffler internals (baffles,
    perforated tubes, end caps) close the measured 12.29 kg at the initial design [kg]."""
    b.add_point_mass(
        flange_node,
        g["flange_mass"],
        "hot_pipe",
        inertia=_box_inertia(g["flange_mass"], 0.006, 0.12, 0.08),
    )
    s0 = b.build()
    from bayesupdate.fe.assembly import Assembler

    m_shells, _ = Assembler(s0).total_mass()
    m_int = MEASURED_MASS_KG - m_shells
    b.add_point_mass(
        mid,
        max(m_int, 0.0),
        "main_muffler",
        inertia=_box_inertia(
            max(m_int, 0.0), 0.8 * g["mm_length"], 0.7 * g["mm_width"], 0.7 * g["mm_height"]
        ),
    )
    return m_int


def _place_sensors(b: StructureBuilder, path: list[int]) -> np.ndarray:
    """20 sensors spread uniformly along the gas path (seed Fig. 9), numbered from the manifold;
    returns the path's arc length at its nodes [m]."""
    nodes = np.array([b.node_xyz(n) for n in path])
    s_path = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(nodes, axis=0), axis=1))])
    targets = (np.arange(N_SENSORS) + 0.5) / N_SENSORS * s_path[-1]
    used: set[int] = set()
    for k, s_target in enumerate(targets, start=1):
        order = np.argsort(np.abs(s_path - s_target))
        pick = next(int(i) for i in order if int(i) not in used)
        used.add(pick)
        b.add_sensor(f"{k}V", path[pick], "V")
        b.add_sensor(f"{k}H", path[pick], "H")
    return s_path


def envelope(structure) -> dict:
    """Bounding box of the nodes: length (x), width (y), height (z) [m]."""
    span = structure.nodes.max(axis=0) - structure.nodes.min(axis=0)
    return {"length": float(span[0]), "width": float(span[1]), "height": float(span[2])}


#: bounds of the joint stiffness factors (nuisance parameters; factor 1 = the fitted geometry)
JOINT_FACTOR_BOUNDS = (0.1, 10.0)


def joint_parameter(part: str) -> str:
    """Parameter name of a joint spring part "A/B": ``k_A__B``."""
    return "k_" + part.replace("/", "__")


def build_exhaust_model(
    geometry: str | int | dict = "best",
    elbow_flexibility: bool = True,
    joint_nuisance: bool = False,
) -> FEModel:
    """The exhaust ``FEModel`` with the five design variables of seed Table 3.

    geometry : "best" (the default set's best fit, ``DEFAULT_GEOMETRY``), an index (0 = best,
    1.. = its runner-up fits), a stored set's name ("table1", "two_design"; ``GEOMETRY_FILES``)
    with an optional ":k" for its k-th runner-up, or a dict of fitted quantities (see
    ``GEOMETRY_QUANTITIES``).  elbow_flexibility : apply the ASME B31.3
    flexibility factor to the bends.  joint_nuisance : also bind each joint spring part "A/B"
    (``JOINTS``) to a parameter ``k_A__B`` (property stiffness_factor, default 1, bounds
    ``JOINT_FACTOR_BOUNDS``), so the connection stiffnesses can be sampled as nuisance
    parameters; off (default) the model is unchanged.
    """
    fitted = geometry if isinstance(geometry, dict) else fitted_geometry(geometry)
    structure = build_exhaust_structure(full_geometry(fitted), elbow_flexibility)
    if structure.metadata["mm_internal_mass_kg"] < 0:
        raise BayesUpdateError(
            f"exhaust geometry: the shells alone weigh more than {MEASURED_MASS_KG} kg; "
            "reduce the sizes"
        )
    bindings, defaults, bounds = dict(DESIGN_BINDINGS), dict(DESIGN_DEFAULTS), dict(DESIGN_BOUNDS)
    if joint_nuisance:
        for part in JOINTS:
            name = joint_parameter(part)
            bindings[name] = Binding(part, "stiffness_factor")
            defaults[name] = 1.0
            bounds[name] = JOINT_FACTOR_BOUNDS
    return FEModel(structure, bindings, defaults, bounds, name="exhaust")


def mode_character(structure, shapes: np.ndarray, threshold: float = 0.05) -> list[dict]:
    """Plane and node count of each mode from its shape.

    shapes : (n_dof, m).  For each mode: ``h_share`` = sum uy^2 / sum (uy^2 + uz^2) over the gas
    path nodes; plane "H" if h_share > 0.5 else "V"; ``nodes`` = number of sign changes of the
    dominant-direction displacement (y for H, z for V) along the path from the manifold to the
    tail, ignoring points with |u| < threshold * max |u| (near a node).
    Returns a list of dicts (plane, h_share, nodes).
    """
    path = structure.metadata["path_nodes"]
    uy = shapes[6 * path + 1]
    uz = shapes[6 * path + 2]
    out = []
    for j in range(shapes.shape[1]):
        ey, ez = float(np.sum(uy[:, j] ** 2)), float(np.sum(uz[:, j] ** 2))
        h_share = ey / max(ey + ez, 1e-300)
        u = uy[:, j] if h_share > 0.5 else uz[:, j]
        big = u[np.abs(u) >= threshold * np.abs(u).max()]
        n_nodes = int(np.sum(np.sign(big[1:]) != np.sign(big[:-1])))
        out.append({"plane": "H" if h_share > 0.5 else "V", "h_share": h_share, "nodes": n_nodes})
    return out
