"""A defensive mixture proposal: a fitted Gaussian mixture plus the prior as a safety component.

g(x) = (1 - w) GMM(x) + w prior(x)  (Hesterberg 1995, "Weighted average importance sampling and
defensive mixture distributions", Technometrics 37(2) 185-194), in the sampler's coordinates x:
the unconstrained y of ``ParameterSpace`` (logit, ``logit=True``; the prior's density there has
the Jacobian) or theta.  The prior component bounds p(x) / g(x) <= (max likelihood) / w, so the
ratio that drives an independence Metropolis-Hastings chain (Tierney 1994) or importance weights
is bounded wherever the posterior has mass, whatever the Gaussian part misses.
"""

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from bayesupdate.inference.moves.gaussian_mixture import GaussianMixture
from bayesupdate.inference.parameter_space import ParameterSpace


@dataclass(frozen=True)
class DefensiveProposal:
    """g = (1 - prior_weight) mixture + prior_weight prior, in y (``logit``) or theta (x (n, d))."""

    mixture: GaussianMixture
    prior_weight: float
    space: ParameterSpace
    logit: bool = True

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
                np.log1p(-w) + self.mixture.logpdf(x), np.log(w) + self.prior_logpdf(x)
            )
        return np.where(np.all(np.isfinite(x), axis=1) & ~np.isnan(out), out, -np.inf)

    @cached_property
    def _inverse_cdfs(self) -> tuple:
        """Per parameter (low, high, F(low), F(high), the untruncated distribution, or None for a
        uniform prior), made once: ``Prior.sample``'s two scipy CDF calls a draw cost more than a
        kept run's step otherwise."""
        out = []
        for spec in self.space.parameters:
            low, high = spec.prior.bounds
            dist = spec.prior._frozen()
            uniform = spec.prior.kind == "uniform"
            out.append((low, high, dist.cdf(low), dist.cdf(high), None if uniform else dist))
        return tuple(out)

    def sample_prior(self, random, n: int) -> np.ndarray:
        """(n, d) prior draws in the sampler's coordinates (exact logit: no margin clip): the
        inverse CDF of each truncated prior, the same draws as ``Prior.sample`` (same uniforms,
        and a uniform prior's quantile u (high - low) + low as scipy computes it)."""
        columns = []
        for low, high, f_low, f_high, dist in self._inverse_cdfs:
            u = random.uniform(f_low, f_high, size=n)
            value = u * (high - low) + low if dist is None else dist.ppf(u)
            columns.append(np.clip(value, low, high))
        theta = np.column_stack(columns)
        if not self.logit:
            return theta
        with np.errstate(all="ignore"):
            return self.space.y_from_theta(theta, margin=0.0)

    def sample(self, random, n: int) -> np.ndarray:
        """(n, d) draws from g; ``random`` is emcee's RandomState (model.random).  Both parts are
        drawn for every row, so the random stream used does not depend on the component picks."""
        from_prior = random.uniform(0.0, 1.0, size=n) < self.prior_weight
        x = self.mixture.sample(random, n)
        prior = self.sample_prior(random, n)
        x[from_prior] = prior[from_prior]
        return x

    def to_dict(self) -> dict:
        """What ``from_dict`` needs besides the space (JSON-able; floats round-trip exactly)."""
        return {
            "mixture": self.mixture.to_dict(),
            "prior_weight": float(self.prior_weight),
            "logit": bool(self.logit),
        }

    @classmethod
    def from_dict(cls, data: dict, space: ParameterSpace) -> "DefensiveProposal":
        mixture = GaussianMixture.from_dict(data["mixture"])
        return cls(mixture, float(data["prior_weight"]), space, bool(data["logit"]))
