"""A defensive mixture proposal: a fitted Gaussian mixture plus the prior as a safety component.

g(x) = (1 - w) GMM(x) + w prior(x)  (Hesterberg 1995, "Weighted average importance sampling and
defensive mixture distributions", Technometrics 37(2) 185-194), in the sampler's coordinates x:
the unconstrained y of ``ParameterSpace`` (logit, ``logit=True``; the prior's density there has
the Jacobian) or theta.  The prior component bounds p(x) / g(x) <= (max likelihood) / w, so the
ratio that drives an independence Metropolis-Hastings chain (Tierney 1994) or importance weights
is bounded wherever the posterior has mass, whatever the Gaussian part misses.

The Gaussian part may live in other coordinates than the walkers (``unit``): a two-sided
parameter's column of y can be fitted as s = logistic(y), its unit-box value, the density in y
then having the Jacobian log s (1 - s).  Why: a posterior with mass against a bound (the demo's
shell seed case, rho_catalyst's density piles at its lower bound) has in logit an exponential
tail to y -> -inf that Gaussians in y cover poorly (walkers that reach it hold for hundreds of
steps), while in s it is a compact edge that Gaussians cover, their mass beyond the edge being
rejected draws.  ``proposal_coordinates`` (``moves.staged``) chooses.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.inference.moves.gaussian_mixture import GaussianMixture
from bayesupdate.inference.parameter_space import ParameterSpace, logistic


def unit_box_coordinates(x: np.ndarray, unit: tuple[bool, ...]) -> tuple:
    """(w (n, d), log |dw / dx| (n,), or 0.0 without unit columns): x (n, d) with its ``unit``
    columns as s = logistic(x)."""
    if not any(unit):
        return x, 0.0
    cols = np.flatnonzero(unit)
    w = x.copy()
    w[:, cols] = logistic(x[:, cols])
    # log s (1 - s) = -|y| - 2 log(1 + exp(-|y|)), stable for large |y|
    a = np.abs(x[:, cols])
    return w, np.sum(-a - 2.0 * np.log1p(np.exp(-a)), axis=1)


def from_unit_box_coordinates(w: np.ndarray, unit: tuple[bool, ...]) -> np.ndarray:
    """x at w (n, d), the inverse of ``unit_box_coordinates``; a unit column outside (0, 1)
    gives -/+inf there (a draw the chain rejects: its log-density is -inf)."""
    if not any(unit):
        return w
    cols = np.flatnonzero(unit)
    s = np.clip(w[:, cols], 0.0, 1.0)
    x = w.copy()
    with np.errstate(divide="ignore"):
        x[:, cols] = np.log(s) - np.log1p(-s)
    return x


@dataclass(frozen=True)
class DefensiveProposal:
    """g = (1 - prior_weight) mixture + prior_weight prior, in y (``logit``) or theta (x (n, d)).

    unit : (d,) bools or () (none): columns whose mixture coordinate is s = logistic(y) (module
    docstring); only with ``logit``, on two-sided parameters.
    """

    mixture: GaussianMixture
    prior_weight: float
    space: ParameterSpace
    logit: bool = True
    unit: tuple[bool, ...] = ()

    def mixture_coordinates(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray | float]:
        """(w (n, d), log |dw / dx| (n,)) of x (n, d): ``unit_box_coordinates``."""
        return unit_box_coordinates(x, self.unit)

    def from_mixture_coordinates(self, w: np.ndarray) -> np.ndarray:
        """x at mixture coordinates w (n, d): ``from_unit_box_coordinates``."""
        return from_unit_box_coordinates(w, self.unit)

    def mixture_logpdf(self, x: np.ndarray) -> np.ndarray:
        """(n, d) -> (n,) log density of the Gaussian part in the sampler's coordinates."""
        w, log_jacobian = self.mixture_coordinates(x)
        return self.mixture.logpdf(w) + log_jacobian

    def prior_logpdf(self, x: np.ndarray) -> np.ndarray:
        """(n, d) -> (n,) log prior density in the sampler's coordinates."""
        with np.errstate(all="ignore"):
            if self.logit:
                return self.space.log_prior_y(x)
            return self.space.log_prior(np.atleast_2d(x))

    def logpdf(self, x: np.ndarray) -> np.ndarray:
        """(n, d) -> (n,) log g(x) (non-finite x: -inf)."""
        x = np.atleast_2d(x)
        w = self.prior_weight
        with np.errstate(all="ignore"):
            out = np.logaddexp(
                np.log1p(-w) + self.mixture_logpdf(x), np.log(w) + self.prior_logpdf(x)
            )
        return np.where(np.all(np.isfinite(x), axis=1) & ~np.isnan(out), out, -np.inf)

    def sample_prior(self, random, n: int) -> np.ndarray:
        """(n, d) prior draws in the sampler's coordinates (exact logit: no margin clip): the
        inverse CDF of each truncated prior (``Prior.quantile``), the same draws as
        ``Prior.sample`` from the same uniforms."""
        columns = []
        for prior in (spec.prior for spec in self.space.parameters):
            u = random.uniform(*prior.cdf_range(), size=n)
            columns.append(np.clip(prior.quantile(u), *prior.bounds))
        theta = np.column_stack(columns)
        if not self.logit:
            return theta
        with np.errstate(all="ignore"):
            return self.space.y_from_theta(theta, margin=0.0)

    def sample(self, random, n: int) -> np.ndarray:
        """(n, d) draws from g; ``random`` is emcee's RandomState (model.random).  Both parts are
        drawn for every row, so the random stream used does not depend on the component picks."""
        from_prior = random.uniform(0.0, 1.0, size=n) < self.prior_weight
        x = self.from_mixture_coordinates(self.mixture.sample(random, n))
        prior = self.sample_prior(random, n)
        x[from_prior] = prior[from_prior]
        return x

    def to_dict(self) -> dict:
        """What ``from_dict`` needs besides the space (JSON-able; floats round-trip exactly)."""
        return {
            "mixture": self.mixture.to_dict(),
            "prior_weight": float(self.prior_weight),
            "logit": bool(self.logit),
            "unit": [bool(u) for u in self.unit],
        }

    @classmethod
    def from_dict(cls, data: dict, space: ParameterSpace) -> "DefensiveProposal":
        mixture = GaussianMixture.from_dict(data["mixture"])
        unit = tuple(bool(u) for u in data.get("unit", ()))
        return cls(mixture, float(data["prior_weight"]), space, bool(data["logit"]), unit)
