"""``FEModel``: a structure with named parameters bound to part properties - the
``ParametricModel`` that inference calibrates (see ``bayesupdate.model_protocol``).

A ``Binding(target, property)`` ties a parameter to every element of a part (or bend) that has the
property.  Each parametric element family declares the properties it binds in its own file
(``elements.base.Bindable``: name, field, how it enters K and M); the built-in ones are:

====================  ===========================================  ======  =========================
property              acts on                                      unit    enters K / M
====================  ===========================================  ======  =========================
thickness             wall of the part's beams                     m       non-linear (re-assembled)
density               the part's beams                             kg/m^3  M linear
youngs_modulus        the part's beams                             Pa      K linear
modulus_factor        factor on the nominal E of the part's beams  -       K linear
mass                  total of the part's point masses (scaled)    kg      M linear
mass_factor           factor on the part's point masses            -       M linear
stiffness_factor      factor on the part's springs                 -       K linear
bend_factor           extra factor dividing EI of a named bend     -       K non-linear
solid_modulus_factor  factor on the E of the part's solids         -       K linear
solid_density_factor  factor on the density of the part's solids   -       M linear
hexa_modulus_factor   factor on the E of the part's bricks         -       K linear
hexa_density_factor   factor on the density of the part's bricks   -       M linear
====================  ===========================================  ======  =========================

On a part with shells, thickness, density, youngs_modulus and modulus_factor act on its shells as
well (shell K and M are exact sums of powers of the thickness, ``fe.assembly``).  A
structure with
shells, supports or rigid elements is solved on the sparse path (``fe.assembly``: constraints
eliminated exactly, shift-invert Lanczos, rigid-body modes the supports allow removed exactly);
a beam structure without them keeps the banded Krylov path (``method="sparse"`` forces the
sparse one).
"""

import dataclasses
from collections.abc import Iterator, Mapping
from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.assembly import Assembler, ElementProperties
from bayesupdate.fe.eigensolve import BandedShiftInvert, ModalSolution, solve_modes
from bayesupdate.fe.elements import parametric_of
from bayesupdate.fe.elements.base import bindable
from bayesupdate.fe.energy import ModalEnergies, general_energies, modal_energies
from bayesupdate.fe.general_plan import GeneralPlan
from bayesupdate.fe.rotations import rigid_body_basis
from bayesupdate.fe.sparse_modal import ModalSettings
from bayesupdate.fe.structure import Structure
from bayesupdate.model_protocol import Prediction

#: the properties that also act on a part's shells (shells are assembled apart, in groups whose
#: K and M are exact powers of the thickness: ``fe.assembly``)
SHELL_PROPERTIES = ("thickness", "density", "youngs_modulus", "modulus_factor")


def bindable_properties() -> tuple[str, ...]:
    """Every property a ``Binding`` may name: the registered parametric families' declarations
    (``elements.base.bindable``) and the shells'."""
    return tuple(dict.fromkeys((*bindable(), *SHELL_PROPERTIES)))


class _PropertyTerms(Mapping):
    """{property: (family, field, enters)} read from the registered families' declarations
    each time (a family registered later is in it): the family a property acts on, the
    ``ElementProperties`` array it sets, and "K" / "M" when that matrix is exactly linear in the
    value or "nonlinear" when the element matrices must be re-computed."""

    def __getitem__(self, name: str) -> tuple[str, str, str]:
        family, p = bindable()[name]
        return family, p.field, p.enters

    def __iter__(self) -> Iterator[str]:
        return iter(bindable())

    def __len__(self) -> int:
        return len(bindable())


#: how each property enters K and M (the module table), a view of the families' declarations
PROPERTY_TERMS = _PropertyTerms()


def _set_material(prop, value, mask, arrays, base_modulus) -> None:
    """Write a thickness / density / modulus binding into (t, rho, E) where ``mask`` (in place);
    ``modulus_factor`` scales ``base_modulus``.  Other properties are left alone."""
    t, rho, E = arrays
    if prop == "thickness":
        t[mask] = value
    elif prop == "density":
        rho[mask] = value
    elif prop == "youngs_modulus":
        E[mask] = value
    elif prop == "modulus_factor":
        E[mask] = base_modulus[mask] * value


@dataclass(frozen=True)
class Binding:
    """Parameter -> (part or bend name, property); see the module table."""

    target: str
    property: str


@dataclass(frozen=True)
class ParameterTerm:
    """Where one parameter acts and how it enters K and M (``FEModel.affine_terms``).

    name, property : the parameter and its bound property (module table).
    family : the parametric family (``elements.base.PARAMETRIC``: "beam", "mass", "spring", ...)
        that declares the property, whose elements ``elements`` indexes.
    elements : (n,) int, the family's elements it acts on (structure order).
    field : the ``ElementProperties`` array its value sets.
    enters : "K" or "M" when that matrix is exactly linear in the value: the parameter's term is
        value x ``scale`` x the element matrices assembled from ``AffineTerms.unit``;
        "nonlinear" (thickness, bend_factor) when the element matrices must be re-computed.
    scale : factor on the value in a linear term (``Bindable.scale``): 1 / (nominal total of the
        part's point masses) [1/kg] for "mass" (the value is the part's total mass), else 1.  On
        shells the element value is ``scale`` x the value for every property (a deck's factor,
        ``NastranModel``).
    shells : (n,) int, the shells (``Structure.shells`` order) it acts on (empty: none).  Shell K
        and M are exact polynomials in it: thickness t enters K as t, t^2, t^3 and M as t, t^2,
        t^3 (``shell.power_matrices``), density M and modulus K linearly.
    """

    name: str
    property: str
    family: str
    elements: np.ndarray
    field: str
    enters: str
    scale: float
    shells: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, dtype=int))


@dataclass(frozen=True)
class AffineTerms:
    """K(theta), M(theta) of the parametric families (beams, point masses, springs, ...) split
    by parameter.

    parameters : one ``ParameterTerm`` per parameter, in ``parameter_names`` order, then a term
        per further family a parameter sets too (``FEModel._companions``: a deck material over
        several element families), which names its parameter (``ParameterTerm.name``).
    defaults : element properties at the default parameters (SI): elements that no parameter
        acts on keep these values for every theta.
    unit : ``defaults`` with every linearly entering parameter at its unit value where it acts
        (``Bindable.set_unit``: density 1 kg/m^3, Young's modulus 1 Pa, modulus factor 1 i.e.
        the nominal E, point-mass and spring factors 1), the non-linear ones (thickness, bend
        factor) at their defaults.  A linear parameter's element matrices assembled from
        ``unit`` times value x ``scale`` are its exact contribution to K or M.
    Shells are not covered (their thickness terms are ``fe.assembly``'s): the reduced model,
    which builds on this, applies to beam structures only (``FEModel.assembler``).
    """

    parameters: tuple[ParameterTerm, ...]
    defaults: ElementProperties
    unit: ElementProperties


@dataclass(frozen=True)
class FEResult:
    """A full FE modal analysis at one parameter point."""

    parameters: dict
    modes: ModalSolution
    mass_kg: float
    centre_of_gravity: np.ndarray
    energies: ModalEnergies | None
    sensor_shapes: np.ndarray  # (n_sensors, m) shapes at the sensor DOFs [m / sqrt(kg)]
    sensor_labels: tuple[str, ...]

    @property
    def frequencies_hz(self) -> np.ndarray:
        return self.modes.frequencies_hz


class FEModel:
    """Parametric FE model: ``predict`` / ``solve`` at a parameter mapping (SI values).

    structure : the ``Structure``; bindings : name -> Binding; defaults : name -> reference value;
    bounds : name -> (low, high).  Unbound names are rejected with the list of known ones.
    """

    #: solver of the general path below ``ModalSettings.dense_below`` DOFs
    #: (``ModalSettings.small_method``; ``NastranModel`` uses the banded block Krylov)
    small_method = "dense"

    def __init__(
        self,
        structure: Structure,
        bindings: Mapping[str, Binding],
        defaults: Mapping[str, float],
        bounds: Mapping[str, tuple[float, float]],
        name: str = "fe_model",
    ):
        self.structure = structure
        self.name = name
        self.bindings = dict(bindings)
        self.parameter_names = tuple(self.bindings)
        missing = [p for p in self.parameter_names if p not in defaults or p not in bounds]
        if missing:
            raise BayesUpdateError(f"model {name}: parameters {missing} need a default and bounds")
        self._defaults = {k: float(defaults[k]) for k in self.parameter_names}
        self._bounds = {k: (float(bounds[k][0]), float(bounds[k][1])) for k in self.parameter_names}
        self._shell_masks = {}
        # the parametric families' instances: the elements a binding selects, a total's sum
        self._parametric = {f.family: f for f in parametric_of(structure)}
        self._masks = {p: self._mask(p, b) for p, b in self.bindings.items()}
        # the further families one parameter sets with the same value (``_companions``)
        self._companion_masks = {p: self._companions(p, b) for p, b in self.bindings.items()}
        a = self._assembler = Assembler(structure, self._shell_keys())
        # a structure with shells, supports or rigid elements is solved on the sparse path
        self._general = a if structure.is_general else None
        if self._general is None:
            self.banded = BandedShiftInvert(a.n_dof, a.rows, a.cols, a.indptr)
        self.rigid_basis = rigid_body_basis(structure.nodes)
        self._rigid_mass_terms = None  # ``mass_properties_function``: built on first use
        self._base = a.default_properties()
        dofs, directions = structure.sensor_dofs()
        self._sensor_dofs = dofs
        self._sensor_dir = directions

    # -- parameters --------------------------------------------------------------------------
    def _mask(self, name, binding: Binding):
        """(n,) bool: the elements of the bound property's family that ``binding`` acts on (its
        ``Bindable.select``, or the target part's); a shell property also keeps the part's
        shells in ``_shell_masks``."""
        s = self.structure
        if binding.property not in bindable_properties():
            raise BayesUpdateError(
                f"parameter {name}: unknown property {binding.property!r}; use one of "
                f"{bindable_properties()}"
            )
        family, prop = bindable().get(binding.property, (None, None))
        if prop is not None and prop.select is not None:
            try:
                return prop.select(s, binding.target)
            except BayesUpdateError as exc:
                raise BayesUpdateError(f"parameter {name}: {exc}") from None
        part = s.part_index(binding.target)
        elements = self._parametric.get(family)  # None: the structure has none of the family
        mask = elements.part == part if elements is not None else np.zeros(0, bool)
        if s.shells is not None and binding.property in SHELL_PROPERTIES:
            self._shell_masks[name] = s.shells.part == part
        if not np.any(mask) and not np.any(self._shell_masks.get(name, False)):
            raise BayesUpdateError(
                f"parameter {name}: part {binding.target!r} has nothing with a {binding.property}"
            )
        return mask

    def _companions(self, name, binding) -> tuple:
        """((property, mask, factor), ...): further parametric families that parameter ``name``
        sets too, each to ``factor`` x its value (one deck material over several element
        families: ``nastran.model``); none for a plain ``Binding``."""
        return ()

    def shells_of(self, name: str) -> np.ndarray:
        """(n_shell,) bool: the shells parameter ``name`` acts on (all False when it binds no
        shell property or the structure has no shells)."""
        n = 0 if self.structure.shells is None else self.structure.shells.n_elements
        return self._shell_masks.get(name, np.zeros(n, bool))

    def _shell_keys(self) -> np.ndarray | None:
        """(n_shell, 3) index of the parameter setting each shell's thickness, modulus and
        density (-1: none; the last binding wins, as in ``element_properties``)."""
        if self.structure.shells is None:
            return None
        keys = -np.ones((self.structure.shells.n_elements, 3))
        column = dict(thickness=0, youngs_modulus=1, modulus_factor=1, density=2)
        for j, (name, mask) in enumerate(self._shell_masks.items()):
            keys[mask, column[self.bindings[name].property]] = j
        return keys

    @property
    def assembler(self) -> Assembler:
        """The ``Assembler`` of a beam structure on the banded path (refused on the sparse path,
        whose matrices ``matrices`` gives)."""
        if self._general is not None:
            raise BayesUpdateError(
                f"model {self.name}: the structure has shells, supports or rigid elements; the "
                "beam-only assembler does not apply (use FEModel.matrices)"
            )
        return self._assembler

    @property
    def beam_assembler(self) -> Assembler:
        """The ``Assembler``, on both paths (the name from when the element families had an
        assembler of their own beside the shells')."""
        return self._assembler

    @property
    def general(self) -> Assembler | None:
        """The ``Assembler`` of a structure on the sparse path (shells, supports or rigid
        elements, or a beam structure once solved with ``method="sparse"``); None on the
        banded beam path."""
        return self._general

    def matrices(self, params: Mapping[str, float] | None = None):
        """Full (K, M) CSR (n_dof, n_dof) [N/m, kg] at ``params``: every element, before the
        supports and rigid elements are applied (``general.transform`` does that)."""
        p = self.full_parameters(params)
        props = self.element_properties(p)
        if self._general is None:
            return self._assembler.assemble(props)[:2]
        shell_props = self.shell_properties(p) if self.structure.shells is not None else None
        return self._general.assemble(props, shell_props)[:2]

    def rigid_motions(self) -> np.ndarray:
        """(n_dof, r) rigid-body motions the supports and rigid elements allow (full DOFs): the
        six of ``rigid_basis`` for a free beam structure."""
        if self._general is None:
            return self.rigid_basis
        g = self._general
        return np.asarray(g.transform.expand(g.rigid))

    def total_mass(self, params: Mapping[str, float] | None = None) -> tuple[float, np.ndarray]:
        """Total mass [kg] and centre of gravity (3,) [m] at ``params``."""
        if self._general is None:
            return self._assembler.total_mass(self.element_properties(params))
        return self._general.matrix_mass(self.matrices(params)[1])

    def mass_properties(self, params: Mapping[str, float] | None = None):
        """Rigid-body mass properties (``fe.mass_properties.MassProperties``: mass, centre of
        gravity, inertia about it) at ``params``, from the assembled mass matrix."""
        from bayesupdate.fe.mass_properties import model_mass_properties

        return model_mass_properties(self, params)

    def mass_properties_function(self):
        """params -> ``mass_properties(params)``: a 6 x 6 sum where the mass matrix is affine in
        each parameter and additive over them or bilinear in pairs of them (a density times a
        section field: ``fe.mass_properties.rigid_mass_terms``, checked once, then kept), else
        the assembly of ``mass_properties``."""
        terms = self._rigid_mass_terms
        if terms is None:
            from bayesupdate.fe.mass_properties import rigid_mass_terms

            terms = self._rigid_mass_terms = rigid_mass_terms(self) or False
        return terms or self.mass_properties

    def default_parameters(self) -> dict[str, float]:
        return dict(self._defaults)

    def affine_terms(self) -> AffineTerms:
        """The parameter-separable form of K(theta), M(theta) (``AffineTerms``): for each
        parameter the elements it acts on and whether it enters K or M linearly."""
        terms, masks = [], []
        for name, binding in self.bindings.items():
            family, prop = bindable()[binding.property]
            mask = self._masks[name]
            shells = np.flatnonzero(self._shell_masks.get(name, np.zeros(0, bool)))
            scale = prop.scale(mask, self._parametric[family])
            terms.append(ParameterTerm(name, binding.property, family, np.flatnonzero(mask),
                                       prop.field, prop.enters, scale, shells))  # fmt: skip
            masks.append(mask)
        # a parameter's further families follow, after one term per parameter in their order
        for name, companions in self._companion_masks.items():
            for prop_name, mask, factor in companions:
                family, prop = bindable()[prop_name]
                scale = prop.scale(mask, self._parametric[family]) * factor
                terms.append(ParameterTerm(name, prop_name, family, np.flatnonzero(mask),
                                           prop.field, prop.enters, scale))  # fmt: skip
                masks.append(mask)
        defaults = self.element_properties(self._defaults)
        fields = {k: v.copy() for k, v in defaults.values.items()}
        for term, mask in zip(terms, masks, strict=True):
            if term.enters != "nonlinear":
                prop = bindable()[term.property][1]
                prop.set_unit(fields[term.field], mask, self._base.values[term.field])
        return AffineTerms(tuple(terms), defaults, ElementProperties(fields))

    def default_bounds(self) -> dict[str, tuple[float, float]]:
        return dict(self._bounds)

    def full_parameters(self, params: Mapping[str, float] | None) -> dict[str, float]:
        """Defaults overridden by ``params``; unknown names are an error."""
        out = dict(self._defaults)
        for k, v in (params or {}).items():
            if k not in self.bindings:
                raise BayesUpdateError(
                    f"unknown parameter {k!r} for model {self.name}; "
                    f"parameters are {list(self.parameter_names)}"
                )
            out[k] = float(v)
        return out

    def element_properties(self, params: Mapping[str, float] | None = None) -> ElementProperties:
        """Per-element property arrays at ``params`` (vectorized masks, no element loop)."""
        p = self.full_parameters(params)
        nominal = self._base.values
        fields = {k: v.copy() for k, v in nominal.items()}
        known = bindable()
        for name, binding in self.bindings.items():
            value, prop = p[name], binding.property
            family, spec = known.get(prop, (None, None))
            strictly = spec is None or spec.positive
            if not np.isfinite(value) or value <= 0 and strictly:
                raise BayesUpdateError(f"parameter {name} = {value}: {prop} must be finite and > 0")
            if not np.isfinite(value) or value < 0:
                raise BayesUpdateError(f"parameter {name} = {value}: {prop} must be >= 0")
            if spec is not None:
                f = spec.field
                spec.set(fields[f], self._masks[name], value, nominal[f], self._parametric[family])
            for prop_name, mask, factor in self._companion_masks[name]:
                family, spec = known[prop_name]
                f = spec.field
                spec.set(fields[f], mask, value * factor, nominal[f], self._parametric[family])
        return ElementProperties(fields)

    def shell_properties(self, params: Mapping[str, float] | None = None):
        """Per-shell (thickness [m], E [Pa], rho [kg/m^3]) arrays (n_shell,) at ``params``; a
        bound thickness is the parameter times the shells' ``thickness_factor``."""
        p = self.full_parameters(params)
        sh = self.structure.shells
        t, E, rho = sh.thickness.copy(), sh.E.copy(), sh.rho.copy()
        for name, mask in self._shell_masks.items():
            _set_material(self.bindings[name].property, p[name], mask, (t, rho, E), sh.E)
            if self.bindings[name].property == "thickness":
                t[mask] *= sh.factor()[mask]
        return t, E, rho

    # -- analysis ----------------------------------------------------------------------------
    def solve(
        self,
        params: Mapping[str, float] | None = None,
        n_modes: int = 12,
        energies: bool = False,
        method: str = "krylov",
    ) -> FEResult:
        """Full modal analysis: first ``n_modes`` elastic modes, mass, CoG, optional energies.

        method : "krylov" (banded, beam structures), "dense" (LAPACK, checks) or "sparse"
        (``fe.assembly``; the only path for shells, supports and rigid elements)."""
        p = self.full_parameters(params)
        props = self.element_properties(p)
        if self._general is not None or method == "sparse":
            return self._solve_general(p, props, n_modes, energies, method)
        K, M, elem = self.assembler.assemble(props)
        modes = solve_modes(
            K,
            M,
            n_modes,
            self.rigid_basis,
            self.banded,
            method=method,
        )
        mass, cog = self.assembler.total_mass(props)
        en = modal_energies(self.assembler, elem, modes.shapes) if energies else None
        return FEResult(
            p, modes, mass, cog, en, self.sensor_shapes(modes.shapes), self.structure.sensor_labels
        )

    def _solve_general(self, p, props, n_modes, energies, method) -> FEResult:
        if self._general is None:  # a beam structure on the sparse path: the same assembler
            self._general = self._assembler
        g = self._general
        shell_props = self.shell_properties(p) if self.structure.shells is not None else None
        K, M, elem = g.assemble(props, shell_props)
        # a structure may ask for MSC's SUPORT convention (metadata "rigid_set": the Nastran
        # reader sets it for a deck with SUPORT; ``fe.sparse_modal.ModalSettings``)
        settings = ModalSettings(
            rigid_set=self.structure.metadata.get("rigid_set", "zero_energy"),
            small_method=self.small_method,
        )
        modes = self._general_modes(g, K, M, n_modes, method, settings)
        mass, cog = g.matrix_mass(M)
        en = general_energies(g, elem, shell_props, modes) if energies else None
        return FEResult(
            p, modes, mass, cog, en, self.sensor_shapes(modes.shapes), self.structure.sensor_labels
        )

    def _general_modes(self, g, K, M, n_modes, method, settings) -> ModalSolution:
        """The general path's modes: for a small model solved by the banded block Krylov
        (``small_method`` "krylov") through ``general_plan.GeneralPlan`` (its reduction and
        band layout found once per assembler), else ``Assembler.solve``."""
        small = g.transform.independent.size < settings.dense_below
        if method == "dense" or self.small_method != "krylov" or not small:
            return g.solve(K, M, n_modes, dense=method == "dense", settings=settings)
        plan = self.__dict__.get("_plan")
        if plan is None or plan.assembler is not g:
            plan = self._plan = GeneralPlan(g)
        return plan.solve(K, M, n_modes, settings)

    def sensor_shapes(self, shapes: np.ndarray) -> np.ndarray:
        """Shapes (n_dof, m) read out at the sensors: (n_sensors, m) translations along each
        sensor's direction."""
        return np.einsum("sk,skm->sm", self._sensor_dir, shapes[self._sensor_dofs])

    def predict(self, params: Mapping[str, float] | None = None, n_modes: int = 12) -> Prediction:
        r = self.solve(params, n_modes)
        return Prediction(r.frequencies_hz, r.sensor_shapes, r.sensor_labels, r.mass_kg)

    def predict_frequencies_batch(
        self, theta: np.ndarray, names: tuple[str, ...], n_modes: int = 12
    ) -> np.ndarray:
        """(n_points, n_modes) frequencies [Hz] for theta (n_points, len(names)); failed points
        (non-physical values) give NaN rows."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        out = np.full((theta.shape[0], n_modes), np.nan)
        for i, row in enumerate(theta):
            try:
                out[i] = self.solve(dict(zip(names, row, strict=True)), n_modes).frequencies_hz
            except BayesUpdateError:
                pass
        return out

    def with_structure(
        self,
        structure: Structure,
        bindings: Mapping[str, Binding] | None = None,
        defaults=None,
        bounds=None,
        name: str | None = None,
    ) -> "FEModel":
        """A new model on a modified structure (e.g. with an added effect), same parameters plus
        any extra ``bindings``/``defaults``/``bounds``."""
        b = dict(self.bindings, **(bindings or {}))
        d = dict(self._defaults, **(defaults or {}))
        bo = dict(self._bounds, **(bounds or {}))
        return FEModel(structure, b, d, bo, name=name or self.name)
