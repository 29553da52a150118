"""Unit conversion at the edges: values typed by users (``2.08mm``, ``8.9e-9t/mm3``) to SI.

Inside the package every number is SI (m, kg, kg/m^3, Pa, N/m).  The seed paper writes thickness in
mm and density in t/mm^3 (1 t/mm^3 = 1e12 kg/m^3).
"""

import re

import numpy as np

from bayesupdate.errors import BayesUpdateError

#: unit suffix -> factor to SI
UNITS = {
    "": 1.0,
    "m": 1.0,
    "mm": 1e-3,
    "cm": 1e-2,
    "kg/m3": 1.0,
    "kg/m^3": 1.0,
    "t/mm3": 1e12,
    "t/mm^3": 1e12,
    "g/cm3": 1e3,
    "g/cm^3": 1e3,
    "kg": 1.0,
    "g": 1e-3,
    "t": 1e3,
    "pa": 1.0,
    "mpa": 1e6,
    "gpa": 1e9,
    "n/m": 1.0,
    "nm/rad": 1.0,
    "n*m/rad": 1.0,
    "hz": 1.0,
}
_NUMBER = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*([A-Za-z/^*0-9]*)\s*$")


def parse_quantity(text: str, what: str = "value") -> float:
    """'2.08mm' -> 0.00208; '8.9e-9 t/mm3' -> 8900.0; '1e-3' -> 0.001 (SI assumed)."""
    match = _NUMBER.match(str(text))
    if not match:
        raise BayesUpdateError(f"{what}: cannot read {text!r} as a number with an optional unit")
    number, unit = match.groups()
    factor = UNITS.get(unit.lower())
    if factor is None:
        raise BayesUpdateError(
            f"{what}: unknown unit {unit!r} in {text!r}; use one of "
            f"{sorted(u for u in UNITS if u)} or SI without a unit"
        )
    return float(number) * factor


def parse_assignments(items, what: str = "--set") -> dict[str, float]:
    """['t_hot_pipe=2mm', 'rho_catalyst=8900'] -> {'t_hot_pipe': 0.002, 'rho_catalyst': 8900.0}."""
    out = {}
    for item in items or ():
        if "=" not in item:
            raise BayesUpdateError(f"{what} {item!r}: expected NAME=VALUE, e.g. t_hot_pipe=2.08mm")
        name, value = item.split("=", 1)
        name = name.strip()
        if not name:
            raise BayesUpdateError(f"{what} {item!r}: missing parameter name before '='")
        out[name] = parse_quantity(value, f"{what} {name}")
    return out


# -- mass properties: a number with a compound unit (``13.76 lb``, ``9560 lb in^2``) ---------------

#: base unit -> (factor to SI, dimension exponents (mass, length, time)).  "lb" is the pound-mass
#: (0.45359237 kg exactly, NIST SP 811 appendix B); "lbf" the pound-force (lb x 9.80665 m/s^2)
BASE_UNITS = {
    "kg": (1.0, (1, 0, 0)),
    "g": (1e-3, (1, 0, 0)),
    "t": (1e3, (1, 0, 0)),
    "lb": (0.45359237, (1, 0, 0)),
    "lbm": (0.45359237, (1, 0, 0)),
    "slug": (0.45359237 * 9.80665 / 0.3048, (1, 0, 0)),
    "m": (1.0, (0, 1, 0)),
    "mm": (1e-3, (0, 1, 0)),
    "cm": (1e-2, (0, 1, 0)),
    "in": (0.0254, (0, 1, 0)),
    "ft": (0.3048, (0, 1, 0)),
    "s": (1.0, (0, 0, 1)),
    "n": (1.0, (1, 1, -2)),
    "lbf": (0.45359237 * 9.80665, (1, 1, -2)),
}
#: dimension (mass, length, time) of each kind of mass property
DIMENSIONS = {"mass": (1, 0, 0), "length": (0, 1, 0), "inertia": (1, 2, 0)}
_EXAMPLES = {"mass": "kg, g, t, lb, slug, lbf s^2/in", "length": "m, mm, cm, in, ft",
             "inertia": "kg m^2, lb in^2, lbf s^2 in, slug ft^2"}  # fmt: skip
_TOKEN = re.compile(r"^([a-z]+)(?:\^?([-+]?\d+))?$")
_VALUE = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


def compound_unit(unit: str, kind: str, what: str) -> float:
    """SI factor of a compound unit of a mass property: products of ``BASE_UNITS`` with
    optional powers, one ``/`` for a denominator (``"lbf s^2/in"`` = 175.127 kg,
    ``"lb in^2"``, ``"kg*m^2"``), checked against the dimension of ``kind`` (``DIMENSIONS``).

    Raises ``BayesUpdateError`` naming ``what`` and the known units for an unknown unit or a
    wrong dimension (a weight in lbf where a mass is meant)."""
    known = f"known units: {', '.join(BASE_UNITS)}; e.g. {_EXAMPLES[kind]}"
    factor, dims = 1.0, np.zeros(3, int)
    parts = unit.lower().replace("·", " ").split("/")
    if len(parts) > 2 or not parts[0].strip():
        raise BayesUpdateError(f"{what}: cannot read the unit {unit!r}; {known}")
    for sign, part in zip((1, -1), parts, strict=False):
        for token in part.replace("*", " ").split():
            match = _TOKEN.match(token)
            if not match or match.group(1) not in BASE_UNITS:
                raise BayesUpdateError(f"{what}: unknown unit {token!r} in {unit!r}; {known}")
            f, d = BASE_UNITS[match.group(1)]
            power = sign * int(match.group(2) or 1)
            factor *= f**power
            dims += power * np.array(d)
    if tuple(dims) != DIMENSIONS[kind]:
        hint = ""
        if kind == "mass" and tuple(dims) == (1, 1, -2):  # a weight: its mass has its number
            hint = " (a weight; give the mass, e.g. '13.76 lb' for a weight of 13.76 lbf)"
        raise BayesUpdateError(f"{what}: {unit!r} is not a {kind} unit{hint}; {known}")
    return factor


def mass_property_value(value, kind: str, what: str) -> tuple[float, bool]:
    """A measured mass property as the study file gives it -> (value, in SI?).

    value : a number (the model's own unit: returned as it stands, flagged False) or a string
    "number unit" (``"13.76 lb"``, ``"9560 lb in^2"``, ``"8.2 in"``; converted to SI, flagged
    True; a string without a unit is a number in the model's unit).  kind : "mass", "length"
    or "inertia" (``DIMENSIONS``)."""
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise BayesUpdateError(f"{what}: give a number or a string like {_first_example(kind)}")
    if not isinstance(value, str):
        return float(value), False
    match = _VALUE.match(value)
    if not match:
        raise BayesUpdateError(
            f"{what}: cannot read {value!r}; give a number and a unit like {_first_example(kind)}"
        )
    number, unit = match.groups()
    if not unit:
        return float(number), False
    return float(number) * compound_unit(unit, kind, what), True


def _first_example(kind: str) -> str:
    return {"mass": "'13.76 lb'", "length": "'8.2 in'", "inertia": "'9560 lb in^2'"}[kind]
