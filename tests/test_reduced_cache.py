"""A certified reduced basis read back from the cache (``fe.reduced.certification``): the load
neither decomposes the model nor projects its terms again (it reads the projected, compressed
terms and their coefficient map), and gives the built basis's reduced frequencies to round-off;
the key, computed without decomposing, changes with a deck value, a bound and a setting.  On
the hand-edited MSC beam deck (``test_nastran_lines._variant``) with a shear-flexible PBEAM's
I1 bound (a line field interpolated in log(theta), ``lines.LineGroup``) and PBAR 1 A (linear),
and on the free closed shell box of ``test_reduced_shells`` (thickness polynomial terms)."""

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from test_nastran_lines import _deck, _load, _variant
from test_reduced_shells import SETTINGS, box_model

from bayesupdate.compute.cache import ArrayStore
from bayesupdate.fe.reduced import ReducedFEModel, ReducedSettings, certification
from bayesupdate.fe.reduced.affine import AffineDecomposition

ROOT = Path(__file__).resolve().parents[1]
LINES = {"bi": {"binds": "PBEAM 3 I1"}, "a": {"binds": "PBAR 1 A"}}
LINE_SETTINGS = ReducedSettings(n_modes=6, tol=1e-5, seed=0, n_snapshots=8, n_validation=8)


@pytest.fixture(scope="module")
def variant(tmp_path_factory):
    return _deck(tmp_path_factory.mktemp("variant"), _variant())


def _built_then_loaded(model: ReducedFEModel, store: ArrayStore, monkeypatch):
    """(built, loaded) models of ``model``: the load with the decomposition and every term
    projection made to fail, so that it must use the stored terms."""
    built = replace(model, certification=certification.build(model, store=store))
    assert built.certified and store.info().entries == 1

    def forbidden(*_args, **_kw):
        raise AssertionError("a cache hit decomposed or projected again")

    with monkeypatch.context() as m:
        m.setattr(certification, "decompose", forbidden)
        m.setattr(AffineDecomposition, "project", staticmethod(forbidden))
        loaded = replace(model, certification=certification.build(model, store=store))
    assert loaded.certified and loaded.size == built.size
    assert not loaded.certification.basis.decomposition.has_terms
    assert loaded.certificate.n_points == built.certificate.n_points + certification.RECHECK_POINTS
    return built, loaded


def _points(model: ReducedFEModel, n: int, seed: int) -> np.ndarray:
    return model.scale(np.random.default_rng(seed).random((n, len(model.parameter_names))))


def _same_frequencies(built, loaded, theta):
    f_built = built.predict_frequencies_batch(theta)
    f_loaded = loaded.predict_frequencies_batch(theta)
    assert np.all(np.isfinite(f_built))
    np.testing.assert_allclose(f_loaded, f_built, rtol=1e-13, atol=0)


def test_a_loaded_basis_on_an_interpolated_line_field_matches_the_built_one(
    variant, tmp_path, monkeypatch
):
    fe = _load(variant, LINES)
    assert fe.line_terms() == () and "bi" in fe.line_nonlinear  # I1 is interpolated
    model = ReducedFEModel(fe, settings=LINE_SETTINGS)
    built, loaded = _built_then_loaded(model, ArrayStore(tmp_path), monkeypatch)
    theta = _points(model, 5, seed=3)
    _same_frequencies(built, loaded, theta)
    # against full solves: the loaded basis keeps the certified tolerance
    full = fe.predict_frequencies_batch(theta, fe.parameter_names, 6)
    rel = loaded.predict_frequencies_batch(theta) / full - 1.0
    assert np.abs(rel).max() <= 1e-5 and rel.min() >= -1e-9
    p = loaded.mapping(theta[0])
    assert loaded.predict(p, 6).mass_kg == pytest.approx(fe.total_mass(p)[0], rel=1e-9)


def test_a_loaded_basis_is_enriched_on_its_model_terms(variant, tmp_path, monkeypatch):
    # an enrichment (``certify_at``) needs the term stacks the load skipped: it decomposes then
    fe = _load(variant, LINES)
    model = ReducedFEModel(fe, settings=LINE_SETTINGS)
    _, loaded = _built_then_loaded(model, ArrayStore(tmp_path), monkeypatch)
    theta = _points(model, 2, seed=5)
    enriched, err = loaded.certify_at(theta, enrich_above=1e-12)  # forces the enrichment
    assert enriched.certified and enriched.size > loaded.size
    assert enriched.certification.basis.decomposition.has_terms
    rel = enriched.predict_frequencies_batch(theta) / fe.predict_frequencies_batch(
        theta, fe.parameter_names, 6
    )
    assert np.abs(rel - 1.0).max() <= 1e-5 and err >= 0


def test_a_loaded_shell_basis_matches_the_built_one(tmp_path, monkeypatch):
    model = ReducedFEModel(box_model(), settings=SETTINGS)
    built, loaded = _built_then_loaded(model, ArrayStore(tmp_path), monkeypatch)
    _same_frequencies(built, loaded, _points(model, 6, seed=7))


def test_the_key_changes_with_a_deck_value_a_bound_and_a_setting(variant, tmp_path):
    fe = _load(variant, LINES)
    key = certification.basis_key(ReducedFEModel(fe, settings=LINE_SETTINGS))
    # the same deck read again (another model object) has the same key
    assert (
        certification.basis_key(ReducedFEModel(_load(variant, LINES), settings=LINE_SETTINGS))
        == key
    )
    # a deck value the parameters do not bind: the PROD's area 1.0 -> 1.1
    other = _deck(tmp_path / "other", _variant(rod_a=1.1))
    changed = ReducedFEModel(_load(other, LINES), settings=LINE_SETTINGS)
    assert certification.basis_key(changed) != key
    lo, hi = fe.default_bounds()["bi"]
    narrower = ReducedFEModel(fe, {"bi": (lo, 0.9 * hi)}, settings=LINE_SETTINGS)
    assert certification.basis_key(narrower) != key
    finer = ReducedFEModel(fe, settings=replace(LINE_SETTINGS, interp_tol=1e-10))
    assert certification.basis_key(finer) != key
    # and in another process (what a second command sees)
    code = (
        "import sys; sys.path.insert(0, 'tests'); "
        "from test_reduced_cache import LINES, LINE_SETTINGS; "
        "from test_nastran_lines import _load; "
        "from bayesupdate.fe.reduced import ReducedFEModel, certification; "
        f"print(certification.basis_key(ReducedFEModel(_load({str(variant)!r}, LINES), "
        "settings=LINE_SETTINGS)))"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                         check=True)  # fmt: skip
    assert out.stdout.strip() == key


def test_a_changed_deck_misses_the_cache(variant, tmp_path):
    store = ArrayStore(tmp_path / "cache")
    model = ReducedFEModel(_load(variant, LINES), settings=LINE_SETTINGS)
    certification.build(model, store=store)
    other = _deck(tmp_path / "other", _variant(rod_a=1.1))
    changed = ReducedFEModel(_load(other, LINES), settings=LINE_SETTINGS)
    again = certification.build(changed, store=store)
    assert again.certified and len(again.checked) == 1  # built (a load adds its check points)
    assert store.info().entries == 2
