"""Delayed-acceptance ensemble moves: screen every proposal with a cheap surrogate posterior and
spend the exact posterior only on the proposals the surrogate lets through.

Christen & Fox (2005), "Markov chain Monte Carlo using an approximation", J. Comput. Graph.
Stat. 14(4) 795-810.  For a proposal y from x with the move's log proposal factor f (zero for
differential evolution, (d - 1) log(|y - z| / |x - z|) for the snooker move):

    stage 1:  accept with  a1 = min(1, exp(f + log q(y) - log q(x)))      (q: surrogate)
    stage 2:  only then compute the exact log p(y); accept with
              a2 = min(1, exp(log p(y) - log p(x) - (log q(y) - log q(x))))

The composed kernel satisfies detailed balance with respect to the exact posterior p whatever
q is, so the chain's target is unchanged; a good surrogate only makes stage 2 accept almost
every survivor, and stage 1 rejects most bad proposals without an exact evaluation.  The
surrogate here is a coarser reduced basis (``ReducedFEModel.coarsened``), typically 1e-4-1e-2
away from the exact model in frequency against a likelihood noise of several per cent.

The surrogate must be finite wherever the posterior is (a walker at a point the surrogate
calls impossible could never move); ``ScreenedLogDensity`` evaluates the exact posterior at
such points and uses that value as the surrogate there.  The surrogate values of the current
walkers are kept in a cache keyed by position, so each position is screened once.
"""

from collections.abc import Callable

import emcee
import numpy as np


class ScreenedLogDensity:
    """The surrogate log-density q with a cache of the current walkers' values.

    screen, exact : vectorized (n, d) -> (n,) log-densities in the sampler's coordinates.
    ``screen_evaluations`` counts the surrogate's evaluations (points).
    """

    def __init__(self, screen: Callable, exact: Callable):
        self.screen = screen
        self.exact = exact
        self._cache: dict[bytes, float] = {}
        self.screen_evaluations = 0

    def __call__(self, x: np.ndarray) -> np.ndarray:
        x = np.atleast_2d(x)
        q = np.asarray(self.screen(x), dtype=float)
        self.screen_evaluations += x.shape[0]
        bad = ~np.isfinite(q)
        if np.any(bad):
            # the surrogate failed (or is -inf) there: use the exact value, so q is finite
            # wherever p is (else the walker there could never leave)
            q[bad] = np.asarray(self.exact(x[bad]), dtype=float)
        return q

    def at(self, x: np.ndarray) -> np.ndarray:
        """Surrogate values at the rows of x, from the cache where known."""
        keys = [row.tobytes() for row in np.ascontiguousarray(x)]
        missing = [i for i, k in enumerate(keys) if k not in self._cache]
        if missing:
            for i, v in zip(missing, self(x[missing]), strict=True):
                self._cache[keys[i]] = float(v)
        return np.array([self._cache[k] for k in keys])

    def remember(self, x: np.ndarray, values: np.ndarray) -> None:
        for row, v in zip(np.ascontiguousarray(x), values, strict=True):
            self._cache[row.tobytes()] = float(v)

    def keep_only(self, coords: np.ndarray) -> None:
        """Forget every position that no walker holds any more."""
        live = {row.tobytes() for row in np.ascontiguousarray(coords)}
        self._cache = {k: v for k, v in self._cache.items() if k in live}


def _two_stage(model, screen: ScreenedLogDensity, current, proposal, factors, current_lp):
    """Both stages for proposals (n, d) from current (n, d) with log proposal factors (n,) and
    the current exact log-densities (n,): (accepted (n,) bool, exact log p of the proposals,
    -inf where not computed).  Draws 2 n uniforms from ``model.random``.

    A proposal with factor -inf (a draw the move's proposal density calls impossible, e.g. the
    independence move's outside the unit box, ``moves.independence``) fails stage 1 whatever q
    says, so it is not screened: the decisions and the random stream are those of screening it
    (on the exhaust's default run 4.7 % of the proposals, the same chain to the bit)."""
    q_current = screen.at(current)
    n = proposal.shape[0]
    possible = factors > -np.inf
    q_proposal = np.full(n, -np.inf)
    if np.any(possible):
        q_proposal[possible] = screen(proposal[possible])
    stage1 = factors + q_proposal - q_current > np.log(model.random.rand(n))
    exact = np.full(n, -np.inf)
    if np.any(stage1):
        exact[stage1] = model.compute_log_prob_fn(proposal[stage1])[0]
    log_u2 = np.log(model.random.rand(n))
    with np.errstate(invalid="ignore"):
        stage2 = exact - current_lp - (q_proposal - q_current) > log_u2
    ok = stage1 & stage2
    screen.remember(proposal[ok], q_proposal[ok])
    return ok, exact


class DelayedAcceptanceMove(emcee.moves.Move):
    """A red-blue ensemble move (DE, DE snooker, ...) with two-stage acceptance (module
    docstring).  ``base`` gives the proposals and the ensemble split; ``screen`` the
    surrogate, shared by all moves of a sampler."""

    def __init__(self, base: emcee.moves.RedBlueMove, screen: ScreenedLogDensity):
        self.base = base
        self.screen = screen

    def propose(self, model, state):
        n_walkers, _ = state.coords.shape
        base = self.base
        base.setup(state.coords)
        accepted = np.zeros(n_walkers, dtype=bool)
        all_inds = np.arange(n_walkers)
        groups = all_inds % base.nsplits
        if base.randomize_split:
            model.random.shuffle(groups)
        for split in range(base.nsplits):
            active = groups == split
            sets = [state.coords[groups == j] for j in range(base.nsplits)]
            current = sets[split]
            proposal, factors = base.get_proposal(
                current, sets[:split] + sets[split + 1 :], model.random
            )
            idx = all_inds[active]
            ok, exact = _two_stage(
                model, self.screen, current, proposal, factors, state.log_prob[idx]
            )
            accepted[idx] = ok
            new = emcee.State(proposal, log_prob=exact, blobs=None)
            state = self.update(state, new, accepted, active)
        self.screen.keep_only(state.coords)
        return state, accepted


class DelayedAcceptanceMHMove(emcee.moves.Move):
    """A Metropolis-Hastings move (every walker proposes at once from its own position, e.g. the
    independence move of ``moves.independence``) with two-stage acceptance."""

    def __init__(self, base: emcee.moves.MHMove, screen: ScreenedLogDensity):
        self.base = base
        self.screen = screen

    def propose(self, model, state):
        proposal, factors = self.base.get_proposal(state.coords, model.random)
        accepted, exact = _two_stage(
            model, self.screen, state.coords, proposal, factors, state.log_prob
        )
        state = self.update(state, emcee.State(proposal, log_prob=exact, blobs=None), accepted)
        self.screen.keep_only(state.coords)
        return state, accepted


def delayed_acceptance_moves(moves: list, screen: ScreenedLogDensity) -> list:
    """Wrap (move, weight) pairs of red-blue or MH moves; every wrapped move shares ``screen``."""
    out = []
    for move, weight in moves:
        if isinstance(move, emcee.moves.RedBlueMove):
            out.append((DelayedAcceptanceMove(move, screen), weight))
        elif isinstance(move, emcee.moves.MHMove):
            out.append((DelayedAcceptanceMHMove(move, screen), weight))
        else:
            raise TypeError(
                f"delayed acceptance needs red-blue or MH moves, got {type(move).__name__}"
            )
    return out
