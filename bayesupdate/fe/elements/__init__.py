"""Element families, one file each: the element arrays of a family as a frozen dataclass and its
element matrices vectorised over elements (SI units, global axes).

* ``beam``: tube beams of the exhaust (Timoshenko, Przemieniecki 1968);
* ``general_beam``: general 3-D beams (Nastran CBAR/CBEAM: sections, offsets, pin flags);
* ``rod``: axial rods (CROD/CONROD);
* ``shell`` and ``shell_tria``: flat shells, quads and triangles (CQUAD4/CTRIA3);
* ``spring``: six-component springs, two-node or grounded (CBUSH);
* ``point_mass``: rigid point masses with inertia and offset (CONM2);
* ``scalar_mass``: scalar masses (CMASS1/CMASS2);
* ``damper``: viscous dampers (data: normal modes ignore them).

``base`` holds the interface of a family without design parameters (``ElementFamily``) and the
registry (``FAMILIES``, ``register``) that assembly, modal energies, the total mass and the
reduced basis loop over (``families_of``).
"""

# importing the families registers them (``base.register``), in this order of assembly
from bayesupdate.fe.elements import general_beam, rod, scalar_mass  # noqa: F401, E402
from bayesupdate.fe.elements.base import (  # noqa: E402
    ElementFamily,
    ElementSettings,
    families_of,
    register,
)

__all__ = ["ElementFamily", "ElementSettings", "families_of", "register"]

# scalar springs between any two DOFs or to ground (CELAS1/CELAS2): registered last, held in
# ``Structure.elements``
from bayesupdate.fe.elements import scalar_spring  # noqa: E402, F401, I001
