"""The TOML study file (``tomllib``): one frozen dataclass per table, strict keys and types.

Example::

    [model]
    source = "exhaust"              # built-in name, or "package.module:function"
    options = {}                    # keyword arguments of the built-in model's factory
    sensors = ["1", "2"]            # custom model only: labels of the rows of its shapes
    test_points = { "12" = 1012 }   # Nastran deck: test node -> GRID id (default: the same id)
    [data]
    source = "paper:ema"            # or a file (.csv, .h5, .uff), or inline:
    # frequencies_hz = [...], weights = [...], sd_hz = [...]
    modes = [1, 7, 10]              # the source's test modes that enter (1-based, as identify
                                    # --json lists them; default: all); weights and sd_hz then
                                    # give one value per selected mode, for a file source too
    mass_kg = 12.29                 # measured mass (test data; overrides the source's own)
    mass_sd_kg = 0.12               # its sd
    # mass = "13.76 lb"             # or with a unit (kg, g, t, lb, slug, "lbf s^2/in"), or a
    # mass_sd = "1.25 %"            # number in the model's own mass unit; sd also in %
    # cg = { x = "8.18 in", sd = "0.05 in" }                  # measured CG (any of x, y, z)
    # inertia = { ixx = "9560 lb in^2", iyy = "1643 lb in^2", sd = "1.25 %" }  # about the CG
    [parameters.t_hot_pipe]         # optional for built-in models (defaults from the model)
    bounds = [0.5e-3, 3.0e-3]
    # binds = "PSHELL 3,5 T"        # Nastran deck: the deck field it sets (deck units), or
                                    # "MAT1 2 E scale" (a factor); bayesupdate.nastran.bindings
    prior = { kind = "uniform" }    # lognormal {mu, sigma} | normal {mean, sd} | halfnormal {scale}
    start = 1.0e-3
    [test]                          # the test's geometry: pairs the data's DOFs with the model
    geometry = "test.unv"           # UFF 15/2411 (+ 2420 frames, 164 units) or CSV (testgeom)
    align = "auto"                  # "none", or [[r11, r12, r13, tx], [...], [...]] (3x4)
    pairs = [[1, 1012], [5, 1050], [9, 1090]]   # auto: test node -> model node (else ICP)
    scale = false                   # allow one uniform scale in the alignment
    pair_tolerance = "5 mm"         # farthest a test point may sit from the model (m or unit)
    length_unit = "mm"              # the geometry file's (a UFF 164 record must agree)
    model_length_unit = "in"        # only for a deck whose units are not recognized
    pair_to = "element"             # or "node": nearest node only
    [pairing]
    method = "auto"                 # auto | order | tracked | mac
    extra_modes = 2
    mac_threshold = 0.6             # MAC pairs (test shapes): lowest MAC kept at the reference
    frequency_window = 0.5          # and largest |f_model / f_test - 1|; other test modes are
                                    # refused (named, left out of the objective)
    [objective]
    mass_kg = 12.29                 # target of the mass term (default: the data's measured mass)
    mass_weight = 10.0              # default: 10 when a measured mass is known, else 0
    use_measured_mass = true        # false (--no-mass): the data's measured mass is ignored
    mac_weight = 0.0
    cg_weight = 10.0                # weights of the measured CG / inertia residuals
    inertia_weight = 10.0
    [optimizer]
    starts = 16
    method = "least_squares"        # or "global" (differential evolution first)
    design = "sobol"                # or "lhs"
    seed = 0
    polish = true                   # Nelder-Mead polish of every end (optima on pairing kinks)
    [likelihood]
    sigma = 0.05                    # fixed, or sigma_prior = { kind = "halfnormal", scale = 0.1 }
    mass_sd = 0.01                  # relative sd of the mass observation (default: the data's)
    pairing = "auto"                # "auto": the pairing above, batched when the model gives
                                    # batch shapes; "order" (batched, in order); "problem"
    [sampler]
    walkers = 32                    # default: 32, or 2 per sampled parameter above 16
    steps = 5000
    seed = 1
    min_autocorr_times = 50
    target_rhat = 1.01              # and run until R-hat <= this for every parameter
    target_ess = 400                # ... and bulk ESS >= this (Vehtari et al. 2021); 0 = off
    check_every = 500
    predictive_draws = 400
    hdi_prob = 0.9
    reduced = true                  # built-in FE models: certified reduced basis (false = --full)
    reduced_tol = 1e-4              # its relative frequency tolerance
    screen = true                   # delayed acceptance: proposals screened on a coarser basis
    transform = "logit"             # walk in unconstrained coordinates ("none": in theta)
    adapt_steps = 250               # each of the mixture moves' three adaptation stages

    [effects]                       # effects the model is extended by before anything else
    add = ["joint_flexibility@cold_pipe/main_muffler:k_rot=2e3"]   # (an earlier discovery's)
    [discovery]                     # discovery.settings.DiscoverySettings
    kinds = ["added_mass", "joint_flexibility"]     # default: the whole library
    locations = { added_mass = ["12", "14"] }       # default: every admissible location
    sigma = 0.005                   # fixed relative noise (default: data sd, else inferred)
    threshold_log_odds = 3.0        # on ln BF + prior log odds
    margin_ln_bf = 2.0
    effect_prior = 0.5              # P(one library effect is present)
    max_refits = 5

Unknown tables and keys, and values of the wrong type, raise ``BayesUpdateError`` naming
``file: table.key``.  The parsed ``[effects]`` (a tuple of spec strings) and ``[discovery]`` (a
``DiscoverySettings``) land in ``StudyConfig.extensions``, and so does ``[compute]``
(``workers = N`` or ``scheduler = "tcp://head:8786"``: a ``compute.settings.ComputeSettings``).
"""

import dataclasses
import math
import numbers
import os
import re
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bayesupdate.compute.settings import SERIAL, ComputeSettings
from bayesupdate.correlation import DEFAULT_MAC_THRESHOLD
from bayesupdate.discovery.effects import parse_effect_spec
from bayesupdate.discovery.settings import DiscoverySettings, flat_names
from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.move_kinds import check_adapt_steps
from bayesupdate.inference.pairing import DEFAULT_FREQUENCY_WINDOW, PairingRules


@dataclass(frozen=True)
class ModelConfig:
    """The ``[model]`` table.  units: a Nastran deck's own unit system by name ("in-lbf-s",
    "si", ...: ``nastran.units``) where its WTMASS and moduli do not say it (None: recognized)."""

    source: str = "exhaust"
    options: dict = field(default_factory=dict)
    sensors: tuple = ()
    test_points: dict = field(default_factory=dict)
    units: str | None = None


def percent_of(value, what: str) -> float | None:
    """N of a "N %" text (finite, > 0; ``what`` names the key in the message), None for a value
    that is not a percentage."""
    text = str(value).strip()
    if not text.endswith("%"):
        return None
    try:
        number = float(text[:-1])
    except ValueError:
        raise BayesUpdateError(
            f'{what}: give a number before "%", e.g. "1.5 %", got {value!r}'
        ) from None
    if not (math.isfinite(number) and number > 0):
        raise BayesUpdateError(f"{what}: must be > 0, got {value!r}")
    return number


@dataclass(frozen=True)
class DataConfig:
    """The ``[data]`` table.  modes : 1-based numbers of the source's modes that enter (None:
    all); weights / sd_hz : one value per mode that enters, for any source
    (``inference.data.select_modes``)."""

    source: str | None = "paper:ema"
    frequencies_hz: tuple | None = None
    weights: tuple | None = None
    sd_hz: tuple | None = None
    mass_kg: float | None = None
    mass_sd_kg: float | None = None
    mass: str | float | None = None
    mass_sd: str | float | None = None
    cg: dict | None = None
    inertia: dict | None = None
    modes: tuple | None = None

    def __post_init__(self):
        if self.modes is not None and not all(
            isinstance(m, int) and not isinstance(m, bool) for m in self.modes
        ):
            raise BayesUpdateError(
                f"data.modes: give 1-based mode numbers (integers), got {list(self.modes)!r}"
            )
        self._check_mass_properties()

    def _check_mass_properties(self):
        """The measured mass properties' units, keys and sds checked when the study is read
        (``inference.mass_properties``); they are converted once the model's units are known.
        ``modes``: 1-based mode numbers."""
        from bayesupdate.inference.mass_properties import parse_tables
        from bayesupdate.units import mass_property_value

        if self.modes is not None and not all(
            isinstance(m, int) and not isinstance(m, bool) for m in self.modes
        ):
            raise BayesUpdateError(
                f"data.modes: give 1-based mode numbers (integers), got {list(self.modes)!r}"
            )
        if self.mass is not None and self.mass_kg is not None:
            raise BayesUpdateError("data: give mass or mass_kg, not both")
        if self.mass_sd is not None and self.mass_sd_kg is not None:
            raise BayesUpdateError("data: give mass_sd or mass_sd_kg, not both")
        if self.mass_sd is not None and self.mass is None and self.mass_kg is None:
            raise BayesUpdateError("data.mass_sd: give the measured mass too (data.mass)")
        if self.mass is not None:
            value = mass_property_value(self.mass, "mass", "data.mass")[0]
            if not value > 0:
                raise BayesUpdateError(f"data.mass: must be > 0, got {self.mass!r}")
        if self.mass_sd is not None and percent_of(self.mass_sd, "data.mass_sd") is None:
            if not mass_property_value(self.mass_sd, "mass", "data.mass_sd")[0] > 0:
                raise BayesUpdateError(f"data.mass_sd: must be > 0, got {self.mass_sd!r}")
        parse_tables(self.cg, self.inertia, "data")

    def as_source(self):
        """What ``inference.data.load_modal_data`` takes (the mass is applied by ``prepare``;
        ``modes``, and ``weights`` / ``sd_hz`` of a file source, by ``selection``)."""
        if self.frequencies_hz is not None:
            table = {"frequencies_hz": self.frequencies_hz}
            if self.modes is None:  # without a selection the table's own lengths are checked
                if self.weights is not None:
                    table["weights"] = self.weights
                if self.sd_hz is not None:
                    table["sd_hz"] = self.sd_hz
            return table
        return self.source

    @property
    def label(self) -> str:
        """The source as the study names it (the file, or "[data] frequencies_hz")."""
        return "[data] frequencies_hz" if self.frequencies_hz is not None else str(self.source)

    def selection(self):
        """The ``inference.data.ModeSelection`` applied to the loaded source."""
        from bayesupdate.inference.data import ModeSelection

        inline = self.frequencies_hz is not None and self.modes is None
        return ModeSelection(
            modes=self.modes,
            weights=None if inline else self.weights,
            sd_hz=None if inline else self.sd_hz,
        )


@dataclass(frozen=True)
class TestConfig:
    """The ``[test]`` table: the test geometry and how it is aligned and paired with the model
    (``testgeom``).  align: "auto", "none" or a 3x4 matrix (tuple of 3 rows of 4); pairs:
    ((test node, model node), ...); pair_tolerance [m]."""

    __test__ = False  # not a pytest class

    geometry: str = ""
    align: str | tuple = "auto"
    pairs: tuple = ()
    scale: bool = False
    pair_tolerance: float = 0.01
    length_unit: str | None = None
    model_length_unit: str | None = None
    pair_to: str = "element"

    def settings(self):
        """The ``testgeom.PairingSettings`` of this table."""
        from bayesupdate.testgeom import PairingSettings

        return PairingSettings(self.align, self.pairs, self.scale, self.pair_tolerance,
                               self.pair_to == "element")  # fmt: skip


@dataclass(frozen=True)
class PairingConfig:
    """The ``[pairing]`` table.  mac_threshold / frequency_window : what a MAC pair (test
    shapes) must meet at the reference design (``inference.pairing.PairingRules``)."""

    method: str = "auto"
    extra_modes: int = 2
    mac_threshold: float = DEFAULT_MAC_THRESHOLD
    frequency_window: float = DEFAULT_FREQUENCY_WINDOW

    def __post_init__(self):
        self.rules()  # a bad threshold or window stops the run when the study is read

    def rules(self) -> PairingRules:
        """The ``inference.pairing.PairingRules`` of this table."""
        return PairingRules(self.mac_threshold, self.frequency_window)


@dataclass(frozen=True)
class ObjectiveConfig:
    """The ``[objective]`` table.  mass: the mass term's target with a unit ("13.76 lb") or a
    number in the model's own mass unit, like mass_kg; cg_weight / inertia_weight: weights of
    the measured CG / inertia residuals (``inference.mass_properties``; default: the mass
    term's default weight)."""

    mass_kg: float | None = None
    mass_weight: float | None = None
    use_measured_mass: bool = True
    mac_weight: float = 0.0
    mass: str | float | None = None
    cg_weight: float | None = None
    inertia_weight: float | None = None

    def __post_init__(self):
        from bayesupdate.units import mass_property_value

        if self.mass is not None and self.mass_kg is not None:
            raise BayesUpdateError("objective: give mass or mass_kg, not both")
        if self.mass is not None:
            mass_property_value(self.mass, "mass", "objective.mass")
        for key in ("cg_weight", "inertia_weight"):
            value = getattr(self, key)
            if value is not None and not value >= 0:
                raise BayesUpdateError(f"objective.{key}: must be >= 0, got {value}")


@dataclass(frozen=True)
class OptimizerConfig:
    """The ``[optimizer]`` table (``inference.optimize.CalibrationSettings``), checked when the
    study is read, so a bad value stops a run before any model is solved."""

    starts: int = 16
    method: str = "least_squares"
    design: str = "sobol"
    seed: int = 0
    polish: bool = True

    def __post_init__(self):
        from bayesupdate.inference.optimize import CalibrationSettings

        CalibrationSettings(starts=self.starts, seed=self.seed, method=self.method,
                            design=self.design, polish=self.polish)  # fmt: skip


@dataclass(frozen=True)
class LikelihoodConfig:
    sigma: float | None = 0.05
    sigma_prior: dict | None = None
    mass_sd: float | None = None
    pairing: str = "auto"


#: the sampler's walkers when ``[sampler] walkers`` is not given, at the least (two per sampled
#: dimension above it: ``SamplerConfig.walkers_for``)
DEFAULT_WALKERS = 32


@dataclass(frozen=True)
class SamplerConfig:
    #: None: ``DEFAULT_WALKERS``, or two per sampled dimension where there are more than 16
    #: (the ensemble's moves need at least two per dimension; ``pipelines.study.prepare``
    #: resolves it once the parameters are known, a deck's DESVARs too)
    walkers: int | None = None
    steps: int = 5000
    seed: int = 1
    min_autocorr_times: float = 50.0
    target_rhat: float | None = 1.01
    target_ess: float | None = 400.0
    check_every: int = 500
    predictive_draws: int = 400
    hdi_prob: float = 0.9
    reduced: bool = True
    reduced_tol: float = 1e-4
    screen: bool = True
    transform: str = "logit"
    moves: str = "mixture"
    #: steps of each of the mixture's three adaptation stages (None: the sampler's default,
    #: ``inference.sampling.ADAPT_STEPS``)
    adapt_steps: int | None = None

    def __post_init__(self):
        if self.adapt_steps is not None:
            check_adapt_steps(self.adapt_steps)
        if not (isinstance(self.seed, numbers.Integral) and self.seed >= 0):
            raise BayesUpdateError(f"sampler.seed: must be an integer >= 0, got {self.seed}")
        if not self.min_autocorr_times > 0:  # NaN fails too
            raise BayesUpdateError(
                f"sampler.min_autocorr_times: must be > 0, got {self.min_autocorr_times}"
            )

    def walkers_for(self, ndim: int) -> int:
        """The walkers of a run with ``ndim`` sampled dimensions: the given number, else
        ``DEFAULT_WALKERS`` or 2 ndim, whichever is more."""
        return self.walkers if self.walkers is not None else max(DEFAULT_WALKERS, 2 * ndim)


@dataclass(frozen=True)
class StudyConfig:
    """A whole study.  ``parameters``: {name: {bounds, prior, start}} (checked against the model
    when the problem is built).  ``extensions``: the discovery tables present in the file,
    ``{"effects": tuple of specs, "discovery": DiscoverySettings}``."""

    model: ModelConfig = field(default_factory=ModelConfig)
    data: DataConfig = field(default_factory=DataConfig)
    parameters: dict = field(default_factory=dict)
    pairing: PairingConfig = field(default_factory=PairingConfig)
    objective: ObjectiveConfig = field(default_factory=ObjectiveConfig)
    optimizer: OptimizerConfig = field(default_factory=OptimizerConfig)
    likelihood: LikelihoodConfig = field(default_factory=LikelihoodConfig)
    sampler: SamplerConfig = field(default_factory=SamplerConfig)
    test: TestConfig | None = None
    extensions: dict = field(default_factory=dict)
    path: str = ""

    def to_dict(self) -> dict:
        """Plain dict (JSON-able) of everything but ``path``; stored in result files."""
        out = dataclasses.asdict(self)
        out.pop("path")
        discovery = self.extensions.get("discovery")
        if discovery is not None:  # stored flat, with the names the study file gives the knobs
            out["extensions"]["discovery"] = discovery.flat()
        return out


_SECTIONS = {
    "model": ModelConfig,
    "data": DataConfig,
    "pairing": PairingConfig,
    "objective": ObjectiveConfig,
    "optimizer": OptimizerConfig,
    "likelihood": LikelihoodConfig,
    "sampler": SamplerConfig,
}
_PARAMETER_KEYS = {"bounds": list, "prior": dict, "start": float, "binds": str}


def _check_type(value, annotation, where: str):
    """Convert/validate a TOML value against a field annotation; raises naming ``where``."""
    text = str(annotation)
    allows_none = "None" in text
    if value is None and allows_none:
        return None
    if "bool" in text:
        if isinstance(value, bool):
            return value
        raise BayesUpdateError(f"{where}: must be true or false, got {value!r}")
    if "float" in text and not isinstance(value, bool) and isinstance(value, int | float):
        return float(value)
    if ("int" in text) and isinstance(value, int) and not isinstance(value, bool):
        return value
    if "str" in text and isinstance(value, str):
        return value
    if "dict" in text and isinstance(value, dict):
        return value
    if "tuple" in text and isinstance(value, list):
        return tuple(value)
    wanted = (
        "a number"
        if "float" in text
        else "an integer"
        if "int" in text
        else "a string"
        if "str" in text
        else "a table"
        if "dict" in text
        else "a list"
    )
    raise BayesUpdateError(f"{where}: must be {wanted}, got {type(value).__name__} {value!r}")


def _parse_section(cls, table, where: str):
    if not isinstance(table, Mapping):
        raise BayesUpdateError(f"{where}: must be a table [{where.split(': ')[-1]}]")
    fields = {f.name: f for f in dataclasses.fields(cls)}
    kwargs = {}
    for key, value in table.items():
        if key not in fields:
            raise BayesUpdateError(f"{where}.{key}: unknown key; valid keys are {sorted(fields)}")
        kwargs[key] = _check_type(value, fields[key].type, f"{where}.{key}")
    return cls(**kwargs)


def _parse_parameters(table, where: str) -> dict:
    if not isinstance(table, Mapping):
        raise BayesUpdateError(f"{where}: must hold tables [parameters.NAME]")
    out = {}
    for name, entry in table.items():
        here = f"{where}.{name}"
        if not isinstance(entry, Mapping):
            raise BayesUpdateError(f"{here}: must be a table with bounds, prior, start")
        clean = {}
        for key, value in entry.items():
            if key not in _PARAMETER_KEYS:
                raise BayesUpdateError(
                    f"{here}.{key}: unknown key; valid keys are bounds, prior, start, binds"
                )
            if key == "bounds":
                ok = (
                    isinstance(value, list)
                    and len(value) == 2
                    and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
                )
                if not ok:
                    raise BayesUpdateError(
                        f"{here}.bounds: must be [low, high] numbers, got {value!r}"
                    )
                if not value[0] < value[1]:
                    raise BayesUpdateError(f"{here}.bounds: low must be < high, got {value!r}")
                clean[key] = [float(v) for v in value]
            elif key == "prior":
                if not isinstance(value, dict):
                    raise BayesUpdateError(
                        f'{here}.prior: must be a table like {{ kind = "uniform" }}'
                    )
                clean[key] = dict(value)
            elif key == "binds":
                clean[key] = _check_type(value, "str", f"{here}.{key}")
            else:
                clean[key] = _check_type(value, "float", f"{here}.{key}")
        out[name] = clean
    return out


_DISCOVERY_INT_KEYS = {
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
_DISCOVERY_FLOAT_KEYS = {
    "sigma",
    "threshold_log_odds",
    "margin_ln_bf",
    "effect_prior",
    "bound_tolerance",
    "adequacy_p",
    "max_noise_rel",
    "alpha",
}


def _parse_effects_table(table: Mapping, where: str) -> tuple[str, ...]:
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


def _parse_discovery_table(table: Mapping, where: str) -> DiscoverySettings:
    """``[discovery]`` -> DiscoverySettings (strict keys and types)."""
    valid = flat_names()
    values = {}
    for key, value in table.items():
        here = f"{where}.{key}"
        if key not in valid:
            raise BayesUpdateError(f"{here}: unknown key; valid keys are {valid}")
        if key in _DISCOVERY_INT_KEYS:
            if isinstance(value, bool) or not isinstance(value, int):
                raise BayesUpdateError(f"{here}: must be an integer, got {value!r}")
        elif key in _DISCOVERY_FLOAT_KEYS:
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
    return DiscoverySettings.from_flat(**values)


def _numbers_matrix(value, where: str) -> tuple:
    ok = (
        isinstance(value, list)
        and len(value) == 3
        and all(isinstance(r, list) and len(r) == 4 for r in value)
        and all(isinstance(x, int | float) and not isinstance(x, bool) for r in value for x in r)
    )
    if not ok:
        raise BayesUpdateError(
            f'{where}: give "auto", "none" or a 3x4 matrix [[r11, r12, r13, tx], ...]'
        )
    return tuple(tuple(float(x) for x in r) for r in value)


def _test_pairs(value, where: str) -> tuple:
    ok = isinstance(value, list) and all(
        isinstance(p, list)
        and len(p) == 2
        and all(isinstance(n, int) and not isinstance(n, bool) for n in p)
        for p in value
    )
    if not ok:
        raise BayesUpdateError(f"{where}: give [[test node, model node], ...] (integers)")
    return tuple((int(a), int(b)) for a, b in value)


def parse_test_table(table: Mapping, where: str = "test") -> TestConfig:
    """``[test]`` -> TestConfig (strict keys; lengths and units checked here)."""
    from bayesupdate.testgeom.units import length_unit, parse_length

    if not isinstance(table, Mapping):
        raise BayesUpdateError(f"{where}: must be a table [test]")
    values = dict(table)
    if not isinstance(values.get("geometry"), str) or not values["geometry"]:
        raise BayesUpdateError(f'{where}.geometry: give the test geometry file, e.g. "test.unv"')
    align = values.get("align", "auto")
    if isinstance(align, str):
        if align not in ("auto", "none"):
            raise BayesUpdateError(
                f"{where}.align = {align!r}: give 'auto', 'none' or a 3x4 matrix"
            )
    else:
        values["align"] = _numbers_matrix(align, f"{where}.align")
    if "pairs" in values:
        values["pairs"] = _test_pairs(values["pairs"], f"{where}.pairs")
    if "pair_tolerance" in values:
        values["pair_tolerance"] = parse_length(values["pair_tolerance"], f"{where}.pair_tolerance")
    for key in ("length_unit", "model_length_unit"):
        if key in values:
            values[key] = length_unit(values[key], f"{where}.{key}")
    if values.get("pair_to", "element") not in ("element", "node"):
        raise BayesUpdateError(f"{where}.pair_to: give 'element' or 'node'")
    checked = {k: v for k, v in values.items() if k not in ("align", "pairs", "pair_tolerance")}
    parsed = _parse_section(TestConfig, checked, where)
    return dataclasses.replace(parsed, **{k: values[k] for k in ("align", "pairs",
                               "pair_tolerance") if k in values})  # fmt: skip


# -- the [compute] table and the command's executor (compute.settings) --
#: the environment variable that names a Dask scheduler when neither the command line nor the
#: study file says where to run (``compute_settings``)
SCHEDULER_VARIABLE = "BAYESUPDATE_SCHEDULER"
# tcp://host:port, tls://host:port, or host:port (Dask's default protocol is tcp)
_ADDRESS = re.compile(r"^(?:(tcp|tls|ucx|ws|wss)://)?(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._-]+):(\d+)$")


def check_address(address: str, where: str = "--scheduler") -> str:
    """The Dask scheduler ``address`` if well formed (``[tcp://]host:port``), else a one-line
    error naming ``where`` it came from."""
    text = str(address).strip()
    match = _ADDRESS.match(text)
    if match is None or not 0 < int(match.group(3)) < 65536:
        raise BayesUpdateError(
            f"{where}: {address!r} is not a Dask scheduler address; give tcp://HOST:PORT "
            "(e.g. tcp://head:8786)"
        )
    return text if match.group(1) else f"tcp://{text}"


def parse_compute_table(table, where: str) -> ComputeSettings:
    """The study file's ``[compute]`` table: ``workers = N`` or ``scheduler = "tcp://..."``
    (not both), optional ``retries``.

    Parameters: table, the parsed TOML table; where, the prefix of error messages (file name and
    table).  Returns: the ``compute.settings.ComputeSettings`` it asks for."""
    unknown = sorted(set(table) - {"workers", "scheduler", "retries"})
    if unknown:
        raise BayesUpdateError(
            f"{where}.{unknown[0]}: unknown key; valid keys are ['retries', 'scheduler', 'workers']"
        )
    for key in ("workers", "retries"):
        if key in table and (isinstance(table[key], bool) or not isinstance(table[key], int)):
            raise BayesUpdateError(f"{where}.{key}: must be an integer, got {table[key]!r}")
    if "workers" in table and "scheduler" in table:
        raise BayesUpdateError(f"{where}: give workers or scheduler, not both")
    scheduler = table.get("scheduler")
    if scheduler is not None:
        scheduler = check_address(scheduler, f"{where}.scheduler")
    return ComputeSettings(table.get("workers", 1), scheduler, table.get("retries", 2))


def compute_settings(
    workers: int | None = None,
    scheduler: str | None = None,
    study: ComputeSettings | None = None,
    environ=None,
) -> ComputeSettings:
    """The executor settings of a command: ``--workers``/``--scheduler`` (not both), else the
    study file's ``[compute]``, else ``BAYESUPDATE_SCHEDULER``, else serial.

    Parameters: workers, ``--workers`` (local processes, >= 1) or None; scheduler,
    ``--scheduler`` (a Dask scheduler address) or None; study, the study file's ``[compute]``
    (``parse_compute_table``) or None; environ, the environment to read
    ``BAYESUPDATE_SCHEDULER`` from (None: ``os.environ``).  Returns: a ``ComputeSettings``."""
    if workers is not None and scheduler is not None:
        raise BayesUpdateError("give --workers (local processes) or --scheduler (Dask), not both")
    retries = (study or SERIAL).retries
    if workers is not None:
        if workers < 1:
            raise BayesUpdateError(f"--workers: must be >= 1, got {workers}")
        return ComputeSettings(workers, None, retries)
    if scheduler is not None:
        return ComputeSettings(1, check_address(scheduler), retries)
    if study is not None and study != SERIAL:
        return study
    env = (os.environ if environ is None else environ).get(SCHEDULER_VARIABLE, "").strip()
    if env:
        return ComputeSettings(1, check_address(env, SCHEDULER_VARIABLE), retries)
    return SERIAL


#: the discovery tables: the study file knows discovery's settings record directly
_EXTENSION_TABLES: dict[str, Callable[[Mapping, str], Any]] = {
    "effects": _parse_effects_table,
    "discovery": _parse_discovery_table,
    "compute": parse_compute_table,
}


def parse_study(document: Mapping, where: str = "study") -> StudyConfig:
    """StudyConfig from a parsed TOML document; ``where`` prefixes error messages (file name)."""
    kwargs: dict[str, Any] = {}
    extensions = {}
    for key, table in document.items():
        if key in _SECTIONS:
            kwargs[key] = _parse_section(_SECTIONS[key], table, f"{where}: {key}")
        elif key == "parameters":
            kwargs[key] = _parse_parameters(table, f"{where}: parameters")
        elif key == "test":
            kwargs[key] = parse_test_table(table, f"{where}: test")
        elif key in _EXTENSION_TABLES:
            extensions[key] = _EXTENSION_TABLES[key](table, f"{where}: {key}")
        else:
            valid = sorted([*_SECTIONS, "parameters", "test", *_EXTENSION_TABLES])
            raise BayesUpdateError(f"{where}: unknown table [{key}]; valid tables are {valid}")
    likelihood = document.get("likelihood", {})
    if "sigma_prior" in likelihood and "sigma" not in likelihood:
        # sigma inferred: the default fixed value no longer applies
        kwargs["likelihood"] = dataclasses.replace(kwargs["likelihood"], sigma=None)
    data = kwargs.get("data")
    if data is not None and "source" not in document.get("data", {}):
        if data.frequencies_hz is None:
            raise BayesUpdateError(f"{where}: data: give source = ... or frequencies_hz = [...]")
        kwargs["data"] = dataclasses.replace(data, source=None)
    if data is not None and "source" in document["data"] and data.frequencies_hz is not None:
        raise BayesUpdateError(f"{where}: data: give source or frequencies_hz, not both")
    model = kwargs.get("model")
    if "test" in kwargs and model is not None and model.test_points:
        raise BayesUpdateError(
            f"{where}: give [test] geometry or [model.test_points], not both (the geometry "
            "pairs the test points with the model by position)"
        )
    return StudyConfig(**kwargs, extensions=extensions, path=where)


def load_study(path: str | os.PathLike) -> StudyConfig:
    """Read and validate a TOML study file."""
    path = Path(path)
    try:
        with path.open("rb") as fh:
            document = tomllib.load(fh)
    except FileNotFoundError as exc:
        raise BayesUpdateError(f"{path}: study file not found") from exc
    except OSError as exc:
        raise BayesUpdateError(f"{path}: cannot read ({exc.strerror})") from exc
    except tomllib.TOMLDecodeError as exc:
        raise BayesUpdateError(f"{path}: not valid TOML ({exc})") from exc
    except UnicodeDecodeError as exc:
        raise BayesUpdateError(f"{path}: not UTF-8 text ({exc.reason}); save it as UTF-8") from exc
    if not document:
        # an empty file would silently run the default study (exhaust vs paper data)
        raise BayesUpdateError(f"{path}: empty study file; give at least [model] and [data]")
    return dataclasses.replace(parse_study(document, str(path)), path=str(path))


def with_overrides(study: StudyConfig, **changes) -> StudyConfig:
    """Copy of ``study`` with command-line overrides such as ``sampler__seed=3`` applied
    (``None`` values are ignored)."""
    sections: dict[str, dict] = {}
    top = {}
    for key, value in changes.items():
        if value is None:
            continue
        if "__" in key:
            section, name = key.split("__", 1)
            sections.setdefault(section, {})[name] = value
        else:
            top[key] = value
    for section, values in sections.items():
        top[section] = dataclasses.replace(getattr(study, section), **values)
    return dataclasses.replace(study, **top)
