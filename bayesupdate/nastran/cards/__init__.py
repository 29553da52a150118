"""Nastran line, point, spring, rigid and solid cards -> ``StructureBuilder`` calls or element
families: one file per card family, one registry.

Each family module (``beams``, ``rods``, ``masses``, ``springs``, ``rigid``, ``solids``,
``shear``) names
its ``CARDS`` and has ``add(ctx)``, which converts them card by card (``common.Context.each``: a
refused card is recorded and the next converted); a family the builder has no call for (scalar
springs, solids) is added to the built structure by a ``Context.finishers`` entry.
``FAMILIES`` is the registry, in the order the reader adds them.  A new card family is one new
file here plus its registrations: an entry in ``FAMILIES`` (its ``CARDS`` join
``deck.ELEMENT_CARDS``), its cards' field tables (``bulk.FIELDS``), its element and property
names (``common.ELEMENTS`` / ``PROPERTIES``, ``deck.FAMILIES``' id spaces) and its GRID fields
(``GRID_FIELDS``).  Shells (thousands) are converted as arrays in ``reader``.
"""

from bayesupdate.nastran.cards import (
    beams,
    laminates,
    masses,
    rigid,
    rods,
    scalar,
    shear,
    solids,
    springs,
)
from bayesupdate.nastran.cards.beams import L_DIMS, L_SECTIONS, library_dims, pbeam_layout
from bayesupdate.nastran.cards.common import (
    ELEMENTS,
    PROPERTIES,
    Context,
    Mat1,
    _by_id,
    components,
    id_list,
    mat1,
    material,
)
from bayesupdate.nastran.cards.rigid import rbe3_groups
from bayesupdate.nastran.cards.rods import rod_values
from bayesupdate.nastran.cards.springs import pbush_k, pbush_lines

#: the card families, in the order the reader adds them (scalar points first: elements use them)
FAMILIES = (scalar, beams, rods, masses, springs, rigid, solids, shear)

# the line families, re-built alone where a binding changes them (``nastran.lines``)
add_beams, add_rods = beams.add, rods.add

#: the grid fields of each element card (RBE2 / RBE3 lists: ``element_grids``)
GRID_FIELDS = {
    "CBAR": ("GA", "GB"), "CBEAM": ("GA", "GB"), "CROD": ("G1", "G2"), "CONROD": ("G1", "G2"),
    "CTUBE": ("G1", "G2"),
    "CBUSH": ("GA", "GB"), "CELAS1": ("G1", "G2"), "CELAS2": ("G1", "G2"), "CONM2": ("G",),
    "CONM1": ("G",), "CMASS1": ("G1", "G2"), "CMASS2": ("G1", "G2"), "RBAR": ("GA", "GB"),
    "CELAS3": (), "CELAS4": (), "CMASS3": (), "CMASS4": (),
    "RBE2": ("GN",), "RBE3": ("REFGRID",), "CQUAD4": ("G1", "G2", "G3", "G4"),
    "CTRIA3": ("G1", "G2", "G3"), "CTETRA": tuple(f"G{i}" for i in range(1, 11)),
    "CHEXA": tuple(f"G{i}" for i in range(1, 21)), "CSHEAR": ("G1", "G2", "G3", "G4"),
}  # fmt: skip


def element_grids(card) -> list[int]:
    """GRID ids an element card connects (blank fields skipped)."""
    ids = [card[f] for f in GRID_FIELDS[card.name]]
    if card.name == "RBE2":
        ids += id_list(card, 3)
    elif card.name == "RBE3":
        ids += [g for _, _, gs in rbe3_groups(card) for g in gs]
    return [int(i) for i in ids if isinstance(i, int) and i > 0]
