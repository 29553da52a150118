"""Bounded adaptive Nelder-Mead simplex, stepped in lockstep over many starts.

The algorithm is that of ``scipy.optimize.minimize(method="Nelder-Mead", bounds=[(0, 1)] * d,
options={"adaptive": True})`` (Lagarias, Reeds, Wright & Wright, SIAM J. Optim. 9 (1998) 112;
the dimension-dependent coefficients of Gao & Han, Comput. Optim. Appl. 51 (2012) 259: reflection
1, expansion 1 + 2/d, contraction 3/4 - 1/(2d), shrink 1 - 1/d; the box handled as scipy does:
the initial simplex reflected into it, every trial point clipped to it; the budget counted per
evaluation, a step cut short by it discarded), step for step, written as a generator that yields
the points each step needs and receives their objective values.  Many polishes (one per start)
then advance together and their points are evaluated as one batch: a reduced model's batched
solve costs a fraction of a one-point solve per point (``optimize._batch_residuals``).  Given the
same objective values, each polish makes the points scipy's loop makes, bit for bit
(``tests/test_nelder_mead.py``), so batching changes only the rounding of the values themselves.
"""

from collections.abc import Callable, Generator
from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError

#: scipy's initial simplex: each coordinate moved by 5 %, or to 2.5e-4 where it is 0
_NONZERO_STEP, _ZERO_STEP = 0.05, 0.00025


@dataclass(frozen=True)
class SimplexSettings:
    """Stopping rules of one polish: the simplex spans <= ``xatol`` in every coordinate (unit box)
    and its values <= ``fatol`` (objective units) -- scipy's ``xatol``, ``fatol`` -- or
    ``max_evaluations`` evaluations were made (scipy's ``maxfev``)."""

    xatol: float = 1e-7
    fatol: float = 1e-10
    max_evaluations: int = 2000

    def __post_init__(self) -> None:
        if not (self.xatol >= 0 and self.fatol >= 0 and self.max_evaluations >= 1):
            raise BayesUpdateError(
                "Nelder-Mead settings: xatol and fatol must be >= 0, max_evaluations >= 1"
            )


Steps = Generator[np.ndarray, np.ndarray, tuple[np.ndarray, float, int]]


def _initial_simplex(x0: np.ndarray) -> np.ndarray:
    """(d + 1, d) scipy's initial simplex around x0 (d,) in [0, 1]^d, reflected into the box."""
    n = x0.size
    sim = np.tile(x0, (n + 1, 1))
    for k in range(n):
        sim[k + 1, k] = (1 + _NONZERO_STEP) * x0[k] if x0[k] != 0 else _ZERO_STEP
    sim = np.where(sim > 1.0, 2.0 - sim, sim)
    return np.clip(sim, 0.0, 1.0)


def simplex_steps(u0: np.ndarray, settings: SimplexSettings = SimplexSettings()) -> Steps:
    """One bounded adaptive Nelder-Mead minimization in [0, 1]^d from u0 (d,) as a generator.

    Yields (k, d) points to evaluate (k = d + 1 for the initial simplex, d for a shrink, else
    1) and is sent their (k,) objective values; returns (x (d,), the best value, evaluations):
    scipy's ``x`` and ``fun`` (module docstring)."""
    x0 = np.clip(np.asarray(u0, dtype=float).ravel(), 0.0, 1.0)
    n, budget = x0.size, settings.max_evaluations
    dim = float(n)
    chi, psi, sigma = 1 + 2 / dim, 0.75 - 1 / (2 * dim), 1 - 1 / dim
    sim = _initial_simplex(x0)
    fsim = np.full(n + 1, np.inf)
    first = min(n + 1, budget)
    fsim[:first] = yield sim[:first].copy()
    used = first
    order = np.argsort(fsim)
    sim, fsim = sim[order], fsim[order]
    while used < budget:
        if (np.max(np.abs(sim[1:] - sim[0])) <= settings.xatol
                and np.max(np.abs(fsim[0] - fsim[1:])) <= settings.fatol):  # fmt: skip
            break
        xbar = np.add.reduce(sim[:-1], 0) / n
        step = yield from _one_step(sim, fsim, xbar, (chi, psi, sigma), budget - used)
        used += step
        order = np.argsort(fsim)
        sim, fsim = sim[order], fsim[order]
        if step < 0:  # the budget ran out inside the step (its points are counted)
            used = budget
    return sim[0], float(np.min(fsim)), min(used, budget)


def _one_step(sim, fsim, xbar, coefficients, left: int):
    """One reflection / expansion / contraction / shrink of ``sim`` (d + 1, d) with values
    ``fsim`` in place (scipy's order of tests); returns the evaluations made, or -1 where the
    budget ``left`` ended the step (scipy discards such a step, bar a shrink's moved points)."""
    chi, psi, sigma = coefficients
    worst = sim[-1]
    xr = np.clip(2 * xbar - worst, 0.0, 1.0)
    fxr = (yield xr[None, :])[0]
    if fxr < fsim[0]:
        if left < 2:
            return -1
        xe = np.clip((1 + chi) * xbar - chi * worst, 0.0, 1.0)
        fxe = (yield xe[None, :])[0]
        sim[-1], fsim[-1] = (xe, fxe) if fxe < fxr else (xr, fxr)
        return 2
    if fxr < fsim[-2]:
        sim[-1], fsim[-1] = xr, fxr
        return 1
    if left < 2:
        return -1
    if fxr < fsim[-1]:
        xc = np.clip((1 + psi) * xbar - psi * worst, 0.0, 1.0)
        fxc = (yield xc[None, :])[0]
        if fxc <= fxr:
            sim[-1], fsim[-1] = xc, fxc
            return 2
    else:
        xcc = np.clip((1 - psi) * xbar + psi * worst, 0.0, 1.0)
        fxcc = (yield xcc[None, :])[0]
        if fxcc < fsim[-1]:
            sim[-1], fsim[-1] = xcc, fxcc
            return 2
    return (yield from _shrink(sim, fsim, sigma, left - 2))


def _shrink(sim, fsim, sigma: float, left: int):
    """Shrink every vertex towards the best, its new points as one batch; with fewer than d
    evaluations ``left``, scipy moves the first left + 1 vertices and evaluates the first left
    (the evaluation that would exceed the budget raises after its vertex moved)."""
    n = sim.shape[0] - 1
    moved = min(n, left + 1)
    sim[1 : moved + 1] = np.clip(sim[0] + sigma * (sim[1 : moved + 1] - sim[0]), 0.0, 1.0)
    k = min(n, left)
    if k:
        fsim[1 : k + 1] = yield sim[1 : k + 1].copy()
    return 2 + k if k == n else -1


def minimize_together(
    objective: Callable[[np.ndarray], np.ndarray],
    starts: np.ndarray,
    settings: SimplexSettings = SimplexSettings(),
    on_done: Callable[[int], None] | None = None,
) -> tuple[np.ndarray, np.ndarray, int]:
    """``simplex_steps`` from every start (n, d), advanced in lockstep: each round, the points
    all unfinished polishes need are evaluated by one call ``objective`` ((B, d) -> (B,)).

    on_done : called with a start's index when its polish ends (progress).
    Returns (ends (n, d), their best values (n,), evaluations in all)."""
    starts = np.atleast_2d(np.asarray(starts, dtype=float))
    ends, values, total = starts.copy(), np.full(starts.shape[0], np.inf), 0
    running: dict[int, Steps] = {}
    wanted: dict[int, np.ndarray] = {}
    for i, u0 in enumerate(starts):
        running[i] = simplex_steps(u0, settings)
        wanted[i] = next(running[i])
    while wanted:
        index = list(wanted)
        sizes = [wanted[i].shape[0] for i in index]
        answers = np.split(np.asarray(objective(np.vstack([wanted[i] for i in index]))),
                           np.cumsum(sizes)[:-1])  # fmt: skip
        for i, answer in zip(index, answers, strict=True):
            try:
                wanted[i] = running[i].send(answer)
            except StopIteration as done:
                ends[i], values[i], used = done.value
                total += used
                del wanted[i], running[i]
                if on_done is not None:
                    on_done(i)
    return ends, values, total
