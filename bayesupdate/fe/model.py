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
"""

from collections.abc import Mapping
from dataclasses import dataclass, replace

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.assembly import Assembler, ElementProperties, rigid_body_basis
from bayesupdate.fe.eigensolve import BandedShiftInvert, ModalSolution, solve_modes
from bayesupdate.fe.energy import ModalEnergies, modal_energies
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


@dataclass(frozen=True)
class Binding:
    """Parameter -> (part or bend name, property); see the module table."""

    target: str
    property: str


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
        self.assembler = Assembler(structure)
        a = self.assembler
        self.banded = BandedShiftInvert(a.n_dof, a.pattern_rows, a.pattern_cols, a.indptr)
        self.rigid_basis = rigid_body_basis(structure.nodes)
        self._base = a.default_properties()
        self._masks = {p: self._mask(p, b) for p, b in self.bindings.items()}
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
        if not np.any(mask):
            raise BayesUpdateError(
                f"parameter {name}: part {binding.target!r} has nothing with a {binding.property}"
            )
        return mask

    def default_parameters(self) -> dict[str, float]:
        return dict(self._defaults)

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
            if prop == "thickness":
                t[mask] = value
            elif prop == "density":
                rho[mask] = value
            elif prop == "youngs_modulus":
                E[mask] = value
            elif prop == "modulus_factor":
                E[mask] = base.beam_E[mask] * value
            elif prop == "mass":
                ms[mask] = value / s.mass_value[mask].sum()
            elif prop == "mass_factor":
                ms[mask] = value
            elif prop == "stiffness_factor":
                ss[mask] = value
            elif prop == "bend_factor":
                bend[mask] = value
        return ElementProperties(t, rho, E, bend, ms, ss)

    # -- analysis ----------------------------------------------------------------------------
    def solve(
        self,
        params: Mapping[str, float] | None = None,
        n_modes: int = 12,
        energies: bool = False,
        method: str = "krylov",
    ) -> FEResult:
        """Full modal analysis: first ``n_modes`` elastic modes, mass, CoG, optional energies."""
        p = self.full_parameters(params)
        props = self.element_properties(p)
        K, M, elem = self.assembler.assemble(props)
        modes = solve_modes(
            K,
            M,
            n_modes,
            self.rigid_basis,
            self.banded,
            method=method,
            ground_stiffness=self.assembler.ground_stiffness(elem),
        )
        mass, cog = self.assembler.total_mass(props)
        en = modal_energies(self.assembler, elem, modes.shapes) if energies else None
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


def structure_with(structure: Structure, **changes) -> Structure:
    """A copy of ``structure`` with some arrays replaced (frozen dataclass ``replace``)."""
    return replace(structure, **changes)
