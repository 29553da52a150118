"""Length units of a test geometry: a ``length_unit`` setting or the UFF 164 units record.

A test's coordinates are held in metres inside (``TestGeometry.xyz``); the unit a file was
written in is converted once, when it is read.  UFF dataset 164 ("Units", I-DEAS universal file
format) record 2 holds factors that convert SI to file units ("to convert from universal file
units to SI divide by the appropriate factor"): 1000 for mm, 39.37 for inches, so a length in
metres is the file's value / the length factor.
"""

import math

from bayesupdate.errors import BayesUpdateError

#: metres per unit of each accepted length unit name
METRES_PER = {
    "m": 1.0,
    "mm": 1e-3,
    "cm": 1e-2,
    "in": 0.0254,
    "ft": 0.3048,
}
_ALIASES = {
    "meter": "m",
    "metre": "m",
    "meters": "m",
    "metres": "m",
    "millimeter": "mm",
    "millimetre": "mm",
    "inch": "in",
    "inches": "in",
    "foot": "ft",
    "feet": "ft",
}
#: UFF 164 units code of each unit this package writes (1 SI, 2 BG foot, 5 mm, 6 cm, 7 inch)
UFF_UNITS_CODE = {"m": 1, "ft": 2, "mm": 5, "cm": 6, "in": 7}


def length_unit(text, where: str = "length_unit") -> str:
    """The canonical name (``m``, ``mm``, ``cm``, ``in``, ``ft``) of a length unit; a one-line
    ``BayesUpdateError`` naming ``where`` for anything else."""
    name = str(text).strip().lower()
    name = _ALIASES.get(name, name)
    if name not in METRES_PER:
        raise BayesUpdateError(
            f"{where} = {text!r}: unknown length unit; use one of {sorted(METRES_PER)}"
        )
    return name


def unit_of_uff164(length_factor: float, where: str) -> tuple[str, float]:
    """(unit name, metres per file unit) of a UFF 164 record's length factor (file units per
    metre: 1000 for mm, 39.37 for inches).  A factor matching none of ``METRES_PER`` within
    1e-6 is named ``"uff164"`` and used as it stands."""
    if not (math.isfinite(length_factor) and length_factor > 0):
        raise BayesUpdateError(
            f"{where}: UFF 164 length factor {length_factor!r} is not a positive number"
        )
    metres = 1.0 / length_factor
    for name, value in METRES_PER.items():
        if abs(metres / value - 1.0) < 1e-6:
            return name, value
    return "uff164", metres


def parse_length(value, where: str) -> float:
    """A length in metres: a number (metres) or a string ``"5 mm"``, ``"0.2in"``."""
    if isinstance(value, int | float) and not isinstance(value, bool):
        number, unit = float(value), "m"
    else:
        text = str(value).strip()
        split = len(text.rstrip("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"))
        try:
            number = float(text[:split])
        except ValueError:
            raise BayesUpdateError(
                f"{where} = {value!r}: give a length, e.g. 0.005 (m) or '5 mm'"
            ) from None
        try:
            unit = length_unit(text[split:] or "m", where)
        except BayesUpdateError:
            raise BayesUpdateError(
                f"{where} = {value!r}: unknown length unit; use one of {sorted(METRES_PER)}"
            ) from None
    if not (math.isfinite(number) and number > 0):
        raise BayesUpdateError(f"{where} = {value!r}: must be a positive length")
    return number * METRES_PER[unit]
