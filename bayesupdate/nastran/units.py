"""The unit system a Nastran deck is written in.

Nastran has no units: a deck is in any consistent set.  The set is recognized from PARAM WTMASS
(1 / 386.09 = 1 / g in in/s^2: weights in lbf, lengths in inches; 1 / 32.174: feet) or else from
the Young's moduli (most of them within steel to aluminium in Pa, MPa or psi); it is reported,
never converted: the model works in the deck's own units (mass = WTMASS x the deck's mass and
density input).
"""

import numpy as np

#: (name, E range of steel to aluminium in this system, length, force, mass unit after WTMASS)
_SYSTEMS = (
    ("SI (m, N, kg, s)", (5e10, 3e11), "m", "N", "kg"),
    ("mm, N, t, s", (5e4, 3e5), "mm", "N", "t (1000 kg)"),
    ("in, lbf, s", (7e6, 4.5e7), "in", "lbf", "lbf s^2/in"),
)


#: 1 / WTMASS of decks whose mass input is weight: standard gravity in the length unit
_GRAVITY = (("in, lbf, s", 386.088, "in"), ("ft, lbf, s", 32.174, "ft"))


def unit_system(moduli, wtmass: float) -> dict:
    """A record of the deck's units from WTMASS and its MAT1 moduli (any shape)."""
    for name, g, length in _GRAVITY:
        if wtmass > 0 and abs(1.0 / (wtmass * g) - 1.0) < 0.01:
            return dict(
                system=name, length=length, force="lbf", mass=f"lbf s^2/{length}", time="s",
                wtmass=wtmass, weight="lbf",
                basis=f"PARAM WTMASS {wtmass:g} = 1/{1 / wtmass:.1f}: weight input in lbf, "
                f"g = {g} {length}/s^2; values are the deck's own",
            )  # fmt: skip
    E = np.asarray(moduli, dtype=float).ravel()
    for name, (lo, hi), length, force, mass in _SYSTEMS:
        if E.size and np.mean((E >= lo) & (E <= hi)) > 0.5:
            return dict(
                system=name,
                length=length,
                force=force,
                mass=mass,
                time="s",
                wtmass=wtmass,
                basis="recognized from the MAT1 Young's moduli; values are the deck's own",
            )
    return dict(
        system="the deck's own consistent units (not recognized)",
        length="deck length",
        force="deck force",
        mass="deck mass x WTMASS",
        time="s",
        wtmass=wtmass,
        basis="MAT1 moduli match no common system; values are the deck's own",
    )


#: unit systems a study may name (``[model] units``): (system, length, force, mass unit)
NAMED = {
    "si": ("SI (m, N, kg, s)", "m", "N", "kg"),
    "mm-n-t-s": ("mm, N, t, s", "mm", "N", "t (1000 kg)"),
    "in-lbf-s": ("in, lbf, s", "in", "lbf", "lbf s^2/in"),
    "ft-lbf-s": ("ft, lbf, s", "ft", "lbf", "lbf s^2/ft"),
}


def named_system(name: str, wtmass: float) -> dict:
    """The record of a unit system the user names (``NAMED``), instead of the recognized one."""
    from bayesupdate.errors import BayesUpdateError

    key = str(name).strip().lower()
    if key not in NAMED:
        raise BayesUpdateError(f"model units = {name!r}: give one of {', '.join(NAMED)}")
    system, length, force, mass = NAMED[key]
    return dict(system=system, length=length, force=force, mass=mass, time="s", wtmass=wtmass,
                basis="named by the study ([model] units); values are the deck's own")  # fmt: skip
