"""An absolute binding over cards whose values differ sets one value on all of them, the
default (their mean) included (``nastran.bindings.uniform_fields``): the model is continuous at
the default, as MSC SOL 200 reads one DESVAR through a DVPREL1 (COEF 1.0) on each card; the
mAEWing1 authors' SOL 200 deck binds PBEAM 1003-1009 I1 to DESVAR 300101 so."""

import numpy as np
import pytest

from bayesupdate.nastran import load_nastran_model
from bayesupdate.nastran.bindings import field_value, parse_binding
from bayesupdate.pipelines import aircraft as ac

OUTER = "PBEAM 1003,1004,1005,1006,1007,1008,1009 I1"


@pytest.fixture(scope="module")
def model():
    tables = {n: {"binds": b, "bounds": list(bd)} for n, (b, bd) in ac.PARAMETERS.items()}
    return load_nastran_model(ac.data_folder() / ac.V33_DECK, tables)


def test_the_seven_cards_are_read_at_their_mean_with_a_note(model):
    # the deck's seven outer I1 [in^4]: 0.0099-0.0563, mean 0.0266516 (test_aircraft_case)
    default = model.default_parameters()["I1_wing"]
    assert default == pytest.approx(0.0266516, rel=1e-5)
    f = parse_binding(OUTER, "I1_wing")
    values = [field_value(model.bdf.table("PBEAM")[i], f) for i in f.ids]
    assert values == [values[0]] * 7  # one value, written to 16 characters
    assert values[0] == pytest.approx(default, rel=1e-14)
    notes = [n for n in model.structure.metadata["nastran"]["notes"] if "I1_wing" in n]
    assert len(notes) == 1 and "(0.009941-0.05627)" in notes[0] and "mean 0.02665" in notes[0]


def test_a_tiny_step_changes_k_by_a_tiny_amount_at_the_default(model):
    """Before, the default alone was the deck: a 1e-13 step of EI_root changed K by 2.8e5."""
    p0 = model.default_parameters()
    K0 = model.matrices(p0)[0]
    scale = np.abs(K0.data).max()
    step_other = model.matrices({**p0, "EI_root": 1.0 + 1e-13})[0]
    assert np.abs((step_other - K0).data).max() < 1e-10 * scale
    step_own = model.matrices({**p0, "I1_wing": p0["I1_wing"] * (1 + 1e-9)})[0]
    change = np.abs((step_own - K0).data).max()
    assert 0 < change < 1e-7 * scale


def test_the_default_is_the_deck_with_one_value_written(model, tmp_path):
    """The model at its default solves as the deck the writer writes there (read unbound)."""
    from bayesupdate.nastran.writer import write_updated_deck

    p0 = model.default_parameters()
    written = write_updated_deck(model, p0, tmp_path / "v33_uniform.bdf")
    again = load_nastran_model(str(written)).solve(None, 8).frequencies_hz
    np.testing.assert_allclose(model.solve(p0, 8).frequencies_hz, again, rtol=5e-8)


def test_cards_that_agree_or_a_scale_leave_the_deck_as_it_is():
    deck = ac.data_folder() / ac.V33_DECK
    for binds in (OUTER + " scale", "PBEAM 1003 I1"):
        model = load_nastran_model(deck, {"p": {"binds": binds}})
        notes = model.structure.metadata["nastran"]["notes"]
        assert not any("read with their mean" in n for n in notes)
        f = parse_binding(OUTER, "p")
        assert field_value(model.bdf.table("PBEAM")[1003], f) == pytest.approx(0.00994078256)
