"""Test geometry in and out of universal files (UFF) through pyuff.

Datasets read: 164 (units), 2420 (coordinate systems: rectangular, cylindrical, spherical;
``frames``), 18 (the older coordinate systems Test.Lab writes: an origin, a point on the +x
axis and a point in the +xz plane, in a reference frame), 15 and 2411 (nodes: label,
definition frame, displacement frame, colour, coordinates in the definition frame, as SDynPy's
``Geometry`` reads both), 82 (trace lines; the zeros padding a Test.Lab record dropped).
Every other dataset (55, 58, ...) is skipped.  Written: 164, 2420 (when frames are named),
15 or 2411 (coordinates in the global frame, definition frame 0), one 82 per trace line.

pyuff pitfalls guarded here: it returns one dataset as a bare dict (wrapped), raises anything on
a corrupt file (one ``BayesUpdateError``), reads integers as floats (cast), and writes only the
``CS_types`` etc. it is given (all given).
"""

import os

import numpy as np

from bayesupdate.atomic import atomic_path
from bayesupdate.errors import BayesUpdateError
from bayesupdate.testgeom.frames import GLOBAL, KINDS, checked_frame, to_global
from bayesupdate.testgeom.geometry import TestGeometry, make_geometry
from bayesupdate.testgeom.units import METRES_PER, UFF_UNITS_CODE, length_unit, unit_of_uff164
from bayesupdate.uff_read import quiet_read

#: which local coordinates of each frame kind are lengths (the rest are angles in degrees)
_LENGTHS = {"rectangular": [1, 1, 1], "cylindrical": [1, 0, 1], "spherical": [1, 0, 0]}
#: UFF 164 force factors (file force units per newton) of the unit systems written
_FORCE = {"m": 1.0, "mm": 1e3, "cm": 1e2, "in": 0.2248089431, "ft": 0.2248089431}


def read_uff_sets(path) -> list[dict]:
    """The datasets of a universal file (pyuff dicts); one-line errors for a missing or
    unreadable file."""
    if not os.path.isfile(path):
        raise BayesUpdateError(f"{path}: test geometry file not found")
    try:
        sets = quiet_read(path)
    except Exception as exc:  # pyuff raises anything on a corrupt file
        raise BayesUpdateError(
            f"{path}: not a readable universal file ({type(exc).__name__}: {exc})"
        ) from None
    return [sets] if isinstance(sets, dict) else list(sets)


def _unit(sets, path, given) -> tuple[str, float]:
    """(unit name, metres per file unit): the 164 record, or ``given``, or metres."""
    records = [s for s in sets if s["type"] == 164]
    from_file = unit_of_uff164(float(records[0]["length"]), str(path)) if records else None
    if given is None:
        return from_file or ("m", 1.0)
    name = length_unit(given)
    if from_file is not None and abs(from_file[1] / METRES_PER[name] - 1) > 1e-6:
        raise BayesUpdateError(
            f"{path}: its UFF 164 record says {from_file[0]} but length_unit = {given!r}; "
            "drop the setting or correct it"
        )
    return name, METRES_PER[name]


def _frame_of_points(label, kind, origin, x_point, xz_point, where) -> np.ndarray:
    """(4, 3) 2420-style matrix of a dataset 18 frame: x along origin -> x_point, z normal to
    the plane through xz_point, y = z x x."""
    x = np.asarray(x_point, float) - origin
    z = np.cross(x, np.asarray(xz_point, float) - origin)
    if np.linalg.norm(x) < 1e-12 or np.linalg.norm(z) < 1e-12 * np.linalg.norm(x) ** 2:
        raise BayesUpdateError(f"{where}: frame {label}: its three UFF 18 points are collinear")
    x, z = x / np.linalg.norm(x), z / np.linalg.norm(z)
    return np.vstack([x, np.cross(z, x), z, origin])


def _frames18(sets, path, metres) -> list:
    """Frames of the dataset 18 records (reference frames defined before use)."""
    frames = {0: GLOBAL}
    for s in (s for s in sets if s["type"] == 18):
        for k, label in enumerate(s["cs_num"]):
            kind, ref = int(s["cs_type"][k]), int(s["ref_cs_num"][k])
            if kind not in (0, 1, 2) or ref not in frames:
                raise BayesUpdateError(
                    f"{path}: UFF 18 frame {int(label)}: type {kind} (0, 1, 2) in reference "
                    f"frame {ref} (defined before it)"
                )
            points = [to_global(frames[ref], np.asarray(s[key][k], float) * metres)[0]
                      for key in ("ref_o", "x_point", "xz_point")]  # fmt: skip
            matrix = _frame_of_points(int(label), KINDS[kind], *points, str(path))
            frames[int(label)] = checked_frame(int(label), KINDS[kind], matrix, str(path))
    return [f for i, f in frames.items() if i != 0]


def _frames(sets, path, metres) -> tuple:
    frames = _frames18(sets, path, metres)
    for s in (s for s in sets if s["type"] == 2420):
        for label, kind, matrix in zip(s["CS_sys_labels"], s["CS_types"], s["CS_matrices"],
                                       strict=True):  # fmt: skip
            if int(kind) not in (0, 1, 2):
                raise BayesUpdateError(f"{path}: frame {label}: UFF 2420 type {kind} (0, 1, 2)")
            frames.append(checked_frame(label, KINDS[int(kind)], matrix, str(path), metres))
    return tuple(frames)


def _nodes(sets, path, metres, frames) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ids, global xyz [m], displacement frame ids) of the 15 and 2411 records."""
    node_sets = [s for s in sets if s["type"] in (15, 2411)]
    if not node_sets:
        raise BayesUpdateError(
            f"{path}: no node coordinates in it (UFF dataset 15 or 2411); export the geometry"
        )
    col = {k: np.concatenate([np.asarray(s[k], float) for s in node_sets])
           for k in ("node_nums", "def_cs", "disp_cs", "x", "y", "z")}  # fmt: skip
    local = np.column_stack([col["x"], col["y"], col["z"]])
    xyz = np.empty_like(local)
    by_id = {f.id: f for f in frames} | {0: GLOBAL}
    for cs in np.unique(col["def_cs"]).astype(int):
        if cs not in by_id:
            raise BayesUpdateError(
                f"{path}: nodes are defined in coordinate frame {cs}, which has no UFF 2420 record"
            )
        rows = col["def_cs"] == cs
        scale = np.where(_LENGTHS[by_id[cs].kind], metres, 1.0)
        xyz[rows] = to_global(by_id[cs], local[rows] * scale)
    return col["node_nums"].astype(np.int64), xyz, col["disp_cs"].astype(np.int64)


def _trace(nodes) -> tuple[int, ...]:
    """A trace line's node ids without the zeros that pad its last record (Test.Lab)."""
    out = [int(n) for n in nodes]
    while out and out[-1] == 0:
        out.pop()
    return tuple(out)


def read_uff_geometry(path, length_unit=None) -> TestGeometry:
    """``TestGeometry`` of a universal file (module docstring).  length_unit : the file's
    length unit when it has no UFF 164 record (default metres); with one, it must agree."""
    sets = read_uff_sets(path)
    unit, metres = _unit(sets, path, length_unit)
    frames = _frames(sets, path, metres)
    ids, xyz, disp = _nodes(sets, path, metres, frames)
    lines = tuple(_trace(s["nodes"]) for s in sets if s["type"] == 82)
    return make_geometry(ids, xyz, disp, frames, lines, (), unit, str(path))


def geometry_datasets(geometry: TestGeometry, unit: str = "m", dataset: int = 15) -> list[dict]:
    """The pyuff dicts (164, 2420, 15 or 2411, 82) that write ``geometry`` in ``unit``."""
    import pyuff

    unit = length_unit(unit)
    if dataset not in (15, 2411):
        raise BayesUpdateError(f"UFF node dataset {dataset}: write 15 or 2411")
    k = 1.0 / METRES_PER[unit]
    sets = [pyuff.prepare_164(units_code=UFF_UNITS_CODE[unit], units_description=unit,
                              temp_mode=1, length=k, force=_FORCE[unit], temp=1.0,
                              temp_offset=273.15)]  # fmt: skip
    if geometry.frames:
        f = geometry.frames
        sets.append(pyuff.prepare_2420(
            Part_UID=1, Part_Name="test", CS_sys_labels=[x.id for x in f],
            CS_types=[KINDS.index(x.kind) for x in f], CS_colors=[8] * len(f),
            CS_names=[f"CS{x.id}" for x in f],
            CS_matrices=[np.vstack([x.rotation, x.origin * k]) for x in f]))  # fmt: skip
    n = len(geometry.node_ids)
    xyz = geometry.xyz * k
    prepare = pyuff.prepare_15 if dataset == 15 else pyuff.prepare_2411
    sets.append(prepare(node_nums=[int(i) for i in geometry.node_ids], def_cs=[0] * n,
                        disp_cs=[int(i) for i in geometry.disp_frame], color=[1] * n,
                        x=xyz[:, 0], y=xyz[:, 1], z=xyz[:, 2]))  # fmt: skip
    for number, line in enumerate(geometry.trace_lines, start=1):
        sets.append(
            pyuff.prepare_82(trace_num=number, n_nodes=len(line), color=1,
                             id=f"trace line {number}", nodes=np.asarray(line, int))
        )  # fmt: skip
    return sets


def write_uff_geometry(path, geometry: TestGeometry, unit: str = "m", dataset: int = 15) -> None:
    """Write ``geometry`` as a universal file in ``unit`` (atomically)."""
    import pyuff

    sets = geometry_datasets(geometry, unit, dataset)
    with atomic_path(path, suffix=".unv") as tmp:
        tmp.unlink()
        pyuff.UFF(str(tmp)).write_sets(sets, mode="add")
