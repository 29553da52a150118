"""Finite-element layer: build a 3D structure (beams, shells, point masses, springs, supports,
rigid elements), assemble K(theta), M(theta), solve its modes.  Knows nothing of tests or
statistics.  ``StructureBuilder.add_shells`` / ``add_support`` / ``add_rbe2`` / ``add_rbe3``
make a structure that ``FEModel`` solves on the sparse path (``fe.assembly``).

Public names: ``StructureBuilder``, ``Structure``, ``Material``, ``STEEL``, sections
(``circular_tube``, ``oval_tube``, ``solid_round``), ``FEModel``, ``Binding``, ``FEResult``,
``ModalSolution``, ``ModalEnergies``.
"""

from bayesupdate.fe.eigensolve import ModalSolution, solve_modes
from bayesupdate.fe.energy import ModalEnergies
from bayesupdate.fe.model import Binding, FEModel, FEResult
from bayesupdate.fe.sections import Section, circular_tube, oval_tube, solid_round
from bayesupdate.fe.structure import STEEL, Material, Structure, StructureBuilder

__all__ = [
    "STEEL",
    "Binding",
    "FEModel",
    "FEResult",
    "Material",
    "ModalEnergies",
    "ModalSolution",
    "Section",
    "Structure",
    "StructureBuilder",
    "circular_tube",
    "oval_tube",
    "solid_round",
    "solve_modes",
]
