"""The model's geometry as the pairing sees it: nodes, line elements and shell faces.

``model_mesh(structure)`` reads a ``fe.Structure`` (duck-typed: its node coordinates, beams,
general beams, rods and shells) in the model's own length unit: a Nastran deck's (its
``metadata["nastran"]["units"]``), metres for the built-in models.  Node labels are the deck's
GRID ids, or the structure's node numbers.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.testgeom.units import METRES_PER, length_unit


@dataclass(frozen=True)
class ModelMesh:
    """nodes (N, 3) [model unit]; node_ids (N,) labels; lines (L, 2), quads (Q, 4), trias
    (T, 3) node rows; unit: the model's length unit; metres: metres per model unit."""

    nodes: np.ndarray
    node_ids: np.ndarray
    lines: np.ndarray
    quads: np.ndarray
    trias: np.ndarray
    unit: str
    metres: float

    def row_of(self, label: int, what: str) -> int:
        """Node row of model node ``label``; a one-line error naming ``what`` if absent."""
        hits = np.flatnonzero(self.node_ids == int(label))
        if hits.size == 0:
            raise BayesUpdateError(f"{what}: the model has no node {label}; name one of its nodes")
        return int(hits[0])


def model_unit(structure, given: str | None) -> str:
    """The model's length unit: ``given`` (the study's ``[test] model_length_unit``), else a
    Nastran deck's recognized unit, else metres (a built-in model); a deck whose units are not
    recognized needs ``given``."""
    if given is not None:
        return length_unit(given, "test.model_length_unit")
    nastran = structure.metadata.get("nastran")
    if nastran is None:
        return "m"
    unit = str(nastran.get("units", {}).get("length", ""))
    if unit not in METRES_PER:
        raise BayesUpdateError(
            f"model {nastran.get('deck', '')}: its length unit is not recognized; give "
            "[test] model_length_unit = 'mm' (m, mm, cm, in, ft)"
        )
    return unit


def model_mesh(structure, unit: str | None = None) -> ModelMesh:
    """``ModelMesh`` of a ``fe.Structure`` (module docstring)."""
    unit = model_unit(structure, unit)
    nastran = structure.metadata.get("nastran") or {}
    ids = np.asarray(nastran.get("grid_ids", np.arange(structure.n_nodes)), dtype=np.int64)
    lines = [np.asarray(structure.beam_nodes, int).reshape(-1, 2)]
    for family in (structure.general_beams, structure.rods):
        if family is not None:
            lines.append(np.asarray(family.nodes, int).reshape(-1, 2))
    shells = structure.shells
    quads = np.zeros((0, 4), int) if shells is None else np.asarray(shells.quads, int)
    trias = np.zeros((0, 3), int) if shells is None else np.asarray(shells.trias, int)
    return ModelMesh(np.asarray(structure.nodes, float), ids, np.concatenate(lines), quads,
                     trias, unit, METRES_PER[unit])  # fmt: skip
