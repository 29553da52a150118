"""Test DOFs in any direction: a node and a unit vector in the test's global frame.

A test DOF label names a node and a direction:

- ``"7V"``, ``"7H"``, ``"7L"``: UFF direction codes +3, +2, +1 (the labels ``ema.uff_io``
  reads UFF 55/58 records into);
- ``"7+Z"``, ``"7-Y"``, ``"7X"``: codes +-3, +-2, +1;
- ``"7+3"``, ``"7-1"``: the UFF 55/58 direction code itself, +-1..+-3;
- a label a CSV geometry declares with a direction vector of its own (``DeclaredDof``).

A code refers to the node's displacement frame (UFF 15/2411 field 3, ``frames``); a declared
vector too.  The result is ``TestDof(label, node, direction)`` with direction (3,) a unit vector
in the test's global frame.
"""

import re
from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.testgeom.geometry import TestGeometry

_LETTER = re.compile(r"^(\d+)([LHV])$")
_AXIS = re.compile(r"^(\d+)([+-]?)([XYZ])$")
_CODE = re.compile(r"^(\d+)([+-])(\d+)$")
_CODE_OF = {"L": 1, "H": 2, "V": 3, "X": 1, "Y": 2, "Z": 3}


@dataclass(frozen=True)
class TestDof:
    """``label`` (as the test data name it), test ``node`` id, ``direction`` (3,) unit vector
    in the test's global frame."""

    __test__ = False  # not a pytest class

    label: str
    node: int
    direction: np.ndarray


def direction_code(label: str) -> tuple[int, int]:
    """(node, signed UFF direction code) of a label; one-line errors for a code outside
    +-1..+-3 or a label of no known form."""
    text = str(label).strip().upper()
    if m := _LETTER.match(text):
        return int(m.group(1)), _CODE_OF[m.group(2)]
    if m := _AXIS.match(text):
        return int(m.group(1)), (-1 if m.group(2) == "-" else 1) * _CODE_OF[m.group(3)]
    if m := _CODE.match(text):
        code = int(m.group(3))
        if not 1 <= code <= 3:
            raise BayesUpdateError(
                f"test DOF {label!r}: direction code {m.group(2)}{code} is outside +-1..+-3 "
                "(translations; rotations 4-6 are not measured test DOFs)"
            )
        return int(m.group(1)), (-1 if m.group(2) == "-" else 1) * code
    raise BayesUpdateError(
        f"test DOF {label!r}: give <node><L|H|V>, <node><+|-><X|Y|Z> or <node><+|-><1|2|3> "
        "(UFF direction code), or declare it in the CSV geometry with a direction vector"
    )


def unit_vector(vector, what: str) -> np.ndarray:
    """``vector`` (3,) normalized; a one-line error for a zero or non-finite vector."""
    v = np.asarray(vector, dtype=float).reshape(3)
    norm = float(np.linalg.norm(v))
    if not (np.isfinite(norm) and norm > 1e-12):
        raise BayesUpdateError(f"{what}: direction vector {v.tolist()} is zero; give its axis")
    return v / norm


def resolve_dofs(geometry: TestGeometry, labels) -> tuple[TestDof, ...]:
    """The ``TestDof`` of every label (module docstring), in order; a label whose node the
    geometry lacks is a one-line error naming the node and the file."""
    declared = {d.label.upper(): d for d in geometry.declared}
    out = []
    for label in labels:
        what = f"test DOF {label!r}"
        entry = declared.get(str(label).strip().upper())
        if entry is not None:
            row = geometry.index(entry.node, what)
            local = unit_vector(entry.vector, what)
            node = entry.node
        else:
            node, code = direction_code(label)
            row = geometry.index(node, what)
            local = np.zeros(3)
            local[abs(code) - 1] = np.sign(code)
        direction = local @ geometry.axes(row)
        out.append(TestDof(str(label), int(node), direction / np.linalg.norm(direction)))
    return tuple(out)
