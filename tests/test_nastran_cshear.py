"""CSHEAR + PSHEAR (``nastran.cards.shear``, ``fe.elements.shear_panel``) against MSC's own
solution, the closed form of a rectangular panel in pure shear, rigid motions and the mass.

``tests/data/msc_cshear.json`` holds what ``studies/msc_cshear.py`` read from pyNastran's
models (BSD-3-Clause): MSC Nastran's static solution of the d173 wing box, each of its 141 shear
panels' corners, material, corner displacements and the largest and average corner shear
stress MSC printed.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.elements import shear_panel
from bayesupdate.fe.elements.base import ElementSettings
from bayesupdate.fe.elements.shear_panel import ShearPanels, corner_areas
from bayesupdate.fe.rotations import rigid_body_basis
from bayesupdate.nastran import load_nastran_model

DATA = json.loads((Path(__file__).parent / "data" / "msc_cshear.json").read_text())
G, NU, T, RHO = 26.3e9, 0.33, 2e-3, 2700.0


def panels(corners, nsm=0.0) -> ShearPanels:
    """ShearPanels on corners (n, 4, 3) numbered 0..4n-1."""
    n = len(corners)
    full = lambda v: np.full(n, v)  # noqa: E731
    return ShearPanels(np.arange(4 * n).reshape(n, 4), np.zeros(n, np.int64), full(G), full(NU),
                       full(T), full(RHO), full(nsm))  # fmt: skip


def test_stresses_are_mscs_on_its_own_solution():
    """MSC's d173: from MSC's displacements each panel's average and largest corner stress are
    MSC's to 2.6e-6 and 2.9e-6 of the median |tau_avg| (medians over 141 panels, up to 37 % off
    a parallelogram), 1.1e-4 and 2.0e-4 at most; with NASTRAN-95's tolerance on parallel sides
    (0.01) the largest stress misses by up to 0.19 of that scale."""
    x, u = np.array(DATA["corners"]), np.array(DATA["u"])
    nu, Gm = np.array(DATA["nu"]), np.array(DATA["G"])
    scale = np.median(np.abs(DATA["tau_avg"]))

    def misses(parallel=shear_panel.PARALLEL):
        tau = shear_panel.panel_stresses(shear_panel.panel_modes(x, nu, parallel), Gm, u)
        return (np.abs(tau.mean(axis=1) - DATA["tau_avg"]) / scale,
                np.abs(np.abs(tau).max(axis=1) - DATA["tau_max"]) / scale)  # fmt: skip

    avg, big = misses()
    assert len(avg) == 141
    assert np.median(avg) < 5e-6 and np.median(big) < 5e-6
    assert avg.max() < 2e-4 and big.max() < 3e-4
    assert misses(parallel=0.01)[1].max() > 0.1


def test_rectangle_in_pure_shear_has_g_t_a_b_gamma_squared_over_two():
    """A 0.4 x 0.25 m panel sheared by gamma (u = gamma y): 1/2 u^T K u = G t a b gamma^2 / 2
    to 1e-12, and the rigid motions cost nothing (1e-12 of K), as on a skewed, tapered and
    slightly warped panel."""
    a, b, gamma = 0.4, 0.25, 1e-3
    x = np.array([[[0, 0, 0], [a, 0, 0], [a, b, 0], [0, b, 0]]], float)
    K, _ = panels(x).matrices(x.reshape(-1, 3), ElementSettings())
    u = np.zeros((4, 6))
    u[:, 0] = gamma * x[0, :, 1]
    assert 0.5 * u.ravel() @ K[0] @ u.ravel() == pytest.approx(0.5 * G * T * a * b * gamma**2,
                                                               rel=1e-12)  # fmt: skip
    odd = np.array([[[0, 0, 0], [0.5, 0.05, 0.01], [0.42, 0.3, -0.01], [0.08, 0.26, 0.004]]])
    for shape in (x, odd):
        K, _ = panels(shape).matrices(shape.reshape(-1, 3), ElementSettings())
        rigid = rigid_body_basis(shape.reshape(-1, 3))
        assert np.abs(K[0] @ rigid).max() < 1e-12 * np.abs(K[0]).max()


def test_lumped_mass_is_the_panels_with_corner_triangles():
    """A trapezoid (sides 0.5 and 0.3, height 0.2, NSM 0.4 kg/m^2): the total mass is
    (rho t + nsm) A on each axis, each corner (A_i + A) / 6 of it (A_i its corner's triangle)."""
    x = np.array([[[0, 0, 0], [0.5, 0, 0], [0.4, 0.2, 0], [0.1, 0.2, 0]]], float)
    _, M = panels(x, nsm=0.4).matrices(x.reshape(-1, 3), ElementSettings())
    area = 0.5 * (0.5 + 0.3) * 0.2
    m = RHO * T + 0.4
    assert np.trace(M[0]) / 3 == pytest.approx(m * area, rel=1e-12)
    triangles = np.array([0.05, 0.05, 0.03, 0.03])  # each corner with its two neighbours
    assert corner_areas(x)[0] == pytest.approx((triangles + area) / 6, rel=1e-12)
    assert np.diag(M[0])[0::6] == pytest.approx(m * corner_areas(x)[0], rel=1e-12)


def _deck(path, pshear="PSHEAR,2,1,0.002", mat="MAT1,1,70.e9,26.3e9,,2700."):
    """A cantilever web: CSHEAR panels 0.5 x 0.25 between two CROD flanges, with CROD
    stiffeners at the stations (four bays; a panel carries no direct stress, so without them
    its corners would part along its sides freely)."""
    lines = ["SOL 103", "CEND", "SPC = 1", "METHOD = 1", "BEGIN BULK", "EIGRL,1,,,4", mat,
             pshear, "PROD,3,1,4.e-4"]  # fmt: skip
    for k in range(5):
        lines += [f"GRID,{k + 1},,{0.5 * k},0.,0.,,345", f"GRID,{k + 11},,{0.5 * k},0.25,0.,,345"]
    for k in range(4):
        lines += [
            f"CSHEAR,{k + 1},2,{k + 1},{k + 2},{k + 12},{k + 11}",
            f"CROD,{k + 21},3,{k + 1},{k + 2}",
            f"CROD,{k + 31},3,{k + 11},{k + 12}",
        ]
    lines += [f"CROD,{k + 41},3,{k + 2},{k + 12}" for k in range(4)]  # the stiffeners
    lines += ["SPC1,1,12,1,11", "ENDDATA"]
    Path(path).write_text("\n".join(lines) + "\n")
    return str(path)


def test_a_web_between_flanges_bends_as_the_idealized_beam(tmp_path):
    """A unit shear at the tip of the cantilever web (half at each flange) deflects it by the
    idealized beam's flexibility to 1e-12: the panels' constant shear flow q = 1 / h gives
    L / (G t h), the flanges' forces M / h, constant in each bar at its middle's moment, give
    sum (L - x_k)^2 dx / EI with EI = E A h^2 / 2 (the stiffeners carry nothing)."""
    model = load_nastran_model(_deck(tmp_path / "web.bdf"))
    K, _ = model.matrices()
    tr = model.general.transform
    grids = list(model.structure.metadata["nastran"]["grid_ids"])
    F = np.zeros(K.shape[0])
    for g in (5, 15):
        F[6 * grids.index(g) + 1] = 0.5
    import scipy.sparse.linalg as spla

    u = tr.T @ spla.spsolve(tr.reduce(K).tocsc(), tr.T.T @ F)
    tip = u[6 * grids.index(5) + 1]
    E, A, h, L = 70e9, 4e-4, 0.25, 2.0
    bending = sum(((k + 0.5) * 0.5) ** 2 * 0.5 / (E * A * h**2 / 2) for k in range(4))
    assert tip == pytest.approx(L / (26.3e9 * 0.002 * h) + bending, rel=1e-12)


@pytest.mark.parametrize("pshear, mat, words", [
    ("PSHEAR,2,1,0.002,,1.0", "MAT1,1,70.e9,26.3e9,,2700.", r"F1 \(the sides' extensional"),
    ("PSHEAR,2,1,0.002", "MAT1,1,70.e9,,,2700.", "a shear panel needs G > 0"),
])  # fmt: skip
def test_refusals_name_their_card(tmp_path, pshear, mat, words):
    with pytest.raises(BayesUpdateError, match=words):
        load_nastran_model(_deck(tmp_path / "bad.bdf", pshear, mat))


def test_a_folded_panel_is_refused_with_its_line(tmp_path):
    deck = Path(_deck(tmp_path / "bad.bdf"))
    deck.write_text(deck.read_text().replace("CSHEAR,2,2,2,3,13,12", "CSHEAR,2,2,2,13,3,12"))
    with pytest.raises(BayesUpdateError, match=r"bad.bdf:\d+ CSHEAR 2: an interior angle"):
        load_nastran_model(str(deck))


def test_a_panels_material_cannot_be_a_parameter(tmp_path):
    """MAT1 1 is the flanges' and the panels': binding its E would leave the panels at the deck's
    G, so it is refused by name."""
    with pytest.raises(BayesUpdateError, match="PSHEAR 2 use"):
        load_nastran_model(_deck(tmp_path / "web.bdf"), {"E": {"binds": "MAT1 1 E"}})
