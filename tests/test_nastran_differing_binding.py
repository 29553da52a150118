"""An absolute binding over cards whose deck values differ is refused, naming the cards' spread
and the fix (``nastran.bindings.refuse_differing``): at its default it would be the deck and
anywhere else one value on all cards, so K would jump there.  The fix it names, a ``scale``,
is the deck at its default and continuous around it (the mAEWing1 v3.3 deck's seven outer-wing
PBEAM I1, 0.0099-0.0563 in^4; v4.2 gives the same seven one section, 0.138 in^4)."""

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran import load_nastran_model
from bayesupdate.pipelines import aircraft as ac

OUTER = "PBEAM 1003,1004,1005,1006,1007,1008,1009 I1"


@pytest.fixture(scope="module")
def v33():
    return ac.data_folder() / ac.V33_DECK


@pytest.fixture(scope="module")
def scaled(v33):
    return load_nastran_model(v33, {"EI_outer": {"binds": OUTER + " scale"}})


def test_an_absolute_binding_over_differing_cards_is_refused_with_the_fix(v33):
    with pytest.raises(BayesUpdateError) as err:
        load_nastran_model(v33, {"I1_wing": {"binds": OUTER, "bounds": [0.0063, 0.4]}})
    message = str(err.value)
    assert "\n" not in message and message.startswith("parameter I1_wing:")
    # the deck's own extremes: PBEAM 1003 (0.00994078 in^4) and the stiffest outer card
    assert "(0.009941-0.05627)" in message
    assert f"bind '{OUTER} scale', or one card" in message


def test_cards_that_agree_or_one_card_stay_absolute(v33):
    # v4.2 gives the seven one section: its I1 is the default, the card value 0.137644 in^4
    v42 = load_nastran_model(ac.data_folder() / ac.V42_DECK, {"I1": {"binds": OUTER}})
    assert v42.default_parameters()["I1"] == pytest.approx(0.137644, rel=1e-12)
    one = load_nastran_model(v33, {"I1": {"binds": "PBEAM 1003 I1"}})
    assert one.default_parameters()["I1"] == pytest.approx(0.00994078256, rel=1e-9)


def test_the_scale_is_the_deck_at_its_default(v33, scaled):
    deck = load_nastran_model(v33).solve(None, 10).frequencies_hz
    at_default = scaled.solve(scaled.default_parameters(), 10).frequencies_hz
    assert scaled.default_parameters() == {"EI_outer": 1.0}
    np.testing.assert_allclose(at_default, deck, rtol=1e-12)
    assert at_default[0] == pytest.approx(5.3772, rel=1e-4)  # v3.3's f06, first flap mode


def test_frequencies_move_by_about_the_step_around_the_default(scaled):
    """A relative step h = 1e-9 either side of the default moves the elastic frequencies by
    S x h (S = d ln f / d ln EI_outer, within [0, 0.5] for a stiffness scale: Rayleigh) plus
    the eigen-solve's round-off (up to about 1.3e-10 on the first flap mode, measured here),
    the stiffer side up; the absolute binding moved them by up to 37 % at once (v3.3's seven
    I1 against their mean)."""
    h, roundoff = 1e-9, 2e-10
    f0, up, down = (scaled.solve({"EI_outer": 1.0 + s}, 10).frequencies_hz for s in (0, h, -h))
    elastic = f0 > 1.0
    rel_up, rel_down = (up / f0 - 1)[elastic], (down / f0 - 1)[elastic]
    for rel in (rel_up, -rel_down):
        assert np.all(np.abs(rel) < 0.5 * h + roundoff) and rel.max() > 0.3 * h


def test_k_is_continuous_at_the_default(scaled):
    p0 = scaled.default_parameters()
    K0 = scaled.matrices(p0)[0]
    size = np.abs(K0.data).max()
    change = np.abs((scaled.matrices({"EI_outer": 1.0 + 1e-9})[0] - K0).data).max()
    assert 0 < change < 1e-8 * size
