"""The parametric element families (``fe.elements.base.ParametricFamily``: tube beams, point
masses, springs) under the one assembler loop (``fe.assembly.Assembler``).

* The assembler's K and M are the element matrices of every family, placed at their DOFs: an
  independent dense sum of the ``FamilyMatrices`` it returns reproduces them.
* Re-assembly recomputes only the elements whose properties changed: after a first assembly at
  other values, K and M are bit-identical to a fresh assembler's at the new values.
* A linear family's matrix is linear in its factor (``ParametricFamily.linear``), to round-off.
* The total mass (a loop over the families' own formulas) equals the rigid-body functional
  m = (1/3) sum_i r_i^T M r_i of the assembled M, and the centre of gravity its first moments.
* The line families share n_elements, dofs and has_mass (``base.LineElements``).
"""

import re
from dataclasses import replace

import numpy as np
import pytest

from bayesupdate.fe import STEEL, StructureBuilder, circular_tube
from bayesupdate.fe.assembly import Assembler
from bayesupdate.fe.elements import base
from bayesupdate.fe.elements.beam import TubeBeams
from bayesupdate.fe.elements.point_mass import PointMasses
from bayesupdate.fe.elements.spring import Springs
from bayesupdate.fe.rotations import rigid_body_basis
from bayesupdate.fe.standard_sections import tube_section


def _structure():
    """A bent tube (two runs) with an offset point mass, a grounded spring, a two-node spring
    with an offset location and a rod brace."""
    b = StructureBuilder()
    tube = circular_tube(0.05, 0.002)
    n0, n1, n2 = b.add_node([0, 0, 0]), b.add_node([1.0, 0, 0]), b.add_node([1.0, 0.8, 0.3])
    run_a = b.add_line(n0, n1, tube, STEEL, "pipe_a", element_length=0.25)
    run_b = b.add_line(n1, n2, tube, STEEL, "pipe_b", element_length=0.25)
    b.add_point_mass(run_a[2], 1.3, "box", inertia=np.diag([0.01, 0.02, 0.03]), offset=(0, 0.1, 0))
    b.add_point_mass(run_b[1], 0.4, "box")
    b.add_spring(n0, None, [2e5, 3e5, 4e5, 1e3, 2e3, 3e3], "mount")
    b.add_spring(run_a[3], run_b[2], [1e4] * 3 + [10.0] * 3, "link", location=[1.0, 0.2, 0.1])
    b.add_rods([(n0, n2)], 1e-4, STEEL, "brace")
    return b.build()


def _dense(elements, n_dof):
    """Dense K, M from the families' element matrices: sum_e P_e^T X_e P_e."""
    K, M = np.zeros((n_dof, n_dof)), np.zeros((n_dof, n_dof))
    for f in elements:
        for X, A in ((f.K, K), (f.M, M)):
            if X is None:
                continue
            for dofs, Xe in zip(f.dofs, X, strict=True):
                # add.at: a grounded spring repeats node A's DOFs (its B blocks are zero)
                np.add.at(A, np.ix_(dofs, dofs), Xe)
    return K, M


def _props(a, factor):
    p = a.default_properties()
    return replace(
        p,
        beam_thickness=p.beam_thickness * np.where(np.arange(p.beam_thickness.size) % 3, 1, 1.3),
        beam_rho=p.beam_rho * factor,
        mass_scale=p.mass_scale * np.array([factor, 1.0]),
        spring_scale=p.spring_scale * np.array([1.0, factor]),
    )


def test_parametric_families_are_registered_in_the_order_of_assembly():
    assert list(base.PARAMETRIC.values())[:3] == [TubeBeams, PointMasses, Springs]
    a = Assembler(_structure())
    assert [f.family for f in a.parametric.values()][:3] == ["beam", "mass", "spring"]
    assert {f.family for f in a.families} == {"rod"}


def test_assembly_is_every_family_placed_at_its_dofs():
    s = _structure()
    a = Assembler(s)
    K, M, elements = a.assemble(_props(a, 1.7))
    assert [f.family for f in elements] == ["beam", "mass", "spring", "rod"]
    assert elements[1].K is None and elements[2].M is None  # masses: no K, springs: no M
    Kd, Md = _dense(elements, s.n_dof)
    np.testing.assert_allclose(K.toarray(), Kd, rtol=0, atol=1e-12 * np.abs(Kd).max())
    np.testing.assert_allclose(M.toarray(), Md, rtol=0, atol=1e-12 * np.abs(Md).max())


def test_reassembly_recomputes_only_what_changed_to_the_bit():
    s = _structure()
    warm = Assembler(s)
    warm.assemble(_props(warm, 1.0))
    warm.assemble(_props(warm, 2.5))  # every field changes on a subset of the elements
    K1, M1, _ = warm.assemble(_props(warm, 1.7))
    fresh = Assembler(s)
    K2, M2, _ = fresh.assemble(_props(fresh, 1.7))
    assert np.array_equal(K1.toarray(), K2.toarray())
    assert np.array_equal(M1.toarray(), M2.toarray())
    # what the caller gets is its own: changing it changes no later assembly
    K1.data[:] = 0.0
    K3, _, _ = warm.assemble(_props(warm, 1.7))
    assert np.array_equal(K3.toarray(), K2.toarray())


@pytest.mark.parametrize("family", ["mass", "spring"])
def test_linear_families_are_linear_in_their_factor(family):
    a = Assembler(_structure())
    fam = a.parametric[family]
    which = {"K": 0, "M": 1}[fam.linear]
    p = a.default_properties()
    field = fam.fields[0]
    factors = np.array([0.3, 4.0])
    X1 = a.matrices(family, replace(p, **{field: np.ones(2)}))[which]
    Xf = a.matrices(family, replace(p, **{field: factors}))[which]
    np.testing.assert_allclose(Xf, factors[:, None, None] * X1, rtol=1e-14, atol=1e-300)
    assert np.abs(X1).max() > 0


def test_total_mass_is_the_rigid_body_functional_of_the_assembled_mass():
    s = _structure()
    a = Assembler(s)
    props = _props(a, 1.7)
    mass, cog = a.total_mass(props)
    _, M, _ = a.assemble(props)
    R = rigid_body_basis(s.nodes, centre=np.zeros(3))
    Mr = R.T @ (M @ R)
    m = np.trace(Mr[:3, :3]) / 3.0
    assert mass == pytest.approx(m, rel=1e-12)
    np.testing.assert_allclose(cog, np.array([Mr[1, 5], Mr[2, 3], Mr[0, 4]]) / m, atol=1e-12)
    # the point masses alone: 1.7 x 1.3 + 0.4 kg, the tubes rho A L and the rod
    beams = a.parametric["beam"].masses(props, s.nodes)[0].sum()
    rod = s.rods.rho[0] * s.rods.area[0] * np.linalg.norm(s.nodes[2] - s.nodes[0])
    assert mass == pytest.approx(beams + 1.7 * 1.3 + 0.4 + rod, rel=1e-12)


def test_line_families_share_one_implementation():
    b = StructureBuilder()
    n = [b.add_node([x, 0, 0]) for x in (0.0, 1.0, 2.0)]
    b.add_rods([(n[0], n[1]), (n[1], n[2])], 1e-4, STEEL, "rods", mass="consistent")
    b.add_beams([(n[0], n[2])], tube_section(0.05, 0.002), STEEL, "beams", mass="none")
    s = b.build()
    rods, beams = s.rods, s.general_beams
    assert type(rods).n_elements is base.LineElements.n_elements
    assert type(beams).dofs is base.LineElements.dofs
    assert rods.n_elements == 2 and beams.n_elements == 1
    np.testing.assert_array_equal(rods.dofs()[1], np.arange(6, 18))
    assert rods.has_mass() and not beams.has_mass()
    np.testing.assert_allclose(rods.mass_per_length(), STEEL.density * 1e-4, rtol=1e-15)


def test_property_table_is_the_families_declarations():
    """The property table of ``fe.model``'s docstring is what the parametric families declare
    (``Bindable``): name, what it acts on, unit and how it enters K and M, row for row."""
    import bayesupdate.fe.model as fe_model

    lines = fe_model.__doc__.splitlines()
    rows = [r for r in lines if r and r.split()[0] in fe_model.PROPERTY_TERMS]
    assert len(rows) == len(base.bindable())
    # the columns are the runs of "=" of the table's rule
    rule = next(r for r in lines if r.startswith("=="))
    spans = [m.span() for m in re.finditer(r"=+", rule)]
    for row in rows:
        name, acts_on, unit = (row[a:b].strip() for a, b in spans[:3])
        enters = row[spans[3][0] :].strip()
        family, p = base.bindable()[name]
        assert (acts_on, unit) == (p.acts_on, p.unit)
        # a non-linear one may name the matrix it acts on ("K non-linear": the bend factor)
        assert ("non-linear" in enters) if p.enters == "nonlinear" else enters.startswith(p.enters)
        assert fe_model.PROPERTY_TERMS[name] == (family, p.field, p.enters)
