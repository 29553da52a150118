"""A large model's full solve at the reference design kept on disk
(``fe.reference_memo``): the pairing's reference of a second ``build_problem`` on the
same model is recalled without a solve and is the first one's to the bit; a changed model or
point is another entry (solved), the store off or a small model solve every time, and an entry
that does not hold the modes asked for is solved again.  On the beam exhaust with the
large-model threshold lowered (a shell exhaust solve takes seconds)."""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from dataclasses import replace  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from bayesupdate.compute.cache import ArrayStore  # noqa: E402
from bayesupdate.fe import reference_memo as memo  # noqa: E402
from bayesupdate.fe.model import FEModel  # noqa: E402
from bayesupdate.fe.reduced import settings as reduced_settings  # noqa: E402
from bayesupdate.inference.data import load_modal_data  # noqa: E402
from bayesupdate.inference.problem import build_problem  # noqa: E402
from bayesupdate.models import get_model  # noqa: E402


@pytest.fixture
def solves(monkeypatch, tmp_path):
    """The environment's store in ``tmp_path``, every model large; the list of the n_modes of
    each ``FEModel.predict`` call made."""
    monkeypatch.setenv("BAYESUPDATE_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("BAYESUPDATE_NO_CACHE", raising=False)
    monkeypatch.setattr(reduced_settings, "LARGE_MODEL_DOFS", 0)
    calls: list[int] = []
    predict = FEModel.predict

    def counted(self, params=None, n_modes=12):
        calls.append(n_modes)
        return predict(self, params, n_modes)

    monkeypatch.setattr(FEModel, "predict", counted)
    return calls


def _problem(model, **options):
    data = load_modal_data("paper:ema")
    return build_problem(model, data, extra_modes=2, reference_solve=memo.remembered_solve,
                         **options)  # fmt: skip


def _same(a, b) -> None:
    np.testing.assert_array_equal(a.frequencies_hz, b.frequencies_hz)
    np.testing.assert_array_equal(a.shapes, b.shapes)
    assert a.dof_labels == b.dof_labels and a.mass_kg == b.mass_kg


def test_a_second_problem_recalls_the_reference_to_the_bit(solves, tmp_path):
    model = get_model("exhaust")
    plain = build_problem(model, load_modal_data("paper:ema"), extra_modes=2)
    assert solves == [14]
    first = _problem(model)
    assert solves == [14, 14] and ArrayStore(tmp_path).info().entries == 1
    second = _problem(model)
    assert solves == [14, 14]  # recalled: no solve
    _same(second.reference, plain.reference)
    _same(first.reference, plain.reference)
    np.testing.assert_array_equal(second.pairing.reference_shapes, plain.pairing.reference_shapes)


def test_another_point_or_model_is_solved_again(solves, tmp_path):
    model = get_model("exhaust")
    base = _problem(model)
    moved = _problem(model, fixed={"rho_catalyst": 9000.0}, parameters={"t_hot_pipe": {}})
    s = model.structure
    stiffer = model.with_structure(replace(s, beam_E=s.beam_E * 1.01))
    other = _problem(stiffer)
    assert len(solves) == 3 and ArrayStore(tmp_path).info().entries == 3
    # each is its own model's solve, not the first entry: the pipes 1 % stiffer raise every
    # frequency, by at most sqrt(1.01) (hangers and masses unchanged)
    _same(other.reference, build_problem(stiffer, load_modal_data("paper:ema")).reference)
    ratio = other.reference.frequencies_hz / base.reference.frequencies_hz
    assert np.all(ratio > 1.001) and np.all(ratio <= np.sqrt(1.01) + 1e-12)
    assert not np.array_equal(moved.reference.frequencies_hz, base.reference.frequencies_hz)


def test_the_store_off_or_a_small_model_solves_every_time(solves, monkeypatch, tmp_path):
    model = get_model("exhaust")
    monkeypatch.setenv("BAYESUPDATE_NO_CACHE", "1")
    _problem(model)
    _problem(model)
    monkeypatch.delenv("BAYESUPDATE_NO_CACHE")
    monkeypatch.setattr(reduced_settings, "LARGE_MODEL_DOFS", model.structure.n_dof + 1)
    _problem(model)
    _problem(model)
    assert solves == [14] * 4 and ArrayStore(tmp_path).info().entries == 0


def test_an_entry_without_the_modes_asked_for_is_solved_again(solves, tmp_path):
    model = get_model("exhaust")
    params = model.default_parameters()
    store = ArrayStore(tmp_path)
    key = memo.solve_key(model, params, 14)
    short = model.predict(params, 12)
    store.save(key, memo.prediction_arrays(short))
    assert memo.prediction_of(store.load(key), 14) is None
    again = memo.remembered_solve(model, params, 14)
    assert solves == [12, 14] and again.frequencies_hz.size == 14
    _same(memo.prediction_of(store.load(key), 14), again)  # replaced by the whole solve
