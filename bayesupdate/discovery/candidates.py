"""Candidate effects and the coordinates they are fitted in.

A *candidate* is one effect kind at one location (``effects.Effect``).  Each is fitted together
with the design variables, so every parameter (design variable or effect parameter) is an
``inference.parameter_space.ParameterSpec``: bounds, prior, and whether it is fitted in log
coordinates (when its bounds span >= 2 decades, e.g. a joint stiffness in [1e2, 1e6] N m/rad).
The refits work in unit-box coordinates u in [0, 1]; the Laplace approximation in z = theta or
z = log(theta) (``ParameterSpace``).

The *null value* of an effect parameter is the value at which the extended model equals the
model without the effect (zero added mass, zero spring, factor 1, the joint's modelled
stiffness, a connection's modelled spring): the localization step probes each candidate by a
small step away from it.
"""

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from bayesupdate.discovery.effects import (
    EFFECT_KINDS,
    Effect,
    effect_locations,
    extend_model,
    model_parameters,
)
from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.parameter_space import ParameterSpec
from bayesupdate.inference.priors import prior_from_mapping


# -- null values ------------------------------------------------------------------------------
def _joint_null(model, location: str) -> float:
    """Geometric mean of the joint springs' modelled bending stiffnesses [N m/rad]."""
    s = model.structure
    k = s.spring_k[s.spring_part == s.parts.index(location)][:, 4:6]
    return float(np.exp(np.mean(np.log(np.maximum(k, 1e-300)))))


#: kind -> (model, location) -> {parameter: null value}
NULL_VALUES: dict[str, Callable] = {
    "added_mass": lambda model, loc: {"m": 0.0},
    "boundary_spring": lambda model, loc: {"k": 0.0},
    "bend_flexibility": lambda model, loc: {"factor": 1.0},
    "stiffness_change": lambda model, loc: {"factor": 1.0},
    "joint_flexibility": lambda model, loc: {"k_rot": _joint_null(model, loc)},
    "connection_flexibility": lambda model, loc: {"k_rot": _joint_null(model, loc)},
}


def null_values(model, effect: Effect) -> dict[str, float]:
    """Null value of each effect parameter, clipped into its bounds."""
    given = NULL_VALUES.get(effect.kind)
    values = given(model, effect.location) if given else {}
    out = {}
    for p in model_parameters(model, effect.kind):
        v = values.get(p.name, p.bounds[0])
        out[p.name] = float(np.clip(v, *p.bounds))
    return out


# -- candidates -------------------------------------------------------------------------------
@dataclass(frozen=True)
class Candidate:
    """One effect at one location, with its extended model and its parameters (each starting at
    its null value, on its natural axis)."""

    effect: Effect
    model: object
    axes: tuple[ParameterSpec, ...]

    @property
    def label(self) -> str:
        return self.effect.tag

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.axes)

    @property
    def null(self) -> dict[str, float]:
        """Full parameter name -> null value (SI)."""
        return {a.name: a.start for a in self.axes}


def make_candidate(model, effect: Effect) -> Candidate:
    """Extend ``model`` by ``effect`` and describe the effect's parameters."""
    extended = extend_model(model, effect)
    nulls = null_values(model, effect)
    axes = []
    for p in model_parameters(model, effect.kind):  # in the model's units (a deck's own)
        full = f"{effect.tag}:{p.name}"
        prior = prior_from_mapping(p.prior, p.bounds, full)
        axes.append(ParameterSpec(full, p.bounds, prior, nulls[p.name]))
    return Candidate(effect, extended, tuple(axes))


def enumerate_effects(
    model, kinds=None, locations: Mapping[str, list] | None = None
) -> list[Effect]:
    """Every (kind, location) pair to consider: all kinds of the library (or ``kinds``) at all
    their admissible locations (or those listed in ``locations[kind]``)."""
    kinds = list(EFFECT_KINDS) if kinds is None else list(kinds)
    out = []
    for kind in kinds:
        if kind not in EFFECT_KINDS:
            raise BayesUpdateError(
                f"discovery: unknown effect kind {kind!r}; kinds are {sorted(EFFECT_KINDS)}"
            )
        admissible = effect_locations(model, kind)
        chosen = admissible if not locations or kind not in locations else list(locations[kind])
        bad = [loc for loc in chosen if loc not in admissible]
        if bad:
            raise BayesUpdateError(
                f"discovery: unknown location(s) {bad} for {kind}; locations are {admissible}"
            )
        out.extend(Effect(kind, str(loc)) for loc in chosen)
    if not out:
        raise BayesUpdateError("discovery: no candidate effects (no kind has a location here)")
    return out
