"""Where the sampler's walkers start: the posterior's scale along each axis, and sigma's start.

A ball of a fixed fraction of the bounds (or of the sampler's unconstrained coordinates) puts
the walkers tens of posterior sds out when the data are precise: identified frequencies with
sds of ~1e-5 relative give the FEMAP exhaust thicknesses a posterior ~1e-6 in wide in a 0.04 in
box, and an ensemble started 1e-4 in wide had not gathered in 20,000 steps (R-hat 1.08).  The
ball is therefore capped by the posterior's own scale, found from the curvature of the log
density along each axis at the optimum, the diagonal of the Laplace approximation's precision
(Gelman et al., "Bayesian Data Analysis", 3rd ed., sec. 4.1 and 13.3): where the old ball
already lay inside the posterior nothing changes.
"""

from collections.abc import Callable
from contextlib import contextmanager

import numpy as np

#: decades below the cap probed for the curvature: a posterior down to 1e-6 of the cap (on the
#: exhaust 1/30 to 1/70 of it); 2 d PROBE_DECADES + 1 model evaluations per probe
PROBE_DECADES = 7
#: the drop of the log density [nats] up to which a probe counts as inside the posterior (2 sd)
INSIDE_DROP = 2.0
#: log sigma grid points for sigma's start; its decades below the prior's upper bound
SIGMA_GRID, SIGMA_DECADES = 41, 8.0
#: how much better [nats] the grid's sigma must be than the old start to replace it
SIGMA_GAIN = 2.0

#: a LogPosterior's counters, reported with the run: the start's probes are not the chain's
COUNTERS = ("evaluations", "failed", "pair_checked", "pair_differs")


@contextmanager
def uncounted(log_posterior):
    """Evaluate ``log_posterior`` inside without changing its counters (``COUNTERS``)."""
    saved = {k: getattr(log_posterior, k) for k in COUNTERS if hasattr(log_posterior, k)}
    try:
        yield log_posterior
    finally:
        for name, value in saved.items():
            setattr(log_posterior, name, value)


def axis_sd(
    density: Callable[[np.ndarray], np.ndarray], centre: np.ndarray, cap: np.ndarray
) -> np.ndarray:
    """The posterior's sd along each axis at ``centre`` (d,), capped by ``cap`` (d,).

    density : (n, d) -> (n,) log density.  Per axis j, central second differences at steps
    h = cap_j 10^-k (k = 0 .. PROBE_DECADES - 1), all in one batch call: drop(h) =
    lp(c) - (lp(c + h e_j) + lp(c - h e_j)) / 2 = h^2 / (2 sd_j^2) for a Gaussian (any gradient
    cancels, so ``centre`` need not be the mode).  sd_j = h / sqrt(2 drop) at the largest h
    whose drop is at most INSIDE_DROP; cap_j where even h = cap_j stays inside; the smallest
    step where none does.  Returns (d,), each in [cap_j 10^(1-K), cap_j]: the conditional sd,
    at most the marginal one, so a ball of this size is inside the posterior.
    """
    centre, cap = np.asarray(centre, dtype=float), np.asarray(cap, dtype=float)
    d = centre.size
    steps = cap[:, None] * 10.0 ** -np.arange(PROBE_DECADES)  # (d, K)
    offsets = np.zeros((2, d, PROBE_DECADES, d))
    idx = np.arange(d)
    offsets[0, idx, :, idx] = steps
    offsets[1, idx, :, idx] = -steps
    points = np.vstack([centre[None, :], (centre + offsets).reshape(-1, d)])
    with np.errstate(invalid="ignore", over="ignore"):
        lp = np.asarray(density(points), dtype=float)
        side = lp[1:].reshape(2, d, PROBE_DECADES)
        drop = lp[0] - 0.5 * (side[0] + side[1])
    if not np.isfinite(lp[0]):  # no density at the centre: nothing to measure
        return cap
    drop = np.where(np.isfinite(drop), drop, np.inf)
    inside = drop <= INSIDE_DROP
    first = np.where(inside.any(axis=1), inside.argmax(axis=1), PROBE_DECADES - 1)
    h = steps[idx, first]
    curvature = drop[idx, first]
    # a drop <= 0 (flat, or noise at a tiny step): the step itself stayed inside
    sd = np.where(curvature > 0, h / np.sqrt(2.0 * np.maximum(curvature, 1e-300)), h)
    # never 0: walkers that coincide in a coordinate cannot leave it by differential moves
    return np.clip(np.where(first == 0, cap, sd), steps[:, -1], cap)


def sigma_start(log_posterior, theta: np.ndarray, s0: float) -> float:
    """sigma's start: ``s0``, unless the log posterior at the model parameters ``theta`` (d,)
    is better by SIGMA_GAIN nats at the best point of a log grid of sigma over the prior's
    SIGMA_DECADES below its upper bound (10 s0 if it has none; one model solve); then that
    point.

    With identified frequency sds the model-error level can go to 0 (the identification sds
    explain the scatter) while the rms relative residual, the old start, stays ~1e-5 to 1e-3.
    """
    prior = log_posterior.spec.sigma_prior
    low, high = prior.bounds
    top = high if np.isfinite(high) else 10.0 * s0  # an unbounded prior: up to 10 x the start
    if not top > 0:
        return s0
    grid = np.geomspace(top * 10.0**-SIGMA_DECADES, top, SIGMA_GRID)
    grid = grid[(grid >= low) & np.isfinite(prior.logpdf(grid))]
    if grid.size == 0:
        return s0
    sigmas = np.append(grid, s0)
    freqs, mass = log_posterior.predict_frequencies(np.asarray(theta, dtype=float)[None, :])
    n = sigmas.size
    with np.errstate(invalid="ignore", divide="ignore"):
        lp = prior.logpdf(sigmas) + log_posterior.log_likelihood(
            np.repeat(freqs, n, axis=0), sigmas, np.repeat(np.atleast_1d(mass), n)
        )
    best = int(np.argmax(np.where(np.isfinite(lp[:-1]), lp[:-1], -np.inf)))
    old = lp[-1] if np.isfinite(lp[-1]) else -np.inf
    return float(grid[best]) if np.isfinite(lp[best]) and lp[best] > old + SIGMA_GAIN else s0
