"""A snapshot of a large model's basis build (``fe.reduced.basis``) gives its modes and their
design-sensitivity vectors from one factorization of K - sigma M (the Lanczos iteration's, used
again for the static corrections of ``fe.reduced.sensitivity``), not two: the same numbers as a
full solve followed by ``static_corrections`` with its own assembly and factorization."""

import numpy as np
import pytest
from test_reduced_shells import STEEL

import bayesupdate.fe.reduced.basis as basis_module
import bayesupdate.fe.reduced.sensitivity as sensitivity_module
from bayesupdate.fe import Binding, FEModel, StructureBuilder
from bayesupdate.fe import shell_mesh as sm
from bayesupdate.fe.reduced.affine import decompose
from bayesupdate.fe.reduced.basis import _shares_factorization, full_solves
from bayesupdate.fe.reduced.sensitivity import static_corrections

N_MODES = 6


def fine_box() -> FEModel:
    """A free closed steel box 0.5 x 0.4 x 0.3 m, 10 x 8 x 6 quads a side (sparse path: more
    independent DOFs than ``ModalSettings.dense_below``), lids 2 mm and walls 1.5 mm, both
    thicknesses and the wall density bound."""
    nodes, quads = sm.box(0.5, 0.4, 0.3, 10, 8, 6)
    z = nodes[quads].mean(axis=1)[:, 2]
    lid = np.isclose(z, 0.0) | np.isclose(z, 0.3)
    b = StructureBuilder()
    for part, sel, t in (("lids", lid, 2e-3), ("walls", ~lid, 1.5e-3)):
        used, local = np.unique(quads[sel], return_inverse=True)
        b.add_shells(nodes[used], local.reshape(-1, 4), thickness=t, material=STEEL, part=part)
    bindings = {
        "t_lids": Binding("lids", "thickness"),
        "t_walls": Binding("walls", "thickness"),
        "rho_walls": Binding("walls", "density"),
    }
    defaults = dict(t_lids=2e-3, t_walls=1.5e-3, rho_walls=7850.0)
    bounds = dict(t_lids=(1e-3, 3e-3), t_walls=(1e-3, 3e-3), rho_walls=(6000.0, 9000.0))
    return FEModel(b.build(), bindings, defaults, bounds, name="fine box")


@pytest.fixture(scope="module")
def fe():
    return fine_box()


def test_one_factorization_gives_the_modes_and_their_sensitivities(fe, monkeypatch):
    assert _shares_factorization(fe)
    names = fe.parameter_names
    point = np.array([[2.4e-3, 1.2e-3, 8100.0]])
    params = dict(zip(names, point[0], strict=True))
    dec = decompose(fe, fe.default_bounds(), 1e-9)
    calls = {"basis": 0, "sensitivity": 0}

    def counting(where, original):
        def factorize(*args, **kwargs):
            calls[where] += 1
            return original(*args, **kwargs)

        return factorize

    monkeypatch.setattr(basis_module, "factorize", counting("basis", basis_module.factorize))
    monkeypatch.setattr(
        sensitivity_module, "factorize", counting("sensitivity", sensitivity_module.factorize)
    )
    freqs, vectors = full_solves(fe, names, point, N_MODES, sensitivities=dec)
    assert calls == {"basis": 1, "sensitivity": 0}
    # the same numbers as a full solve and static corrections with their own factorization
    sol = fe.solve(params, N_MODES).modes
    separate = static_corrections(fe, dec, params, sol.eigenvalues, sol.shapes)
    assert calls["sensitivity"] == 1
    np.testing.assert_allclose(freqs[0], sol.frequencies_hz, rtol=1e-12)
    np.testing.assert_allclose(
        vectors[:, :N_MODES], sol.shapes, rtol=0, atol=1e-12 * np.abs(sol.shapes).max()
    )
    assert vectors.shape[1] == N_MODES * (1 + len(names))
    X = vectors[:, N_MODES:]
    # T^T K T - sigma T^T M T against T^T (K - sigma M) T: the same matrix up to round-off
    assert np.max(np.abs(X - separate)) <= 1e-9 * np.abs(separate).max()
