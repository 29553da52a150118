"""Unit conversion at the edges: values typed by users (``2.08mm``, ``8.9e-9t/mm3``) to SI.

Inside the package every number is SI (m, kg, kg/m^3, Pa, N/m).  The seed paper writes thickness in
mm and density in t/mm^3 (1 t/mm^3 = 1e12 kg/m^3).
"""

import re

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
