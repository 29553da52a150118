"""Finite-element layer: build a 3D frame structure, assemble K(theta), M(theta), solve the
free-free modes.  Knows nothing of tests or statistics.

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
