"""The interface of an element family and the registry that assembly, energies, the total mass
and the reduced basis loop over.

An element family (``ElementFamily``) is a frozen dataclass of element arrays, one row per
element, with its global DOF map and its element matrices at its own properties, vectorised over
elements.  A registered family (``register``) is then, with no other edit:

* assembled into K and M on both solution paths (``fe.assembly.Assembler``: its blocks join the
  sparse pattern, its (K, M) are scattered once and added to every assembly);
* counted in the modal strain and kinetic energies per part (``fe.energy``):
  U_e = 1/2 phi_e^T K_e phi_e, T_e = 1/2 lambda phi_e^T M_e phi_e (seed eq. 3 over the element);
* counted in the total mass and centre of gravity (``rigid_mass``: the rigid-body functional of
  its M, exact for any mass matrix);
* taken into the constant term of the reduced basis's affine split (``fe.reduced.affine``):
  no design parameter acts on a registered family, so its affine split in the design parameters
  is K(theta) = K_e, M(theta) = M_e for every theta.

The families whose properties are design parameters (tube beams, point masses, springs and
shells: ``fe.model.PROPERTY_TERMS``) keep their element maths in their own files of this package
but are bound, assembled and split by ``FEModel``, ``Assembler`` and ``fe.reduced`` by name
(their affine split needs the parameter bindings).

A structure holds the registered families' instances in its named fields (``general_beams``,
``rods``, ``scalar_masses``) or, for any other registered family, in ``Structure.elements``;
each class's ``of(structure)`` finds its instance.  Units: SI in, SI out; K [N/m, N m/rad], M
[kg, kg m^2]; DOF numbers 6 * node + (ux, uy, uz, rx, ry, rz).
"""

from dataclasses import dataclass
from typing import Any, ClassVar, Protocol

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.rotations import rigid_body_basis


@dataclass(frozen=True)
class ElementSettings:
    """What a structure decides for all its elements: ``shear`` (shear deformation of beams),
    ``rotary_inertia`` (rotary inertia of bending)."""

    shear: bool = True
    rotary_inertia: bool = True


class ElementFamily(Protocol):
    """One element family without design parameters (module docstring).

    family : the registry name; nodes : (n, k) node indices of each element (-1: ground);
    part : (n,) part indices (``Structure.parts``).
    """

    family: ClassVar[str]
    nodes: np.ndarray
    part: np.ndarray

    @property
    def n_elements(self) -> int:
        """Number of elements n."""
        ...

    def dofs(self) -> np.ndarray:
        """(n, d) global DOF numbers of each element's matrix rows (a grounded end may repeat a
        node whose block of the matrices is zero)."""
        ...

    def matrices(self, xyz: np.ndarray, settings: ElementSettings) -> tuple[np.ndarray, np.ndarray]:
        """Global-axis (K, M), each (n, d, d), on nodes xyz (N, 3) [m]."""
        ...

    def has_mass(self) -> bool:
        """True if some element carries mass."""
        ...

    @classmethod
    def of(cls, structure: Any) -> "ElementFamily | None":
        """The structure's elements of this family (None: none)."""
        ...


#: family name -> class, in registration order (the order of assembly)
FAMILIES: dict[str, type] = {}


def register(cls: type) -> type:
    """Register an element family class (a class decorator); returns the class."""
    if not isinstance(getattr(cls, "family", None), str):
        raise BayesUpdateError(f"{cls.__name__}: an element family needs a class name `family`")
    FAMILIES[cls.family] = cls
    return cls


def in_elements(cls: type, structure: Any):
    """The instance of ``cls`` in ``structure.elements`` (None: none): the ``of`` of a registered
    family that has no field of its own on ``Structure``."""
    return next((e for e in structure.elements if isinstance(e, cls)), None)


def families_of(structure: Any) -> tuple:
    """The registered families' instances present in ``structure`` (registration order);
    raises when ``structure.elements`` holds an instance of an unregistered class."""
    for e in structure.elements:
        if FAMILIES.get(getattr(e, "family", None)) is not type(e):
            raise BayesUpdateError(
                f"element family {type(e).__name__} is not registered; decorate its class with "
                "bayesupdate.fe.elements.base.register"
            )
    found = (cls.of(structure) for cls in FAMILIES.values())
    return tuple(f for f in found if f is not None and f.n_elements)


@dataclass(frozen=True)
class FamilyMatrices:
    """One family's element matrices at its properties: dofs (n, d), K, M (n, d, d), part (n,)."""

    family: str
    dofs: np.ndarray
    K: np.ndarray
    M: np.ndarray
    part: np.ndarray

    @classmethod
    def of(cls, family: ElementFamily, xyz: np.ndarray, settings: ElementSettings):
        K, M = family.matrices(xyz, settings)
        return cls(family.family, family.dofs(), K, M, family.part)


def line_dofs(nodes: np.ndarray) -> np.ndarray:
    """(n, 12) global DOF numbers of two-node elements with end nodes ``nodes`` (n, 2)."""
    return (6 * nodes[:, :, None] + np.arange(6)).reshape(-1, 12)


def quadratic_forms(mats: np.ndarray, dofs: np.ndarray, shapes: np.ndarray) -> np.ndarray:
    """(n_e, m) phi_e^T A_e phi_e of stacks A (n_e, k, k) with DOF maps (n_e, k) for shapes
    (n_dof, m): twice an element's strain energy (A = K) or its kinetic energy per unit
    eigenvalue (A = M)."""
    if mats.shape[0] == 0:
        return np.zeros((0, shapes.shape[1]))
    local = shapes[dofs]  # (n_e, k, m)
    return np.einsum("ekm,ekl,elm->em", local, mats, local, optimize=True)


def rigid_mass(M: np.ndarray, dofs: np.ndarray, xyz: np.ndarray) -> np.ndarray:
    """(6, 6) sum_e R_e^T M_e R_e: the elements' share of the rigid-body mass matrix about the
    origin (R the 3 translations and 3 rotations of nodes xyz (N, 3) [m]).  Its translational
    block is m I [kg] for a mass that moves with its nodes; the first moments m c are
    (Mr[1, 5], Mr[2, 3], Mr[0, 4]) [kg m]."""
    R = rigid_body_basis(xyz, centre=np.zeros(3))
    Re = R[dofs]  # (n_e, d, 6)
    return np.einsum("eki,ekl,elj->ij", Re, M, Re)
