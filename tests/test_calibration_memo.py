"""A large model's calibration kept on disk (``pipelines.calibration_memo``): the second run of
the same command recalls the optimum and checks it by one full solve, which reproduces the first
run's full numbers to the bit; other data is another entry; an entry whose optimum a full solve
does not reproduce, or that cannot be read, is calibrated again with a note.  On the beam exhaust
with its large-model path forced (the shell exhaust's search takes minutes)."""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from dataclasses import replace  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from bayesupdate.cli import build_parser  # noqa: E402
from bayesupdate.commands._shared import study_from_args  # noqa: E402
from bayesupdate.compute.cache import ArrayStore  # noqa: E402
from bayesupdate.pipelines import calibrate as pipeline  # noqa: E402
from bayesupdate.pipelines import calibration_memo as memo  # noqa: E402
from bayesupdate.pipelines.study import prepare  # noqa: E402
from bayesupdate.pipelines.surrogates import sampling_problem  # noqa: E402


def _prepared(*extra):
    args = ["calibrate", "--model", "exhaust", "--data", "paper:ema", "--starts", "2", *extra]
    return prepare(study_from_args(build_parser().parse_args(args)))


@pytest.fixture(scope="module")
def first():
    """(prepared study, its reduced basis, the calibration on the large-model path, the key)."""
    prepared = _prepared()
    search, rom = sampling_problem(prepared.problem, None)
    settings = pipeline.CalibrationSettings(starts=2, seed=0, polish=False)
    run = pipeline.calibrate_on_exact_basis(prepared.problem, search, rom, settings)
    return prepared, rom, run, memo.memo_key(prepared.problem, rom.tol, settings), settings


def test_a_kept_calibration_is_recalled_with_the_same_full_numbers(first, tmp_path):
    prepared, rom, run, key, _ = first
    store = ArrayStore(tmp_path)
    memo.keep(store, key, run.result, run.error_at_optimum, run.solve_modes)
    again = memo.recalled(prepared.problem, store.load(key), rom.tol)
    result = run.result
    np.testing.assert_array_equal(again.theta, result.theta)
    assert again.objective == result.objective and again.expr == result.expr
    np.testing.assert_array_equal(again.frequencies_hz, result.frequencies_hz)
    assert again.mass_kg == result.mass_kg
    np.testing.assert_array_equal(again.end_objectives, result.end_objectives)
    assert (again.starts, again.converged_starts, again.evaluations) == (
        result.starts, result.converged_starts, result.evaluations,
    )  # fmt: skip
    assert again.distinct_optima == result.distinct_optima and again.method == result.method


def test_an_optimum_from_the_best_ends_solve_is_recalled_to_the_bit(first, tmp_path):
    """An optimum at the best end takes its numbers from that solve of the basis's modes and its
    extra modes (``calibrate.evaluated_in_full``); the recall solves as many, so that the same
    computation gives the same bits, where a solve of the pairing's 14 modes alone differs in
    the objective's tenth digit, near ``RECALL_AGREES``."""
    prepared, rom, run, key, _ = first
    problem, exact = prepared.problem, run.made_exact
    at_best = replace(run.result, theta=exact.point.copy())
    result, error = pipeline.evaluated_in_full(
        problem, exact.basis, at_best, (exact.point, exact.solution)
    )
    modes = exact.solution.frequencies_hz.size
    assert modes == problem.pairing.n_model + rom.settings.extra_modes
    store = ArrayStore(tmp_path)
    memo.keep(store, key, result, error, modes)
    again = memo.recalled(problem, store.load(key), rom.tol)
    assert again.objective == result.objective and again.mass_kg == result.mass_kg
    np.testing.assert_array_equal(again.frequencies_hz, result.frequencies_hz)


def test_other_data_or_settings_is_another_entry(first):
    prepared, rom, _, key, settings = first
    assert memo.memo_key(prepared.problem, rom.tol, settings) == key
    assert memo.memo_key(prepared.problem, rom.tol, replace(settings, seed=1)) != key
    assert memo.memo_key(prepared.problem, 2 * rom.tol, settings) != key
    data = prepared.problem.data
    moved = replace(data, frequencies_hz=data.frequencies_hz * (1 + 1e-6))
    assert memo.memo_key(replace(prepared.problem, data=moved), rom.tol, settings) != key


def test_the_key_holds_the_basis_the_calibration_searches_on(first):
    """The basis enters the key by its own content key, computed without a build: that of the
    basis ``sampling_problem`` builds (the same box, modes, tolerance and seed)."""
    prepared, rom = first[0], first[1]
    assert memo.basis_of(prepared.problem, rom.tol).content_key() == rom.content_key()


def test_an_optimum_a_full_solve_does_not_reproduce_is_not_used(first, tmp_path):
    prepared, rom, run, key, _ = first
    arrays = memo.memo_arrays(run.result, run.error_at_optimum)
    arrays["objective"] = np.array(run.result.objective * (1 + 1e-6))
    with pytest.warns(RuntimeWarning, match="not reproduced by a full solve"):
        assert memo.recalled(prepared.problem, arrays, rom.tol) is None
    del arrays["counts"]
    with pytest.warns(RuntimeWarning, match="unreadable"):
        assert memo.recalled(prepared.problem, arrays, rom.tol) is None


def test_the_second_run_does_not_search(first, tmp_path, monkeypatch):
    monkeypatch.setenv("BAYESUPDATE_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("BAYESUPDATE_NO_CACHE", "0")
    monkeypatch.setattr(pipeline, "large_model", lambda rom: True)
    monkeypatch.setattr(pipeline, "large_fe_model", lambda model: True)
    prepared = _prepared("--no-polish")
    once = pipeline.run_calibration(prepared)

    def searched(*args, **kwargs):
        raise AssertionError("the kept calibration was not recalled")

    # neither the search nor the basis (its load and check at fresh points) is needed
    monkeypatch.setattr(pipeline, "calibrate_on_exact_basis", searched)
    monkeypatch.setattr(pipeline, "sampling_problem", searched)
    twice = pipeline.run_calibration(prepared)
    np.testing.assert_array_equal(twice.theta, once.theta)
    assert twice.objective == once.objective
    np.testing.assert_array_equal(twice.table.model_hz, once.table.model_hz)


def test_a_model_without_a_reduced_form_keeps_nothing():
    """Two parameters on one shell property have no affine decomposition: the calibration runs
    on full solves (``sampling_problem`` warns), and nothing is kept for it (key "")."""
    from test_reduced_shells import box_model

    from bayesupdate.fe import Binding, FEModel
    from bayesupdate.inference import build_problem
    from bayesupdate.inference.problem import ObjectiveSpec
    from bayesupdate.modal_data import ModalData

    box = box_model()
    fe = FEModel(
        box.structure,
        {"a": Binding("lids", "thickness"), "b": Binding("lids", "thickness")},
        {"a": 2e-3, "b": 2e-3},
        {"a": (1e-3, 3e-3), "b": (1e-3, 3e-3)},
    )
    data = ModalData(box.predict(None, 4).frequencies_hz)
    problem = build_problem(fe, data, None, "order", extra_modes=0, objective=ObjectiveSpec())
    settings = pipeline.CalibrationSettings(starts=1)
    assert memo.memo_key(problem, 1e-4, settings) == ""
