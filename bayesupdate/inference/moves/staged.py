"""Staged adaptation of the mixture proposal before the kept run: adapt, refit, freeze.

1. ``adapt_steps`` steps of the DE moves from the start; a K-component Gaussian mixture is
   fitted (``fit_gaussian_mixture``) to the second half of them, with the prior as a 20 %
   defensive component (``DefensiveProposal``).
2. ``adapt_steps`` steps of that proposal (weight 0.8) mixed with DE (0.2); the mixture is refitted
   to all of them, the prior at 10 %.
3. ``adapt_steps`` more such steps with the refitted proposal; refitted once more and **frozen**,
   the prior at 10 %.
4. The kept run (``sampling.sample_posterior``) uses the frozen proposal (0.8) and DE (0.2).

Every fitted component's sd is widened by ``SD_SCALE`` (1.25): a mixture fitted to a short chain
is narrower than the posterior in its tails, and an independence proposal lighter-tailed than p
leaves walkers stuck there (p / g large; Tierney 1994).  On the exhaust posterior of
``benchmarks/posterior_speed.py`` (seeds 1, 2) the widening and the third fit took tau from
10-18 steps to 6-8 and the steps to R-hat <= 1.01 from 2000-3000 to 1500-1750, with fewer exact
solves (the wider proposal's draws fail the cheap screen more often).

Why the kept chain is valid: nothing in the kept run adapts.  The independence move's g is a
fixed density for the whole kept run (Tierney 1994: a fixed MH kernel leaves p invariant; the
prior component bounds p / g, so it is uniformly ergodic), DE is a fixed ensemble kernel (ter
Braak 2006), and a random choice between kernels that each leave p invariant leaves p invariant.
The adaptation stages only choose g and the walkers' starting points, as a burn-in does; their
draws are discarded.  (Adaptive MCMC that learns from the kept chain needs diminishing adaptation,
Roberts & Rosenthal 2009; freezing avoids that question.)  Setting-up costs (the stages'
evaluations and wall time) count in the run's totals.

(Issue 21: tau fell from ~56 steps with DE to 7-23 with a two-fit scheme on the exhaust
posterior, and DE alone under-estimates its sds by 4-10 %.)
"""

from collections.abc import Callable
from dataclasses import replace

import emcee
import numpy as np

from bayesupdate.inference.moves.defensive_proposal import DefensiveProposal
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


def mixture_moves(proposal: DefensiveProposal) -> list:
    """(move, weight) pairs: the independence move with ``proposal`` 0.8, DE 0.2."""
    return [
        (IndependenceMove(proposal), INDEPENDENCE_WEIGHT),
        (emcee.moves.DEMove(), 1.0 - INDEPENDENCE_WEIGHT),
    ]


def fit_proposal(
    points: np.ndarray, space: ParameterSpace, logit: bool, prior_weight: float, seed: int
) -> DefensiveProposal:
    """A defensive proposal fitted to points (n, d): N_COMPONENTS components, fewer when there
    are too few distinct points for them; ValueError when not even one can be fitted."""
    error = None
    for k in range(N_COMPONENTS, 0, -1):
        try:
            mixture = fit_gaussian_mixture(points, k, seed)
        except (ValueError, np.linalg.LinAlgError) as exc:
            error = exc
            continue
        return DefensiveProposal(mixture, prior_weight, space, logit)
    raise ValueError(str(error))


def widened(proposal: DefensiveProposal, scale: float | None = None) -> DefensiveProposal:
    """``proposal`` with each component's sd multiplied by ``scale`` (default ``SD_SCALE``)."""
    scale = SD_SCALE if scale is None else scale
    mixture = replace(proposal.mixture, chols=proposal.mixture.chols * scale)
    return replace(proposal, mixture=mixture)


def staged_proposal(
    run_steps: Callable[[list, int], np.ndarray | None],
    de_moves: list,
    space: ParameterSpace,
    logit: bool,
    adapt_steps: int,
    seed: int,
) -> tuple[DefensiveProposal | None, dict]:
    """Stages 1-3 of the module docstring: (frozen proposal or None, info).

    run_steps(moves, n) : runs n steps of the ensemble from where it is with these (move,
    weight) pairs and returns the coords (n, n_walkers, d), or None when stopped.
    info : {"fallback": None or why DE alone is used, "interrupted", "components",
    "adapt_steps"}; the proposal is None on a fallback or a stop.
    """
    info = {"fallback": None, "interrupted": False, "components": 0, "adapt_steps": 0}
    coords = run_steps(de_moves, adapt_steps)
    proposal = None
    for stage, prior_weight in enumerate(STAGE_PRIOR_WEIGHTS):
        if coords is None:
            info["interrupted"] = True
            return None, info
        info["adapt_steps"] += coords.shape[0]
        points = coords[coords.shape[0] // 2 if stage == 0 else 0 :].reshape(-1, coords.shape[-1])
        try:
            proposal = widened(fit_proposal(points, space, logit, prior_weight, seed + stage))
        except ValueError as exc:
            info["fallback"] = f"mixture proposal not fitted ({exc}); DE moves used"
            return None, info
        if stage < len(STAGE_PRIOR_WEIGHTS) - 1:
            coords = run_steps(mixture_moves(proposal), adapt_steps)
    info["components"] = proposal.mixture.n_components
    return proposal, info
