"""A test geometry as plain CSV, for data that have no universal file.

Rows (a header line and ``#`` comments allowed; lengths in the file's ``length_unit``)::

    node, x, y, z[, frame]          # global coordinates; frame: the displacement frame id
    frame, id, kind, r11, r12, r13, r21, r22, r23, r31, r32, r33, ox, oy, oz
                                    # kind rectangular|cylindrical|spherical; rows of R are
                                    # the frame's axes in global, (ox, oy, oz) its origin
    dof, label, node, dx, dy, dz    # a test DOF in a skewed direction (in the node's
                                    # displacement frame; need not be normalized)

A ``dof`` row lets test data name a DOF that no UFF direction code describes (a sensor glued at
an angle): the data's label ``label`` reads the model along that vector.
"""

import csv
from pathlib import Path

import numpy as np

from bayesupdate.atomic import atomic_path
from bayesupdate.errors import BayesUpdateError
from bayesupdate.testgeom.dofs import unit_vector
from bayesupdate.testgeom.frames import checked_frame
from bayesupdate.testgeom.geometry import DeclaredDof, TestGeometry, make_geometry
from bayesupdate.testgeom.units import METRES_PER, length_unit


def _numbers(cells, where: str) -> list[float]:
    try:
        values = [float(c) for c in cells]
    except ValueError:
        raise BayesUpdateError(f"{where}: {','.join(cells)!r} are not all numbers") from None
    if not np.all(np.isfinite(values)):
        raise BayesUpdateError(f"{where}: {','.join(cells)!r} are not all finite")
    return values


def _rows(path: Path):
    """(line number, stripped cells) of the data rows (header and comments skipped)."""
    try:
        text = path.read_text()
    except OSError as exc:
        raise BayesUpdateError(f"{path}: cannot read the test geometry ({exc.strerror})") from None
    except UnicodeDecodeError as exc:
        raise BayesUpdateError(
            f"{path}: not a text CSV file ({exc.reason}); export the test geometry as UTF-8 CSV"
        ) from None
    first = True
    for number, row in enumerate(csv.reader(text.splitlines()), start=1):
        cells = [c.strip() for c in row]
        while cells and not cells[-1]:
            cells.pop()
        if not cells or cells[0].startswith("#"):
            continue
        head = cells[0].lower()
        if first and head not in ("frame", "dof") and not head.lstrip("+-").isdigit():
            first = False
            continue  # a header line
        first = False
        yield number, cells


def read_csv_geometry(path, length_unit_name: str = "m") -> TestGeometry:
    """``TestGeometry`` of a CSV file (module docstring); lengths in ``length_unit_name``."""
    path = Path(path)
    metres = METRES_PER[length_unit(length_unit_name)]
    ids, xyz, disp, frames, declared = [], [], [], [], []
    for number, cells in _rows(path):
        where, head = f"{path}:{number}", cells[0].lower()
        if head == "frame":
            if len(cells) != 15:
                raise BayesUpdateError(
                    f"{where}: a frame row is 'frame, id, kind, 9 axis numbers, 3 origin numbers'"
                )
            values = _numbers(cells[3:], where)
            frame_id = _numbers(cells[1:2], where)[0]
            matrix = np.reshape(values, (4, 3))
            frames.append(checked_frame(int(frame_id), cells[2].lower(), matrix, where, metres))
        elif head == "dof":
            if len(cells) != 6:
                raise BayesUpdateError(f"{where}: a dof row is 'dof, label, node, dx, dy, dz'")
            node, *vector = _numbers(cells[2:], where)
            unit_vector(vector, f"{where}: DOF {cells[1]!r}")
            declared.append(DeclaredDof(cells[1], int(node), tuple(vector)))
        else:
            if len(cells) not in (4, 5) or not cells[0].lstrip("+-").isdigit():
                raise BayesUpdateError(
                    f"{where}: give 'node, x, y, z[, frame]' (or a frame or dof row), got "
                    f"{','.join(cells)!r}"
                )
            values = _numbers(cells[1:], where)
            ids.append(int(cells[0]))
            xyz.append(np.asarray(values[:3]) * metres)
            disp.append(int(values[3]) if len(values) == 4 else 0)
    unit = length_unit(length_unit_name)
    return make_geometry(ids, np.reshape(xyz, (-1, 3)), disp, frames, (), declared, unit, str(path))


def write_csv_geometry(path, geometry: TestGeometry, unit: str = "m") -> None:
    """Write ``geometry``'s nodes, frames and declared DOFs as CSV in ``unit``."""
    k = 1.0 / METRES_PER[length_unit(unit)]
    lines = [f"# test geometry, lengths in {unit}", "node,x,y,z,frame"]
    for n, p, f in zip(geometry.node_ids, geometry.xyz * k, geometry.disp_frame, strict=True):
        lines.append(f"{n}," + ",".join(repr(float(v)) for v in p) + f",{f}")
    for f in geometry.frames:
        numbers = [*f.rotation.ravel(), *(f.origin * k)]
        lines.append(f"frame,{f.id},{f.kind}," + ",".join(repr(float(v)) for v in numbers))
    for d in geometry.declared:
        lines.append(f"dof,{d.label},{d.node}," + ",".join(repr(float(v)) for v in d.vector))
    with atomic_path(path, suffix=".csv") as tmp:
        tmp.write_text("\n".join(lines) + "\n")
