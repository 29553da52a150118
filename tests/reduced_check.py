"""One check that several deck tests share: a model's certified reduced basis against its full
solves."""

import pytest

from bayesupdate.fe.reduced import ReducedFEModel
from bayesupdate.fe.reduced.settings import ReducedSettings


def assert_basis_matches_full_solves(model, name: str, values, n_modes: int = 8, tol=1e-6):
    """The basis over the parameter's default bounds (seed 0, tolerance ``tol``) is certified,
    and at each of ``values`` of parameter ``name`` its first ``n_modes`` frequencies are the
    full solve's to ``tol``."""
    rom = ReducedFEModel(model, settings=ReducedSettings(n_modes=n_modes, tol=tol, seed=0)).build()
    assert rom.certified
    for value in values:
        full = model.predict({name: value}, n_modes=n_modes).frequencies_hz
        reduced = rom.predict({name: value}).frequencies_hz[:n_modes]
        assert reduced == pytest.approx(full, rel=tol)
