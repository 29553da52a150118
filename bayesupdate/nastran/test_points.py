"""Test DOF labels on a Nastran deck: ``"12V"`` / ``"12+Z"`` -> GRID 12, direction +z.

A label is ``<node><L|H|V>`` (UFF: L = x, H = y, V = z) or ``<node><+|-><X|Y|Z>`` (sign
optional).  The node is the deck's GRID id unless a test-point table maps it; the table is the
study's ``[model.test_points]`` or a ``--test-points`` file (``read_test_points``)::

    "12" = 1012                              # test node 12 is GRID 1012
    "13" = { grid = 1013, frame = "output" } # its directions are in GRID 1013's CD frame
    set = 5                                  # every GRID of SET1 5 (or case control SET 5)
    frame = "output"                         # default frame of every point (else "basic")

Directions are in the deck's basic frame, or in the GRID's output (displacement, CD) frame
(rows of ``metadata["nastran"]["grid_frames"]``: a rectangular CD's axes, or a cylindrical /
spherical CD's local axes at the GRID), mapped to basic by d_basic = R_cd^T d_cd.
"""

import csv
import re
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np

from bayesupdate.errors import BayesUpdateError

_UFF = re.compile(r"^(\d+)([LHV])$")
_AXIS = re.compile(r"^(\d+)([+-]?)([XYZ])$")
_LETTER = {"L": 0, "H": 1, "V": 2, "X": 0, "Y": 1, "Z": 2}
_FRAMES = ("basic", "output")
#: how to give test points, for the error when a deck has none
HOW = (
    "give the study's [model.test_points] table or --test-points FILE "
    '(CSV rows "point,grid" or TOML "12" = 1012 / set = 5)'
)


def parse_test_label(label: str) -> tuple[int, np.ndarray]:
    """(test node, unit direction (3,)) of a DOF label; a one-line error otherwise."""
    text = str(label).strip().upper()
    m = _UFF.match(text) or _AXIS.match(text)
    if not m:
        raise BayesUpdateError(
            f"test DOF {label!r}: give <node><L|H|V> or <node><+|-><X|Y|Z>, e.g. '12V' or '12+Z'"
        )
    direction = np.zeros(3)
    sign = -1.0 if len(m.groups()) == 3 and m.group(2) == "-" else 1.0
    direction[_LETTER[m.groups()[-1]]] = sign
    return int(m.group(1)), direction


def read_test_points(path) -> dict:
    """The test-point table of a ``--test-points`` file: CSV rows ``point,grid[,frame]`` (a
    header line and ``#`` comments allowed) or TOML (the table above, at the top level or under
    ``[test_points]``)."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise BayesUpdateError(f"--test-points {path}: cannot read ({exc.strerror})") from exc
    except UnicodeDecodeError as exc:
        raise BayesUpdateError(
            f"--test-points {path}: not a text file ({exc.reason}); give CSV rows point,grid"
        ) from None
    if path.suffix.lower() == ".toml":
        try:
            doc = tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise BayesUpdateError(f"--test-points {path}: not valid TOML ({exc})") from exc
        return dict(doc.get("test_points", doc))
    table, line_of = {}, {}
    for number, row in enumerate(csv.reader(text.splitlines()), start=1):
        cells = [c.strip() for c in row]
        if not cells or not cells[0] or cells[0].startswith("#"):
            continue
        if not (len(cells) in (2, 3) and cells[0].isdigit() and cells[1].isdigit()):
            if number == 1 and not cells[0].isdigit():
                continue  # a header line
            raise BayesUpdateError(
                f"--test-points {path}:{number}: give 'point,grid' or 'point,grid,frame' "
                f"(integers; frame basic|output), got {','.join(row)!r}"
            )
        if cells[0] in table:  # a typo would silently move the point to the later row's GRID
            raise BayesUpdateError(
                f"--test-points {path}:{number}: point {cells[0]} is given twice (line "
                f"{line_of[cells[0]]} too); give each test point one row"
            )
        grid = int(cells[1])
        table[cells[0]] = grid if len(cells) == 2 else {"grid": grid, "frame": cells[2]}
        line_of[cells[0]] = number
    if not table:
        raise BayesUpdateError(f"--test-points {path}: no test points in it")
    return table


def _grid_and_frame(point, entry, default: str) -> tuple[int | None, str]:
    """(GRID id or None, frame) of a table entry (an int, or {grid, frame})."""
    where = f"model.test_points: {point} = {entry!r}"
    if isinstance(entry, dict):
        unknown = set(entry) - {"grid", "frame"}
        if unknown or "grid" not in entry:
            raise BayesUpdateError(f"{where}: give {{ grid = <GRID id>, frame = 'output' }}")
        grid, frame = entry["grid"], entry.get("frame", default)
    else:
        grid, frame = entry, default
    if grid is not None and (isinstance(grid, bool) or not isinstance(grid, int)):
        raise BayesUpdateError(f"{where}: give a GRID id (an integer)")
    if frame not in _FRAMES:
        raise BayesUpdateError(f"{where}: frame must be 'basic' or 'output' (the GRID's CD)")
    return grid, frame


def _checked_table(table, structure) -> tuple[dict, str]:
    """({test node: entry}, default frame) with ``set = n`` expanded to its GRIDs."""
    table = {str(k).strip(): v for k, v in (table or {}).items()}
    default = table.pop("frame", "basic")
    if default not in _FRAMES:
        raise BayesUpdateError(f"model.test_points: frame = {default!r}: give 'basic' or 'output'")
    if "set" in table:
        sid = table.pop("set")
        sets = structure.metadata["nastran"].get("grid_sets", {})
        if isinstance(sid, bool) or not isinstance(sid, int) or sid not in sets:
            raise BayesUpdateError(
                f"model.test_points: set = {sid!r}: the deck has no SET1 or case control SET "
                f"{sid} (it has {sorted(sets) or 'none'})"
            )
        table = {**{str(g): g for g in sets[sid]}, **table}
    bad = [k for k in table if not k.isdigit()]
    if bad:
        raise BayesUpdateError(
            f"model.test_points: key {bad[0]!r}: give test node numbers, 'set' or 'frame'"
        )
    return table, default


def table_points(structure, table) -> list[int]:
    """The test node numbers a test-point table names, ascending (``simulate``'s points)."""
    return sorted(int(k) for k in _checked_table(table, structure)[0])


def with_test_points(structure, labels, table=None, deck="deck"):
    """``structure`` with one sensor per test DOF label (its GRID's structure node, direction in
    basic).  table : the test-point table (module docstring)."""
    table, default = _checked_table(table, structure)
    meta = structure.metadata["nastran"]
    grid_of_node = np.asarray(meta["grid_ids"])
    frames = meta.get("grid_frames")
    node_of_grid = {int(g): i for i, g in enumerate(grid_of_node)}
    nodes, directions = [], []
    for label in labels:
        point, direction = parse_test_label(label)
        mapped, frame = _grid_and_frame(point, table.get(str(point)), default)
        grid = int(mapped) if mapped is not None else point
        if grid not in node_of_grid:
            how = "mapped by model.test_points" if mapped is not None else "no [model.test_points]"
            raise BayesUpdateError(
                f"test DOF {label!r}: {deck} has no GRID {grid} in its elements ({how}); "
                f'map it in [model.test_points], e.g. "{point}" = <GRID id>'
            )
        node = node_of_grid[grid]
        nodes.append(node)
        # rows of the frame are the CD axes in basic: d_basic = R^T d_cd
        directions.append(direction @ frames[node] if frame == "output" else direction)
    return replace(
        structure,
        sensor_labels=tuple(str(x) for x in labels),
        sensor_node=np.array(nodes, dtype=int),
        sensor_direction=np.array(directions, dtype=float).reshape(-1, 3),
    )
