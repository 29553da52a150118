"""Staged adaptation of the mixture proposal before the kept run: adapt, refit, freeze.

1. ``adapt_steps`` steps of the DE moves from the start; a K-component Gaussian mixture is
   fitted (``fit_gaussian_mixture``) to the second half of them, with the prior as a 20 %
   defensive component (``DefensiveProposal``).
2. ``adapt_steps`` steps of that proposal (weight 0.8) mixed with DE (0.2); the mixture is refitted
   to all of them, the prior at 10 %.
3. ``adapt_steps`` more such steps with the refitted proposal; refitted once more and **frozen**,
   the prior at 10 %.
   Each fit first chooses the mixture's coordinates (``proposal_coordinates``): the walkers'
   own (y, logit) or the unit box s = logistic(y) of every two-sided parameter, whichever
   proposal, fitted to half the walkers, has the higher independence acceptance rate on the
   other half (``log_acceptance``, from the stage's own log densities: no extra solve).
4. The coverage check (``moves.coverage``, ``coverage_fallback``), on information from before the
   kept run only: the frozen proposal's importance ESS fraction over 1000 draws from it (their
   own seeded generator: the chain's random stream is untouched; their log densities are the
   delayed-acceptance surrogate's when the run screens, ``sampling._checked``) must be at
   least ``MIN_COVERAGE`` and the share of the last stage's draws where w / Z > 10 (an
   independence proposal accepted less than once in ten tries there) at most ``MAX_STUCK``.
5. The repair (``repaired_proposal``; the sampler asks for ``REPAIR_ROUNDS``): a proposal that
   fails the check, or passes it narrowly (importance ESS below ``REPAIR_COVERAGE`` or stuck
   share above ``REPAIR_STUCK``), is refitted twice, each time on draws from the previous fit
   resampled by their importance weights (so on where p is, including the tails the prior
   component reached) plus the last stage's draws, with up to 8 components; each refit is
   checked with fresh draws and, of the proposals that pass (a narrowly passing first one
   included), the one with the highest importance ESS is frozen; when none passes, the one
   with the highest importance ESS of those with a stuck share at most ``MAX_STUCK`` and an
   importance ESS at least ``LOW_COVERAGE`` (``low_coverage_kept``, which says why DE is not
   the fallback); when none of them qualifies either, the kept run uses DE alone, from the
   adapted walkers, and says why (``info["fallback"]``).
6. The kept run (``sampling.sample_posterior``) uses the frozen proposal (0.8) and DE (0.2).

Why the check: on the demo's seed case (seed Table 2 with the weighed mass in the likelihood)
the mass term makes a thin, curved posterior whose lower rho_catalyst tail (logit y down to -5.6
against -4.0 in the adaptation's draws) four Gaussians do not cover; walkers that reach it hold
for hundreds of steps and R-hat stalls at 1.04-1.06.  On 4 sampler seeds there the check gave
importance ESS 0.05-0.19 and a stuck share 0.066-0.168; on the benchmark's exhaust posterior (9
seeds), where the mixture is accurate and 2-2.7 x faster than DE, 0.22-0.42 and 0.000-0.045.
The thresholds sit between the two.

Why the repair (2026-11-24, docs/validation/posterior.md): the check's thresholds did not hold
out - the benchmark's fresh sampler seeds 11 and 12 gave importance ESS 0.127 and 0.074 - and
DE, the fallback, is not accurate where it converges: on the demo's seed case (against an
importance-sampling reference, studies/posterior_reference.py) the demo's DE posterior had sds
5-11 % small, as on the benchmark (4-10 %).  Refitted, those proposals passed (0.31-0.40) and
the kept runs met the reference criterion (means within 0.05 sd, sds within 5 %).

Every fitted component's sd is widened by ``SD_SCALE`` (1.25): a mixture fitted to a short chain
is narrower than the posterior in its tails, and an independence proposal lighter-tailed than p
leaves walkers stuck there (p / g large; Tierney 1994).  On the exhaust posterior of
``benchmarks/posterior_speed.py`` (seeds 1, 2) the widening and the third fit took tau from
10-18 steps to 6-8 and the steps to R-hat <= 1.01 from 2000-3000 to 1500-1750, with fewer exact
solves (the wider proposal's draws fail the cheap screen more often).

When the run screens (delayed acceptance, ``inference.delayed_acceptance``), stages 1-3 sample
the surrogate q itself, with no exact evaluation (``sampling._adaptation_stage``): they only
choose g and the walkers' starting points, and the coverage check's draws are q's already.  On
the exhaust (``sample --model exhaust --data paper:ema``, seed 1) the stages' exact solves were
about 7,000 of the run's 15,200 (the kept chain spends 12.8 a step) and about half of the stages'
cost; now none.  The kept run starts from the walkers' exact log densities.

Why the kept chain is valid: nothing in the kept run adapts.  The independence move's g is a
fixed density for the whole kept run (Tierney 1994: a fixed MH kernel leaves p invariant; the
prior component bounds p / g, so it is uniformly ergodic), DE is a fixed ensemble kernel (ter
Braak 2006), and a random choice between kernels that each leave p invariant leaves p invariant.
The adaptation stages only choose g and the walkers' starting points, as a burn-in does; their
draws are discarded.  (Adaptive MCMC that learns from the kept chain needs diminishing adaptation,
Roberts & Rosenthal 2009; freezing avoids that question.)  Setting-up costs (the stages'
evaluations and wall time) count in the run's totals.

Why the choice of coordinates (2026-11-24, docs/validation/posterior.md): the demo's shell seed
case weighs the exhaust, so the two densities lie on a thin straight ridge (their total mass
fixed) that runs into rho_catalyst's lower bound; in y the ridge is an L whose arm runs to
y -> -inf, which Gaussians in y cover poorly: walkers held there for hundreds of steps, runs took
up to 24,000 kept steps and missed the reference on 2 of 5 seeds.  In the unit box the ridge is
straight and the Gaussians' mass beyond the bound is only rejected draws.  On the benchmark's
exhaust posterior the walkers' own coordinates keep winning (its chains are unchanged).

(docs/validation/posterior.md: tau fell from ~56 steps with DE to 7-23 with a two-fit scheme
on the exhaust posterior, and DE alone under-estimates its sds by 4-10 %.)
"""

from collections.abc import Callable
from dataclasses import replace

import emcee
import numpy as np

from bayesupdate.inference.moves.coverage import COVERAGE_DRAWS, STUCK_RATIO, proposal_coverage
from bayesupdate.inference.moves.defensive_proposal import (
    DefensiveProposal,
    unit_box_coordinates,
)
from bayesupdate.inference.moves.gaussian_mixture import fit_gaussian_mixture
from bayesupdate.inference.moves.independence import IndependenceMove
from bayesupdate.inference.parameter_space import ParameterSpace

#: mixture components, prior weight while adapting / frozen, independence-move weight
N_COMPONENTS = 4
PRIOR_WEIGHT_ADAPT = 0.2
PRIOR_WEIGHT_FROZEN = 0.1
#: the prior weight of each fit, in order (a stage of ``adapt_steps`` steps before each but the
#: first); the last fit is frozen
STAGE_PRIOR_WEIGHTS = (PRIOR_WEIGHT_ADAPT, PRIOR_WEIGHT_FROZEN, PRIOR_WEIGHT_FROZEN)
INDEPENDENCE_WEIGHT = 0.8
#: the fitted components' sds are multiplied by this (heavier tails than the chain's draws)
SD_SCALE = 1.25
#: the kept run uses the frozen proposal only when its importance ESS fraction is at least
#: MIN_COVERAGE and at most MAX_STUCK of the last stage's draws lie where it is accepted less
#: than once in ``coverage.STUCK_RATIO`` tries (``moves.coverage``); else DE alone
MIN_COVERAGE = 0.15
MAX_STUCK = 0.06
#: a proposal that fails the check is refitted (``repaired_proposal``) REPAIR_ROUNDS times,
#: each on the last stage's draws plus REPAIR_DRAWS draws from the previous fit resampled by
#: their importance weights, with up to REPAIR_COMPONENTS components, each checked again
REPAIR_ROUNDS = 2
REPAIR_DRAWS = 4000
REPAIR_COMPONENTS = 8
#: a proposal that passes the check narrowly (importance ESS below REPAIR_COVERAGE or stuck
#: share above REPAIR_STUCK) is refitted as well, and kept only when no refit passes with a
#: higher importance ESS
REPAIR_COVERAGE = 0.25
REPAIR_STUCK = 0.03
#: the coordinates' choice (``proposal_coordinates``) fits and scores at most about this many
#: points per half of the walkers (thinned by steps)
SELECTION_POINTS = 1000
#: when no proposal passes, the one with the highest importance ESS of those with a stuck share
#: at most MAX_STUCK and an importance ESS at least LOW_COVERAGE is kept rather than DE alone
#: (``low_coverage_kept``)
LOW_COVERAGE = 0.05


def mixture_moves(proposal: DefensiveProposal) -> list:
    """(move, weight) pairs: the independence move with ``proposal`` 0.8, DE 0.2."""
    return [
        (IndependenceMove(proposal), INDEPENDENCE_WEIGHT),
        (emcee.moves.DEMove(), 1.0 - INDEPENDENCE_WEIGHT),
    ]


def fit_proposal(
    points: np.ndarray,
    space: ParameterSpace,
    logit: bool,
    prior_weight: float,
    seed: int,
    n_components: int = N_COMPONENTS,
    unit: tuple[bool, ...] = (),
) -> DefensiveProposal:
    """A defensive proposal fitted to points (n, d) (the sampler's coordinates), its mixture in
    the coordinates ``unit`` says (``DefensiveProposal``): ``n_components`` components, fewer
    when there are too few distinct points for them; ValueError when not even one fits."""
    error = None
    w = unit_box_coordinates(points, unit)[0]
    for k in range(n_components, 0, -1):
        try:
            mixture = fit_gaussian_mixture(w, k, seed)
        except (ValueError, np.linalg.LinAlgError) as exc:
            error = exc
            continue
        return DefensiveProposal(mixture, prior_weight, space, logit, unit)
    raise ValueError(str(error))


def proposal_coordinates(
    coords: np.ndarray,
    log_probs: np.ndarray,
    space: ParameterSpace,
    logit: bool,
    prior_weight: float,
    seed: int,
) -> tuple[bool, ...]:
    """The mixture's coordinates for a stage's draws coords (n, walkers, d) in y, with their
    log posterior densities log_probs (n, walkers): () (y itself) or the unit box on every
    two-sided parameter (``DefensiveProposal``), whichever proposal has the higher estimated
    independence acceptance rate (``log_acceptance``) on held-out draws (two-fold over the
    walkers: a proposal fitted to the even walkers is scored on the odd ones and vice versa).
    () without ``logit`` or a two-sided parameter, and when a fit fails."""
    two_sided = tuple(bool(b) for b in np.isfinite(space.lower) & np.isfinite(space.upper))
    if not logit or not any(two_sided) or coords.shape[1] < 2:
        return ()
    d = coords.shape[-1]
    # every k-th step: successive steps are correlated, and the fits' cost grows with the points
    k = -(-coords.shape[0] * coords.shape[1] // (2 * SELECTION_POINTS))
    halves = [(coords[::k, j::2].reshape(-1, d), log_probs[::k, j::2].ravel()) for j in (0, 1)]
    scores = []
    for unit in ((), two_sided):
        total = 0.0
        for (fit_on, _), (score_on, log_p) in (halves, halves[::-1]):
            try:
                g = widened(fit_proposal(fit_on, space, logit, prior_weight, seed, unit=unit))
            except ValueError:
                return ()
            total += log_acceptance(g.logpdf(score_on), log_p)
        scores.append(total)
    return two_sided if scores[1] > scores[0] else ()


def log_acceptance(log_g: np.ndarray, log_p: np.ndarray) -> float:
    """log of the independence Metropolis-Hastings acceptance rate of a proposal g at
    stationarity, up to an additive constant the same for every g, from draws x_i ~ p with
    log g(x_i) and log p(x_i) (p unnormalized, (n,) each).

    With w = p / g, the rate is E_{x ~ p/Z, y ~ g} min(1, w(y) / w(x)) = Z E_{x, y ~ p/Z}
    min(1 / w(x), 1 / w(y)) (substitute g(y) = p(y) / w(y)), Z = the integral of p: over pairs
    of draws, the smaller 1 / w.  The i-th smallest of n values is the smaller of 2 (n - i) - 1
    ordered pairs (i from 0), so the pair mean is a weighted sum over the sorted values."""
    log_v = np.sort(np.where(np.isfinite(log_p), log_g - log_p, np.nan))
    log_v = log_v[~np.isnan(log_v)]
    n = log_v.size
    if n == 0:
        return -np.inf
    terms = log_v + np.log(2.0 * (n - np.arange(n)) - 1.0)
    top = np.max(terms)
    if not np.isfinite(top):
        return -np.inf
    return float(top + np.log(np.sum(np.exp(terms - top))) - 2.0 * np.log(n))


def widened(proposal: DefensiveProposal, scale: float | None = None) -> DefensiveProposal:
    """``proposal`` with each component's sd multiplied by ``scale`` (default ``SD_SCALE``)."""
    scale = SD_SCALE if scale is None else scale
    mixture = replace(proposal.mixture, chols=proposal.mixture.chols * scale)
    return replace(proposal, mixture=mixture)


def staged_proposal(
    run_steps: Callable[[list, int], tuple | None],
    de_moves: list,
    space: ParameterSpace,
    logit: bool,
    adapt_steps: int,
    seed: int,
    log_density: Callable[[np.ndarray], np.ndarray | None] | None = None,
    repair_rounds: int = 0,
) -> tuple[DefensiveProposal | None, dict]:
    """Stages 1-3 of the module docstring, then the coverage check: (frozen proposal or None,
    info).

    run_steps(moves, n) : runs n steps of the ensemble from where it is with these (move,
    weight) pairs and returns (coords (n, n_walkers, d), log p (n, n_walkers)), or None when
    stopped.
    log_density(x) : log p at (n, d) sampler coordinates (None when stopped); given, the frozen
    proposal must cover p (``coverage_fallback``), else it is refitted up to ``repair_rounds``
    times (``repaired_proposal``) and DE alone is used when none passes.
    info : {"fallback": None or why DE alone is used, "interrupted", "components",
    "adapt_steps", "coverage": the importance ESS fraction, "stuck": the stuck share (both None
    without the check)}; the proposal is None on a fallback or a stop.
    """
    info = {
        "fallback": None, "interrupted": False, "components": 0, "adapt_steps": 0,
        "coverage": None, "stuck": None, "coordinates": [],
    }  # fmt: skip
    stage_out = run_steps(de_moves, adapt_steps)
    proposal = None
    for stage, prior_weight in enumerate(STAGE_PRIOR_WEIGHTS):
        if stage_out is None:
            info["interrupted"] = True
            return None, info
        coords, log_probs = stage_out
        info["adapt_steps"] += coords.shape[0]
        first = coords.shape[0] // 2 if stage == 0 else 0
        kept, kept_log_p = coords[first:], log_probs[first:]
        points = kept.reshape(-1, coords.shape[-1])
        unit = proposal_coordinates(kept, kept_log_p, space, logit, prior_weight, seed + stage)
        info["coordinates"].append("unit box" if any(unit) else "sampler")
        try:
            proposal = widened(
                fit_proposal(points, space, logit, prior_weight, seed + stage, unit=unit)
            )
        except ValueError as exc:
            info["fallback"] = f"mixture proposal not fitted ({exc}); DE moves used"
            return None, info
        if stage < len(STAGE_PRIOR_WEIGHTS) - 1:
            stage_out = run_steps(mixture_moves(proposal), adapt_steps)
    info["components"] = proposal.mixture.n_components
    if log_density is not None:
        chain = (coords.reshape(-1, coords.shape[-1]), np.ravel(log_probs))
        return repaired_proposal(proposal, log_density, seed, info, chain, repair_rounds)
    return proposal, info


def repaired_proposal(
    proposal: DefensiveProposal, log_density, seed: int, info: dict, chain, rounds: int
) -> tuple[DefensiveProposal | None, dict]:
    """``coverage_fallback`` of ``proposal``; when it fails or passes narrowly (importance ESS
    below ``REPAIR_COVERAGE`` or stuck share above ``REPAIR_STUCK``), ``rounds`` refits
    (``resampled_refit``), each from the previous one's draws and each checked with fresh
    draws; of the proposals that pass (the first one included), the one with the highest
    importance ESS is kept; when none passes, ``low_coverage_kept``'s choice (info then has
    "low_coverage_kept": why), else DE alone.  Nothing here touches the walkers or
    the chain's random stream; it all happens before the kept run.  When a refit runs, info
    gets "repairs" (refits made), "first_check" and "repair_checks" ([importance ESS, stuck
    share] of the first proposal and of each refit); "coverage", "stuck" and "components" are
    then the kept one's (or the last refit's)."""
    checked, info = coverage_fallback(proposal, log_density, seed, info, chain)
    if info["interrupted"] or rounds < 1 or (checked is not None and _covers_well(info)):
        return checked, info
    first = {"first_check": [info["coverage"], info["stuck"]], "repair_checks": []}
    best, last = (None if checked is None else (checked, info)), info
    low = low_coverage_kept(None, proposal, info)
    for round_ in range(1, rounds + 1):
        proposal = resampled_refit(proposal, log_density, chain[0], seed + round_)
        if proposal is None:
            info["interrupted"] = True
            return None, info
        if proposal is False:
            break
        trial = {**info, "fallback": None, "components": proposal.mixture.n_components}
        passed, trial = coverage_fallback(proposal, log_density, seed + round_ + 1, trial, chain)
        if trial["interrupted"]:
            return None, trial
        first["repair_checks"].append([trial["coverage"], trial["stuck"]])
        last = trial
        if passed is not None and (best is None or trial["coverage"] > best[1]["coverage"]):
            best = (passed, trial)
        low = low_coverage_kept(low, proposal, trial)
    chosen, out = best if best is not None else (low or (None, last))
    return chosen, {**out, "repairs": len(first["repair_checks"]), **first}


def low_coverage_kept(kept, proposal: DefensiveProposal, info: dict):
    """Of ``kept`` ((proposal, info) or None) and ``proposal`` (checked: ``info``), the one the
    kept run uses when no proposal passes the check: stuck share at most ``MAX_STUCK``,
    importance ESS at least ``LOW_COVERAGE``, the higher ESS; None when neither qualifies.

    Why not DE (2026-11-24, docs/validation/posterior.md): DE is narrow where it converges on
    these posteriors (sds 4-13 % small: the benchmark, the demo's seed cases), while an
    independence proposal with a defensive prior component is a valid MH kernel whatever its
    coverage (module docstring).  What the check guards is efficiency and regions the chain has
    not seen; a small stuck share says the last stage's draws (the posterior the adaptation
    saw) are not where g under-covers, and an ESS fraction e makes 1 / e the holding-time scale
    there (``moves.coverage``): 20 steps at 0.05, against DE's tau of 100-150 steps on these
    posteriors.  The demo's shell seed case, sampler seed 5: first check 0.138 / 0.067, refits
    0.100 / 0.0045 and 0.132 / 0.0032; DE alone converged with sds 7-13 % small."""
    ok = info["coverage"] >= LOW_COVERAGE and (info["stuck"] or 0.0) <= MAX_STUCK
    if not ok or (kept is not None and kept[1]["coverage"] >= info["coverage"]):
        return kept
    reason = (
        f"no proposal passed the coverage check (importance ESS >= {MIN_COVERAGE}); the one "
        f"with the highest ({info['coverage']:.3f}, >= {LOW_COVERAGE}) and a stuck share "
        f"<= {MAX_STUCK} kept: DE is narrow on these posteriors"
    )
    return proposal, {**info, "fallback": None, "low_coverage_kept": reason}


def _covers_well(info: dict) -> bool:
    """Whether a proposal that passed the check did so clearly (``REPAIR_COVERAGE``,
    ``REPAIR_STUCK``), so no refit is tried."""
    return info["coverage"] >= REPAIR_COVERAGE and (info["stuck"] or 0.0) <= REPAIR_STUCK


def resampled_refit(proposal: DefensiveProposal, log_density, points: np.ndarray, seed: int):
    """``proposal`` refitted on where p is: REPAIR_DRAWS draws y ~ g (own seeded generator),
    weighted by w = p / g and resampled in proportion to w (sampling importance resampling,
    Rubin 1988; one population Monte Carlo step, Cappe et al. 2004), are approximately draws
    from p, also where g's prior component reached tails the chain missed; the mixture (up to
    REPAIR_COMPONENTS components, widened by SD_SCALE, the prior at PRIOR_WEIGHT_FROZEN) is
    fitted to them and the last stage's ``points`` (m, d).  None when the run was stopped
    meanwhile, False when nothing could be fitted (no finite weight, too few points)."""
    rng = np.random.default_rng([seed, 13])
    y = proposal.sample(rng, REPAIR_DRAWS)
    log_p = log_density(y)
    if log_p is None:
        return None
    with np.errstate(invalid="ignore"):  # -inf - -inf where log_p is not finite: masked
        log_w = np.where(np.isfinite(log_p), log_p - proposal.logpdf(y), -np.inf)
    if not np.any(np.isfinite(log_w)):
        return False
    w = np.exp(log_w - np.max(log_w))
    points = np.concatenate([points, y[rng.choice(y.shape[0], y.shape[0], p=w / w.sum())]])
    try:
        refit = fit_proposal(
            points, proposal.space, proposal.logit, PRIOR_WEIGHT_FROZEN, seed + 10,
            REPAIR_COMPONENTS, proposal.unit,
        )  # fmt: skip
    except ValueError:
        return False
    return widened(refit)


def coverage_fallback(
    proposal: DefensiveProposal, log_density, seed: int, info: dict, chain=None
) -> tuple[DefensiveProposal | None, dict]:
    """(proposal, info) when the frozen proposal covers p (``moves.coverage``: importance ESS
    fraction of ``COVERAGE_DRAWS`` draws from it at least ``MIN_COVERAGE``, and at most
    ``MAX_STUCK`` of the last stage's draws ``chain`` = (points (m, d), log p (m,)) where
    w / Z > ``STUCK_RATIO``), else (None, info with the fallback's reason): DE alone for the kept
    run.  Both numbers go in info ("coverage", "stuck").  A stop meanwhile: (None, info with
    "interrupted")."""
    coverage = proposal_coverage(proposal, log_density, seed, chain)
    if coverage is None:
        info["interrupted"] = True
        return None, info
    ess = coverage["ess"]
    info["coverage"] = round(ess, 4)
    info["stuck"] = None if coverage["stuck"] is None else round(coverage["stuck"], 4)
    stuck = coverage["stuck"] or 0.0
    if ess < MIN_COVERAGE or stuck > MAX_STUCK:
        info["fallback"] = (
            f"mixture proposal covers the posterior poorly (importance ESS {ess:.3f} of "
            f"{COVERAGE_DRAWS} draws, >= {MIN_COVERAGE} needed; {stuck:.3f} of the last "
            f"stage's draws where it is accepted < 1 in {STUCK_RATIO:g} tries, <= {MAX_STUCK} "
            "allowed); DE moves used"
        )
        return None, info
    return proposal, info
