"""Strain-energy density maps on shells (``report.energy_maps``): the densities
integrate to the mode's strain energy, sit where the analytic mode shape puts them, and are drawn
(in the report and by ``bayesupdate modes --sed-map``)."""

import numpy as np
import pytest

from bayesupdate.cli import main
from bayesupdate.fe import Binding, FEModel, Material, StructureBuilder
from bayesupdate.fe import shell_mesh as sm
from bayesupdate.report.energy_maps import (
    plot_energy_density_map,
    shell_energy_map,
    write_energy_density_maps,
)

STEEL = Material(210e9, 0.3, 7850.0, "steel")
A, T, N = 0.5, 2e-3, 20  # square plate side [m], thickness [m], cells per side


def _simply_supported_plate(split: bool = False):
    """A square steel plate, hard simply supported on its four edges (w and the edge's slope
    along it held, in-plane motion held at the edges: no membrane-bending coupling on a flat
    plate); ``split``: the half x > a/2 is a second part, 3 mm thick."""
    b = StructureBuilder()
    nodes, quads, _ = sm.plate(A, A, N, N)
    right = nodes[quads].mean(axis=1)[:, 0] > 0.5 * A if split else np.zeros(len(quads), bool)
    ids = np.full(len(nodes), -1)
    for mine, part, t in ((~right, "left", T), (right, "right", 1.5 * T)):
        if split or part == "left":
            used, local = np.unique(quads[mine], return_inverse=True)
            name = part if split else "plate"
            q = local.reshape(-1, 4)
            ids[used] = b.add_shells(nodes[used], q, thickness=t, material=STEEL, part=name)
    x, y = nodes[:, 0], nodes[:, 1]
    on_x = np.isclose(x, 0) | np.isclose(x, A)  # edges x = 0, a: dw/dy = 0 (rotation about x)
    on_y = np.isclose(y, 0) | np.isclose(y, A)
    for n, ex, ey in zip(ids, on_x, on_y, strict=True):
        if ex or ey:
            b.add_support(int(n), "123" + "4" * bool(ex) + "5" * bool(ey))
    parts = ("left", "right") if split else ("plate",)
    bindings = {f"t_{p}": Binding(p, "thickness") for p in parts}
    defaults = {k: T * (1.5 if k == "t_right" else 1.0) for k in bindings}
    return FEModel(b.build(), bindings, defaults, {k: (1e-4, 1e-2) for k in bindings})


@pytest.fixture(scope="module")
def plate():
    model = _simply_supported_plate()
    return model, model.solve(n_modes=3, energies=True)


def test_densities_times_areas_sum_to_the_modal_strain_energy(plate):
    model, result = plate
    emap = shell_energy_map(model.structure, result)
    # every element is a shell: the map holds the whole strain energy 1/2 phi^T K phi
    K, _ = model.matrices()
    phi = result.modes.shapes
    half_phi_k_phi = 0.5 * np.einsum("im,im->m", phi, K @ phi)
    np.testing.assert_allclose(emap.shell_energy(), half_phi_k_phi, rtol=1e-8)
    np.testing.assert_allclose(emap.modal_energy, half_phi_k_phi, rtol=1e-8)
    np.testing.assert_allclose(emap.area.sum(), A * A, rtol=1e-12)


def test_mode_one_energy_sits_where_the_navier_solution_puts_it(plate):
    """Mode (1, 1) of a simply supported square plate, w = sin(pi x/a) sin(pi y/a): Kirchhoff
    strain energy per area D/2 [(w_xx + w_yy)^2 - 2 (1 - nu)(w_xx w_yy - w_xy^2)], i.e.
    proportional to (1 + nu) sx^2 sy^2 + (1 - nu) cx^2 cy^2: largest at the centre, (1 - nu) /
    (1 + nu) of that at the corners, zero at the edges' midpoints."""
    model, result = plate
    emap = shell_energy_map(model.structure, result)
    nu = STEEL.poisson
    D = STEEL.youngs_modulus * T**3 / (12 * (1 - nu**2))
    f11 = np.pi / A**2 * np.sqrt(D / (STEEL.density * T))  # (pi/2)(2/a^2) sqrt(D/rho h)
    assert result.frequencies_hz[0] == pytest.approx(f11, rel=5e-3)
    # element averages of the analytic density (4 x 4 Gauss points per cell), normalized
    g = (np.polynomial.legendre.leggauss(4)[0] + 1) / 2
    lo = emap.polygons[:, 0, :2]  # the cells' lower-left corners (sm.plate's node order)
    h = A / N
    px = (lo[:, 0, None] + h * g[None, :])[:, :, None] * np.pi / A
    py = (lo[:, 1, None] + h * g[None, :])[:, None, :] * np.pi / A
    sed = (1 + nu) * (np.sin(px) * np.sin(py)) ** 2 + (1 - nu) * (np.cos(px) * np.cos(py)) ** 2
    exact = sed.mean(axis=(1, 2))
    exact /= exact @ emap.area
    ours = emap.density[:, 0] / emap.shell_energy()[0]
    assert np.abs(ours - exact).max() < 0.01 * exact.max()  # measured 0.38 %
    centre = np.flatnonzero(np.all(np.isclose(lo, A / 2), axis=1))[0]  # a centre cell
    corner = np.flatnonzero(np.all(np.isclose(lo, 0.0), axis=1))[0]
    assert ours[centre] / ours.max() > 0.99  # the peak is at the centre
    assert ours[corner] / ours[centre] == pytest.approx(exact[corner] / exact[centre], rel=5e-3)


def test_part_shares_match_the_energy_per_part():
    model = _simply_supported_plate(split=True)
    result = model.solve(n_modes=2, energies=True)
    emap = shell_energy_map(model.structure, result)
    s = model.structure
    expected = result.energies.strain_by_part[[s.part_index("left"), s.part_index("right")]]
    np.testing.assert_allclose(emap.part_shares()[[s.part_index(p) for p in ("left", "right")]],
                               expected, rtol=1e-8)  # fmt: skip
    np.testing.assert_allclose(emap.part_shares().sum(axis=0), 1.0, rtol=1e-8)
    # the thicker half is stiffer (D ~ t^3): mode 1 leans to it, more than half its energy there
    assert expected[1, 0] > 0.5


def test_maps_are_drawn_one_png_per_mode(plate, tmp_path):
    model, result = plate
    written = write_energy_density_maps(model.structure, result, tmp_path / "maps", n_show=2)
    assert [p.name for p, _ in written] == ["sed_mode01.png", "sed_mode02.png"]
    png = plot_energy_density_map(shell_energy_map(model.structure, result), 2, tmp_path / "m.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_map_needs_shells_and_energies(plate, capsys, tmp_path):
    from bayesupdate.errors import BayesUpdateError

    model, _ = plate
    with pytest.raises(BayesUpdateError, match="solve with energies=True"):
        shell_energy_map(model.structure, model.solve(n_modes=1))
    code = main(["modes", "--model", "exhaust", "--sed-map", str(tmp_path / "sed")])
    err = capsys.readouterr().err
    assert code == 2 and "--sed-map: model 'exhaust' has no shell elements" in err
    assert "Traceback" not in err and not (tmp_path / "sed").exists()


def test_the_demo_report_shows_the_maps_when_the_model_has_shells(plate, tmp_path):
    from bayesupdate.pipelines.demo import FePart
    from bayesupdate.report.demo_report import SED_MAP_MODES, _fe_figures

    model, _ = plate
    result = model.solve(n_modes=SED_MAP_MODES + 1, energies=True)  # the report keeps 4 maps
    figures = _fe_figures(FePart(model, result, []), tmp_path)
    maps = [p.name for p, _ in figures if p.name.startswith("sed_mode")]
    assert maps == [f"sed_mode{k:02d}.png" for k in range(1, SED_MAP_MODES + 1)]
