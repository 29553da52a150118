"""Independence Metropolis-Hastings as an emcee move, with a frozen proposal density g.

Each walker proposes y ~ g independently of where it is and accepts with
min(1, p(y) g(x) / (p(x) g(y))) (Tierney 1994, "Markov chains for exploring posterior
distributions", Ann. Stat. 22(4) 1701-1762, sec. 2.3.3): emcee's ``MHMove`` with the log
proposal factor log g(x) - log g(y).  g must not change while the kept chain is drawn (a fixed g
makes each walker's kernel a fixed Metropolis-Hastings kernel that leaves p invariant; one that
learns from the chain it moves would not be), and g should have tails at least as heavy as p's
(``DefensiveProposal``: the prior component bounds p / g, so the chain is uniformly ergodic).
"""

import emcee
import numpy as np


class IndependenceMove(emcee.moves.MHMove):
    """``proposal``: an object with ``sample(random, n) -> (n, d)`` and ``logpdf((n, d)) ->
    (n,)`` (``DefensiveProposal``), fixed for the move's lifetime."""

    def __init__(self, proposal):
        self.proposal = proposal
        super().__init__(self._proposal)

    def _proposal(self, coords: np.ndarray, random) -> tuple[np.ndarray, np.ndarray]:
        """(proposals (n, d), log g(x) - log g(y) (n,)) for the walkers' coords (n, d)."""
        y = self.proposal.sample(random, coords.shape[0])
        log_g_y = self.proposal.logpdf(y)
        possible = np.isfinite(log_g_y)
        # a draw g calls impossible (a unit-box coordinate outside (0, 1): y = -/+inf) is
        # rejected: the walker proposes its own position with factor -inf (emcee refuses
        # non-finite points; the delayed-acceptance screen then rejects it without a solve)
        y = np.where(possible[:, None], y, coords)
        with np.errstate(invalid="ignore"):
            factors = np.where(possible, self.proposal.logpdf(coords) - log_g_y, -np.inf)
        return y, factors
