"""``stiffness_change`` on a Nastran deck's line property (``stiffness_change@PBEAM 2``): a factor
on E and G of that PBEAM's CBEAMs alone (``nastran.bindings.modulus_binding``).

A clamped steel cantilever deck, 1 m in ten shear-flexible CBEAMs (PBEAM K1 = K2 = 1, MAT1 with
E and G both given), PBEAM 1 on the root half and PBEAM 2 on the tip half.  Closed forms: every
stiffness of a Timoshenko beam (EA, EI, GJ, k G A) scales with E and G together, so scaling the
whole beam's multiplies every frequency by sqrt(factor) exactly (K -> c K, M unchanged); scaling
PBEAM 2 alone equals the deck edited by hand with PBEAM 2 on its own MAT1 at c E, c G."""

import numpy as np
import pytest

from bayesupdate.discovery.effects import effect_locations, extend_model, parse_effect_spec
from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran import load_nastran_model

E, G, RHO = 2.1e11, 8.0e10, 7850.0


def _cantilever(path, pids=(1, 2), tip_mat=(1, E, G)):
    """The deck (module docstring); ``pids``: the root and tip halves' PBEAMs; ``tip_mat``:
    (MID, E, G) of the tip half's PBEAM (MID 1 is the shared steel)."""
    lines = ["SOL 103", "CEND", "METHOD = 1", "SPC = 1", "BEGIN BULK", "EIGRL,1,,,8"]
    lines += [f"GRID,{k + 1},,{0.1 * k:.3f},0.,0." for k in range(11)]
    for k in range(10):
        pid = pids[0] if k < 5 else pids[1]
        lines.append(f"CBEAM,{k + 1},{pid},{k + 1},{k + 2},0.,1.,0.")
    # a 30 x 10 mm bar: A, I1 (flap), I2, J; K1 = K2 = 1: shear flexible
    section = "3.0e-4,2.5e-9,2.25e-8,,7.9e-9"
    lines.append(f"PBEAM,{pids[0]},1,{section}")
    if pids[1] != pids[0]:
        lines.append(f"PBEAM,{pids[1]},{tip_mat[0]},{section}")
    lines.append(f"MAT1,1,{E!r},{G!r},,{RHO!r}")
    if tip_mat[0] != 1:
        lines.append(f"MAT1,{tip_mat[0]},{tip_mat[1]!r},{tip_mat[2]!r},,{RHO!r}")
    lines += ["SPC1,1,123456,1", "ENDDATA"]
    path.write_text("\n".join(lines) + "\n")
    return path


def _hz(model, params=None, n=8):
    return np.asarray(model.solve(params, n_modes=n).frequencies_hz)


def test_effect_locations_are_the_decks_line_properties(tmp_path):
    model = load_nastran_model(_cantilever(tmp_path / "c.bdf"))
    assert effect_locations(model, "stiffness_change") == ["PBEAM 1", "PBEAM 2"]
    # a parameter on the shared MAT1's E already sets every element's modulus: none is offered
    bound = load_nastran_model(_cantilever(tmp_path / "c.bdf"), {"e": {"binds": "MAT1 1 E scale"}})
    assert effect_locations(bound, "stiffness_change") == []
    # an I1 scale leaves the modulus free: offered, and the two compose
    i1 = load_nastran_model(_cantilever(tmp_path / "c.bdf"), {"i": {"binds": "PBEAM 2 I1 scale"}})
    assert effect_locations(i1, "stiffness_change") == ["PBEAM 1", "PBEAM 2"]


@pytest.mark.parametrize("factor", [0.5, 1.37])
def test_scaling_the_whole_cantilever_scales_every_frequency_by_sqrt_factor(tmp_path, factor):
    model = load_nastran_model(_cantilever(tmp_path / "c.bdf", pids=(1, 1)))
    extended = extend_model(model, parse_effect_spec("stiffness_change@PBEAM 1"))
    name = "stiffness_change@PBEAM 1:factor"
    f0 = _hz(model)
    assert _hz(extended, {name: 1.0}) == pytest.approx(f0, rel=1e-12)
    assert _hz(extended, {name: factor}) == pytest.approx(np.sqrt(factor) * f0, rel=1e-9)
    assert extended.total_mass({name: factor})[0] == pytest.approx(model.total_mass()[0])


def test_scaling_one_pbeam_equals_its_own_material_typed_in(tmp_path):
    factor = 0.8
    model = load_nastran_model(_cantilever(tmp_path / "c.bdf"))
    extended = extend_model(model, parse_effect_spec("stiffness_change@PBEAM 2"))
    by_hand = load_nastran_model(
        _cantilever(tmp_path / "hand.bdf", tip_mat=(2, factor * E, factor * G))
    )
    got = _hz(extended, {"stiffness_change@PBEAM 2:factor": factor})
    assert got == pytest.approx(_hz(by_hand), rel=1e-10)
    # the elements' records are affine in the factor: each solve recomputes them from records,
    # not from re-read cards (``nastran.lines.LineFields``)
    assert extended.general.fields_note == ""
    assert not np.allclose(got, np.sqrt(factor) * _hz(model), rtol=1e-3)  # the tip half alone


def test_with_an_i1_parameter_on_the_same_pbeam_both_act(tmp_path):
    """PBEAM 2 I1 x 1.5 (a deck parameter) and its modulus x 0.8 (the effect) together equal the
    deck with both typed in."""
    params = {"i": {"binds": "PBEAM 2 I1 scale", "bounds": [0.5, 2.0]}}
    model = load_nastran_model(_cantilever(tmp_path / "c.bdf"), params)
    extended = extend_model(model, parse_effect_spec("stiffness_change@PBEAM 2"))
    by_hand = load_nastran_model(
        _cantilever(tmp_path / "hand.bdf", tip_mat=(2, 0.8 * E, 0.8 * G)), params
    )
    got = _hz(extended, {"i": 1.5, "stiffness_change@PBEAM 2:factor": 0.8})
    assert got == pytest.approx(_hz(by_hand, {"i": 1.5}), rel=1e-10)


def test_an_unknown_line_property_is_a_clear_error(tmp_path):
    model = load_nastran_model(_cantilever(tmp_path / "c.bdf"))
    with pytest.raises(BayesUpdateError, match="unknown location"):
        extend_model(model, parse_effect_spec("stiffness_change@PBEAM 7"))


def test_discover_names_the_softer_pbeam_of_a_deck(tmp_path):
    """A virtual test of the deck with PBEAM 2 on its own MAT1 at 0.8 E, 0.8 G (8 frequencies,
    0.2 % noise), against the deck with one design variable (both PBEAMs' torsion constant J:
    a line field of the same elements, which the effect composes with; a density or modulus of
    the whole beam would make a softer tip and a stiffer root one model up to that scale):
    discover names ``stiffness_change@PBEAM 2`` with its factor."""
    from bayesupdate.discovery.results_io import discovery_summary
    from bayesupdate.discovery.settings import DiscoverySettings, EvidenceSettings, RefitBudget
    from bayesupdate.discovery.workflow import discover
    from bayesupdate.modal_data import noisy_modes

    params = {"j": {"binds": "PBEAM 1,2 J scale", "bounds": [0.5, 2.0]}}
    model = load_nastran_model(_cantilever(tmp_path / "c.bdf"), params)
    truth = load_nastran_model(_cantilever(tmp_path / "t.bdf", tip_mat=(2, 0.8 * E, 0.8 * G)))
    data = noisy_modes(truth.predict(None, 8), 0.002, 0.0, np.random.default_rng(0), "virtual")
    settings = DiscoverySettings(
        refit=RefitBudget(baseline_starts=2, max_refits=2, max_nfev=15),
        evidence=EvidenceSettings(loo_top=1, loo_draws=200),
    )
    out = discovery_summary(discover(model, data, settings))
    assert out["verdict"] == "explained", out["reason"]
    assert out["named_effect"]["location"] == "PBEAM 2"
    assert out["named_effect"]["parameters"]["factor"] == pytest.approx(0.8, rel=0.02)
    assert out["gap_after"] < 0.01 * out["gap_before"]
