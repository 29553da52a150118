"""Modal strain and kinetic energy per element and per part (seed section 3.2, eq. 3 integrated
over each element): where each mode works the structure.

For a mass-normalised mode phi with eigenvalue lambda, the strain energy of element e is
U_e = 1/2 phi_e^T K_e phi_e and the kinetic energy amplitude is T_e = 1/2 lambda phi_e^T M_e phi_e;
sum_e U_e = lambda / 2 = sum_e T_e, so shares are fractions of lambda / 2.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.fe.elements.base import quadratic_forms


@dataclass(frozen=True)
class ModalEnergies:
    """Energy shares of each mode.

    strain_by_part, kinetic_by_part : (n_parts, m) fractions of the mode's total (columns sum to 1).
    strain_by_element : (n_beams, m) fractions carried by each beam element.
    parts : part names (row labels).
    Structures with shells (``general_energies``): shell_strain, shell_kinetic (n_shell, m)
    fractions carried by each shell element (quads first); shell_strain_density,
    shell_kinetic_density (n_shell, m) those fractions per element area [1/m^2] (times the
    mode's energy lambda / 2 they give J/m^2: the strain-energy density maps of the seed).
    """

    strain_by_part: np.ndarray
    kinetic_by_part: np.ndarray
    strain_by_element: np.ndarray
    parts: tuple[str, ...]
    shell_strain: np.ndarray | None = None
    shell_kinetic: np.ndarray | None = None
    shell_strain_density: np.ndarray | None = None
    shell_kinetic_density: np.ndarray | None = None


def _family_energies(strain, kinetic, assembler, shapes) -> None:
    """Add the registered element families' strain and kinetic energies (``fe.elements.base``:
    general beams, rods, scalar masses, ...) to ``strain``, ``kinetic`` (n_parts, m) by part,
    in place."""
    for f in assembler.families:
        np.add.at(strain, f.part, 0.5 * quadratic_forms(f.K, f.dofs, shapes))
        np.add.at(kinetic, f.part, 0.5 * quadratic_forms(f.M, f.dofs, shapes))


def modal_energies(assembler, element_matrices: dict, shapes: np.ndarray) -> ModalEnergies:
    """Energy shares of modes ``shapes`` (n_dof, m).

    ``element_matrices`` is the dict returned by ``Assembler.assemble``.
    """
    s = assembler.structure
    n_parts = len(s.parts)
    m = shapes.shape[1]
    ub = 0.5 * quadratic_forms(element_matrices["beam_K"], assembler.beam_dofs, shapes)
    us = 0.5 * quadratic_forms(element_matrices["spring_K"], assembler.spring_dofs, shapes)
    tb = 0.5 * quadratic_forms(element_matrices["beam_M"], assembler.beam_dofs, shapes)
    tm = 0.5 * quadratic_forms(element_matrices["mass_M"], assembler.mass_dofs, shapes)
    strain = np.zeros((n_parts, m))
    kinetic = np.zeros((n_parts, m))
    np.add.at(strain, s.beam_part, ub)
    np.add.at(strain, s.spring_part, us)
    np.add.at(kinetic, s.beam_part, tb)
    np.add.at(kinetic, s.mass_part, tm)
    _family_energies(strain, kinetic, assembler, shapes)
    total_u = np.maximum(strain.sum(axis=0), 1e-300)
    total_t = np.maximum(kinetic.sum(axis=0), 1e-300)
    return ModalEnergies(
        strain_by_part=strain / total_u,
        kinetic_by_part=kinetic / total_t,
        strain_by_element=ub / total_u,
        parts=s.parts,
    )


def general_energies(g, element_matrices: dict, shell_props, modes) -> ModalEnergies:
    """Energy shares of a general structure's modes (``fe.sparse_assembly.GeneralAssembler`` ``g``):
    beams, springs, point masses and the registered element families as ``modal_energies``, plus
    every shell element (direct
    element matrices at ``shell_props`` = (t, E, rho)).  The shapes are full-DOF (dependent DOFs
    of rigid elements included), so the element energies sum to the mode's lambda / 2."""
    s = g.structure
    shapes = modes.shapes
    m = shapes.shape[1]
    quad = quadratic_forms
    b = g.beams
    strain = np.zeros((len(s.parts), m))
    kinetic = np.zeros((len(s.parts), m))
    ub = 0.5 * quad(element_matrices["beam_K"], b.beam_dofs, shapes)
    np.add.at(strain, s.beam_part, ub)
    np.add.at(
        strain, s.spring_part, 0.5 * quad(element_matrices["spring_K"], b.spring_dofs, shapes)
    )
    np.add.at(kinetic, s.beam_part, 0.5 * quad(element_matrices["beam_M"], b.beam_dofs, shapes))
    np.add.at(kinetic, s.mass_part, 0.5 * quad(element_matrices["mass_M"], b.mass_dofs, shapes))
    _family_energies(strain, kinetic, b, shapes)
    fields = {}
    if s.shells is not None:
        n_sh = s.shells.n_elements
        us, ts, area = np.zeros((n_sh, m)), np.zeros((n_sh, m)), np.zeros(n_sh)
        for (idx, dofs, K, M), (*_, frames, _p) in zip(
            g.shell_element_matrices(*shell_props), g.shells.families, strict=True
        ):
            us[idx] = 0.5 * quad(K, dofs, shapes)
            ts[idx] = 0.5 * quad(M, dofs, shapes)
            area[idx] = frames.area
        np.add.at(strain, s.shells.part, us)
        np.add.at(kinetic, s.shells.part, ts)
        fields = dict(shell_strain=us, shell_kinetic=ts)
    total_u = np.maximum(strain.sum(axis=0), 1e-300)
    total_t = np.maximum(kinetic.sum(axis=0), 1e-300)
    if fields:
        fields = dict(
            shell_strain=fields["shell_strain"] / total_u,
            shell_kinetic=fields["shell_kinetic"] / total_t,
            shell_strain_density=fields["shell_strain"] / total_u / area[:, None],
            shell_kinetic_density=fields["shell_kinetic"] / total_t / area[:, None],
        )
    return ModalEnergies(
        strain_by_part=strain / total_u,
        kinetic_by_part=kinetic / total_t,
        strain_by_element=ub / total_u,
        parts=s.parts,
        **fields,
    )
