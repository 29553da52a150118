"""``fe.line_update.LineUpdate``: a few general beams, rods and point masses changed in place
equal the structure built with those values (K, M to round-off), and the rest is untouched."""

from dataclasses import replace

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.assembly import GeneralAssembler
from bayesupdate.fe.line_update import LineUpdate, PointMassValues
from bayesupdate.fe.standard_sections import general_section
from bayesupdate.fe.structure import Material, StructureBuilder

MAT = Material(7.0e10, 0.33, 2700.0, "alu")


def _frame(iz_tip=2e-8, area_rod=3e-5, tip_mass=0.4):
    """A shear-flexible L frame of general beams with offsets, a brace rod and a tip
    mass; the last beam's iz, the rod's area and the tip mass are the values to change."""
    b = StructureBuilder()
    xyz = [(0, 0, 0), (0.3, 0, 0), (0.6, 0, 0), (0.6, 0.3, 0), (0.6, 0.6, 0.1)]
    ids = [b.add_node(p) for p in xyz]
    sec = general_section(4e-5, 1e-8, 2e-8, 5e-9, 0.0, 0.8, 0.8)
    tip = general_section(4e-5, 1e-8, iz_tip, 5e-9, 0.0, 0.8, 0.8)
    b.add_beams([[ids[0], ids[1]], [ids[1], ids[2]]], sec, MAT, "beam",
                offsets=[[0, 0, 0.01], [0, 0, 0.01]])  # fmt: skip
    b.add_beams([[ids[2], ids[3]]], sec, MAT, "beam")
    b.add_beams([[ids[3], ids[4]]], tip, MAT, "tip", mass="lumped")
    b.add_rods([[ids[0], ids[3]]], area_rod, MAT, "brace")
    b.add_point_mass(ids[4], tip_mass, "tip mass", inertia=[1e-4, 2e-4, 3e-4], offset=(0, 0, 0.02))
    b.add_support(ids[0])
    return b.build()


def test_changed_elements_equal_the_rebuilt_structure():
    s0, s1 = _frame(), _frame(iz_tip=5e-8, area_rod=7e-5, tip_mass=0.9)
    g0, g1 = GeneralAssembler(s0), GeneralAssembler(s1)
    update = LineUpdate(g0, beams=[3], rods=[0], masses=[0])
    # the torsional inertia per length is a field of its own (the builder's rho (iy + iz))
    beams = replace(
        update.beams, iz=np.array([5e-8]), torsion_inertia=np.array([2700.0 * (1e-8 + 5e-8)])
    )
    rods = replace(update.rods, area=np.array([7e-5]))
    masses = PointMassValues(np.array([0.9]), s0.mass_inertia[[0]])
    dK, dM = update.delta(beams, rods, masses)
    K0, M0, _ = g0.assemble(g0.beams.default_properties())
    K1, M1, _ = g1.assemble(g1.beams.default_properties())
    assert np.array_equal(g0.rows, g1.rows) and np.array_equal(g0.cols, g1.cols)
    assert np.abs(K0.data + dK - K1.data).max() < 1e-13 * np.abs(K1.data).max()
    assert np.abs(M0.data + dM - M1.data).max() < 1e-13 * np.abs(M1.data).max()
    # the change sits on the changed elements' DOFs only, and it is a real change
    moved = np.flatnonzero(np.abs(dK) > 0)
    assert moved.size and np.all(np.isin(g0.rows[moved] // 6, [0, 3, 4]))
    f0 = g0.solve(K0, M0, 4, dense=True).frequencies_hz
    f1 = g1.solve(K1, M1, 4, dense=True).frequencies_hz
    f = g0.solve(g0.csr(K0.data + dK), g0.csr(M0.data + dM), 4, dense=True).frequencies_hz
    assert f == pytest.approx(f1, rel=1e-11)
    assert np.abs(f / f0 - 1).max() > 1e-3


def test_unchanged_values_give_zero_and_errors_are_named():
    s = _frame()
    g = GeneralAssembler(s)
    dK, dM = LineUpdate(g, beams=[0, 2], rods=[0]).delta()
    assert not dK.any() and not dM.any()
    b = StructureBuilder()
    n = [b.add_node((0, 0, 0)), b.add_node((1, 0, 0))]
    b.add_rods([n], 1e-4, MAT, "rod")
    with pytest.raises(BayesUpdateError, match="no general beams"):
        LineUpdate(GeneralAssembler(b.build()), beams=[0])
