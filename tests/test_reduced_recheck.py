"""The check of a reduced basis read back from the cache (``fe.reduced.certification._load``):
one full solve at a fresh point (``RECHECK_POINTS``), after the entry's checksum matched.  A
stored basis whose projected stiffness terms are off by 0.2 % either way (reduced frequencies
0.1 % above the full ones, or below them, which Rayleigh-Ritz forbids) is refused there and
rebuilt with a note; the good basis passes with its certificate grown by that point.  On the
beam exhaust with a small basis (6 modes, 8 snapshots, 8 validation points)."""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from test_compute_cache import _counting_solves as _counted  # noqa: E402

from bayesupdate.compute.cache import ArrayStore  # noqa: E402
from bayesupdate.fe.reduced import ReducedFEModel, ReducedSettings, certification  # noqa: E402
from bayesupdate.models import get_model  # noqa: E402

SETTINGS = ReducedSettings(n_modes=6, tol=1e-4, seed=0, n_snapshots=8, n_validation=8)


@pytest.fixture(scope="module")
def stored(tmp_path_factory):
    """(model, store, key, the built certification) with the basis kept in ``store``."""
    store = ArrayStore(tmp_path_factory.mktemp("cache"))
    model = ReducedFEModel(get_model("exhaust"), settings=SETTINGS)
    built = certification.build(model, store=store)
    assert built.certified and store.info().entries == 1
    return model, store, certification.basis_key(model), built


def test_a_loaded_basis_is_checked_by_one_full_solve(stored, monkeypatch):
    model, store, _, built = stored
    points = _counted(monkeypatch)
    loaded = certification.build(model, store=store)
    assert points == [1] == [certification.RECHECK_POINTS]
    assert loaded.certified and loaded.certificate.n_points == built.certificate.n_points + 1
    theta, f_full = loaded.checked[-1]
    # a fresh point: none of the build's validation points
    assert not any(np.any(np.all(np.isclose(t, theta[0]), axis=1)) for t, _ in built.checked)
    # the loaded basis is within its tolerance there, from above (Rayleigh-Ritz)
    lam = loaded.basis.eigen(theta, SETTINGS.n_modes)
    rel = np.sqrt(lam) / (2 * np.pi) / f_full - 1.0
    assert np.all(rel >= -1e-9) and np.max(rel) <= SETTINGS.tol
    assert loaded.max_rel_error == max(built.max_rel_error, float(np.max(np.abs(rel))))


@pytest.mark.parametrize("scale", [1.002, 0.998])
def test_a_stored_basis_with_its_stiffness_terms_off_is_refused(stored, scale, tmp_path):
    model, good_store, key, built = stored
    store = ArrayStore(tmp_path)
    arrays = good_store.load(key)
    arrays["K_B"] = arrays["K_B"] * scale  # a valid entry (its own checksum): terms 0.2 % off
    store.save(key, arrays)
    # the off basis is off at any point: 0.1 % in every frequency, 10x the tolerance
    off = certification._stored(model, arrays)[0]
    theta, f_full = built.checked[0]
    f_off = np.sqrt(np.maximum(off.eigen(theta, SETTINGS.n_modes), 0)) / (2 * np.pi)
    np.testing.assert_allclose(f_off / f_full, np.sqrt(scale), rtol=2 * SETTINGS.tol)
    with pytest.warns(RuntimeWarning, match="misses its tolerance at fresh points"):
        again = certification.build(model, store=store)
    # rebuilt: the build's own validation set, and the good basis stored in its place
    assert again.certified and len(again.checked) == 1
    np.testing.assert_array_equal(store.load(key)["K_B"], good_store.load(key)["K_B"])
