"""Study-file tables of the discovery layer (registered with ``config.register_table``).

``[effects]`` - effects the model is extended by before anything else (a model found by an
earlier discovery, or a hypothesis)::

    [effects]
    add = ["joint_flexibility@cold_pipe/main_muffler:k_rot=2e3"]

``[discovery]`` - the ``workflow.DiscoverySettings`` knobs::

    [discovery]
    kinds = ["added_mass", "joint_flexibility"]     # default: the whole library
    locations = { added_mass = ["12", "14"] }       # default: every admissible location
    sigma = 0.005                                   # fixed relative noise (default: data sd,
                                                    # else inferred)
    threshold_log_odds = 3.0                        # on ln BF + prior log odds
    margin_ln_bf = 2.0
    effect_prior = 0.5                              # P(one library effect is present)
    max_refits = 5
"""

import dataclasses
from collections.abc import Mapping

from bayesupdate.config import register_table
from bayesupdate.discovery.effects import parse_effect_spec
from bayesupdate.discovery.workflow import DiscoverySettings
from bayesupdate.errors import BayesUpdateError

_INT_KEYS = {
    "baseline_starts",
    "seed",
    "quick_refits",
    "per_kind",
    "quick_nfev",
    "max_refits",
    "max_nfev",
    "loo_top",
    "loo_draws",
}
_FLOAT_KEYS = {
    "sigma",
    "threshold_log_odds",
    "margin_ln_bf",
    "effect_prior",
    "adequacy_p",
    "alpha",
}


def parse_effects_table(table: Mapping, where: str) -> tuple[str, ...]:
    """``[effects] add = [...]`` -> validated spec strings."""
    unknown = sorted(set(table) - {"add"})
    if unknown:
        raise BayesUpdateError(f"{where}.{unknown[0]}: unknown key; valid keys are ['add']")
    specs = table.get("add", [])
    if not isinstance(specs, list) or not all(isinstance(s, str) for s in specs):
        raise BayesUpdateError(f"{where}.add: must be a list of effect specs (strings)")
    for spec in specs:
        parse_effect_spec(spec)  # raises a clear error for an unknown kind or a bad value
    return tuple(specs)


def parse_discovery_table(table: Mapping, where: str) -> DiscoverySettings:
    """``[discovery]`` -> DiscoverySettings (strict keys and types)."""
    valid = {f.name for f in dataclasses.fields(DiscoverySettings)}
    values = {}
    for key, value in table.items():
        here = f"{where}.{key}"
        if key not in valid:
            raise BayesUpdateError(f"{here}: unknown key; valid keys are {sorted(valid)}")
        if key in _INT_KEYS:
            if isinstance(value, bool) or not isinstance(value, int):
                raise BayesUpdateError(f"{here}: must be an integer, got {value!r}")
        elif key in _FLOAT_KEYS:
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise BayesUpdateError(f"{here}: must be a number, got {value!r}")
            value = float(value)
        elif key == "kinds":
            if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
                raise BayesUpdateError(f"{here}: must be a list of effect kinds")
            value = tuple(value)
        elif key == "locations":
            ok = isinstance(value, dict) and all(
                isinstance(v, list) and all(isinstance(x, str | int) for x in v)
                for v in value.values()
            )
            if not ok:
                raise BayesUpdateError(f"{here}: must be a table kind = [locations]")
            value = {k: [str(x) for x in v] for k, v in value.items()}
        values[key] = value
    return DiscoverySettings(**values)


for _name, _parser in (("effects", parse_effects_table), ("discovery", parse_discovery_table)):
    try:
        register_table(_name, _parser)
    except ValueError:  # a built-in table of that name: nothing to register
        pass
