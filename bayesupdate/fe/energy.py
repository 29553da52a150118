"""Modal strain and kinetic energy per element and per part (seed section 3.2, eq. 3 integrated
over each element): where each mode works the structure.

For a mass-normalized mode phi with eigenvalue lambda, the strain energy of element e is
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


def _family_energies(strain, kinetic, elements, shapes) -> dict:
    """Add every family's strain and kinetic energies (``elements``: the ``FamilyMatrices`` of
    ``Assembler.assemble``) to ``strain``, ``kinetic`` (n_parts, m) by part, in place; returns
    {family: (n_e, m) element strain energies}."""
    by_element = {}
    for f in elements:
        if f.K is not None:
            u = by_element[f.family] = 0.5 * quadratic_forms(f.K, f.dofs, shapes)
            np.add.at(strain, f.part, u)
        if f.M is not None:
            np.add.at(kinetic, f.part, 0.5 * quadratic_forms(f.M, f.dofs, shapes))
    return by_element


def modal_energies(assembler, elements: tuple, shapes: np.ndarray) -> ModalEnergies:
    """Energy shares of modes ``shapes`` (n_dof, m).

    ``elements`` is the tuple of ``FamilyMatrices`` returned by ``Assembler.assemble``.
    """
    s = assembler.structure
    strain = np.zeros((len(s.parts), shapes.shape[1]))
    kinetic = np.zeros_like(strain)
    ub = _family_energies(strain, kinetic, elements, shapes)["beam"]  # the tube beams
    total_u = np.maximum(strain.sum(axis=0), 1e-300)
    total_t = np.maximum(kinetic.sum(axis=0), 1e-300)
    return ModalEnergies(
        strain_by_part=strain / total_u,
        kinetic_by_part=kinetic / total_t,
        strain_by_element=ub / total_u,
        parts=s.parts,
    )


def general_energies(g, elements: tuple, shell_props, modes) -> ModalEnergies:
    """Energy shares of a general structure's modes (``fe.assembly.GeneralAssembler`` ``g``):
    every element family as ``modal_energies``, plus every shell element (direct element
    matrices at ``shell_props`` = (t, E, rho)).  The shapes are full-DOF (dependent DOFs of
    rigid elements included), so the element energies sum to the mode's lambda / 2."""
    s = g.structure
    shapes = modes.shapes
    m = shapes.shape[1]
    quad = quadratic_forms
    strain = np.zeros((len(s.parts), m))
    kinetic = np.zeros((len(s.parts), m))
    ub = _family_energies(strain, kinetic, elements, shapes)["beam"]  # the tube beams
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
