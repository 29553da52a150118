"""Modal strain and kinetic energy per element and per part (seed section 3.2, eq. 3 integrated
over each element): where each mode works the structure.

For a mass-normalised mode phi with eigenvalue lambda, the strain energy of element e is
U_e = 1/2 phi_e^T K_e phi_e and the kinetic energy amplitude is T_e = 1/2 lambda phi_e^T M_e phi_e;
sum_e U_e = lambda / 2 = sum_e T_e, so shares are fractions of lambda / 2.
"""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ModalEnergies:
    """Energy shares of each mode.

    strain_by_part, kinetic_by_part : (n_parts, m) fractions of the mode's total (columns sum to 1).
    strain_by_element : (n_beams, m) fractions carried by each beam element.
    parts : part names (row labels).
    """

    strain_by_part: np.ndarray
    kinetic_by_part: np.ndarray
    strain_by_element: np.ndarray
    parts: tuple[str, ...]


def _quadratic_forms(mats, dofs, shapes):
    """phi_e^T A_e phi_e for stacks A (n_e, k, k) with DOF maps (n_e, k); returns (n_e, m)."""
    if mats.shape[0] == 0:
        return np.zeros((0, shapes.shape[1]))
    local = shapes[dofs]  # (n_e, k, m)
    return np.einsum("ekm,ekl,elm->em", local, mats, local, optimize=True)


def modal_energies(assembler, element_matrices: dict, shapes: np.ndarray) -> ModalEnergies:
    """Energy shares of modes ``shapes`` (n_dof, m).

    ``element_matrices`` is the dict returned by ``Assembler.assemble``.
    """
    s = assembler.structure
    n_parts = len(s.parts)
    m = shapes.shape[1]
    ub = 0.5 * _quadratic_forms(element_matrices["beam_K"], assembler.beam_dofs, shapes)
    us = 0.5 * _quadratic_forms(element_matrices["spring_K"], assembler.spring_dofs, shapes)
    tb = 0.5 * _quadratic_forms(element_matrices["beam_M"], assembler.beam_dofs, shapes)
    tm = 0.5 * _quadratic_forms(element_matrices["mass_M"], assembler.mass_dofs, shapes)
    strain = np.zeros((n_parts, m))
    kinetic = np.zeros((n_parts, m))
    np.add.at(strain, s.beam_part, ub)
    np.add.at(strain, s.spring_part, us)
    np.add.at(kinetic, s.beam_part, tb)
    np.add.at(kinetic, s.mass_part, tm)
    total_u = np.maximum(strain.sum(axis=0), 1e-300)
    total_t = np.maximum(kinetic.sum(axis=0), 1e-300)
    return ModalEnergies(
        strain_by_part=strain / total_u,
        kinetic_by_part=kinetic / total_t,
        strain_by_element=ub / total_u,
        parts=s.parts,
    )
