"""The total mass of the reduced model's ``predict`` from per-term masses (``fe.reduced.mass``,
no K and M assembly) against the assembled mass matrix (``FEModel.total_mass``) and the
analytic mass of shells, on a free closed box with offsets and non-structural mass, on a clamped
plate with a point mass on a rigid element, and on the shell exhaust (beams, shells, spiders)."""

import numpy as np
import pytest
from test_reduced_shells import SETTINGS, box_model, clamped_plate_model

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.reduced import ReducedFEModel
from bayesupdate.fe.reduced.mass import total_mass
from bayesupdate.models import get_model


def _random_points(fe, n, seed):
    rng = np.random.default_rng(seed)
    b = fe.default_bounds()
    return [{k: float(rng.uniform(*b[k])) for k in fe.parameter_names} for _ in range(n)]


def test_box_mass_is_the_analytic_sheet_mass():
    """Lids 0.4 m^2 (rho t + 0.5 kg/m^2 of non-structural mass), walls 0.54 m^2 (rho t); the
    lids' modulus does not enter the mass."""
    fe = box_model()
    for p in [fe.default_parameters(), *_random_points(fe, 4, 1)]:
        lids = 0.4 * (7850.0 * p["t_lids"] + 0.5)
        walls = 0.54 * p["rho_walls"] * p["t_walls"]
        assert total_mass(fe, p) == pytest.approx(lids + walls, rel=1e-12)


@pytest.mark.parametrize("make", [box_model, clamped_plate_model])
def test_mass_equals_the_assembled_mass(make):
    fe = make()
    for p in _random_points(fe, 5, 2):
        assert total_mass(fe, p) == pytest.approx(fe.total_mass(p)[0], rel=1e-12)


def test_shell_exhaust_mass_equals_the_assembled_mass():
    fe = get_model("exhaust_shell", mesh_density=16)
    assert total_mass(fe, fe.default_parameters()) == pytest.approx(12.29, rel=1e-12)
    for p in _random_points(fe, 3, 3):
        assert total_mass(fe, p) == pytest.approx(fe.total_mass(p)[0], rel=1e-12)


def test_reduced_predict_reports_the_assembled_mass_and_rejects_bad_values():
    fe = box_model()
    rom = ReducedFEModel(fe, settings=SETTINGS).build()
    p = dict(t_lids=2.5e-3, t_walls=1.2e-3, E_lids=200e9, rho_walls=8000.0)
    assert rom.predict(p, 6).mass_kg == pytest.approx(fe.total_mass(p)[0], rel=1e-12)
    with pytest.raises(BayesUpdateError, match="t_walls"):
        total_mass(fe, dict(p, t_walls=-1e-3))
