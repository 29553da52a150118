"""The README tour: a frame on supports, a plate and a closed box of shells, each in a few lines of
the public API, checked against an independent path or a published value.

- frame: the same frame with very stiff springs to ground (1e13 N/m, N m/rad) instead of the
  supports (no elimination); the two agree to ~1e-8 (measured) on the sparse solver.  The banded
  Krylov and dense beam paths are only ~1e-4 accurate with such springs (ill-conditioning), so
  they are not the reference here.
- plate: NAFEMS FV16 (cantilevered thin square plate) 0.421, 1.029, 2.582, 3.306, 3.753,
  6.555 Hz; 16 x 16 MITC4 quads land within 0.7 % (measured), asserted at 1 %.
- box: exactly six rigid-body modes, the mass rho t area, and the same modes as the shell layer
  solved on its own (``ShellAssembly`` + ``solve_sparse_modes``).
"""

import numpy as np
import pytest

from bayesupdate.fe import STEEL, Binding, FEModel, Material, StructureBuilder, circular_tube
from bayesupdate.fe import shell_mesh as sm
from bayesupdate.fe.shell_model import ShellAssembly, shell_mesh
from bayesupdate.fe.sparse_modal import ModalSettings, solve_sparse_modes


def _portal(supports=True):
    b = StructureBuilder()
    tube = circular_tube(0.06, 3e-3)
    feet = [b.add_node((0, 0, 0)), b.add_node((2, 0, 0))]
    tops = [b.add_node((0, 0, 1.5)), b.add_node((2, 0, 1.5))]
    for foot, top in zip(feet, tops, strict=True):
        b.add_line(foot, top, tube, STEEL, "columns")
    b.add_line(tops[0], tops[1], tube, STEEL, "beam")
    for foot in feet:
        if supports:
            b.add_support(foot)  # clamped; "123" pins it
        else:
            b.add_spring(foot, None, [1e13] * 6, "ground")
    return b.build()


def test_tour_frame_on_supports():
    r = FEModel(_portal(), {}, {}, {}).solve(n_modes=4)
    springs = FEModel(_portal(supports=False), {}, {}, {}).solve(n_modes=4, method="sparse")
    assert r.modes.n_rigid == 0
    np.testing.assert_allclose(r.frequencies_hz, springs.frequencies_hz, rtol=1e-6)


def test_tour_plate():
    nodes, quads, _ = sm.plate(10.0, 10.0, 16, 16)
    b = StructureBuilder()
    steel = Material(200e9, 0.3, 8000.0)
    ids = b.add_shells(nodes, quads, thickness=0.05, material=steel, part="plate")
    for n in ids[nodes[:, 0] == 0.0]:
        b.add_support(n)
    model = FEModel(
        b.build(), {"t": Binding("plate", "thickness")}, {"t": 0.05}, {"t": (0.02, 0.08)}
    )
    r = model.solve(n_modes=6)
    nafems_fv16 = [0.421, 1.029, 2.582, 3.306, 3.753, 6.555]
    np.testing.assert_allclose(r.frequencies_hz, nafems_fv16, rtol=0.01)
    # thin-plate bending: f ~ t for a clamped plate (membrane and shear do not enter its modes)
    thinner = model.solve({"t": 0.025}, n_modes=6).frequencies_hz
    np.testing.assert_allclose(thinner / r.frequencies_hz, 0.5, rtol=2e-3)


def test_tour_closed_box():
    nodes, quads = sm.box(0.6, 0.4, 0.3, 12, 8, 6)
    b = StructureBuilder()
    al = Material(70e9, 0.33, 2700.0)
    b.add_shells(nodes, quads, thickness=2e-3, material=al, part="box")
    r = FEModel(b.build(), {}, {}, {}).solve(n_modes=10)
    assert r.modes.n_rigid == 6
    assert r.mass_kg == pytest.approx(2700 * 2e-3 * 2 * (0.24 + 0.18 + 0.12), rel=1e-12)
    mesh = shell_mesh(nodes, quads, thickness=2e-3, E=70e9, nu=0.33, rho=2700.0)
    K, M = ShellAssembly(mesh).assemble()
    direct = solve_sparse_modes(K, M, nodes, ModalSettings(n_modes=10))
    np.testing.assert_allclose(r.frequencies_hz, direct.frequencies_hz, rtol=1e-9)
