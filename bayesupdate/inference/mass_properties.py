"""Measured rigid-body mass properties as data: centre of gravity and inertia (the measured mass
itself keeps its own path: ``ObjectiveSpec.mass_target_kg`` and ``LikelihoodSpec.mass_sd_rel``).

A study gives them with units (``[data] cg``, ``[data] inertia``; ``parse_tables``); they are
converted once to the model's own consistent units (``ModelUnits``: SI for built-in models, a
Nastran deck's own, e.g. in and lbf s^2 in) and compared there with the model's
``mass_properties(params)`` (mass, cg (3,), inertia (3, 3) about the CG, ``inertia_about``).

Each measured component p_T with sd s enters

* the likelihood as (p(theta) - p_T) ~ N(0, s^2) (``MassPropertyTargets.log_likelihood``);
* the fit objective as the residual sqrt(w) (p(theta) - p_T) / S, beside seed eq. 19 and the
  mass term, with S = |p_T| for a moment of inertia (a relative error, as the mass term and the
  mAEWing1 authors' SOL 200 objective DEQATN ((IXX - 9560) / 9560)^2), and for a CG coordinate
  or a product of inertia, whose measured value may be zero, the model's largest radius of
  gyration sqrt(max J_ii / m) or its largest moment of inertia max J_ii at the reference design.

Products of inertia follow Nastran's CONM2 / grid point weight generator I(S) sign: I_xy =
integral of x y dm, so the tensor's off-diagonal J_xy = -I_xy.  Moments and products are about
the CG unless ``about`` names a point (MSC's DRESP1 WEIGHT rows 4-6 are about PARAM GRDPNT).
"""

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.units import DIMENSIONS, compound_unit, mass_property_value

CG_AXES = ("x", "y", "z")
INERTIA_NAMES = ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")
_TENSOR = {"ixx": (0, 0, 1), "iyy": (1, 1, 1), "izz": (2, 2, 1),
           "ixy": (0, 1, -1), "ixz": (0, 2, -1), "iyz": (1, 2, -1)}  # fmt: skip
_LOG_2PI = float(np.log(2.0 * np.pi))


@dataclass(frozen=True)
class RawProperty:
    """One measured component as the study gives it (before the model's units are known).

    name : "cg_x".. or "ixx"..; kind : "length" or "inertia"; value, sd : numbers, in SI where
    ``value_si`` / ``sd_si`` (else the model's own unit); sd_rel : a relative sd instead."""

    name: str
    kind: str
    value: float
    value_si: bool
    sd: float | None = None
    sd_si: bool = False
    sd_rel: float | None = None


@dataclass(frozen=True)
class ModelUnits:
    """The model's consistent units: SI factors of its mass and length unit (None: not
    recognized, then only plain numbers in the model's units are accepted) and their names."""

    mass_si: float | None = 1.0
    length_si: float | None = 1.0
    mass: str = "kg"
    length: str = "m"

    @property
    def inertia(self) -> str:
        """Name of the inertia unit: ``lbf s^2 in`` for ``lbf s^2/in`` and ``in``."""
        tail = f"/{self.length}"
        if self.mass.endswith(tail):
            return f"{self.mass[: -len(tail)]} {self.length}"
        return f"{self.mass} {self.length}^2"

    def unit(self, kind: str) -> str:
        return {"mass": self.mass, "length": self.length, "inertia": self.inertia}[kind]

    def factor(self, kind: str) -> float | None:
        """SI value of one model unit of ``kind`` (None where the units are not recognized)."""
        if self.mass_si is None or self.length_si is None:
            return None
        power = DIMENSIONS[kind]
        return self.mass_si ** power[0] * self.length_si ** power[1]


def model_units(units: Mapping | None) -> ModelUnits:
    """``ModelUnits`` of a Nastran deck's units record (``nastran.units.unit_system``: names
    like "lbf s^2/in", "in", "t (1000 kg)"); None (a built-in or user model): SI."""
    if units is None:
        return ModelUnits()
    mass, length = str(units["mass"]), str(units["length"])
    factors = []
    for text, kind in ((mass.split(" (")[0], "mass"), (length, "length")):
        try:
            factors.append(compound_unit(text, kind, "model units"))
        except BayesUpdateError:
            factors.append(None)
    return ModelUnits(factors[0], factors[1], mass.split(" (")[0], length)


def in_model_units(value: float, is_si: bool, kind: str, units: ModelUnits, what: str) -> float:
    """A measured value in the model's own units (SI values divided by the model unit's SI
    factor; plain numbers are the model's already)."""
    if not is_si:
        return float(value)
    factor = units.factor(kind)
    if factor is None:
        raise BayesUpdateError(
            f"{what}: the model's units are not recognized; give a plain number in the model's "
            "own units or name them with [model] units"
        )
    return float(value) / factor


def _sd_entry(sd, name: str, kind: str, where: str) -> tuple[float | None, bool, float | None]:
    """(sd, sd_si, sd_rel) of one sd as given: a number or unit string, or "N %" (relative)."""
    if sd is None:
        return None, False, None
    if isinstance(sd, str) and sd.strip().endswith("%"):
        try:
            rel = float(sd.strip()[:-1]) / 100.0
        except ValueError:
            raise BayesUpdateError(f"{where}: cannot read {sd!r}; e.g. '1.25 %'") from None
        if not rel > 0:
            raise BayesUpdateError(f"{where}: must be > 0, got {sd!r}")
        return None, False, rel
    value, si = mass_property_value(sd, kind, where)
    if not value > 0:
        raise BayesUpdateError(f"{where}: must be > 0, got {sd!r}")
    return value, si, None


def _table(table, names: tuple[str, ...], prefix: str, kind: str, where: str) -> list:
    """RawProperty entries of one ``[data] cg`` / ``inertia`` table: ``{name = value, ...,
    sd = value or {name = value}}``; every component needs an sd."""
    if not isinstance(table, Mapping):
        raise BayesUpdateError(f"{where}: must be a table like {{ {names[0]} = ..., sd = ... }}")
    extra = {"sd", "about"} if kind == "inertia" else {"sd"}
    unknown = sorted(set(table) - set(names) - extra)
    if unknown:
        raise BayesUpdateError(
            f"{where}.{unknown[0]}: unknown key; valid keys are {[*names, *sorted(extra)]}"
        )
    given = [n for n in names if n in table]
    if not given:
        raise BayesUpdateError(f"{where}: give at least one of {list(names)}")
    sd = table.get("sd")
    if isinstance(sd, Mapping):
        stray = sorted(set(sd) - set(given))
        if stray:
            raise BayesUpdateError(f"{where}.sd.{stray[0]}: no measured value {stray[0]!r}")
    out = []
    for name in given:
        here = f"{where}.{name}"
        value, si = mass_property_value(table[name], kind, here)
        one = sd.get(name) if isinstance(sd, Mapping) else sd
        if one is None:
            raise BayesUpdateError(f"{where}.sd: give the sd of {name} (e.g. sd = '1.25 %')")
        sd_value, sd_si, rel = _sd_entry(one, name, kind, f"{where}.sd")
        if rel is not None and value == 0:
            raise BayesUpdateError(f"{where}.sd: {name} is 0; give its sd as a value, not in %")
        out.append(RawProperty(prefix + name, kind, value, si, sd_value, sd_si, rel))
    return out


def _about(value, where: str) -> tuple[tuple[float, bool], ...] | None:
    """``[data] inertia.about``: "cg" (None) or a point [x, y, z] (numbers or lengths)."""
    if value is None or value == "cg":
        return None
    if not isinstance(value, list | tuple) or len(value) != 3:
        raise BayesUpdateError(f'{where}: give "cg" or a point [x, y, z] (e.g. ["8.18 in", 0, 0])')
    return tuple(mass_property_value(v, "length", where) for v in value)


def parse_tables(cg, inertia, where: str = "data") -> tuple[tuple[RawProperty, ...], tuple | None]:
    """The study's ``cg`` and ``inertia`` tables (either may be None) -> (raw properties,
    inertia reference point as ((value, is_si),) * 3 or None for the CG).  Raises one line for a
    bad key, unit or a missing sd."""
    raw: list[RawProperty] = []
    if cg is not None:
        raw += _table(cg, CG_AXES, "cg_", "length", f"{where}.cg")
    about = None
    if inertia is not None:
        raw += _table(inertia, INERTIA_NAMES, "", "inertia", f"{where}.inertia")
        about = _about(inertia.get("about"), f"{where}.inertia.about")
    return tuple(raw), about


@dataclass(frozen=True)
class MassPropertyTargets:
    """Measured CG / inertia components in the model's units.

    names : (k,) component names ("cg_x", "ixx", ...); values, sd, scale : (k,) measured values,
    their sd and the objective's normalization S (module docstring); weights : (k,) objective
    weights w; units : (k,) unit names; about : (3,) inertia reference point or None (the CG)."""

    names: tuple[str, ...]
    values: np.ndarray
    sd: np.ndarray
    scale: np.ndarray
    weights: np.ndarray
    units: tuple[str, ...]
    about: np.ndarray | None = None

    def predicted(self, props) -> np.ndarray:
        """(k,) the model's values of the measured components from its mass properties
        (``mass``, ``cg``, ``inertia``, ``inertia_about``)."""
        J = props.inertia if self.about is None else props.inertia_about(self.about)
        out = np.empty(len(self.names))
        for i, name in enumerate(self.names):
            if name.startswith("cg_"):
                out[i] = props.cg[CG_AXES.index(name[3:])]
            else:
                r, c, sign = _TENSOR[name]
                out[i] = sign * J[r, c]
        return out

    def residuals(self, predicted: np.ndarray) -> np.ndarray:
        """(k,) objective residuals sqrt(w) (p - p_T) / S."""
        return np.sqrt(self.weights) * (np.asarray(predicted) - self.values) / self.scale

    def log_likelihood(self, predicted: np.ndarray) -> np.ndarray:
        """Predicted values (n, k) -> (n,) Gaussian log-likelihood (NaN rows give NaN)."""
        e = (np.atleast_2d(predicted) - self.values) / self.sd
        return -0.5 * np.sum(e * e + 2.0 * np.log(self.sd) + _LOG_2PI, axis=1)


def build_targets(raw, about, units: ModelUnits, reference, weights: Mapping[str, float],
                  where: str = "data") -> MassPropertyTargets | None:  # fmt: skip
    """``MassPropertyTargets`` from ``parse_tables``'s output in the model's ``units``.

    reference : the model's mass properties at the reference design (the objective's scales S);
    weights : {"length": w_cg, "inertia": w_inertia}.  None when nothing is measured."""
    if not raw:
        return None
    J = np.diag(reference.inertia)
    gyration = float(np.sqrt(max(J.max(), 0.0) / reference.mass))
    values, sds, scales, ws, unit_names = [], [], [], [], []
    for p in raw:
        here = f"{where}.{'cg' if p.kind == 'length' else 'inertia'}.{p.name.removeprefix('cg_')}"
        value = in_model_units(p.value, p.value_si, p.kind, units, here)
        sd = value * p.sd_rel if p.sd_rel is not None else None
        if sd is None:
            sd = in_model_units(p.sd, p.sd_si, p.kind, units, here + " sd")
        if p.name in ("ixx", "iyy", "izz"):
            if not value > 0:
                raise BayesUpdateError(f"{here}: a moment of inertia must be > 0, got {value:g}")
            scale = value
        else:
            scale = gyration if p.kind == "length" else float(J.max())
        values.append(value)
        sds.append(abs(sd))
        scales.append(scale)
        ws.append(float(weights[p.kind]))
        unit_names.append(units.unit(p.kind))
    point = None
    if about is not None:
        point = np.array([in_model_units(v, si, "length", units, f"{where}.inertia.about")
                          for v, si in about])  # fmt: skip
    return MassPropertyTargets(
        tuple(p.name for p in raw), np.array(values), np.array(sds), np.array(scales),
        np.array(ws), tuple(unit_names), point,
    )  # fmt: skip


def mass_properties_function(model) -> Callable[[dict], object] | None:
    """params -> the model's rigid-body mass properties: its own (FE models:
    ``mass_properties_function()``, a cheap affine sum where the model certifies one, else
    ``mass_properties``), else those of the full model a reduced model wraps (``outer`` /
    ``fe``); None for models that cannot give them."""
    for candidate in (model, getattr(model, "outer", None), getattr(model, "fe", None)):
        factory = getattr(candidate, "mass_properties_function", None)
        if callable(factory):
            return factory()
        function = getattr(candidate, "mass_properties", None)
        if callable(function):
            return function
    return None


def records(targets: MassPropertyTargets | None, predicted: np.ndarray | None,
            mass: tuple | None = None) -> list[dict]:  # fmt: skip
    """The result's ``mass_properties``: [{name, measured, predicted, unit, sd}] for the mass
    (``mass`` = (measured, predicted, unit, sd) or None) and each measured component."""
    out = []
    if mass is not None:
        measured, value, unit, sd = mass
        out.append(dict(name="mass", measured=_num(measured), predicted=_num(value), unit=unit,
                        sd=_num(sd)))  # fmt: skip
    if targets is not None:
        pred = np.full(len(targets.names), np.nan) if predicted is None else predicted
        for i, name in enumerate(targets.names):
            out.append(dict(name=name, measured=float(targets.values[i]),
                            predicted=_num(pred[i]), unit=targets.units[i],
                            sd=float(targets.sd[i])))  # fmt: skip
    return out


def _num(value) -> float | None:
    return None if value is None or not np.isfinite(value) else float(value)


def mass_property_report(problem, params: Mapping[str, float]) -> list[dict]:
    """``records`` of a calibration problem at ``params`` (all model parameters): the measured
    mass (``objective.mass_target_kg``, sd ``data.mass_sd_kg``) and CG / inertia components
    against the model's values there.  Empty when nothing is measured; predicted values are
    None where the model cannot give them or rejects ``params``."""
    objective = problem.objective
    targets = objective.mass_properties
    if objective.mass_target_kg is None and targets is None:
        return []
    function = mass_properties_function(problem.model)
    props = None
    if function is not None:
        try:
            props = function(dict(params))
        except BayesUpdateError:
            props = None
    mass = None
    if objective.mass_target_kg is not None:
        sd = problem.data.mass_sd_kg if problem.data.mass_kg == objective.mass_target_kg else None
        value = None if props is None else props.mass
        mass = (objective.mass_target_kg, value, objective.mass_unit, sd)
    predicted = None if props is None or targets is None else targets.predicted(props)
    return records(targets, predicted, mass)
