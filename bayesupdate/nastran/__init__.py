"""Nastran bulk data in: a user's deck (.bdf, .dat, .nas, .blk) as an FE model.

``load_nastran_model(path)`` reads the deck with pyNastran (optional extra:
``pip install bayesupdate[nastran]``), converts it to a ``Structure`` (``reader``) and returns an
``FEModel`` whose ``structure.metadata["nastran"]`` records the units, PARAMs and notes.
"""

from bayesupdate.nastran.deck import SUFFIXES, is_nastran_path

__all__ = ["SUFFIXES", "is_nastran_path", "load_nastran_model"]


def load_nastran_model(path, **options):
    """``FEModel`` of the Nastran deck at ``path`` (no parameters yet: the deck's values)."""
    from bayesupdate.errors import BayesUpdateError
    from bayesupdate.fe.model import FEModel
    from bayesupdate.nastran.reader import build_structure

    if options:
        raise BayesUpdateError(f"Nastran model {path}: options {sorted(options)} not accepted")
    structure, info = build_structure(path)
    if not _has_mass(structure):
        raise BayesUpdateError(
            f"Nastran model {path}: the deck has no mass (MAT1 RHO, NSM, CONM2 all zero)"
        )
    return FEModel(structure, {}, {}, {}, name=info["deck"])


def _has_mass(structure) -> bool:
    s = structure
    shells = s.shells is not None and bool(
        (s.shells.rho > 1e-200).any() or (s.shells.nsm > 0).any()
    )
    lines = any(x is not None and x.has_mass() for x in (s.general_beams, s.rods))
    return bool(shells or lines or (s.beam_rho > 1e-200).any() or (s.mass_value > 0).any())
