"""The two interfaces of an element family and the registries that assembly, energies, the
total mass and the reduced basis loop over.

An element family is a frozen dataclass of element arrays, one row per element, with its global
DOF map and its element matrices vectorized over elements.  Two kinds:

* ``ParametricFamily`` (registry ``PARAMETRIC``, ``register_parametric``): its properties are
  design parameters (tube beams, point masses, springs).  Its element matrices are taken at an
  ``fe.assembly.ElementProperties`` record, of which it reads the arrays named in ``fields``;
  ``linear`` names the matrices that are linear in its factors (point masses: "M", springs:
  "K", solids: "KM", E in K and rho in M, each property's ``enters`` saying which), or "" when
  the matrices must be recomputed (tube beams: wall thickness and bend factor).
  It declares the properties a parameter may bind (``properties``: ``Bindable`` records, the
  property name of ``fe.model.Binding``, the field it sets and how it enters K and M), its
  fields' nominal values (``nominal``) and their physical limits (``check``):
  ``fe.model`` binds, validates and splits parameters from these declarations alone.
* ``ElementFamily`` (registry ``FAMILIES``, ``register``): no design parameter acts on it
  (general beams, rods, scalar masses, a user's family); its (K, M) are computed once.

A registered family is then, with no other edit:

* assembled into K and M on both solution paths (``fe.assembly.Assembler``: its blocks join the
  sparse pattern, its (K, M) are scattered into every assembly);
* counted in the modal strain and kinetic energies per part (``fe.energy``):
  U_e = 1/2 phi_e^T K_e phi_e, T_e = 1/2 lambda phi_e^T M_e phi_e (seed eq. 3 over the element);
* counted in the total mass and centre of gravity (a parametric family's ``masses``; for the
  others ``rigid_mass``: the rigid-body functional of its M, exact for any mass matrix);
* taken into the reduced basis's affine split (``fe.reduced.affine``): an ``ElementFamily``
  into the constant term (K(theta) = K_e, M(theta) = M_e for every theta), a linear parametric
  family as one term per parameter acting on it, the tube beams' groups interpolated.

Shells (``elements.shell``, ``shell_tria``) are assembled by ``fe.assembly.Assembler`` apart, in
parameter groups whose K and M are exact powers of the thickness (``fe.shell_model``).

A structure holds the parametric families' arrays in its ``beam_*``, ``mass_*`` and
``spring_*`` columns (each class's ``of(structure)`` gathers them), the other registered
families' instances in its named fields (``general_beams``, ``rods``, ``scalar_masses``) or,
for any other registered family, in ``Structure.elements``.  Units: SI in, SI out; K [N/m,
N m/rad], M [kg, kg m^2]; DOF numbers 6 * node + (ux, uy, uz, rx, ry, rz).
"""

from collections.abc import Callable
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


@dataclass(frozen=True)
class Bindable:
    """A property of a ``ParametricFamily`` that a parameter binds (``fe.model.Binding``): the
    family's own declaration, so that ``fe.model`` names no family.

    name : the property name a ``Binding`` gives (``thickness``, ``mass``, ...).
    field : the ``fe.assembly.ElementProperties`` array (one of the family's ``fields``) it sets.
    enters : "K" or "M" when that matrix is exactly linear in the value, "nonlinear" when the
        element matrices must be recomputed (``fe.reduced.affine`` interpolates them).
    rule : how the value v sets the field f on the bound elements: "value" (f = v), "factor"
        (f = nominal f x v) or "total" (f = v / the bound elements' sum of ``total_of``: v is the
        bound elements' total, each scaled alike).
    total_of : for "total", the family's (n,) attribute whose sum the value is (point masses:
        ``mass`` [kg]).
    positive : True when the value must be > 0, False when >= 0 (a factor may switch off).
    select : (structure, target) -> (n,) bool, the elements a target name binds, raising
        ``BayesUpdateError`` for an unknown one; None: the elements of the part named target.
    unit, acts_on : the value's unit and what it acts on (the property table of ``fe.model``).
    """

    name: str
    field: str
    enters: str
    rule: str = "value"
    total_of: str = ""
    positive: bool = True
    select: Callable[[Any, str], np.ndarray] | None = None
    unit: str = "-"
    acts_on: str = ""

    def __post_init__(self):
        if self.enters not in ("K", "M", "nonlinear") or self.rule not in RULES:
            raise BayesUpdateError(
                f"bindable property {self.name}: enters must be K, M or nonlinear and rule one "
                f"of {RULES}, got {self.enters!r}, {self.rule!r}"
            )

    def set(self, field: np.ndarray, mask: np.ndarray, value: float, nominal, family) -> None:
        """Write ``value`` into the (n,) ``field`` where ``mask`` (in place) by ``rule``;
        ``nominal`` (n,) is the field's nominal value, ``family`` the family instance."""
        if self.rule == "value":
            field[mask] = value
        elif self.rule == "factor":
            field[mask] = nominal[mask] * value
        else:
            field[mask] = value / getattr(family, self.total_of)[mask].sum()

    def scale(self, mask: np.ndarray, family) -> float:
        """Factor on the value in the parameter's linear term (``fe.model.ParameterTerm``):
        1 / the bound elements' total for "total", else 1."""
        if self.rule == "total":
            return 1.0 / getattr(family, self.total_of)[mask].sum()
        return 1.0

    def set_unit(self, field: np.ndarray, mask: np.ndarray, nominal) -> None:
        """Write the unit value of a linear term into ``field`` where ``mask`` (in place): 1
        ("value": 1 kg/m^3, 1 Pa), the nominal ("factor" 1) or 1 ("total": the elements as
        they are, the value's 1 / total going into ``scale``)."""
        field[mask] = nominal[mask] * 1.0 if self.rule == "factor" else 1.0


#: how a ``Bindable`` value sets its field
RULES = ("value", "factor", "total")


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


class ParametricFamily(Protocol):
    """One element family whose properties are design parameters (tube beams, point masses,
    springs): its element matrices at an ``fe.assembly.ElementProperties`` record, of which it
    reads the (n,) arrays named in ``fields``.

    family : the registry name (``fe.model.ParameterTerm.family``); linear : the matrices ("K",
    "M" or "KM") that are linear in its fields (factors on the elements; each property's
    ``enters`` names its matrix), or "" when the matrices
    must be recomputed (``fe.reduced.affine`` interpolates them); properties : the ``Bindable``
    properties a parameter may bind on it.
    """

    family: ClassVar[str]
    fields: ClassVar[tuple[str, ...]]
    linear: ClassVar[str]
    properties: ClassVar[tuple[Bindable, ...]]
    nodes: np.ndarray
    part: np.ndarray

    def nominal(self) -> dict[str, np.ndarray]:
        """{field: (n,) array}: each of ``fields`` at the structure's own values (new arrays)."""
        ...

    def check(self, props: Any, parts: tuple[str, ...]) -> None:
        """Raise ``BayesUpdateError`` naming the part (``parts``: the structure's part names)
        when a field of ``props`` is non-physical (``check_fields``)."""
        ...

    @property
    def n_elements(self) -> int:
        """Number of elements n."""
        ...

    def dofs(self) -> np.ndarray:
        """(n, d) global DOF numbers of each element's matrix rows."""
        ...

    def matrices(
        self, props: Any, settings: ElementSettings, elements: np.ndarray | None = None
    ) -> tuple[np.ndarray | None, np.ndarray | None]:
        """Global-axis (K, M), each (n_e, d, d) or None (the family adds nothing to that
        matrix), of ``elements`` (index array, default all) at ``props``."""
        ...

    def masses(self, props: Any, xyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n,) element masses [kg] and (n, 3) their centres [m] at ``props`` on nodes xyz
        (N, 3) [m] (the total mass and centre of gravity)."""
        ...

    @classmethod
    def of(cls, structure: Any) -> "ParametricFamily":
        """The structure's elements of this family (possibly none)."""
        ...


#: family name -> class, in registration order (the order of assembly)
FAMILIES: dict[str, type] = {}
#: the parametric families (``ParametricFamily``), in the order of assembly
PARAMETRIC: dict[str, type] = {}


def register_parametric(cls: type) -> type:
    """Register a ``ParametricFamily`` class (a class decorator); returns the class.  Its
    ``properties`` become bindable (``fe.model.Binding``); a property name another registered
    family declares, or a field not among its ``fields``, is refused."""
    if not isinstance(getattr(cls, "family", None), str):
        raise BayesUpdateError(f"{cls.__name__}: an element family needs a class name `family`")
    taken = {n: f for n, (f, _) in bindable().items() if f != cls.family}
    for p in cls.properties:
        if p.name in taken or p.field not in cls.fields:
            raise BayesUpdateError(
                f"{cls.__name__}: property {p.name!r} is already bound by family "
                f"{taken.get(p.name)!r} or its field {p.field!r} is not in `fields`"
            )
    PARAMETRIC[cls.family] = cls
    return cls


def bindable() -> dict[str, tuple[str, Bindable]]:
    """{property name: (family name, ``Bindable``)} of the registered parametric families, in
    the order of registration (read each call: a family registered later is in it)."""
    return {p.name: (name, p) for name, cls in PARAMETRIC.items() for p in cls.properties}


def register(cls: type) -> type:
    """Register an element family class (a class decorator); returns the class."""
    if not isinstance(getattr(cls, "family", None), str):
        raise BayesUpdateError(f"{cls.__name__}: an element family needs a class name `family`")
    FAMILIES[cls.family] = cls
    return cls


def parametric_of(structure: Any) -> tuple:
    """The structure's parametric families (``PARAMETRIC`` order), one instance per registered
    class, empty ones included (a parameter's element indices refer to them); a family held in
    ``Structure.elements`` (``in_elements``) is left out when the structure has none."""
    found = (cls.of(structure) for cls in PARAMETRIC.values())
    return tuple(f for f in found if f is not None)


def check_fields(checks, part: np.ndarray, parts: tuple[str, ...]) -> None:
    """Raise ``BayesUpdateError`` naming the part of the first non-physical value.

    checks : (label, values (n,), elements (n,) int or None: all, strictly) tuples: the values
    must be finite and > 0 (strictly) or >= 0; part (n_family,) the family's part indices."""
    for label, values, elements, strictly in checks:
        bad = ~np.isfinite(values) | ((values <= 0) if strictly else (values < 0))
        if np.any(bad):
            i = np.flatnonzero(bad)[0]
            e = i if elements is None else elements[i]
            limit = "> 0" if strictly else ">= 0"
            raise BayesUpdateError(
                f"part {parts[part[e]]!r}: {label} must be finite and {limit}, got {values[i]}"
            )


def in_elements(cls: type, structure: Any):
    """The instance of ``cls`` in ``structure.elements`` (None: none): the ``of`` of a registered
    family that has no field of its own on ``Structure``."""
    return next((e for e in structure.elements if isinstance(e, cls)), None)


def families_of(structure: Any) -> tuple:
    """The registered ``ElementFamily`` instances present in ``structure`` (registration
    order); raises when ``structure.elements`` holds an instance of an unregistered class."""
    for e in structure.elements:
        name = getattr(e, "family", None)
        if type(e) not in (FAMILIES.get(name), PARAMETRIC.get(name)):
            raise BayesUpdateError(
                f"element family {type(e).__name__} is not registered; decorate its class with "
                "bayesupdate.fe.elements.base.register (or register_parametric)"
            )
    found = (cls.of(structure) for cls in FAMILIES.values())
    return tuple(f for f in found if f is not None and f.n_elements)


def held_families(structure: Any) -> tuple:
    """The family instances a structure holds outside its beam, point-mass and spring columns:
    the registered ``ElementFamily`` ones (``families_of``) and the parametric ones kept in
    ``Structure.elements`` (solids), each with elements (for the connectivity and mass checks,
    which read the columns themselves)."""
    parametric = (e for e in structure.elements if type(e) is PARAMETRIC.get(e.family))
    return (*families_of(structure), *(e for e in parametric if e.n_elements))


@dataclass(frozen=True)
class FamilyMatrices:
    """One family's element matrices at its properties: dofs (n, d), K, M (n, d, d) (None: the
    family adds nothing to that matrix), part (n,)."""

    family: str
    dofs: np.ndarray
    K: np.ndarray
    M: np.ndarray
    part: np.ndarray

    @classmethod
    def of(cls, family: ElementFamily, xyz: np.ndarray, settings: ElementSettings):
        K, M = family.matrices(xyz, settings)
        return cls(family.family, family.dofs(), K, M, family.part)


class LineElements:
    """The shared part of the two-node line families (general beams, rods): n_elements, their
    12 DOFs and ``has_mass`` from ``mass_per_length`` (n,) [kg/m], which each family defines
    (a general beam whose mass kind is "none" carries none)."""

    nodes: np.ndarray

    @property
    def n_elements(self) -> int:
        """Number of elements n."""
        return int(self.nodes.shape[0])

    def dofs(self) -> np.ndarray:
        """(n, 12) global DOF numbers, end a then end b."""
        return line_dofs(self.nodes)

    def has_mass(self) -> bool:
        """True if some element carries mass of its own."""
        return bool(np.any(self.mass_per_length() > 1e-200))

    def mass_per_length(self) -> np.ndarray:
        """(n,) mass per unit length [kg/m] (each line family's own)."""
        raise NotImplementedError


def line_dofs(nodes: np.ndarray) -> np.ndarray:
    """(n, 12) global DOF numbers of two-node elements with end nodes ``nodes`` (n, 2)."""
    return (6 * nodes[:, :, None] + np.arange(6)).reshape(-1, 12)


def grounded_line_dofs(nodes: np.ndarray) -> np.ndarray:
    """(n, 12) global DOF numbers of two-node elements whose second node may be ground (-1):
    a grounded element repeats node A there (its B block is zero)."""
    return line_dofs(np.where(nodes >= 0, nodes, nodes[:, :1]))


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
