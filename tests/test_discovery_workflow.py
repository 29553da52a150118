"""Discovery end to end on a small frame (two pipes, a joint spring, a bend, six sensor points):
each effect kind hidden in synthetic frequencies is named at the right place, the null case says
"no discrepancy", a change outside the library says "unexplained"; results file and plots."""

import dataclasses
import json

import numpy as np
import pytest

from bayesupdate.discovery.effects import extend_model, parse_effect_spec
from bayesupdate.discovery.results_io import (
    discovery_summary,
    extend_with_specs,
    read_discovery_summary,
    write_discovery,
)
from bayesupdate.discovery.settings import (
    DiscoverySettings,
    EvidenceSettings,
    LibraryScan,
    RefitBudget,
)
from bayesupdate.discovery.workflow import discover
from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import STEEL, Binding, FEModel, StructureBuilder, circular_tube
from bayesupdate.modal_data import ModalData, noisy_modes

SEC = circular_tube(0.045, 1.5e-3)
NOISE = 0.002  # relative frequency sd of the synthetic tests
TRUE_T = 1.8e-3
FAST = DiscoverySettings(
    refit=RefitBudget(baseline_starts=1, quick_refits=5, per_kind=2, max_refits=2, max_nfev=15),
    evidence=EvidenceSettings(loo_top=1, loo_draws=200),
)


def frame_model(length_b: float = 1.6) -> FEModel:
    b = StructureBuilder()
    a = b.add_pipe_run(
        [(0, 0, 0), (1.2, 0, 0), (1.6, 0.7, 0.1)],
        SEC,
        STEEL,
        "pipe_a",
        bend_radii=[0.15],
        bend_names=["elbow"],
        element_length=0.2,
    )
    j = b.add_node(b.node_xyz(a[-1]))
    d = np.array([0.4, 0.7, 0.1]) / np.linalg.norm([0.4, 0.7, 0.1])
    e2 = np.cross([0, 0, 1.0], d)
    e2 /= np.linalg.norm(e2)
    b.add_spring(
        a[-1],
        j,
        [1e8, 1e8, 1e8, 1e5, 3e4, 3e4],
        "pipe_a/pipe_b",
        frame=np.array([d, e2, np.cross(d, e2)]),
    )
    c = b.add_pipe_run(
        [b.node_xyz(j), b.node_xyz(j) + (length_b, 0.3, -0.1)],
        SEC,
        STEEL,
        "pipe_b",
        start_node=j,
        element_length=0.2,
    )
    for k, node in enumerate([a[0], a[3], a[-2], c[2], c[5], c[-1]], start=1):
        b.add_sensor(f"{k}V", node, "V")
        b.add_sensor(f"{k}H", node, "H")
    return FEModel(
        b.build(),
        {"t_a": Binding("pipe_a", "thickness")},
        {"t_a": 1.5e-3},
        {"t_a": (0.5e-3, 3e-3)},
        name="frame",
    )


@pytest.fixture(scope="module")
def frame():
    return frame_model()


def synthetic(model, specs=(), n_modes=8, seed=0, truth_model=None, shape_noise=0.0):
    """Noisy frequencies of the truth; with ``shape_noise`` > 0 also its shapes at the 12
    sensor DOFs with Gaussian noise of that fraction of each shape's RMS amplitude."""
    truth = truth_model or model
    for spec in specs:
        truth = extend_model(truth, parse_effect_spec(spec))
    prediction = truth.predict({"t_a": TRUE_T}, n_modes)
    rng = np.random.default_rng(seed)
    source = "synthetic with shapes" if shape_noise > 0 else "synthetic"
    return noisy_modes(prediction, NOISE, shape_noise, rng, source)


@pytest.mark.parametrize(
    "spec",
    [
        "added_mass@5:m=0.3",
        "joint_flexibility@pipe_a/pipe_b:k_rot=3e3",
        "bend_flexibility@elbow:factor=3",
        "boundary_spring@4:k=2e4",
        "stiffness_change@pipe_b:factor=0.8",
    ],
)
def test_each_kind_is_named_at_its_location(frame, spec):
    effect = parse_effect_spec(spec)
    result = discover(frame, synthetic(frame, [spec]), FAST)
    out = discovery_summary(result)
    assert out["verdict"] == "explained", out["reason"]
    assert (out["named_effect"]["kind"], out["named_effect"]["location"]) == (
        effect.kind,
        effect.location,
    )
    ((name, true_value),) = effect.parameters.items()
    fitted = out["named_effect"]["parameters"][name]
    assert fitted == pytest.approx(true_value, rel=0.1)
    # the gap closes to the noise: rms error after within 2 x noise, design variable recovered
    assert np.sqrt(np.mean(result.final.residual_rel**2)) < 2 * NOISE
    assert out["gap_after"] < 0.1 * out["gap_before"]
    assert out["design_after"]["t_a"] == pytest.approx(TRUE_T, rel=0.05)
    best = out["candidates"][0]
    assert best["log_posterior_odds"] > 3
    assert best["log_posterior_odds"] == pytest.approx(
        best["log_bayes_factor"] - np.log(len(result.localization.scores))
    )
    assert best["loo"] > out["baseline"]["loo"]


def test_no_effect_gives_no_discrepancy(frame):
    out = discovery_summary(discover(frame, synthetic(frame, [], seed=4), FAST))
    assert out["verdict"] == "no discrepancy"
    assert out["named_effect"] is None and out["flagged_modes"] == []
    assert out["gap_after"] == out["gap_before"]


def test_shapes_name_a_mass_the_frequencies_alone_cannot(frame):
    """A 50 g mass at point 3 moves frequencies by ~2x noise: from frequencies alone the best
    candidate cannot be told apart; the shapes (3 % noise, 1 - MAC ~ 1e-3) name it."""
    spec = "added_mass@3:m=0.05"
    without = discovery_summary(discover(frame, synthetic(frame, [spec]), FAST))
    assert without["verdict"] != "explained"
    with_shapes = discovery_summary(
        discover(frame, synthetic(frame, [spec], shape_noise=0.03), FAST)
    )
    assert with_shapes["verdict"] == "explained", with_shapes["reason"]
    named = with_shapes["named_effect"]
    assert (named["kind"], named["location"]) == ("added_mass", "3")
    assert named["parameters"]["m"] == pytest.approx(0.05, rel=0.15)
    assert with_shapes["candidates"][0]["log_bayes_factor"] > 10
    # PSIS-LOO, with each mode's frequency and shape as one observation, agrees
    assert with_shapes["candidates"][0]["loo"] > with_shapes["baseline"]["loo"]


def test_noisy_and_biased_shapes_cause_no_false_discovery(frame):
    """No effect; shapes with 3 % noise, and one mode's shape biased to 1 - MAC ~ 2e-2 (as the
    virtual roving-hammer test identifies the modes its reference barely sees), with no stated sd
    and with a stated 3 %: either way the bias rejects the stated level at the frequency-only
    baseline, the mode's level is raised to its misfit there, and nothing is named."""
    data = synthetic(frame, [], seed=4, shape_noise=0.03)
    shapes = np.array(data.shapes)
    rng = np.random.default_rng(9)
    bias = rng.normal(size=shapes.shape[0])
    bias -= shapes[:, 2] * (bias @ shapes[:, 2]) / (shapes[:, 2] @ shapes[:, 2])
    shapes[:, 2] += 0.15 * np.linalg.norm(shapes[:, 2]) * bias / np.linalg.norm(bias)
    biased = ModalData(
        data.frequencies_hz,
        shapes=shapes,
        dof_labels=data.dof_labels,
        frequency_sd_hz=data.frequency_sd_hz,
        source="biased shapes",
    )
    result = discover(frame, biased, FAST)
    out = discovery_summary(result)
    assert 1 - result.baseline.mac[2] > 1e-2
    assert out["verdict"] == "no discrepancy", out["reason"]
    assert out["named_effect"] is None
    assert out["noise"]["shapes"]["source"] == "floor"
    assert 3 in out["noise"]["shapes"]["raised_to_baseline_misfit"]
    stated = dataclasses.replace(biased, shape_sd_rel=np.full(biased.n_modes, 0.03))
    out = discovery_summary(discover(frame, stated, FAST))
    assert out["noise"]["shapes"]["source"] == "data sd"
    assert out["noise"]["shapes"]["raised_to_baseline_misfit"] == [3]
    assert out["noise"]["shapes"]["sd_rel"][2] > 0.1  # ~ sqrt(2e-2): the bias, not the 3 %
    assert out["verdict"] == "no discrepancy" and out["named_effect"] is None, out["reason"]


def test_geometry_change_outside_the_library_is_unexplained(frame):
    """pipe_b 10 % longer in the 'real' structure: no library effect fits within noise."""
    data = synthetic(frame, [], truth_model=frame_model(1.75))
    out = discovery_summary(discover(frame, data, FAST))
    assert out["verdict"] == "unexplained"
    assert out["named_effect"] is None
    assert out["flagged_modes"]


def test_a_longer_pipe_seen_in_known_noise_shapes_is_unexplained(frame):
    """pipe_b 3 % longer, shapes with their stated 3 % noise: the best library effect (a softer
    pipe_b) gains a large Bayes factor but leaves modes misfitting beyond the stated noise."""
    data = synthetic(frame, [], truth_model=frame_model(1.65), shape_noise=0.03)
    out = discovery_summary(discover(frame, data, FAST))
    assert out["verdict"] == "unexplained" and out["named_effect"] is None, out["reason"]
    assert out["candidates"][0]["log_bayes_factor"] > 100
    assert "misfit remains" in out["reason"]


def test_two_effects_at_once_are_not_named(frame):
    data = synthetic(frame, ["added_mass@6:m=0.4", "stiffness_change@pipe_a:factor=0.7"])
    out = discovery_summary(discover(frame, data, FAST))
    assert out["verdict"] == "unexplained" and out["named_effect"] is None


def test_bad_inputs_are_clear_errors(frame):
    data = synthetic(frame, [])
    with pytest.raises(BayesUpdateError, match="unknown effect kind"):
        discover(frame, data, DiscoverySettings(LibraryScan(kinds=("added_mas",))))
    with pytest.raises(BayesUpdateError, match="unknown location"):
        discover(frame, data, DiscoverySettings(LibraryScan(locations={"added_mass": ["9"]})))
    with pytest.raises(BayesUpdateError, match="cannot decide"):
        discover(frame, data.subset(slice(0, 2)), FAST)
    with pytest.raises(BayesUpdateError, match="sigma"):
        EvidenceSettings(sigma=-1.0)
    with pytest.raises(BayesUpdateError, match="outside the bounds"):
        extend_with_specs(frame, ["added_mass@2:m=7"])


@pytest.fixture(scope="module")
def named_mass(frame):
    """A run that names added_mass@2 (shared: each discover run on the frame costs seconds)."""
    return discover(frame, synthetic(frame, ["added_mass@2:m=0.3"], seed=2), FAST)


def test_result_file_round_trip_and_extended_model(frame, named_mass, tmp_path):
    result = named_mass
    assert result.verdict == "explained"
    path = tmp_path / "d.h5"
    write_discovery(path, result, config={"note": "test"})
    summary = read_discovery_summary(path)
    assert summary["verdict"] == "explained"
    assert summary["effects"] == result.effects and summary["effects"][0].startswith(
        "added_mass@2:m="
    )
    assert json.loads(json.dumps(summary))["gap_after"] == pytest.approx(result.final.expr)
    # the stored spec list rebuilds the extended model: same frequencies at the final design
    extended = extend_with_specs(frame, summary["effects"])
    f = extended.solve({"t_a": summary["final_parameters"]["t_a"]}, 8).frequencies_hz
    np.testing.assert_allclose(f, result.final.frequencies_hz, rtol=1e-5)
    # the optional posterior of the re-calibrated model: walkers from the Laplace Gaussian,
    # a short emcee run; its mean mass sits within 4 posterior sd of the truth (0.3 kg).  DE
    # moves: the default mixture's adaptation (2 x 250 steps + 1000 coverage solves) would be
    # 19x this 40-step run; the moves' accuracy is test_posterior_reference's and
    # test_inference_moves' subject, the extended model's parameters are this test's
    from bayesupdate.discovery.posterior import sample_final

    chain, _ = sample_final(result, steps=40, walkers=8, seed=3, moves="de")
    assert chain.diagnostics["moves"]["kind"] == "de"
    draws = chain.chain[10:, :, 1].ravel()
    assert np.all(np.isfinite(chain.log_prob))
    assert abs(draws.mean() - 0.3) < 4 * max(draws.std(), 1e-3)
    from bayesupdate.discovery.plots import save_plots

    written = save_plots(result, tmp_path / "figs", frame.structure)
    assert [p.name for p in written] == ["residuals.png", "localization.png", "ranking.png"]
    assert all(p.stat().st_size > 5000 for p in written)


def test_an_effect_pinned_on_its_bound_is_never_named(named_mass):
    """The out-of-library guard: the same winning fit, with its effect parameter moved onto the
    bound, is "unexplained" (a library effect stretched to its limit absorbs something else)."""

    from bayesupdate.discovery.workflow import _effect_at_bound, decide

    result = named_mass
    assert result.verdict == "explained" and result.named.label == "added_mass@2"
    d = len(result.baseline.names)
    assert _effect_at_bound(result.named, d, 0.005) == []
    theta = result.named.theta.copy()
    theta[d] = 2.0  # added_mass m bounds (0, 2) kg
    pinned = dataclasses.replace(result.named, theta=theta)
    assert _effect_at_bound(pinned, d, 0.005) == ["added_mass@2:m"]
    fits = [pinned, *result.fits[1:]]
    prior = result.prior_log_odds
    verdict, reason, named, _ = decide(
        result.baseline, fits, result.flags, result.noise, result.settings.verdict, prior
    )
    assert (verdict, named) == ("unexplained", None)
    assert "on its bound" in reason
    verdict, _, named, _ = decide(
        result.baseline, result.fits, result.flags, result.noise, result.settings.verdict, prior
    )
    assert verdict == "explained" and named is result.fits[0]


def test_prior_odds_spread_over_the_library_set_the_bar(named_mass):
    """Multiplicity (Scott & Berger 2010): P(one library effect) = 1/2 spread over the N
    candidates scanned, so a candidate needs ln BF > 3 + ln N.  The same adequate, well-placed
    fit at ln BF 5 is named when it is the only candidate considered, not among the frame's."""

    from bayesupdate.discovery.workflow import decide

    result = named_mass
    n = len(result.localization.scores)
    assert n == 6 + 6 + 2 + 1 + 1  # masses and springs at 6 points, 2 parts, a joint, a bend
    assert result.prior_log_odds == pytest.approx(-np.log(16))
    s = result.settings.verdict
    assert dataclasses.replace(s, effect_prior=0.9).prior_log_odds(58) == pytest.approx(
        np.log(9 / 58)
    )
    weak = dataclasses.replace(result.named, log_evidence=result.baseline.log_evidence + 5.0)
    args = (result.baseline, [weak], result.flags, result.noise, s)
    verdict, reason, named, _ = decide(*args, s.prior_log_odds(n))
    # the 0.3 kg mass leaves the baseline misfitting: misfit remains, nothing named
    assert (verdict, named) == ("unexplained", None), reason
    assert f"posterior log odds {5 - np.log(16):.2f} <= 3" in reason
    verdict, _, named, _ = decide(*args, s.prior_log_odds(1))
    assert verdict == "explained" and named is weak
    # posterior probabilities over the baseline and the fitted candidates: normalized, and
    # each in proportion to exp(ln BF + prior log odds)
    log_probability = result.log_posterior_probabilities()
    assert np.exp(log_probability).sum() == pytest.approx(1.0)
    odds = [result.log_posterior_odds(f) for f in result.fits[:2]]
    assert log_probability[1] - log_probability[0] == pytest.approx(odds[0])
    assert log_probability[2] - log_probability[0] == pytest.approx(odds[1])
    out = discovery_summary(result)
    assert out["candidates"][0]["posterior_probability"] == pytest.approx(
        np.exp(log_probability[1])
    )
    assert out["candidates"][0]["posterior_probability"] > 0.9


def test_a_fit_solves_each_point_once():
    """``fit_model`` asks for points again: the chosen start (picked by its chi^2, then the
    solver's first call) and the end point's forward-difference points (TRF's last Jacobian,
    then the evidence's own, with the same steps).  Each distinct point is solved once, and
    ``evaluations`` counts solves: the fit's points, plus its own look at the optimum."""
    from bayesupdate.discovery.evidence import FitSpace, fit_model
    from bayesupdate.inference.likelihood_blocks import NoiseModel
    from bayesupdate.inference.parameter_space import ParameterSpec
    from bayesupdate.inference.priors import prior_from_mapping
    from bayesupdate.inference.problem import Evaluation

    truth = np.array([1.2, 0.4])
    slopes = np.array([[0.10, 0.02], [0.05, 0.08], [0.02, 0.10], [0.07, 0.01]])

    def frequencies(theta):  # a smooth, non-linear toy model [Hz]
        return np.array([10.0, 20.0, 30.0, 40.0]) * np.sqrt(1 + slopes @ theta**2)

    solved = []

    class Problem:
        data = ModalData(frequencies(truth))

        def evaluate(self, theta):
            solved.append(tuple(theta))
            f = frequencies(theta)
            return Evaluation(True, f, f)

        def expr(self, f):
            return float(np.sum(((f - self.data.frequencies_hz) / self.data.frequencies_hz) ** 2))

    axes = tuple(
        ParameterSpec(n, (0.0, 2.0), prior_from_mapping(None, (0.0, 2.0), n), axis="linear")
        for n in ("a", "b")
    )
    noise = NoiseModel(np.full(4, 1e-3), np.ones(4), False, "fixed", 1e-3)
    space = FitSpace(Problem(), axes, noise)
    starts = [np.array([0.5, 0.5]), np.array([1.0, 0.6]), np.array([1.9, 1.9])]
    fit = fit_model(space, starts, max_nfev=40, best_start_only=True)
    np.testing.assert_allclose(fit.theta, truth, rtol=1e-4)
    assert fit.evaluations == len(solved)
    fitted = solved[:-1]  # the last: fit_model's look at its optimum (theta from z)
    assert len(fitted) == len(set(fitted)) > len(starts) + 2 * len(axes)
