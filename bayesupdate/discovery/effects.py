"""The library of named physical effects a model may be missing (DESIGN.md vocabulary), their
spec syntax ``KIND@LOCATION[:name=value,...]`` and how each extends an ``FEModel``.

Each kind has its own parameters (SI, with bounds and a prior in the study-file prior syntax) and
a rule for where it may sit:

=================  =====================  ============================================  =========
kind               location               parameters                                    prior
=================  =====================  ============================================  =========
added_mass         sensor point (1..20)   m [kg] in [0, 2]                              uniform
joint_flexibility  joint ``partA/partB``  k_rot [N m/rad] in [1e2, 1e6], both planes    lognormal
connection_        pipe-to-shell-body     k_rot [N m/rad] in [1e3, 1e8] of the spring   lognormal
flexibility        connection ``a/b``     between pipe and spider, both planes
bend_flexibility   a named bend           factor [-] in [1, 6] dividing EI              uniform
boundary_spring    sensor point (1..20)   k [N/m] in [0, 1e5], 3 translations           uniform
stiffness_change   a part (beams, a       factor [-] on Young's modulus in [0.5, 1.5]   uniform
                   shell body's sheets,
                   a deck's PBEAM/PBAR)
=================  =====================  ============================================  =========

A stiffness change sits on a part with beams or shells (a shell body of ``exhaust_shell``; on a
Nastran deck a PSHELL property, ``stiffness_change@PSHELL 3``, or a line property, the CBEAMs
of one PBEAM, ``stiffness_change@PBEAM 1003``: E and G of those elements alone, the shear
stiffness with them, so their K scales by the factor and their mass stays), unless a parameter
already sets the modulus of those elements.

Joints are the spring parts ``a/b`` of a beam model (``exhaust``); connections are the spring
parts a model lists in ``structure.metadata["connections"]``: springs in series with a rigid
spider that joins a pipe to a shell body (``exhaust_shell``), whose modelled stiffness is
effectively rigid, so their range reaches far higher than a beam joint's.

A user adds a kind with ``register_effect_kind``.  Extended models name their extra parameters
``KIND@LOCATION:NAME`` (e.g. ``added_mass@14:m``).
"""

import re
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.model import Binding, FEModel
from bayesupdate.fe.modify import split_joint_bending, with_point_mass, with_spring


@dataclass(frozen=True)
class EffectParameter:
    """One parameter of an effect kind: default value, bounds and prior (SI units)."""

    name: str
    default: float
    bounds: tuple[float, float]
    prior: dict
    unit: str
    description: str = ""


@dataclass(frozen=True)
class EffectKind:
    """A kind of effect: its parameters, where it may sit, and how it extends a model.

    ``locations(model)`` lists admissible locations; ``extend(model, location, tag)`` returns
    (structure, {param_name: Binding}) for the extended model, the bindings keyed by the short
    parameter names of ``parameters``.
    """

    name: str
    parameters: tuple[EffectParameter, ...]
    locations: Callable
    extend: Callable
    description: str = ""


@dataclass(frozen=True)
class Effect:
    """A concrete effect: kind, location and (possibly partial) parameter values."""

    kind: str
    location: str
    parameters: dict = field(default_factory=dict)

    @property
    def tag(self) -> str:
        return f"{self.kind}@{self.location}"

    def spec(self) -> str:
        values = ",".join(f"{k}={v:g}" for k, v in self.parameters.items())
        return self.tag + (f":{values}" if values else "")


# -- locations --------------------------------------------------------------------------------
def _sensor_points(model: FEModel) -> list[str]:
    numbers = sorted(
        {
            int(m.group(1))
            for lab in model.structure.sensor_labels
            if (m := re.fullmatch(r"(\d+)[A-Za-z]+", lab))
        }
    )
    return [str(n) for n in numbers]


def _sensor_node(model: FEModel, location: str) -> int:
    s = model.structure
    for label, node in zip(s.sensor_labels, s.sensor_node, strict=True):
        if re.fullmatch(rf"{re.escape(location)}[A-Za-z]+", label):
            return int(node)
    raise BayesUpdateError(f"unknown sensor point {location!r}; points are {_sensor_points(model)}")


def _joints(model: FEModel) -> list[str]:
    s = model.structure
    listed = s.metadata.get("connections", ())
    return [
        p
        for i, p in enumerate(s.parts)
        if "/" in p
        and np.any(s.spring_part == i)
        and p not in listed
        and not p.startswith("connection_flexibility@")
    ]


def _connections(model: FEModel) -> list[str]:
    """Spring parts the model names as pipe-to-shell connections (``metadata["connections"]``)
    that still carry their bending stiffness (a connection already extended by
    ``connection_flexibility`` has moved it to the effect's part: it is not offered again)."""
    s = model.structure
    listed = s.metadata.get("connections", ())
    return [
        p
        for i, p in enumerate(s.parts)
        if p in listed and np.any(s.spring_k[s.spring_part == i][:, 4:6] > 0)
    ]


def _bends(model: FEModel) -> list[str]:
    return list(model.structure.bends)


# -- extensions -------------------------------------------------------------------------------
def _extend_added_mass(model, location, tag):
    s = with_point_mass(model.structure, _sensor_node(model, location), 1.0, tag)
    return s, {"m": Binding(tag, "mass")}


def _extend_boundary_spring(model, location, tag):
    s = with_spring(
        model.structure, _sensor_node(model, location), None, [1.0, 1.0, 1.0, 0.0, 0.0, 0.0], tag
    )
    return s, {"k": Binding(tag, "stiffness_factor")}


def _extend_joint(model, location, tag):
    if location not in _joints(model):
        raise BayesUpdateError(f"unknown joint {location!r}; joints are {_joints(model)}")
    return split_joint_bending(model.structure, location, tag), {
        "k_rot": Binding(tag, "stiffness_factor")
    }


def _extend_connection(model, location, tag):
    if location not in _connections(model):
        raise BayesUpdateError(
            f"unknown connection {location!r}; connections are {_connections(model)}"
        )
    return split_joint_bending(model.structure, location, tag), {
        "k_rot": Binding(tag, "stiffness_factor")
    }


def _extend_bend(model, location, tag):
    if location not in model.structure.bends:
        raise BayesUpdateError(f"unknown bend {location!r}; bends are {_bends(model)}")
    return model.structure, {"factor": Binding(location, "bend_factor")}


def _stiffness_parts(model: FEModel) -> list[str]:
    """Parts with beams or shells (a modulus factor acts on both), in part order; a shell part
    only where no parameter already sets its shells' modulus (a deck's MAT1 E binding).  On a
    Nastran deck also its line properties (``"PBEAM 1003"``: the elements of one PBEAM, PBAR,
    PBARL, PBEAML or PROD, the model's ``line_parts``), whose E and G the factor scales for
    those elements alone, unless a parameter already sets their modulus."""
    s = model.structure
    line_parts = getattr(model, "line_parts", None)
    lines = set(line_parts()) if callable(line_parts) else set()
    free = np.zeros(0, int)
    if s.shells is not None:
        taken = np.zeros(s.shells.n_elements, bool)
        for name, binding in model.bindings.items():
            if binding.property in ("youngs_modulus", "modulus_factor"):
                taken |= model.shells_of(name)
        free = s.shells.part[~taken]
    return [
        p
        for i, p in enumerate(s.parts)
        if np.any(s.beam_part == i) or np.any(free == i) or p in lines
    ]


def _extend_stiffness(model, location, tag):
    if location not in _stiffness_parts(model):
        raise BayesUpdateError(f"unknown part {location!r}; parts are {_stiffness_parts(model)}")
    return model.structure, {"factor": Binding(location, "modulus_factor")}


_UNIFORM = {"kind": "uniform"}
EFFECT_KINDS: dict[str, EffectKind] = {}


def register_effect_kind(kind: EffectKind) -> None:
    """Add (or replace) an effect kind in the library."""
    EFFECT_KINDS[kind.name] = kind


for _kind in (
    EffectKind(
        "added_mass",
        (EffectParameter("m", 0.3, (0.0, 2.0), _UNIFORM, "kg", "point mass at the sensor point"),),
        _sensor_points,
        _extend_added_mass,
        "an unmodelled mass (bracket, sensor cable, heat shield) at a point",
    ),
    EffectKind(
        "joint_flexibility",
        (
            EffectParameter(
                "k_rot",
                3e3,
                (1e2, 1e6),
                {"kind": "lognormal", "mu": float(np.log(1e4)), "sigma": 2.0},
                "N m/rad",
                "bending stiffness of the joint in both planes",
            ),
        ),
        _joints,
        _extend_joint,
        "a connection more flexible than modelled",
    ),
    EffectKind(
        "bend_flexibility",
        (
            EffectParameter(
                "factor", 2.0, (1.0, 6.0), _UNIFORM, "-", "factor dividing the bend's EI"
            ),
        ),
        _bends,
        _extend_bend,
        "ovalization of a bend beyond the B31.3 factor",
    ),
    EffectKind(
        "boundary_spring",
        (
            EffectParameter(
                "k", 2e3, (0.0, 1e5), _UNIFORM, "N/m", "translational stiffness to ground"
            ),
        ),
        _sensor_points,
        _extend_boundary_spring,
        "the test suspension (elastic cords) acting at a point",
    ),
    EffectKind(
        "stiffness_change",
        (
            EffectParameter(
                "factor", 0.8, (0.5, 1.5), _UNIFORM, "-", "factor on the part's Young's modulus"
            ),
        ),
        _stiffness_parts,
        _extend_stiffness,
        "a part stiffer or softer than modelled",
    ),
    EffectKind(
        "connection_flexibility",
        (
            EffectParameter(
                "k_rot",
                1e5,
                (1e3, 1e8),
                {"kind": "lognormal", "mu": float(np.log(10**5.5)), "sigma": 3.0},
                "N m/rad",
                "bending stiffness of the pipe-to-spider spring in both planes",
            ),
        ),
        _connections,
        _extend_connection,
        "a pipe-to-shell-body connection (weld, neck, clamp) more flexible than the rigid spider",
    ),
):
    register_effect_kind(_kind)


# -- specs ------------------------------------------------------------------------------------
_SPEC = re.compile(r"^\s*([A-Za-z_][\w]*)@([^:]+?)\s*(?::(.*))?$")


def parse_effect_spec(text: str) -> Effect:
    """``KIND@LOCATION[:name=value,...]`` -> Effect (values SI, units allowed: ``m=400g``)."""
    from bayesupdate.units import parse_quantity

    match = _SPEC.match(str(text))
    if not match:
        raise BayesUpdateError(
            f"effect {text!r}: expected KIND@LOCATION[:name=value,...], e.g. added_mass@14:m=0.4"
        )
    kind_name, location, rest = match.groups()
    if kind_name not in EFFECT_KINDS:
        raise BayesUpdateError(
            f"effect {text!r}: unknown kind {kind_name!r}; kinds are {sorted(EFFECT_KINDS)}"
        )
    kind = EFFECT_KINDS[kind_name]
    known = {p.name: p for p in kind.parameters}
    values = {}
    for item in filter(None, (rest or "").split(",")):
        if "=" not in item:
            raise BayesUpdateError(f"effect {text!r}: {item!r} is not name=value")
        name, value = (x.strip() for x in item.split("=", 1))
        if name not in known:
            raise BayesUpdateError(
                f"effect {text!r}: {kind_name} has no parameter {name!r}; it has {sorted(known)}"
            )
        v = parse_quantity(value, f"effect {kind_name} {name}")
        lo, hi = known[name].bounds
        if not lo <= v <= hi:
            raise BayesUpdateError(
                f"effect {text!r}: {name}={v:g} is outside the bounds [{lo:g}, {hi:g}] "
                f"[{known[name].unit}]"
            )
        values[name] = v
    return Effect(kind_name, location.strip(), values)


def effect_locations(model: FEModel, kind: str) -> list[str]:
    """Admissible locations of ``kind`` on ``model``."""
    return list(EFFECT_KINDS[kind].locations(model))


#: SI unit of an effect parameter -> its dimension (mass, length) exponents; time is in s in
#: every consistent unit system a deck uses
_DIMENSIONS = {"kg": (1, 0), "N/m": (1, 0), "N m/rad": (1, 2)}


def si_per_model_unit(model: FEModel, unit: str) -> float:
    """SI value of one model unit of an effect parameter whose SI unit is ``unit`` ("kg",
    "N/m", "N m/rad"; 1 for a factor): a Nastran deck's own units (its ``units`` record, e.g.
    lbf s^2/in: 175.1 kg; lbf/in: 175.1 N/m), 1 for a built-in model (SI) or a deck whose
    units are not recognized."""
    from bayesupdate.inference.mass_properties import model_units

    record = model.structure.metadata.get("nastran", {}).get("units")
    if record is None or unit not in _DIMENSIONS:
        return 1.0
    units = model_units(record)
    mass, length = units.factor("mass"), units.factor("length")
    if mass is None or length is None:
        return 1.0
    a, b = _DIMENSIONS[unit]
    return float(mass**a * length**b)


def model_parameters(model: FEModel, kind: str) -> tuple[EffectParameter, ...]:
    """The parameters of effect ``kind`` in ``model``'s units: the library's SI defaults,
    bounds and prior (a lognormal's median) divided by ``si_per_model_unit``.  On the
    mAEWing1 deck (lbf s^2/in) a point mass of 0-2 kg is 0-0.0114 lbf s^2/in; taken as deck
    units, the same numbers would allow 350 kg and widen the prior, and so lower every
    candidate's evidence, by ln 175 = 5.2."""
    out = []
    for p in EFFECT_KINDS[kind].parameters:
        f = 1.0 / si_per_model_unit(model, p.unit)
        if f == 1.0:
            out.append(p)
            continue
        prior = dict(p.prior)
        if prior.get("kind") == "lognormal":
            prior["mu"] = float(prior["mu"]) + float(np.log(f))
        bounds = (p.bounds[0] * f, p.bounds[1] * f)
        out.append(replace(p, default=p.default * f, bounds=bounds, prior=prior))
    return tuple(out)


#: kinds placed at the model node of a sensor point (``_sensor_node``): two test points read
#: on one node (e.g. the mAEWing1's accelerometers 17 and 18, on one beam node of v3.3)
#: give one and the same extended model
_AT_SENSOR_NODE = ("added_mass", "boundary_spring")


def effect_site(model: FEModel, effect: Effect) -> tuple:
    """(kind, where it acts): equal for two effects whose extended models are the same
    structure up to the names of the effect's part and parameters (the same kind at one model
    node); a kind placed elsewhere acts at its location (every location its own)."""
    if effect.kind in _AT_SENSOR_NODE:
        return effect.kind, "node", _sensor_node(model, effect.location)
    return effect.kind, "location", effect.location


def extend_model(model: FEModel, effect: Effect) -> FEModel:
    """``model`` with ``effect`` added: new parameters ``KIND@LOCATION:NAME`` whose defaults are
    the effect's given values (else the kind's defaults) and whose bounds are the kind's, in
    the model's units (``model_parameters``: a deck's own)."""
    if effect.kind not in EFFECT_KINDS:
        raise BayesUpdateError(
            f"unknown effect kind {effect.kind!r}; kinds: {sorted(EFFECT_KINDS)}"
        )
    kind = EFFECT_KINDS[effect.kind]
    if effect.location not in kind.locations(model):
        raise BayesUpdateError(
            f"effect {effect.tag}: unknown location {effect.location!r} for {effect.kind}; "
            f"locations are {kind.locations(model)}"
        )
    structure, short_bindings = kind.extend(model, effect.location, effect.tag)
    bindings, defaults, bounds = {}, {}, {}
    for p in model_parameters(model, effect.kind):
        full = f"{effect.tag}:{p.name}"
        bindings[full] = short_bindings[p.name]
        given = effect.parameters.get(p.name)  # SI, as the spec says
        si = si_per_model_unit(model, p.unit)
        defaults[full] = float(p.default if given is None else given / si)
        bounds[full] = p.bounds
    return model.with_structure(
        structure, bindings, defaults, bounds, name=f"{model.name}+{effect.tag}"
    )
