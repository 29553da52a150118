"""Discovery end to end: baseline -> flag -> localize -> name -> add and show.

``discover(model, data, settings)`` returns a ``DiscoveryResult`` (the knobs named below are
fields of ``settings.DiscoverySettings``' records):

1. the baseline calibration of the design variables (or the one given), its noise model and
   Laplace evidence (``flagging``, ``evidence``);
2. flagged modes (z-scores, p-values, MAC);
3. the localization views; every candidate of the library at every admissible location gets a
   score test (``localization``);
4. two-tier refits with the design variables.  Quick tier: the ``quick_refits`` best candidates
   by score, plus the best ``per_kind`` of every kind (the broad-scan fallback: the linear score
   misjudges large effects, whose baseline optimum sits far from the truth), each a few
   Gauss-Newton iterations (``quick_nfev``) from the best (smallest chi^2) of 30-51 starts: the
   score test's suggestion, 3x and 10x that step, and the screen grid (7 magnitudes per side),
   each with the design variables at the baseline optimum, the reference design and the centre
   of the bounds box (one model solve per start: a cheap multi-start search, without which a
   large effect's refit stalls in the basin of the baseline that absorbed it).
   Full tier: the ``max_refits`` best by quick evidence, re-fitted to convergence from two
   starts (the quick end point, and the box centre with the quick fit's effect value).  All
   are compared by Laplace evidence (quick fits keep their quick value, a lower bound in
   practice, and are marked ``stage: quick``); the best few also by PSIS-LOO;
   Candidates that are one model (the same kind at one model node: two test points read on
   one node) are scored and refitted once, each keeping its own name (``twins``).
5. the verdict (``decide``):

   * ``explained``: the posterior log odds of the best candidate against the baseline,
     ln BF + ``prior_log_odds``, exceed ``threshold_log_odds`` (3: "strong" on the
     Kass-Raftery scale), ln BF(best vs runner-up) >= ``margin_ln_bf`` (2: the runner-up is
     e^2 ~ 7 times less probable; candidates share one prior, so this is their posterior
     odds too), its fitted effect parameters sit off their bounds (by >
     ``bound_tolerance`` = 0.5 % of the range: an effect pinned on a bound is absorbing a change
     the library does not describe), and the extended model fits within the noise (no mode
     misfits at family-wise level ``adequacy_p`` = 1e-3, Bonferroni over its frequency and, with
     shapes, shape tests at their fixed levels; for known noise also the global chi^2 p-value >
     ``adequacy_p``; for inferred noise its own robust noise level <= ``max_noise_rel``);
   * ``no discrepancy``: no candidate beats the baseline by the threshold and the baseline fits
     within the noise (for inferred noise: no flagged mode and an inferred level <=
     ``max_noise_rel`` = 1 %, the scatter of a repeated modal test; a larger "noise" is model
     error, not noise);
   * ``unexplained``: misfit remains and no single library effect explains it, or the best
     candidates cannot be told apart (listed in ``ambiguous_with``; identifiability: an added
     mass and a softer joint nearby can move the same frequencies).

Prior odds (the multiplicity correction of Scott & Berger 2010, Ann. Statist. 38, 2587-2619):
with probability ``effect_prior`` (1/2) one library effect is present, and that probability is
spread equally over the N candidates scanned (kind x location), so each candidate's prior odds
against the baseline are p / (1 - p) / N.  On the exhaust (N = 58) a candidate needs
ln BF > 3 + ln 58 = 7.1 to be named.  Without this the threshold would be a per-candidate one:
the more places the library looks, the likelier that some candidate fits noise, or a change
outside the library, well enough by chance; with it, the prior probability of "some effect"
does not grow with the library, and a user who restricts the library (``kinds``,
``locations``) to a hypothesis they already hold pays less.

The named effect's model (baseline + effect at its fitted values, design variables re-fitted)
is the re-calibrated model; ``effects`` holds its spec list for later use as a model source.

A large FE model with shells (``reduced_candidates.use_reduced``: the shell exhaust) runs every
step on certified reduced models instead of full solves: the design variables' basis for the
baseline, each candidate on that basis enriched for its effect, and every compared fit checked
by a full solve at its optimum (its ``model_error``); ``DiscoveryResult.reduced`` says how.
Other models (the beam exhaust) take the full-solve path unchanged.
"""

import time
from contextlib import contextmanager
from dataclasses import dataclass, field, replace

import numpy as np
from scipy import stats
from scipy.special import logsumexp

from bayesupdate.compute.progress import phase
from bayesupdate.discovery import twins
from bayesupdate.discovery.candidates import Candidate, enumerate_effects, make_candidate
from bayesupdate.discovery.effects import EFFECT_KINDS, Effect, si_per_model_unit
from bayesupdate.discovery.evidence import FitSpace, ModelFit, fit_model, laplace_loo
from bayesupdate.discovery.flagging import ModeFlags, ShapeTests, flag_modes
from bayesupdate.discovery.localization import (
    CANDIDATES_PHASE,
    Localization,
    candidate_problem,
    full_model,
    localize,
    score_candidate,
    score_task,
    screen_grid,
)
from bayesupdate.discovery.mass_block import MassBlock
from bayesupdate.discovery.reduced_candidates import (
    CandidateReducer,
    certified_fit,
    on_reduced_basis,
    reduced_problem,
    stripped,
    use_reduced,
)
from bayesupdate.discovery.settings import DiscoverySettings, VerdictThresholds
from bayesupdate.discovery.shape_evidence import FAILURE_RATE, STATED_REJECTION, shape_evidence
from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.reduced import ReducedFEModel
from bayesupdate.inference.likelihood_blocks import NoiseModel, noise_model, relative_errors
from bayesupdate.inference.optimize import CalibrationSettings, calibrate
from bayesupdate.inference.pairing import PairingRules
from bayesupdate.inference.problem import build_problem


@dataclass
class DiscoveryResult:
    """Everything a discovery run found (see module docstring)."""

    verdict: str
    reason: str
    baseline: ModelFit
    noise: NoiseModel
    flags: ModeFlags
    localization: Localization
    fits: list  # ModelFit of the refitted candidates, best evidence first
    named: ModelFit | None
    ambiguous_with: list
    settings: DiscoverySettings
    wall_s: float
    data_source: str = ""
    model_name: str = ""
    timings: dict = field(default_factory=dict)
    reduced: dict | None = None
    pairing: dict = field(default_factory=dict)

    @property
    def best(self) -> ModelFit | None:
        return self.fits[0] if self.fits else None

    def log_bayes_factor(self, fit: ModelFit) -> float:
        return float(fit.log_evidence - self.baseline.log_evidence)

    @property
    def prior_log_odds(self) -> float:
        """Prior log odds of each scanned candidate against the baseline."""
        return self.settings.verdict.prior_log_odds(len(self.localization.scores))

    def log_posterior_odds(self, fit: ModelFit) -> float:
        """ln BF + prior log odds: what ``threshold_log_odds`` is compared with."""
        return self.log_bayes_factor(fit) + self.prior_log_odds

    def log_posterior_probabilities(self) -> np.ndarray:
        """(1 + len(fits),) log posterior probabilities of the baseline and of each fitted
        candidate, normalized over these hypotheses (Laplace evidence x prior).  Candidates the
        score test left unfitted are omitted, so these are upper bounds for the fitted ones."""
        log_weight = np.array([0.0, *(self.log_posterior_odds(f) for f in self.fits)])
        return log_weight - logsumexp(log_weight)

    @property
    def effects(self) -> list[str]:
        """Spec list of the extended model (empty when nothing was named); values in SI, as a
        spec is read (the fit's are in the model's units: a deck's own)."""
        if self.named is None:
            return []
        model = full_model(self.baseline.space.problem.model)
        units = {p.name: p.unit for p in EFFECT_KINDS[self.named.kind].parameters}
        values = {
            k: v * si_per_model_unit(model, units[k])
            for k, v in self.named.effect_parameters.items()
        }
        return [Effect(self.named.kind, self.named.location, values).spec()]

    @property
    def final(self) -> ModelFit:
        return self.named if self.named is not None else self.baseline


def _within_noise(flags: ModeFlags, sigma: float, inferred: bool, s: VerdictThresholds) -> bool:
    """A model fits within the noise: no flagged mode, and (inferred noise) its robust relative
    level ``sigma`` [-] <= ``max_noise_rel`` or (known noise) the global chi^2 p >
    ``adequacy_p``."""
    return not flags.flagged_modes and (
        sigma <= s.max_noise_rel if inferred else flags.chi2_p > s.adequacy_p
    )


def source_modes(flags: ModeFlags, fit: ModelFit) -> list[int]:
    """The flagged modes of ``flags`` by their number in the data source (a study's selection
    of GVT modes 1, 7, 10 flags "7" and "10", not the problem's 2 and 3), from the problem
    of ``fit``; the problem's own numbers where it has none."""
    problem = getattr(getattr(fit, "space", None), "problem", None)
    numbers = getattr(problem, "mode_numbers", None)
    if numbers is None:
        return flags.flagged_modes
    return [int(numbers[i - 1]) for i in flags.flagged_modes]


def _below_threshold(
    best: ModelFit,
    ln_bf: float,
    log_odds: float,
    prior_log_odds: float,
    baseline_ok: bool,
    flags: ModeFlags,
    s: VerdictThresholds,
) -> tuple[str, str, None, list]:
    """Verdict when the best candidate's posterior log odds do not exceed the threshold:
    "no discrepancy" if the baseline fits within noise, else "unexplained"."""
    odds = (
        f"ln BF {ln_bf:.2f}, posterior log odds {log_odds:.2f} <= {s.threshold_log_odds:g} "
        f"with prior log odds {prior_log_odds:.2f}"
    )
    if baseline_ok:
        return (
            "no discrepancy",
            f"baseline fits within noise; best candidate {best.label}: {odds}",
            None,
            [],
        )
    return (
        "unexplained",
        f"misfit remains (flagged modes {source_modes(flags, best)}) and no library effect "
        f"beats the baseline clearly (best {best.label}: {odds})",
        None,
        [],
    )


def _not_confident(
    fits: list, ln_bf: float, n_design: int, s: VerdictThresholds
) -> tuple[str, str, None, list] | None:
    """The "unexplained" verdict of a winner ``fits[0]`` that beats the baseline but cannot be
    named: runners-up within ``margin_ln_bf`` (returned as ambiguous), or an effect parameter
    within ``bound_tolerance`` of its bound; None when neither holds."""
    best = fits[0]
    close = [f for f in fits[1:] if best.log_evidence - f.log_evidence < s.margin_ln_bf]
    if close:
        return (
            "unexplained",
            f"{best.label} beats the baseline (ln BF {ln_bf:.2f}) but the data cannot tell it "
            f"from {[f.label for f in close]} (ln BF difference < {s.margin_ln_bf:g})",
            None,
            close,
        )
    at_bound = _effect_at_bound(best, n_design, s.bound_tolerance)
    if at_bound:
        return (
            "unexplained",
            f"{best.label} beats the baseline (ln BF {ln_bf:.2f}) only with {at_bound} on its "
            "bound: the library effect is stretched to absorb a change it does not describe",
            None,
            [],
        )
    return None


def _adequacy(
    best: ModelFit, baseline: ModelFit, noise: NoiseModel, s: VerdictThresholds
) -> tuple[ModeFlags, bool]:
    """The winner's mode flags at family-wise level ``adequacy_p`` and whether it fits within
    the noise (for inferred noise judged at its own robust residual level)."""
    d = len(best.names)
    # the named model is judged at family-wise level adequacy_p (1e-3), stricter than the
    # finding step's alpha: at alpha = 0.05 about 1 true model in 20 is rejected by chance, while
    # a change outside the library misfits far beyond either level (study: chi^2 p < 1e-100)
    # inferred noise: judged against its own residual scale, which must look like test noise
    own = (
        noise_model(baseline.space.problem.data, best.residual_rel, d) if noise.inferred else noise
    )
    after = flag_modes(
        best.residual_rel,
        own,
        d,
        None,
        best.mac,
        s.adequacy_p,
        shapes=shape_tests(best),
    )
    return after, _within_noise(after, own.sigma, noise.inferred, s)


def decide(
    baseline: ModelFit,
    fits: list,
    flags: ModeFlags,
    noise: NoiseModel,
    s: VerdictThresholds,
    prior_log_odds: float,
    polish=None,
) -> tuple[str, str, ModelFit | None, list]:
    """Verdict, reason, named fit (or None), ambiguous fits (module docstring, step 5).
    ``prior_log_odds``: of each candidate against the baseline (``s.prior_log_odds``).
    ``polish(fit) -> ModelFit | None``: the winner re-fitted at its own noise level before it is
    judged (``polish_at_own_level``); its Bayes factors stay those of the comparison."""
    baseline_ok = _within_noise(flags, noise.sigma, noise.inferred, s)
    if not fits:
        if baseline_ok:
            return "no discrepancy", "no candidate fitted; the baseline fits within noise", None, []
        return "unexplained", "misfit remains and no candidate could be fitted", None, []
    best = fits[0]
    ln_bf = best.log_evidence - baseline.log_evidence
    log_odds = ln_bf + prior_log_odds
    if log_odds <= s.threshold_log_odds:
        return _below_threshold(best, ln_bf, log_odds, prior_log_odds, baseline_ok, flags, s)
    rejected = _not_confident(fits, ln_bf, len(baseline.names), s)
    if rejected is not None:
        return rejected
    if polish is not None:
        best = polish(best) or best
    after, adequate = _adequacy(best, baseline, noise, s)
    if not adequate:
        return (
            "unexplained",
            f"{best.label} improves the fit (ln BF {ln_bf:.2f}) but misfit remains "
            f"(modes {source_modes(after, best)}, chi2 p {after.chi2_p:.2g}); nothing in the "
            "library explains it all",
            None,
            [],
        )
    runner_up = (
        f"{best.log_evidence - fits[1].log_evidence:.2f} vs runner-up {fits[1].label}"
        if len(fits) > 1
        else "no runner-up"
    )
    reason = f"{best.label}: ln BF {ln_bf:.2f} vs baseline (posterior log odds {log_odds:.2f}), "
    return "explained", reason + runner_up, best, []


def polish_at_own_level(
    fit: ModelFit, noise: NoiseModel, max_nfev: int, rounds: int = 4
) -> ModelFit | None:
    """The winning candidate re-fitted with an inferred frequency level re-estimated at its own
    fit (the robust level of its residuals, floored) and held fixed, repeated while the level
    falls by more than half (at most ``rounds`` times); None for known noise or when the level
    does not fall.  The comparison's level was the baseline's, which the missing effect itself
    inflates (3.8 % for a 0.5 kg mass whose identified frequencies carry 0.005 % noise), so the
    comparison's fit stops far short of what the test resolves: that mass came out 3 % light,
    its frequencies 0.1 % off and its shapes off their stated level in six modes."""
    if not noise.inferred:
        return None
    data, level, polished = fit.space.problem.data, noise, None
    for _ in range(rounds):
        current = polished or fit
        own = noise_model(data, current.residual_rel, len(fit.names))
        if not own.sigma < 0.5 * level.sigma:
            break
        level = own
        polished = fit_model(
            replace(fit.space, noise=own), [current.theta], fit.label, fit.kind, fit.location,
            max_nfev=max_nfev, stage=fit.stage,
        )  # fmt: skip
    if polished is not None:
        # the comparison's evidence and LOO, not this level's
        polished = replace(polished, log_evidence=fit.log_evidence, loo=fit.loo)
    return polished


def shape_tests(fit: ModelFit) -> ShapeTests | None:
    """The per-mode shape tests of ``fit`` (``flagging.ShapeTests``), None without shapes: each
    mode's chi^2 at its level, and the count of modes rejecting their stated level against the
    identification failure rate (``shape_evidence.FAILURE_RATE`` + the 1 % test level); the count
    test needs a stated sd (with the 1 % floor as a fallback it is not made)."""
    shapes = fit.space.shapes
    if shapes is None:
        return None
    r = fit.space.shape_residuals(fit.best.r)
    m = fit.residual_rel.size
    p = np.full(m, np.nan)
    p[shapes.modes] = stats.chi2.sf(shapes.chi2(r), shapes.dof)
    rejected = np.zeros(m, dtype=bool)
    rejected[shapes.modes] = shapes.stated_rejections(r)
    rate = FAILURE_RATE + STATED_REJECTION
    count_p = float(stats.binom.sf(int(rejected.sum()) - 1, shapes.modes.size, rate))
    if shapes.source != "data sd":  # the floor is a guess, not a stated accuracy: no count test
        count_p = 1.0
    return ShapeTests(p, rejected, count_p)


def _effect_at_bound(fit: ModelFit, n_design: int, tolerance: float) -> list[str]:
    """Names of the fit's effect parameters within ``tolerance`` (fraction of the z range) of
    a bound.  A library effect pinned on a bound is a symptom of a change outside the library
    (e.g. a longer pipe mimicked by the softest joint), so it is never named confidently."""
    axes = fit.space.axes[n_design:]
    z = [float(axis.to_z(v)) for axis, v in zip(axes, fit.theta[n_design:], strict=True)]
    return [
        axis.name
        for axis, zi in zip(axes, z, strict=True)
        if min(zi - axis.z_bounds[0], axis.z_bounds[1] - zi)
        <= tolerance * (axis.z_bounds[1] - axis.z_bounds[0])
    ]


def _select(scores, settings: DiscoverySettings) -> list:
    """Top ``quick_refits`` by score plus the best ``per_kind`` of every kind, score order."""
    chosen = list(scores[: settings.refit.quick_refits])
    seen = {s.label for s in chosen}
    per_kind: dict[str, int] = {}
    for s in scores:
        kind = s.candidate.effect.kind
        per_kind[kind] = per_kind.get(kind, 0) + 1
        if per_kind[kind] <= settings.refit.per_kind and s.label not in seen:
            chosen.append(s)
            seen.add(s.label)
    return chosen


def _candidate_starts(design_theta, score, reference_theta=()) -> list[np.ndarray]:
    """Refit starts.  Effect values: the score test's suggestion (plus a quarter of the range
    when that step is small), 3x and 10x the step from null (the linear step underestimates
    large effects), and the screen grid on both sides of null
    (``localization.screen_grid``; the linear step can even point the wrong way when the
    baseline sits at a bound).  Each with the design variables at the baseline optimum and
    (if given) at the reference design: a baseline that absorbed a large effect can sit at a
    bound, far from the truth.  The first start is the score's suggestion at the baseline."""
    axis = score.candidate.axes[0]
    null = score.candidate.null[axis.name]
    z0, z1 = float(axis.to_z(null)), float(axis.to_z(score.step_theta))
    suggested = z1
    lo, hi = axis.z_bounds
    if abs(z1 - z0) < 0.05 * (hi - lo):
        # the suggested step is small (or blocked at a bound): it stays a start (a small true
        # effect is where a sharp likelihood, e.g. known shape noise, wants it), and a quarter
        # of the range inward sets the scale of the far starts
        z1 = z0 + (0.25 if z0 - lo <= hi - z0 else -0.25) * (hi - lo)
    far = [float(np.clip(z0 + f * (z1 - z0), lo, hi)) for f in (3.0, 10.0)]
    designs = [np.asarray(design_theta, dtype=float)]
    for other in reference_theta or ():
        designs.append(np.asarray(other, dtype=float))
    values = [suggested, *([z1] if z1 != suggested else []), *far, *screen_grid(axis, z0)]
    return [np.append(d, axis.from_z(z)) for d in designs for z in values]


def check_enough_modes(problem, n_extra: int = 1) -> None:
    """Clear error when the data have too few modes to compare candidates: each candidate fits
    d design variables + its effect parameters and needs at least one more mode to be tested."""
    used = int(np.sum(problem.weights > 0))
    d = len(problem.parameters)
    if used < d + n_extra + 1:
        raise BayesUpdateError(
            f"data {problem.data.source!r}: {used} modes with weight > 0 cannot decide between "
            f"effects with {d} design variables + {n_extra} effect parameter(s); give at least "
            f"{d + n_extra + 1} modes or fix some design variables ([parameters])"
        )


@dataclass(frozen=True)
class DiscoveryPairing:
    """How discovery pairs the test modes, as ``calibrate`` does (``pipelines.study.prepare``).

    method : "auto" | "mac" | "order" | "tracked" ("auto": ``discover`` says how it resolves).
    rules : a MAC pairing's ``inference.pairing.PairingRules`` (the study's ``[pairing]``; None:
    every test mode is paired).  extra_modes : model modes computed beyond the highest test mode
    (the study's ``[pairing] extra_modes``), >= 0.  test_modes : (m,) 1-based number of each
    test mode of the data in its source (a study's ``[data] modes``; () : 1..m).  The model
    computes up to mode max(test_modes) + extra_modes: test mode k of a source lies near model
    mode k, so a selection such as GVT modes [1, 7, 10] must reach past model mode 3."""

    method: str = "auto"
    rules: PairingRules | None = None
    extra_modes: int = 2
    test_modes: tuple[int, ...] = ()

    def __post_init__(self):
        if int(self.extra_modes) < 0:
            raise BayesUpdateError(f"pairing.extra_modes: {self.extra_modes}; must be >= 0")


def discovery_problem(
    model, data, parameters, pairing: str = "auto", rules=None, objective=None, **choice
):
    """(calibration problem, pairing record): the problem discovery calibrates and compares
    its candidates on, set up with one reference solve (``inference.problem.build_problem``,
    with the test modes' source numbers and extra modes of ``DiscoveryPairing``: ``choice``
    holds its ``extra_modes`` and ``test_modes``), so that discovery pairs what ``calibrate``
    and ``correlate`` pair on the same study.

    ``pairing`` "auto" is resolved as ``discover`` says.  A MAC pairing with ``rules``
    (``inference.pairing.PairingRules``: the study's ``[pairing]``) refuses, at the reference
    design, the test modes whose best pair misses them: they are left out of ``problem.data``
    and named in the record (``ModePairing.to_dict``: method, rules, refused).  The candidates'
    problems (``localization.candidate_problem``) pair without a frequency window, so the
    baseline's drops it too: both sides of every Bayes factor pair alike.  The record is {}
    when no rules applied (no rules, no test shapes, or a pairing other than MAC).
    ``objective`` (``ObjectiveSpec``): the measured mass and CG / inertia, as ``calibrate``'s
    problem has them (the baseline calibration's objective terms, and the ``mass_block`` of
    every fit); None: frequencies (and shapes) only."""
    choice = DiscoveryPairing(pairing, rules, **choice)
    method = choice.method
    if method == "auto":
        method = "mac" if data.shapes is not None else "order"
    problem = build_problem(
        model, data, parameters, pairing=method, extra_modes=choice.extra_modes,
        objective=objective, rules=rules, test_modes=tuple(choice.test_modes),
    )  # fmt: skip
    if problem.pairing.rules is None:
        return problem, {}
    record = problem.pairing.to_dict()
    unwindowed = replace(problem.pairing, rules=None, test_hz=None, refused=())
    return replace(problem, pairing=unwindowed), record


def _prepare(
    model, data, settings: DiscoverySettings, parameters, baseline, pairing, say, executor,
    objective=None,
) -> tuple[object, list, object, dict]:  # fmt: skip
    """The calibration problem and its pairing record (``discovery_problem``; ``pairing``: a
    ``DiscoveryPairing``); on the design variables' certified basis for a large model,
    ``reduced_candidates``), the library's effects and the baseline ``CalibrationResult``
    (calibrated here from ``baseline_starts`` starts, seeded by ``seed``, on ``executor``, when
    none is given)."""
    problem, record = discovery_problem(
        model, data, parameters, pairing.method, pairing.rules, objective,
        extra_modes=pairing.extra_modes, test_modes=pairing.test_modes,
    )  # fmt: skip
    check_enough_modes(problem)
    if use_reduced(model):
        say("certified reduced basis of the design variables")
        problem = reduced_problem(problem, executor)[0]
    effects = enumerate_effects(model, settings.scan.kinds, settings.scan.locations)
    if baseline is None:
        starts = settings.refit.baseline_starts
        say(f"baseline calibration ({starts} starts)")
        baseline = calibrate(
            problem,
            CalibrationSettings(starts=starts, seed=settings.seed, max_nfev=100),
            executor=executor,
        )
    return problem, effects, baseline, record


def _box_centre(problem) -> np.ndarray:
    """(d,) centre of the design variables' bounds box [SI]: a start for every full fit."""
    return 0.5 * (problem.lower + problem.upper)


def _baseline_fit(problem, baseline, settings: DiscoverySettings) -> ModelFit:
    """The baseline refitted for its evidence: the noise model from the calibration's relative
    errors (m,), the shape block (MAC pairing only) and the same design starts as the
    candidates' full tier (its optimum and the box centre), so that both sides of every Bayes
    factor sum over the same basins.  Its ``space`` carries the noise and shapes."""
    data = problem.data
    e0 = relative_errors(baseline.frequencies_hz, data.frequencies_hz)
    noise = noise_model(data, e0, len(problem.parameters), settings.evidence.sigma)
    shapes = None
    if problem.pairing.method == "mac":  # the test's shapes are evidence too (shape_evidence)
        at_baseline = problem.evaluate(baseline.theta)
        if at_baseline.ok:
            shapes = shape_evidence(data, at_baseline.paired.shapes, noise.used)
    base_space = FitSpace(problem, problem.parameters, noise, shapes, MassBlock.of(problem))
    starts = [baseline.theta, _box_centre(problem)]
    nfev = settings.refit.max_nfev
    fit = fit_model(base_space, starts, "baseline", max_nfev=nfev)
    return certified_fit(fit, lambda space, theta: fit_model(space, [theta], max_nfev=nfev))


def _flag_baseline(
    base_fit: ModelFit, baseline, predictive_rel_var, settings: DiscoverySettings
) -> ModeFlags:
    """Mode flags of the baseline fit at level ``alpha`` (z-scores widened by the (m,)
    ``predictive_rel_var`` when given, MAC of the calibration when the test has shapes)."""
    mac = baseline.table.mac if base_fit.space.problem.data.shapes is not None else None
    return flag_modes(
        base_fit.residual_rel,
        base_fit.space.noise,
        len(base_fit.space.axes),
        predictive_rel_var,
        mac,
        settings.scan.alpha,
        shapes=shape_tests(base_fit),
    )


def _localize(
    model, effects: list, base_fit: ModelFit, baseline, flags: ModeFlags, settings, executor=None
):
    """``localization.localize`` of every library effect around the baseline fit (score tests
    in the noise units of the baseline's likelihood, on ``executor``); on a reduced baseline
    ``_reduced_scores`` instead."""
    base_space = base_fit.space
    model_modes = baseline.table.model_mode - 1
    args = (base_space.problem, base_fit.theta, base_fit.best.jac_z, base_space.residual_vector)
    if isinstance(base_space.problem.model, ReducedFEModel):
        scored = _reduced_scores(model, effects, args, settings)
        return localize(*args, [], model_modes, flags.flagged, scored=scored)
    candidates: list[Candidate] = [make_candidate(model, e) for e in effects]
    # candidates that are one model (``twins``) are scored once
    with phase(CANDIDATES_PHASE, twins.count_once(candidates), "candidates") as shown:
        scored = twins.map_once(
            executor, discovery_task, candidates, candidates, ("score", args), twins.twin_score,
            shown.progress_callback(),
        )  # fmt: skip
    return localize(*args, [], model_modes, flags.flagged, scored=scored)


def _reduced_scores(model, effects: list, args: tuple, settings: DiscoverySettings) -> list:
    """Score tests of every effect, each candidate on its enriched basis
    (``reduced_candidates.CandidateReducer``), made one after another in this process (the
    reducer's sparse LU does not travel to workers).  A candidate that can no longer enter the
    quick tier (``_select``: more candidates only push it further down) keeps a ``Stripped``
    marker instead of its models, so that at most the quick tier's candidates are held."""
    problem, theta = args[0], args[1]
    reducer = CandidateReducer.at(problem.model, problem, theta)
    scores: list = []
    with phase(CANDIDATES_PHASE, len(effects), "candidates") as shown:
        for effect in effects:
            candidate = reducer.reduce(make_candidate(model, effect))
            scores.append(score_candidate(*args, candidate))
            ranked = sorted(scores, key=lambda s: -s.delta_chi2)
            keep = {s.label for s in _select(ranked, settings)}
            scores = [s if s.label in keep else stripped(s) for s in scores]
            shown.advance()
    return scores


def _quick_refit(shared: tuple, score) -> ModelFit:
    """Quick-tier fit of one candidate (an executor task; shared: (base_fit, settings))."""
    base_fit, settings = shared
    problem, axes = base_fit.space.problem, base_fit.space.axes
    problem_c = candidate_problem(problem, base_fit.theta, score.candidate)
    space = replace(base_fit.space, problem=problem_c, axes=axes + score.candidate.axes)
    effect = score.candidate.effect
    fit = fit_model(
        space,
        _candidate_starts(base_fit.theta, score, (problem.start, _box_centre(problem))),
        score.label,
        effect.kind,
        effect.location,
        max_nfev=settings.refit.quick_nfev,
        stage="quick",
        best_start_only=True,
    )
    nfev = settings.refit.quick_nfev
    return certified_fit(fit, lambda s, theta: _refit_from(fit, s, theta, nfev))


def _refit_from(fit: ModelFit, space: FitSpace, theta, max_nfev: int) -> ModelFit:
    """``fit`` repeated from theta on ``space`` (its enriched reduced model), evaluations
    added up."""
    again = fit_model(
        space, [theta], fit.label, fit.kind, fit.location, max_nfev=max_nfev, stage=fit.stage
    )
    return replace(again, evaluations=again.evaluations + fit.evaluations)


def _quick_refits(
    scores: list, base_fit: ModelFit, settings: DiscoverySettings, executor=None
) -> list:
    """Quick tier (module docstring, step 4): (fit, score) of the ``_select``-ed candidates,
    each ``quick_nfev`` iterations from its best ``_candidate_starts`` start, best evidence
    first (fits on ``executor``)."""
    chosen = _select(scores, settings)
    candidates = [score.candidate for score in chosen]
    with phase("discovery: quick refits", twins.count_once(candidates), "fits") as shown:
        fits = twins.map_once(
            executor, discovery_task, chosen, candidates, ("quick", (base_fit, settings)),
            twins.twin_fit,
            shown.progress_callback(),
        )  # fmt: skip
    quick = list(zip(fits, chosen, strict=True))
    quick.sort(key=lambda item: -item[0].log_evidence)
    return quick


def _full_refit(shared: tuple, fit: ModelFit) -> ModelFit:
    """Full-tier fit from one quick fit (an executor task; shared: (box centre, number of
    design variables, settings))."""
    centre, n_design, settings = shared
    # the quick end point, plus the box centre with the quick fit's effect value: the
    # design variables of a far-off baseline can hold the fit in another basin
    starts = [fit.theta, np.append(centre, fit.theta[n_design:])]
    nfev = settings.refit.max_nfev
    full = fit_model(fit.space, starts, fit.label, fit.kind, fit.location, max_nfev=nfev)
    full = replace(full, evaluations=full.evaluations + fit.evaluations)
    return certified_fit(full, lambda s, theta: _refit_from(full, s, theta, nfev))


def _full_refits(
    quick: list, base_fit: ModelFit, settings: DiscoverySettings, say, executor=None
) -> list:
    """Full tier: the ``max_refits`` best quick (fit, score) pairs re-fitted to convergence
    (on ``executor``); the rest keep their quick fit.  All fits, best evidence first."""
    shared = (_box_centre(base_fit.space.problem), len(base_fit.space.axes), settings)
    best = [fit for fit, _ in quick[: settings.refit.max_refits]]
    candidates = [score.candidate for _, score in quick[: settings.refit.max_refits]]
    say("full refits: " + ", ".join(fit.label for fit in best))
    fits = [f for f, _ in quick[settings.refit.max_refits :]]
    with phase("discovery: full refits", twins.count_once(candidates), "fits") as shown:
        fits.extend(
            twins.map_once(
                executor,
                discovery_task,
                best,
                candidates,
                ("full", shared),
                twins.twin_fit,
                shown.progress_callback(),
            )
        )
    fits.sort(key=lambda f: -f.log_evidence)
    return fits


#: the discovery's executor tasks by kind (``discovery_task``)
_TASKS = {"score": score_task, "quick": _quick_refit, "full": _full_refit}


def discovery_task(shared: tuple, item):
    """The one function the discovery hands an executor (``compute.executors``: it calls
    fn(shared, item) per item): shared = (kind, that task's shared data), kind "score"
    (``localization.score_task``, item a Candidate), "quick" (``_quick_refit``, item a
    CandidateScore) or "full" (``_full_refit``, item a quick ModelFit).  Every step's map
    goes through this entry, so the executor calls into discovery at one place whatever the
    step (the callback the lower room holds is one function), and the step's result is that
    task's, unchanged.  Returns that task's result."""
    kind, data = shared
    return _TASKS[kind](data, item)


def _refits(
    scores: list, base_fit: ModelFit, settings: DiscoverySettings, say, executor=None
) -> list:
    """Both refit tiers (module docstring, step 4): every fitted candidate, best evidence
    first."""
    quick = _quick_refits(scores, base_fit, settings, executor)
    say("quick refits: " + ", ".join(f"{f.label} {f.log_evidence:.1f}" for f, _ in quick))
    return _full_refits(quick, base_fit, settings, say, executor)


def _with_loo(base_fit: ModelFit, fits: list, settings: DiscoverySettings) -> tuple[ModelFit, list]:
    """The baseline and the fits, the baseline and the ``loo_top`` best with their PSIS-LOO
    (``laplace_loo``, ``loo_draws`` draws; the k-th of them seeded ``seed + k``)."""
    loo, seed = settings.evidence, settings.seed
    top = [base_fit, *fits[: loo.loo_top]]
    done = []
    with phase("discovery: LOO", len(top), "fits") as shown:
        for k, fit in enumerate(top):
            done.append(replace(fit, loo=laplace_loo(fit, loo.loo_draws, seed=seed + k)))
            shown.advance()
    return done[0], done[1:] + list(fits[loo.loo_top :])


@contextmanager
def _stopwatch(timings: dict, key: str):
    """Store the wall time [s] of the ``with`` block as ``timings[key]``."""
    t = time.perf_counter()
    yield
    timings[key] = time.perf_counter() - t


def _verdict(
    base_fit: ModelFit, fits: list, flags: ModeFlags, n_scanned: int, settings: DiscoverySettings
) -> tuple[str, str, ModelFit | None, list]:
    """``decide`` with the prior odds of ``n_scanned`` candidates, the winner polished at its
    own noise level (``polish_at_own_level``)."""
    noise = base_fit.space.noise
    return decide(
        base_fit,
        fits,
        flags,
        noise,
        settings.verdict,
        settings.verdict.prior_log_odds(n_scanned),
        polish=lambda fit: _certified_polish(fit, noise, settings.refit.max_nfev),
    )


def _certified_polish(fit: ModelFit, noise: NoiseModel, max_nfev: int) -> ModelFit | None:
    """``polish_at_own_level``, its end point checked like every compared fit
    (``reduced_candidates.certified_fit``; the comparison's evidence and LOO kept)."""
    polished = polish_at_own_level(fit, noise, max_nfev)
    if polished is None:
        return None

    def refit(space, theta):
        again = _refit_from(polished, space, theta, max_nfev)
        return replace(again, log_evidence=polished.log_evidence, loo=polished.loo)

    return certified_fit(polished, refit)


def reduced_summary(base_fit: ModelFit, where: Localization, fits: list) -> dict | None:
    """JSON-ready account of the reduced models (``reduced_candidates``; None on full solves):
    the design basis (size, certified error), the candidates on enriched bases and on full
    solves, and the largest ``model_error`` of the compared fits (baseline included)."""
    rom = base_fit.space.problem.model
    if not isinstance(rom, ReducedFEModel):
        return None
    on_basis = [on_reduced_basis(s.candidate.model) for s in where.scores]
    errors = [f.model_error for f in (base_fit, *fits) if f.model_error is not None]
    return {
        "design_basis": rom.summary(),
        "candidates_reduced": int(sum(on_basis)),
        "candidates_full": int(len(on_basis) - sum(on_basis)),
        "max_fit_model_error": float(max(errors)) if errors else None,
        "fits_checked": len(errors),
    }


def discover(
    model,
    data,
    settings: DiscoverySettings | None = None,
    parameters=None,
    baseline=None,
    pairing: "str | DiscoveryPairing" = "auto",
    predictive_rel_var: np.ndarray | None = None,
    progress=None,
    executor=None,
    rules=None,
    objective=None,
) -> DiscoveryResult:
    """Run discovery (module docstring).

    model : an ``FEModel`` (effects extend its structure).  data : ``ModalData``.  parameters :
    the design variables to calibrate (as ``build_problem``; None: model defaults).  baseline : a
    ``CalibrationResult`` of the same problem to start from (else calibrated here).
    predictive_rel_var : (m,) posterior-predictive variance of the relative frequencies, if a
    posterior is available (widens the flagging z-scores).  progress : optional callable(str)
    for progress messages.  executor : where the baseline's starts, the score tests and the
    refits run (``compute.executors``; None: in this process); the same bits on every executor.
    pairing : "auto" pairs by MAC when the test has shapes and *by order* otherwise (sorted test
    frequencies against the model's sorted ones: the honest likelihood without shapes; shape
    tracking, the calibration default, puts a wall in the objective where a hidden effect
    reorders two close modes, and a refit stalls there); or a ``DiscoveryPairing`` (method,
    rules, extra modes and the test modes' source numbers: a study's selection of modes).
    rules : a MAC pairing's ``PairingRules`` (None: every test mode is paired; with a
    ``DiscoveryPairing`` its own rules are used): test modes refused at the reference design
    are left out and named in the result's ``pairing`` (``discovery_problem``).
    objective : an ``inference.problem.ObjectiveSpec`` with the measured mass properties (as
    ``calibrate`` builds it from a study); their terms enter every fit's likelihood
    (``mass_block``).  None: none.
    """
    if isinstance(pairing, str):
        pairing = DiscoveryPairing(pairing, rules)
    settings, t0 = settings or DiscoverySettings(), time.perf_counter()
    say = progress or (lambda message: None)
    problem, effects, baseline, record = _prepare(
        model, data, settings, parameters, baseline, pairing, say, executor, objective
    )
    timings = {"baseline_calibration_s": time.perf_counter() - t0}
    base_fit = _baseline_fit(problem, baseline, settings)
    flags = _flag_baseline(base_fit, baseline, predictive_rel_var, settings)
    say(f"flagged modes {source_modes(flags, base_fit)}; scanning {len(effects)} candidates")
    with _stopwatch(timings, "localization_s"):
        where = _localize(model, effects, base_fit, baseline, flags, settings, executor)
    with _stopwatch(timings, "refits_s"):
        fits = _refits(where.scores, base_fit, settings, say, executor)
    with _stopwatch(timings, "loo_s"):
        base_fit, fits = _with_loo(base_fit, fits, settings)
    verdict, reason, named, ambiguous = _verdict(base_fit, fits, flags, len(where.scores), settings)
    say(f"verdict: {verdict} ({reason})")
    return DiscoveryResult(
        verdict=verdict, reason=reason, baseline=base_fit, noise=base_fit.space.noise,
        flags=flags, localization=where, fits=fits, named=named, ambiguous_with=ambiguous,
        settings=settings, wall_s=time.perf_counter() - t0, data_source=data.source,
        model_name=getattr(model, "name", ""), timings=timings,
        reduced=reduced_summary(base_fit, where, fits), pairing=record,
    )  # fmt: skip
