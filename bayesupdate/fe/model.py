"""``FEModel``: a structure with named parameters bound to part properties - the
``ParametricModel`` that inference calibrates (see ``bayesupdate.model_protocol``).

A ``Binding(target, property)`` ties a parameter to every element of a part (or bend) that has the
property:

=================  ==========================================  ========  =====================
property           acts on                                      unit      enters K / M
=================  ==========================================  ========  =====================
thickness          wall of the part's beams                     m         non-linear (re-assembled)
density            the part's beams                             kg/m^3    M linear
youngs_modulus     the part's beams                             Pa        K linear
modulus_factor     factor on the nominal E of the part's beams  -         K linear
mass               total of the part's point masses (scaled)    kg        M linear
mass_factor        factor on the part's point masses            -         M linear
stiffness_factor   factor on the part's springs                 -         K linear
bend_factor        extra factor dividing EI of a named bend     -         K non-linear
=================  ==========================================  ========  =====================

On a part with shells, thickness, density, youngs_modulus and modulus_factor act on its shells as
well (shell K and M are exact sums of powers of the thickness, ``fe.assembly``).  A
structure with
shells, supports or rigid elements is solved on the sparse path (``fe.assembly``: constraints
eliminated exactly, shift-invert Lanczos, rigid-body modes the supports allow removed exactly);
a beam structure without them keeps the banded Krylov path (``method="sparse"`` forces the
sparse one).
"""

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.assembly import Assembler, ElementProperties, GeneralAssembler
from bayesupdate.fe.eigensolve import BandedShiftInvert, ModalSolution, solve_modes
from bayesupdate.fe.energy import ModalEnergies, general_energies, modal_energies
from bayesupdate.fe.rotations import rigid_body_basis
from bayesupdate.fe.sparse_modal import ModalSettings
from bayesupdate.fe.structure import Structure
from bayesupdate.model_protocol import Prediction

PROPERTIES = (
    "thickness",
    "density",
    "youngs_modulus",
    "modulus_factor",
    "mass",
    "mass_factor",
    "stiffness_factor",
    "bend_factor",
)
#: the properties that also act on a part's shells
SHELL_PROPERTIES = ("thickness", "density", "youngs_modulus", "modulus_factor")


#: bound properties shared by beams and shells (``_set_material``)
MATERIAL_PROPERTIES = ("thickness", "density", "youngs_modulus", "modulus_factor")

#: how each property enters K and M (the module table): (element family it acts on,
#: ``ElementProperties`` array it sets, "K" / "M" when that matrix is exactly linear in the value,
#: "nonlinear" when the element matrices must be re-computed: A, I are polynomials in the wall
#: thickness, the Timoshenko shear parameter is rational and the B31.3 elbow factor has a kink)
PROPERTY_TERMS = MappingProxyType(
    {
        "thickness": ("beam", "beam_thickness", "nonlinear"),
        "density": ("beam", "beam_rho", "M"),
        "youngs_modulus": ("beam", "beam_E", "K"),
        "modulus_factor": ("beam", "beam_E", "K"),
        "mass": ("mass", "mass_scale", "M"),
        "mass_factor": ("mass", "mass_scale", "M"),
        "stiffness_factor": ("spring", "spring_scale", "K"),
        "bend_factor": ("beam", "beam_bend_factor", "nonlinear"),
    }
)


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
    family : "beam", "mass" or "spring": the element family ``elements`` indexes.
    elements : (n,) int, the beams / point masses / springs it acts on (structure order).
    field : the ``ElementProperties`` array its value sets.
    enters : "K" or "M" when that matrix is exactly linear in the value: the parameter's term is
        value x ``scale`` x the element matrices assembled from ``AffineTerms.unit``;
        "nonlinear" (thickness, bend_factor) when the element matrices must be re-computed.
    scale : factor on the value in a linear term: 1 / (nominal total of the part's point masses)
        [1/kg] for "mass" (the value is the part's total mass), else 1.  On shells the element
        value is ``scale`` x the value for every property (a deck's factor, ``NastranModel``).
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
    """K(theta), M(theta) of the beams, point masses and springs split by parameter.

    parameters : one ``ParameterTerm`` per parameter, in ``parameter_names`` order.
    defaults : element properties at the default parameters (SI): elements that no parameter
        acts on keep these values for every theta.
    unit : ``defaults`` with every linearly entering parameter at its unit value where it acts
        (density 1 kg/m^3, Young's modulus 1 Pa, modulus factor 1 i.e. the nominal E) and all
        point-mass and spring scales 1, the non-linear ones (thickness, bend factor) at their
        defaults.  A linear parameter's element matrices assembled from ``unit`` times
        value x ``scale`` are its exact contribution to K or M.
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
        self._masks = {p: self._mask(p, b) for p, b in self.bindings.items()}
        self._general = None
        if structure.is_general:
            self._general = GeneralAssembler(structure, self._shell_keys())
            a = self._assembler = self._general.beams
        else:
            a = self._assembler = Assembler(structure)
            self.banded = BandedShiftInvert(a.n_dof, a.pattern_rows, a.pattern_cols, a.indptr)
        self.rigid_basis = rigid_body_basis(structure.nodes)
        self._rigid_mass_terms = None  # ``mass_properties_function``: built on first use
        self._base = a.default_properties()
        dofs, directions = structure.sensor_dofs()
        self._sensor_dofs = dofs
        self._sensor_dir = directions

    # -- parameters --------------------------------------------------------------------------
    def _mask(self, name, binding: Binding):
        s = self.structure
        if binding.property not in PROPERTIES:
            raise BayesUpdateError(
                f"parameter {name}: unknown property {binding.property!r}; use one of {PROPERTIES}"
            )
        if binding.property == "bend_factor":
            if binding.target not in s.bends:
                raise BayesUpdateError(
                    f"parameter {name}: unknown bend {binding.target!r}; bends are {list(s.bends)}"
                )
            return s.beam_bend == s.bends.index(binding.target)
        part = s.part_index(binding.target)
        if binding.property in ("mass", "mass_factor"):
            mask = s.mass_part == part
        elif binding.property == "stiffness_factor":
            mask = s.spring_part == part
        else:
            mask = s.beam_part == part
            if s.shells is not None and binding.property in SHELL_PROPERTIES:
                self._shell_masks[name] = s.shells.part == part
        if not np.any(mask) and not np.any(self._shell_masks.get(name, False)):
            raise BayesUpdateError(
                f"parameter {name}: part {binding.target!r} has nothing with a {binding.property}"
            )
        return mask

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
        """The beam ``Assembler`` of a beam structure (the banded path)."""
        if self._general is not None:
            raise BayesUpdateError(
                f"model {self.name}: the structure has shells, supports or rigid elements; the "
                "beam-only assembler does not apply (use FEModel.matrices)"
            )
        return self._assembler

    @property
    def beam_assembler(self) -> Assembler:
        """The ``Assembler`` of the structure's tube beams, point masses and springs (on both
        paths; on the general one it is ``general.beams``)."""
        return self._assembler

    @property
    def general(self) -> GeneralAssembler | None:
        """The ``GeneralAssembler`` (shells, general beams, rods, constraints) of a general
        structure; None on the banded beam path."""
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
        return self._general.total_mass(self.matrices(params)[1])

    def mass_properties(self, params: Mapping[str, float] | None = None):
        """Rigid-body mass properties (``fe.mass_properties.MassProperties``: mass, centre of
        gravity, inertia about it) at ``params``, from the assembled mass matrix."""
        from bayesupdate.fe.mass_properties import model_mass_properties

        return model_mass_properties(self, params)

    def mass_properties_function(self):
        """params -> ``mass_properties(params)``: a 6 x 6 affine sum where the mass matrix is
        affine in each parameter and additive over them (``fe.mass_properties.rigid_mass_terms``,
        checked once, then kept), else the assembly of ``mass_properties``."""
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
        s = self.structure
        terms = []
        for name, binding in self.bindings.items():
            family, field, enters = PROPERTY_TERMS[binding.property]
            mask = self._masks[name]
            scale = 1.0 / s.mass_value[mask].sum() if binding.property == "mass" else 1.0
            shells = np.flatnonzero(self._shell_masks.get(name, np.zeros(0, bool)))
            terms.append(
                ParameterTerm(
                    name,
                    binding.property,
                    family,
                    np.flatnonzero(mask),
                    field,
                    enters,
                    scale,
                    shells,
                )
            )
        defaults = self.element_properties(self._defaults)
        t, rho = defaults.beam_thickness.copy(), defaults.beam_rho.copy()
        E = defaults.beam_E.copy()
        for term in terms:
            if term.enters != "nonlinear" and term.property in MATERIAL_PROPERTIES:
                _set_material(
                    term.property, 1.0, self._masks[term.name], (t, rho, E), self._base.beam_E
                )
        unit = ElementProperties(
            t,
            rho,
            E,
            defaults.beam_bend_factor.copy(),
            np.ones_like(defaults.mass_scale),
            np.ones_like(defaults.spring_scale),
        )
        return AffineTerms(tuple(terms), defaults, unit)

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
        """Per-element property arrays at ``params`` (vectorised masks, no element loop)."""
        p = self.full_parameters(params)
        base = self._base
        t, rho, E = base.beam_thickness.copy(), base.beam_rho.copy(), base.beam_E.copy()
        bend = base.beam_bend_factor.copy()
        ms, ss = base.mass_scale.copy(), base.spring_scale.copy()
        s = self.structure
        for name, binding in self.bindings.items():
            value, mask = p[name], self._masks[name]
            prop = binding.property
            if (
                not np.isfinite(value)
                or value <= 0
                and prop not in ("mass", "mass_factor", "stiffness_factor")
            ):
                raise BayesUpdateError(f"parameter {name} = {value}: {prop} must be finite and > 0")
            if not np.isfinite(value) or value < 0:
                raise BayesUpdateError(f"parameter {name} = {value}: {prop} must be >= 0")
            if prop in MATERIAL_PROPERTIES:
                _set_material(prop, value, mask, (t, rho, E), base.beam_E)
            elif prop == "mass":
                ms[mask] = value / s.mass_value[mask].sum()
            elif prop == "mass_factor":
                ms[mask] = value
            elif prop == "stiffness_factor":
                ss[mask] = value
            elif prop == "bend_factor":
                bend[mask] = value
        return ElementProperties(t, rho, E, bend, ms, ss)

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
        if self._general is None:  # a beam structure on the sparse path, built on demand
            self._general = GeneralAssembler(self.structure)
        g = self._general
        shell_props = self.shell_properties(p) if self.structure.shells is not None else None
        K, M, elem = g.assemble(props, shell_props)
        # a structure may ask for MSC's SUPORT convention (metadata "rigid_set": the Nastran
        # reader sets it for a deck with SUPORT; ``fe.sparse_modal.ModalSettings``)
        settings = ModalSettings(
            rigid_set=self.structure.metadata.get("rigid_set", "zero_energy"),
            small_method=self.small_method,
        )
        modes = g.solve(K, M, n_modes, dense=method == "dense", settings=settings)
        mass, cog = g.total_mass(M)
        en = general_energies(g, elem, shell_props, modes) if energies else None
        return FEResult(
            p, modes, mass, cog, en, self.sensor_shapes(modes.shapes), self.structure.sensor_labels
        )

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
