"""Nastran bulk data in: a user's deck (.bdf, .dat, .nas, .blk) as an FE model.

``load_nastran_model(path)`` reads the deck with the package's own bulk-data reader (``deck``,
``bulk``: no extra needed), converts it to a ``Structure`` (``reader``) and returns an
``FEModel`` whose ``structure.metadata["nastran"]`` records the units, PARAMs and notes.
"""

from bayesupdate.nastran.deck import SUFFIXES, is_nastran_path

__all__ = ["SUFFIXES", "is_nastran_path", "load_nastran_model"]


def load_nastran_model(
    path, parameters=None, test_labels=(), test_points=None, units=None, strict=True, **options
):
    """``NastranModel`` of the deck at ``path``.

    parameters : the study's ``{name: {binds, bounds, ...}}`` tables (``nastran.bindings``); none:
    the deck's DESVARs (``nastran.desvar``) if it has any, else no parameters.
    test_labels : test DOF labels the model reads shapes at (``nastran.test_points``);
    test_points : ``[model.test_points]`` {test node: GRID id}; units : the deck's unit system
    by name (``units.NAMED``: "in-lbf-s", "si", ...) instead of the one recognized from WTMASS
    and the MAT1 moduli; strict : where the DESVARs become the parameters, refuse each DVPREL1
    on a field that cannot be bound (a command that fits them); False (``modes``,
    ``correlate``, ``sensitivity``: the model at its own values) leaves such a DESVAR out,
    named in the note with the others (``desvar.unbound_note``)."""
    from bayesupdate.errors import BayesUpdateError
    from bayesupdate.nastran.bindings import refuse_differing
    from bayesupdate.nastran.model import NastranModel, deck_bindings
    from bayesupdate.nastran.reader import read_structure
    from bayesupdate.nastran.test_points import with_test_points

    if options:
        raise BayesUpdateError(f"Nastran model {path}: options {sorted(options)} not accepted")
    structure, info, deck = read_structure(path, design=strict and not parameters)
    if units is not None:
        from bayesupdate.nastran.units import named_system

        info["units"] = named_system(units, info["wtmass"])
    if not _has_mass(structure):
        raise BayesUpdateError(
            f"Nastran model {path}: the deck has no mass (MAT1 RHO, NSM, CONM2 all zero)"
        )
    if test_labels:
        structure = with_test_points(structure, test_labels, test_points, info["deck"])
    if not parameters and deck.of("DESVAR"):
        from bayesupdate.nastran.desvar import desvar_parameters, unbound_note

        parameters = desvar_parameters(deck, strict)
        note = unbound_note(deck, parameters)
        if note:
            info["notes"].append(note)
    refuse_differing(parameters or {}, deck)
    bindings, defaults, bounds = deck_bindings(parameters or {}, deck, structure)
    _refuse_tapered(bindings, deck)
    return NastranModel(
        structure, bindings, defaults, bounds, name=info["deck"], deck=path, bdf=deck
    )


def _has_mass(structure) -> bool:
    from bayesupdate.fe.elements.base import held_families

    s = structure
    shells = s.shells is not None and bool(
        (s.shells.rho > 1e-200).any() or (s.shells.nsm > 0).any()
    )
    families = any(f.has_mass() for f in held_families(s))  # lines, scalar masses, solids
    # 1e-200: the 1e-300 that stands in for a zero RHO (a rod's lumped end masses) is no mass
    points = bool((s.mass_value > 1e-200).any() or (abs(s.mass_inertia) > 1e-200).any())
    return bool(shells or families or points or (s.beam_rho > 1e-200).any())


def _refuse_tapered(bindings, deck) -> None:
    """A binding writes one value at every PBEAM / PBEAML station (``bindings.set_field``),
    which would make a tapered one constant: refused, naming the parameter and the card."""
    from bayesupdate.errors import BayesUpdateError
    from bayesupdate.nastran.cards.beams import is_tapered, library_is_tapered

    tapered = {"PBEAM": is_tapered, "PBEAML": library_is_tapered}
    for name, b in bindings.items():
        kind = b.field.card
        for i in b.field.ids if kind in tapered else ():
            card = deck.table(kind).get(i)
            if card is not None and tapered[kind](card):
                raise BayesUpdateError(
                    f"parameter {name}: binds {b.target!r}: {kind} {i} ({card.where}) is "
                    f"tapered and a binding sets one value at every station; bind a constant "
                    f"{kind}"
                )
