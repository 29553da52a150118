"""Element families, one file each: the element arrays of a family as a frozen dataclass and its
element matrices vectorized over elements (SI units, global axes).

* ``beam``: tube beams of the exhaust (Timoshenko, Przemieniecki 1968);
* ``general_beam``: general 3-D beams (Nastran CBAR/CBEAM: sections, offsets, pin flags);
* ``rod``: axial rods (CROD/CONROD);
* ``shell`` and ``shell_tria``: flat shells, quads and triangles (CQUAD4/CTRIA3);
* ``spring``: six-component springs, two-node or grounded (CBUSH);
* ``point_mass``: rigid point masses with inertia and offset (CONM2);
* ``scalar_mass``: scalar masses (CMASS1/CMASS2);
* ``tetra``: linear tetrahedra (CTETRA with four GRIDs);
* ``hexa``: eight-node bricks (CHEXA with eight GRIDs; Nastran's assumed-strain brick);
  both solids derive from ``solid.Solids`` (their record and factors);
* ``shear_panel``: Garvey's shear panels (CSHEAR);
* ``damper``: viscous dampers (data: normal modes ignore them).

``base`` holds the two interfaces: a family whose properties are design parameters
(``ParametricFamily``: tube beams, point masses, springs; registry ``PARAMETRIC``,
``register_parametric``) and a family without them (``ElementFamily``: general beams, rods,
scalar masses; registry ``FAMILIES``, ``register``).  A parametric family declares the
properties a parameter binds on it (``Bindable``: name, field, how it enters K and M) in its own
file.  Assembly, modal energies, the total mass, the parameter bindings and the reduced basis
loop over both (``parametric_of``, ``families_of``, ``base.bindable``).
"""

# importing the families registers them (``base.register``, ``base.register_parametric``), in
# this order of assembly: the parametric families first, then the others
from bayesupdate.fe.elements import beam, point_mass, spring  # noqa: F401, E402, I001
from bayesupdate.fe.elements import general_beam, rod, scalar_mass  # noqa: F401, E402
from bayesupdate.fe.elements.base import (  # noqa: E402
    Bindable,
    ElementFamily,
    ElementSettings,
    ParametricFamily,
    families_of,
    parametric_of,
    register,
    register_parametric,
)

__all__ = [
    "Bindable",
    "ElementFamily",
    "ElementSettings",
    "ParametricFamily",
    "families_of",
    "parametric_of",
    "register",
    "register_parametric",
]

# scalar springs between any two DOFs or to ground (CELAS1/CELAS2), linear tetrahedra (CTETRA),
# bricks (CHEXA) and shear panels (CSHEAR): registered last, held in ``Structure.elements``
from bayesupdate.fe.elements import scalar_spring, tetra, hexa, shear_panel  # noqa: E402, F401, I001
