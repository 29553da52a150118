"""Test DOF labels on a Nastran deck: ``"12V"`` / ``"12+Z"`` -> GRID 12, direction +z (basic).

A label is ``<node><L|H|V>`` (UFF: L = x, H = y, V = z) or ``<node><+|-><X|Y|Z>`` (sign
optional).  The node is the deck's GRID id unless the study's ``[model.test_points]`` table
maps it (``"12" = 1012``: test node 12 is GRID 1012).  Directions are in the deck's basic frame.
"""

import re
from dataclasses import replace

import numpy as np

from bayesupdate.errors import BayesUpdateError

_UFF = re.compile(r"^(\d+)([LHV])$")
_AXIS = re.compile(r"^(\d+)([+-]?)([XYZ])$")
_LETTER = {"L": 0, "H": 1, "V": 2, "X": 0, "Y": 1, "Z": 2}


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


def with_test_points(structure, labels, table=None, deck="deck"):
    """``structure`` with one sensor per test DOF label (its GRID's structure node, direction).

    table : {test node (str or int): GRID id}, the study's ``[model.test_points]``."""
    table = {str(k).strip(): v for k, v in (table or {}).items()}
    grid_of_node = np.asarray(structure.metadata["nastran"]["grid_ids"])
    node_of_grid = {int(g): i for i, g in enumerate(grid_of_node)}
    nodes, directions = [], []
    for label in labels:
        point, direction = parse_test_label(label)
        mapped = table.get(str(point))
        if mapped is not None and not (isinstance(mapped, int) and not isinstance(mapped, bool)):
            raise BayesUpdateError(
                f"model.test_points: {point} = {mapped!r}: give a GRID id (an integer)"
            )
        grid = int(mapped) if mapped is not None else point
        if grid not in node_of_grid:
            how = "mapped by model.test_points" if mapped is not None else "no [model.test_points]"
            raise BayesUpdateError(
                f"test DOF {label!r}: {deck} has no GRID {grid} in its elements ({how}); "
                f'map it in [model.test_points], e.g. "{point}" = <GRID id>'
            )
        nodes.append(node_of_grid[grid])
        directions.append(direction)
    return replace(
        structure,
        sensor_labels=tuple(str(x) for x in labels),
        sensor_node=np.array(nodes, dtype=int),
        sensor_direction=np.array(directions, dtype=float).reshape(-1, 3),
    )
