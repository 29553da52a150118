"""Builder steps for shells, supports, rigid elements, general beams, rods and node frames (the
``StructureBuilder`` methods ``add_shells``, ``add_support``, ``add_rbe2``, ``add_rbe3``,
``add_beams``, ``add_rods`` and ``set_frame`` delegate here), and their arrays for the frozen
``Structure`` (``general_parts``).

Shell points that lie within ``merge_tol`` of an existing node reuse that node, so shell faces
built separately, or a shell and the beams on its edge, share DOFs (6 per node everywhere).
"""

from dataclasses import replace

import numpy as np
from scipy.spatial import cKDTree

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.constraints import Constraints, parse_components
from bayesupdate.fe.shell_model import WARP_LIMIT, ShellElements, shell_mesh


def add_shells(
    builder,
    points,
    quads,
    trias,
    thickness,
    material,
    part: str,
    offset=0.0,
    offset_ratio=0.0,
    nsm=0.0,
    merge_tol: float = 1e-6,
    warp_limit: float = WARP_LIMIT,
) -> np.ndarray:
    """Add shell elements to ``builder``.

    points (n, 3) [m]; quads (nq, 4) / trias (nt, 3) indices into ``points``; thickness [m],
    offset [m], offset_ratio, nsm [kg/m^2]: scalars or one per element (quads first);
    material : ``Material``.  The elements are checked on their own (``shell_mesh``: repeated
    nodes, zero area, order, warp, properties; errors name the element of this call).
    Returns (n,) the structure node number of each point.
    """
    try:
        mesh = shell_mesh(
            points,
            quads,
            trias,
            thickness=thickness,
            E=material.youngs_modulus,
            nu=material.poisson,
            rho=material.density,
            offset=offset,
            offset_ratio=offset_ratio,
            nsm=nsm,
            warp_limit=warp_limit,
        )
    except BayesUpdateError as exc:
        raise BayesUpdateError(f"shells of part {part!r}: {exc}") from None
    ids = _merge_points(builder, mesh.nodes, merge_tol)
    builder._shell_blocks.append(  # noqa: SLF001 - the builder's own store
        dict(mesh=mesh, ids=ids, part=builder._part(part))  # noqa: SLF001
    )
    return ids


def _merge_points(builder, points: np.ndarray, tol: float) -> np.ndarray:
    """Node numbers for points (n, 3): an existing node within ``tol`` or a new node."""
    existing = np.array(builder._nodes, dtype=float).reshape(-1, 3)  # noqa: SLF001
    ids = np.full(len(points), -1)
    if len(existing):
        dist, near = cKDTree(existing).query(points, distance_upper_bound=tol)
        hit = np.isfinite(dist)
        ids[hit] = near[hit]
    new = np.flatnonzero(ids < 0)
    ids[new] = len(existing) + np.arange(new.size)
    builder._nodes.extend(map(tuple, points[new].tolist()))  # noqa: SLF001 - checked finite
    return ids


def _shell_elements(builder) -> ShellElements | None:
    blocks = builder._shell_blocks  # noqa: SLF001
    if not blocks:
        return None
    quads = [b["ids"][b["mesh"].quads] for b in blocks]
    trias = [b["ids"][b["mesh"].trias] for b in blocks]
    names = ("thickness", "E", "nu", "rho", "offset", "offset_ratio", "nsm")

    def per_element(get):
        q = [get(b)[: len(b["mesh"].quads)] for b in blocks]
        t = [get(b)[len(b["mesh"].quads) :] for b in blocks]
        return np.concatenate(q + t)

    props = {n: per_element(lambda b, n=n: getattr(b["mesh"], n)) for n in names}
    part = per_element(lambda b: np.full(b["mesh"].n_elements, b["part"]))
    return ShellElements(
        quads=np.concatenate(quads).reshape(-1, 4),
        trias=np.concatenate(trias).reshape(-1, 3),
        part=part.astype(int),
        **props,
    )


def _constraints(builder) -> Constraints | None:
    sup, r2, r3 = builder._supports, builder._rbe2, builder._rbe3  # noqa: SLF001
    frames, mpcs = builder._frames, builder._mpcs  # noqa: SLF001
    if not (sup or r2 or r3 or frames or mpcs):
        return None
    terms = [(e, *t) for e, equation in enumerate(mpcs) for t in equation]
    legs2 = [(e, ind, d, c) for e, (ind, deps, c) in enumerate(r2) for d in deps]
    legs3 = [
        (e, n, w, c)
        for e, (_, _, ns, ws, nc, _) in enumerate(r3)
        for n, w, c in zip(ns, ws, nc, strict=True)
    ]
    um = [(e, n, c) for e, r in enumerate(r3) for n, c in r[5]]
    return Constraints(
        fixed_node=np.array([n for n, _ in sup], dtype=int),
        fixed_components=np.array([c for _, c in sup], dtype=bool).reshape(-1, 6),
        rbe2_element=np.array([leg[0] for leg in legs2], dtype=int),
        rbe2_independent=np.array([leg[1] for leg in legs2], dtype=int),
        rbe2_dependent=np.array([leg[2] for leg in legs2], dtype=int),
        rbe2_components=np.array([leg[3] for leg in legs2], dtype=bool).reshape(-1, 6),
        rbe3_reference=np.array([r[0] for r in r3], dtype=int),
        rbe3_ref_components=np.array([r[1] for r in r3], dtype=bool).reshape(-1, 6),
        rbe3_element=np.array([leg[0] for leg in legs3], dtype=int),
        rbe3_node=np.array([leg[1] for leg in legs3], dtype=int),
        rbe3_weight=np.array([leg[2] for leg in legs3], dtype=float),
        rbe3_components=np.array([leg[3] for leg in legs3], dtype=bool).reshape(-1, 6),
        rbe3_um_element=np.array([u[0] for u in um], dtype=int),
        rbe3_um_node=np.array([u[1] for u in um], dtype=int),
        rbe3_um_components=np.array([u[2] for u in um], dtype=bool).reshape(-1, 6),
        frame_node=np.array(list(frames), dtype=int),
        frame_axes=np.array(list(frames.values()), dtype=float).reshape(-1, 3, 3),
        mpc_equation=np.array([t[0] for t in terms], dtype=int),
        mpc_node=np.array([t[1] for t in terms], dtype=int),
        mpc_component=np.array([t[2] for t in terms], dtype=int),
        mpc_coef=np.array([t[3] for t in terms], dtype=float),
    )


def general_parts(builder) -> dict:
    """``shells``, ``constraints``, ``general_beams`` and ``rods`` fields of the ``Structure``
    being built."""
    from bayesupdate.fe.elements.general_beam import GeneralBeams
    from bayesupdate.fe.elements.rod import Rods

    return dict(
        shells=_shell_elements(builder),
        constraints=_constraints(builder),
        general_beams=_concat(builder._general_beams, GeneralBeams),  # noqa: SLF001
        rods=_concat(builder._rods, Rods),  # noqa: SLF001
    )


# -- general beams, rods and node frames --------------------------------------------------------
def _pairs(builder, node_pairs, what: str) -> np.ndarray:
    """(n, 2) node pairs, checked: existing nodes, two different nodes per element."""
    pairs = np.asarray(node_pairs)
    if pairs.ndim == 1 and pairs.size == 2:
        pairs = pairs.reshape(1, 2)
    if pairs.ndim != 2 or pairs.shape[1] != 2 or len(pairs) == 0:
        raise BayesUpdateError(f"{what}: node_pairs must be (n, 2) node numbers, n >= 1")
    if not np.issubdtype(pairs.dtype, np.integer):
        raise BayesUpdateError(f"{what}: node_pairs must be integer node numbers")
    n_nodes = len(builder._nodes)  # noqa: SLF001
    bad = np.flatnonzero((pairs < 0).any(axis=1) | (pairs >= n_nodes).any(axis=1))
    if bad.size:
        k = int(bad[0])
        raise BayesUpdateError(
            f"{what}: element {k} uses node {pairs[k].tolist()} but nodes are 0..{n_nodes - 1}"
        )
    same = np.flatnonzero(pairs[:, 0] == pairs[:, 1])
    if same.size:
        k = int(same[0])
        raise BayesUpdateError(f"{what}: element {k} repeats node {int(pairs[k, 0])}")
    return pairs.astype(int)


def _per_element(value, n: int, shape: tuple, what: str, name: str) -> np.ndarray:
    """``value`` broadcast to (n, *shape) floats, or a one-line error naming the field."""
    a = np.asarray(value, dtype=float)
    try:
        a = np.broadcast_to(a, (n, *shape)) if a.shape != (n, *shape) else a
    except ValueError:
        raise BayesUpdateError(
            f"{what}: {name} must have shape {shape} or ({n}, {', '.join(map(str, shape))})"
        ) from None
    if not np.all(np.isfinite(a)):
        raise BayesUpdateError(f"{what}: {name} must be finite")
    return np.array(a, dtype=float)


def _pin_masks(pins, n: int, what: str) -> np.ndarray:
    """(n, 2, 6) bool from None, one (pa, pb) pair or n pairs of component digits ('' = none)."""
    out = np.zeros((n, 2, 6), bool)
    if pins is None:
        return out
    rows = [pins] * n if len(pins) == 2 and not isinstance(pins[0], list | tuple) else list(pins)
    if len(rows) != n or any(len(r) != 2 for r in rows):
        raise BayesUpdateError(f"{what}: pins must be (pa, pb) or one (pa, pb) per element")
    for k, pair in enumerate(rows):
        for end, comps in enumerate(pair):
            if comps not in (None, "", 0):
                out[k, end] = parse_components(comps, f"{what}: element {k} pins")
    return out


def _default_up(axis: np.ndarray) -> np.ndarray:
    """Global z as local z reference, global y for near-vertical elements (as ``add_beam``)."""
    L = np.linalg.norm(axis, axis=1)
    vertical = np.abs(axis[:, 2]) >= 0.99 * L
    return np.where(vertical[:, None], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0])


def add_beams(
    builder,
    node_pairs,
    section,
    material,
    part,
    up=None,
    offsets=None,
    pins=None,
    mass="consistent",
    nsm=0.0,
    shear_modulus=None,
    torsion_inertia=None,
    taper=None,
):
    """General beams (``fe.elements.general_beam``) on existing node pairs; returns their indices.

    section : ``standard_sections.BeamSection``; material : ``Material`` (G = E / 2(1 + nu)
    unless ``shear_modulus`` [Pa]); up : local z reference (3,) or (n, 3), default global z
    (global y for vertical elements); offsets : (2, 3) or (n, 2, 3) [m] from each node to its
    element end (global axes); pins : (pa, pb) or n pairs of released element-axis components
    ('456', 'rz', ...); mass : 'consistent', 'lumped', 'none' or 'translational' (consistent,
    no rotary or torsional inertia); nsm [kg/m]; torsion_inertia [kg m] per length (default
    rho (iy + iz)); taper : (2, 4) or (n, 2, 4) a tapered element's A [m^2], iy, iz, J [m^4] at
    its end a and end b, linear between (``section`` is then its mean section, for the mass and
    the taper's ratios; the section's iyz must be 0); default the section's at both ends.
    """
    from bayesupdate.fe.elements import general_beam as gb
    from bayesupdate.fe.standard_sections import BeamSection

    what = f"add_beams (part {part!r})"
    if not isinstance(section, BeamSection):
        raise BayesUpdateError(f"{what}: section must be a BeamSection (fe.standard_sections)")
    if mass not in gb.MASS_KINDS:
        raise BayesUpdateError(f"{what}: mass must be one of {gb.MASS_KINDS}, got {mass!r}")
    pairs = _pairs(builder, node_pairs, what)
    n = len(pairs)
    xyz = np.array(builder._nodes, dtype=float)  # noqa: SLF001
    off = _per_element(0.0 if offsets is None else offsets, n, (2, 3), what, "offsets")
    axis = xyz[pairs[:, 1]] + off[:, 1] - xyz[pairs[:, 0]] - off[:, 0]
    values, per = _beam_properties(material, section, shear_modulus, torsion_inertia, what)
    per = _per_beam(per["torsion_inertia"], nsm, _default_up(axis) if up is None else up, n, what)
    per["taper"] = _taper(section, taper, n, what)
    beams = gb.GeneralBeams(
        nodes=pairs,
        part=np.zeros(n, int),
        offset=off,
        pins=_pin_masks(pins, n, what),
        mass=np.full(n, gb.MASS_KINDS.index(mass)),
        **{k: np.full(n, float(v)) for k, v in values.items()},
        **per,
    )
    _check_beams(xyz, beams, what)
    beams = replace(beams, part=np.full(n, builder._part(part)))  # noqa: SLF001
    start = sum(b.n_elements for b in builder._general_beams)  # noqa: SLF001
    builder._general_beams.append(beams)  # noqa: SLF001
    return start + np.arange(n)


def _per_beam(torsion_inertia, nsm, up, n: int, what: str) -> dict:
    """{nsm, torsion_inertia, up} per element (``add_beams``), checked >= 0."""
    per = dict(
        nsm=_per_element(nsm, n, (), what, "nsm"),
        torsion_inertia=_per_element(torsion_inertia, n, (), what, "torsion_inertia"),
        up=_per_element(up, n, (3,), what, "up"),
    )
    if min(per["nsm"].min(), per["torsion_inertia"].min()) < 0:
        raise BayesUpdateError(f"{what}: needs shear modulus > 0, nsm >= 0, torsion_inertia >= 0")
    return per


def _taper(section, taper, n: int, what: str) -> np.ndarray:
    """(n, 2, 4) ``GeneralBeams.taper``: the elements' A, iy, iz, J at each end (``add_beams``'s
    ``taper``) over the section's (its mean); ones without ``taper``.  A tapered element needs
    A, iy, iz, J > 0 at both ends and iyz = 0."""
    if taper is None:
        return np.ones((n, 2, 4))
    ends = _per_element(taper, n, (2, 4), what, "taper")
    own = np.array([section.area, section.iy, section.iz, section.torsion], dtype=float)
    varies = np.any(ends[:, 0] != ends[:, 1], axis=1)
    if not np.any(varies):
        return np.ones((n, 2, 4))
    if section.iyz != 0 or not (np.all(ends[varies] > 0) and np.all(own > 0)):
        raise BayesUpdateError(f"{what}: a tapered element needs A, iy, iz, J > 0 at both ends "
                               "and no product of inertia (iyz = 0)")  # fmt: skip
    return np.where(varies[:, None, None], ends / own, 1.0)


def _beam_properties(material, section, shear_modulus, torsion_inertia, what: str):
    """(uniform element values: E, G [Pa], rho [kg/m^3], section A [m^2], I [m^4], shear
    factors; {"torsion_inertia": [kg m] per length, default rho (iy + iz)})."""
    E = material.youngs_modulus
    G = E / (2 * (1 + material.poisson)) if shear_modulus is None else float(shear_modulus)
    if not (np.isfinite(G) and G > 0):
        raise BayesUpdateError(f"{what}: needs shear modulus > 0, nsm >= 0, torsion_inertia >= 0")
    if torsion_inertia is None:
        torsion_inertia = material.density * (section.iy + section.iz)
    values = dict(E=E, G=G, rho=material.density, area=section.area, iy=section.iy,
                  iz=section.iz, iyz=section.iyz, torsion=section.torsion,
                  shear_y=section.shear_y, shear_z=section.shear_z)  # fmt: skip
    return values, {"torsion_inertia": torsion_inertia}


def _check_beams(xyz, b, what: str) -> None:
    """Zero length (after offsets), an orientation along the axis, pins that free the element."""
    from bayesupdate.fe.elements import general_beam as gb

    xa = xyz[b.nodes[:, 0]] + b.offset[:, 0]
    d = xyz[b.nodes[:, 1]] + b.offset[:, 1] - xa
    L = np.linalg.norm(d, axis=1)
    size = max(1.0, float(np.abs(xyz).max()))
    short = np.flatnonzero(L <= 1e-12 * size)
    if short.size:
        raise BayesUpdateError(f"{what}: element {int(short[0])} has zero length")
    cross = np.linalg.norm(np.cross(b.up, d), axis=1)
    along = np.flatnonzero(cross <= 1e-6 * L * np.linalg.norm(b.up, axis=1))
    if along.size:
        raise BayesUpdateError(
            f"{what}: element {int(along[0])}: the orientation vector is parallel to the axis"
        )
    released = b.pins.reshape(-1, 12)
    pinned = np.flatnonzero(released.any(axis=1))
    if pinned.size:
        K, _ = gb.element_local(L[pinned], b, pinned, True, True)
        bad = gb.pin_mechanisms(K, released[pinned])
        if np.any(bad):
            raise BayesUpdateError(
                f"{what}: element {int(pinned[np.flatnonzero(bad)[0]])}: its pin flags let it "
                "move without strain (e.g. the axial or twist DOF released at both ends)"
            )


def add_rods(
    builder,
    node_pairs,
    area,
    material,
    part,
    torsion=0.0,
    nsm=0.0,
    mass="consistent",
    shear_modulus=None,
):
    """Rods (``fe.elements.rod``): area [m^2] and torsion constant [m^4] (scalars or one per
    element),
    nsm [kg/m], mass 'consistent' or 'lumped'.  Returns their indices."""
    from bayesupdate.fe.elements.rod import Rods

    what = f"add_rods (part {part!r})"
    if mass not in ("consistent", "lumped", "none"):
        raise BayesUpdateError(f"{what}: mass must be 'consistent', 'lumped' or 'none'")
    pairs = _pairs(builder, node_pairs, what)
    n = len(pairs)
    a = _per_element(area, n, (), what, "area")
    j = _per_element(torsion, n, (), what, "torsion")
    m = _per_element(nsm, n, (), what, "nsm")
    bad = np.flatnonzero((a <= 0) | (j < 0) | (m < 0))
    if bad.size:
        raise BayesUpdateError(
            f"{what}: element {int(bad[0])} needs area > 0, torsion >= 0 and nsm >= 0"
        )
    xyz = np.array(builder._nodes, dtype=float)  # noqa: SLF001
    L = np.linalg.norm(xyz[pairs[:, 1]] - xyz[pairs[:, 0]], axis=1)
    short = np.flatnonzero(L <= 1e-12 * max(1.0, float(np.abs(xyz).max())))
    if short.size:
        raise BayesUpdateError(f"{what}: element {int(short[0])} has zero length")
    E = material.youngs_modulus
    G = E / (2 * (1 + material.poisson)) if shear_modulus is None else float(shear_modulus)
    keep = float(mass != "none")
    full = {k: np.full(n, v) for k, v in (("E", E), ("G", G), ("rho", keep * material.density))}
    part_id = np.full(n, builder._part(part))  # noqa: SLF001
    lumped = np.full(n, mass == "lumped")
    rods = Rods(pairs, part_id, area=a, torsion=j, nsm=keep * m, lumped=lumped, **full)
    start = sum(r.n_elements for r in builder._rods)  # noqa: SLF001
    builder._rods.append(rods)  # noqa: SLF001
    return start + np.arange(n)


def set_frame(builder, nodes, frame) -> None:
    """Give ``nodes`` the DOF axes of ``frame`` (``fe.frames.CoordinateFrame``) at their
    positions: their supports and rigid-element components act in those axes."""
    from bayesupdate.fe.frames import CoordinateFrame

    if not isinstance(frame, CoordinateFrame):
        raise BayesUpdateError("set_frame: frame must be a fe.frames.CoordinateFrame")
    ids = [builder._check_node(n) for n in np.atleast_1d(nodes)]  # noqa: SLF001
    axes = frame.axes_at(np.array([builder._nodes[i] for i in ids], dtype=float))  # noqa: SLF001
    for i, A in zip(ids, axes, strict=True):
        if i in builder._frames:  # noqa: SLF001
            raise BayesUpdateError(f"set_frame: node {i} already has a coordinate frame")
        builder._frames[i] = A  # noqa: SLF001


def _concat(blocks, cls):
    if not blocks:
        return None
    return cls(
        **{k: np.concatenate([getattr(b, k) for b in blocks]) for k in cls.__dataclass_fields__}
    )
