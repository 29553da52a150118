"""Changing a few line elements (general beams, rods) and point masses of an assembled general
structure at new property values, without rebuilding the structure.

A deck parameter bound to a beam section or material field (Nastran PBEAM/PBAR A, I1, I2, J,
NSM, MAT1 E, G, RHO) changes only the elements that use it, and it enters their matrices
non-affinely where shear is flexible (the Timoshenko parameter 12 EI / (k G A L^2)).  The exact
way is to recompute those elements at the new values; ``LineUpdate`` does it in the vectorized
kernels (``general_beam.general_beam_matrices``, ``rod.rod_matrices``, the point-mass rigid link
M = T^T D T of ``assembly.Assembler.mass_matrices``) and scatters the change into the general
pattern at positions found once:

    K(theta) = K(deck) + sum_e P_e^T (K_e(theta) - K_e(deck)) P_e,   M likewise,

P_e the element's place in the CSR data of ``assembly.GeneralAssembler`` (``delta`` returns
the
(nnz,) data of the sum).  The elements' new values are whole ``GeneralBeams`` / ``Rods`` records
of the chosen elements (``beams`` / ``rods`` hold the deck's; ``dataclasses.replace`` the fields
that change), so any field of them can follow a parameter, the mapping from card fields to these
records staying with the reader (e.g. PBEAM I1 -> ``iz``; a PBEAM's A also moves the shear areas,
which are factors on A; the torsional inertia per length ``torsion_inertia`` is stored as a number,
rho (iy + iz) by default when built, so a caller changing iy, iz or rho sets it too).  Lumped line
mass carried by point masses (Nastran COUPMASS < 1) is changed through ``masses``: new mass [kg]
and inertia (3, 3) [kg m^2] of chosen point masses.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.assembly import _block_keys
from bayesupdate.fe.elements.general_beam import _subset, general_beam_matrices
from bayesupdate.fe.elements.rod import Rods, rod_matrices


@dataclass(frozen=True)
class PointMassValues:
    """New values of chosen point masses: mass (n,) [kg], inertia (n, 3, 3) [kg m^2] about
    their own centre (global axes); offsets and nodes stay the structure's."""

    mass: np.ndarray
    inertia: np.ndarray


class LineUpdate:
    """(dK, dM) on a general assembler's pattern from new values of chosen elements.

    g : ``assembly.GeneralAssembler``; beams, rods, masses : indices (into the structure's
    ``general_beams``, ``rods`` and point masses) of the elements that may change."""

    def __init__(self, g, beams=(), rods=(), masses=()):
        s = self.structure = g.structure
        self.nnz = g.nnz
        self.beam_index = np.asarray(beams, dtype=int)
        self.rod_index = np.asarray(rods, dtype=int)
        self.mass_index = np.asarray(masses, dtype=int)
        keys = g.rows.astype(np.int64) * g.n_dof + g.cols
        self.beams = self.rods = None
        if self.beam_index.size:
            if s.general_beams is None:
                raise BayesUpdateError("LineUpdate: the structure has no general beams")
            self.beams = _subset(s.general_beams, self.beam_index)
            self._pos_beam = _positions(keys, g.n_dof, self.beams.dofs())
        if self.rod_index.size:
            if s.rods is None:
                raise BayesUpdateError("LineUpdate: the structure has no rods")
            r = s.rods
            self.rods = Rods(**{k: getattr(r, k)[self.rod_index] for k in r.__dataclass_fields__})
            self._pos_rod = _positions(keys, g.n_dof, self.rods.dofs())
        if self.mass_index.size:
            masses = g.beams.parametric["mass"]
            self._pos_mass = _positions(keys, g.n_dof, masses.dofs()[self.mass_index])
            self._mass_T = masses.link[self.mass_index]
        #: (K, M) (nnz,) of the chosen elements at the structure's values
        self.base = self._data(self.beams, self.rods, self.masses())

    def masses(self) -> PointMassValues:
        """The chosen point masses' values in the structure."""
        s = self.structure
        return PointMassValues(
            s.mass_value[self.mass_index].copy(), s.mass_inertia[self.mass_index].copy()
        )

    def contribution(self, beams=None, rods=None, masses=None) -> tuple[np.ndarray, np.ndarray]:
        """(K, M) (nnz,) CSR data of the chosen elements alone: ``beams`` (``GeneralBeams`` of
        the chosen beams, in ``beam_index`` order), ``rods`` (``Rods``), ``masses``
        (``PointMassValues``) at their new values; None keeps the structure's."""
        if beams is None and rods is None and masses is None:
            return self.base[0].copy(), self.base[1].copy()
        return self._data(
            self.beams if beams is None else beams,
            self.rods if rods is None else rods,
            self.masses() if masses is None else masses,
        )

    def delta(self, beams=None, rods=None, masses=None) -> tuple[np.ndarray, np.ndarray]:
        """(dK, dM) (nnz,) CSR data of the change from the structure's values to ``beams``,
        ``rods``, ``masses`` (as ``contribution``)."""
        K, M = self.contribution(beams, rods, masses)
        return K - self.base[0], M - self.base[1]

    def _data(self, beams, rods, masses) -> tuple[np.ndarray, np.ndarray]:
        s, n = self.structure, self.nnz
        K, M = np.zeros(n), np.zeros(n)
        if self.beams is not None:
            Kb, Mb = general_beam_matrices(s.nodes, beams, s.shear, s.rotary_inertia)
            K += np.bincount(self._pos_beam, Kb.ravel(), n)
            M += np.bincount(self._pos_beam, Mb.ravel(), n)
        if self.rods is not None:
            Kr, Mr = rod_matrices(s.nodes, rods)
            K += np.bincount(self._pos_rod, Kr.ravel(), n)
            M += np.bincount(self._pos_rod, Mr.ravel(), n)
        if self.mass_index.size:
            D = np.zeros((self.mass_index.size, 6, 6))
            D[:, :3, :3] = masses.mass[:, None, None] * np.eye(3)
            D[:, 3:, 3:] = masses.inertia
            T = self._mass_T
            Mm = np.einsum("pji,pjk,pkl->pil", T, D, T)
            M += np.bincount(self._pos_mass, Mm.ravel(), n)
        return K, M


def _positions(keys: np.ndarray, n_dof: int, dofs: np.ndarray) -> np.ndarray:
    """(n_e * d * d,) positions in the sorted pattern ``keys`` (row * n_dof + col) of every
    entry of element matrices with DOF maps dofs (n_e, d), row-major."""
    want = _block_keys(dofs, n_dof)
    pos = np.searchsorted(keys, want)
    if np.any(pos >= keys.size) or np.any(keys[np.minimum(pos, keys.size - 1)] != want):
        raise BayesUpdateError("LineUpdate: an element lies outside the assembled pattern")
    return pos
