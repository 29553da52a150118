"""Prior distributions of calibration parameters, truncated to the parameter's bounds.

Kinds: ``uniform`` (on the bounds), ``normal`` (mean, sd), ``lognormal`` (mu, sigma of the log of
the value), ``halfnormal`` (scale; for the noise level sigma).  Each density is normalized over the
bounds (the truncation constant log(F(high) - F(low)) is included), so log-evidence comparisons in
the discovery layer see proper densities.  A prior with no mass inside the bounds is an error.
"""

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from scipy import special

from bayesupdate.errors import BayesUpdateError

#: kind -> required keys
PRIOR_KEYS = {
    "uniform": (),
    "normal": ("mean", "sd"),
    "lognormal": ("mu", "sigma"),
    "halfnormal": ("scale",),
}

#: kind -> the support (a, b) of the standardized distribution (scipy.stats' ``a``, ``b``)
_SUPPORT = {
    "uniform": (0.0, 1.0),
    "normal": (-np.inf, np.inf),
    "lognormal": (0.0, np.inf),
    "halfnormal": (0.0, np.inf),
}

#: smallest probability mass inside the bounds accepted as "support"
_MIN_MASS = 1e-12


@dataclass(frozen=True)
class Prior:
    """A prior on one scalar parameter, truncated to ``bounds`` = (low, high) (SI units).

    ``kind`` is a key of ``PRIOR_KEYS``; ``args`` holds that kind's numbers.
    """

    kind: str
    bounds: tuple[float, float]
    args: tuple[tuple[str, float], ...] = ()
    name: str = ""
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def __post_init__(self):
        where = f"prior of {self.name!r}" if self.name else "prior"
        if self.kind not in PRIOR_KEYS:
            raise BayesUpdateError(
                f"{where}: unknown kind {self.kind!r}; use one of {sorted(PRIOR_KEYS)}"
            )
        given = dict(self.args)
        missing = [k for k in PRIOR_KEYS[self.kind] if k not in given]
        extra = sorted(set(given) - set(PRIOR_KEYS[self.kind]))
        if missing or extra:
            raise BayesUpdateError(
                f"{where}: kind {self.kind!r} needs keys {list(PRIOR_KEYS[self.kind])}"
                + (f", missing {missing}" if missing else "")
                + (f", unknown {extra}" if extra else "")
            )
        for key, value in given.items():
            if not np.isfinite(value):
                raise BayesUpdateError(f"{where}: {key} must be finite, got {value}")
        for key in ("sd", "sigma", "scale"):
            if key in given and given[key] <= 0:
                raise BayesUpdateError(f"{where}: {key} must be > 0, got {given[key]}")
        low, high = (float(b) for b in self.bounds)
        if not (low < high) or np.isnan(low) or np.isnan(high):
            raise BayesUpdateError(f"{where}: bounds must satisfy low < high, got {[low, high]}")
        if self.kind == "uniform" and not (np.isfinite(low) and np.isfinite(high)):
            raise BayesUpdateError(f"{where}: a uniform prior needs finite bounds")
        object.__setattr__(self, "bounds", (low, high))
        if self.mass_inside_bounds() < _MIN_MASS:
            raise BayesUpdateError(
                f"{where}: {self.kind} {given} has no support inside bounds {[low, high]}; "
                "move the prior or widen the bounds"
            )

    @property
    def params(self) -> dict[str, float]:
        return dict(self.args)

    def _location_scale(self) -> tuple[float, float]:
        """(loc, scale) of the untruncated distribution in scipy.stats' parametrization
        (``uniform(low, high - low)``, ``norm(mean, sd)``, ``lognorm(sigma, scale=exp(mu))``,
        ``halfnorm(scale=scale)``)."""
        p = self.params
        if self.kind == "uniform":
            low, high = self.bounds
            return low, high - low
        if self.kind == "normal":
            return p["mean"], p["sd"]
        if self.kind == "lognormal":
            return 0.0, float(np.exp(p["mu"]))
        return 0.0, p["scale"]

    def cdf(self, x: float) -> float:
        """The untruncated distribution's CDF at x (SI units of the parameter): scipy.stats'
        ``cdf`` in closed form, the same numbers (its ``_cdf((x - loc) / scale)`` inside the
        open support, 1 at or above the support's top, NaN at NaN, 0 elsewhere) without importing
        scipy.stats, which costs a command over a second (every calibration builds priors)."""
        loc, scale = self._location_scale()
        z = (np.float64(x) - loc) / scale
        bottom, top = _SUPPORT[self.kind]
        if np.isnan(z):
            return float("nan")
        if z >= top:
            return 1.0
        if not bottom < z < top:
            return 0.0
        if self.kind == "uniform":
            return float(z)
        if self.kind == "normal":
            return float(special.ndtr(z))
        if self.kind == "lognormal":
            return float(special.ndtr(np.log(z) / self.params["sigma"]))
        return float(special.erf(z / np.sqrt(2)))

    def cdf_range(self) -> tuple[float, float]:
        """(F(low), F(high)) of the untruncated distribution at the bounds, made once: two
        CDF calls cost more than a kept run's step (the mixture proposal draws from the
        prior at every step)."""
        if "cdf" not in self._cache:
            low, high = self.bounds
            self._cache["cdf"] = (self.cdf(low), self.cdf(high))
        return self._cache["cdf"]

    def mass_inside_bounds(self) -> float:
        f_low, f_high = self.cdf_range()
        return f_high - f_low

    def logpdf(self, x: np.ndarray) -> np.ndarray:
        """Log density of the truncated prior; -inf outside [low, high].  x : any shape."""
        x = np.asarray(x, dtype=float)
        low, high = self.bounds
        inside = (x >= low) & (x <= high)
        log_mass = np.log(self.mass_inside_bounds())
        p = self.params
        # closed forms: scipy.stats' generic logpdf costs ~50 us per call, too slow per step
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.kind == "uniform":
                value = np.full(x.shape, -np.log(high - low))
            elif self.kind == "normal":
                z = (x - p["mean"]) / p["sd"]
                value = -0.5 * z * z - np.log(p["sd"]) - 0.5 * np.log(2 * np.pi)
            elif self.kind == "lognormal":
                logx = np.log(x)
                z = (logx - p["mu"]) / p["sigma"]
                value = -0.5 * z * z - np.log(p["sigma"]) - logx - 0.5 * np.log(2 * np.pi)
            else:
                z = x / p["scale"]
                value = np.where(
                    x >= 0, -0.5 * z * z - np.log(p["scale"]) + 0.5 * np.log(2 / np.pi), -np.inf
                )
            value = value - log_mass
        return np.where(inside, value, -np.inf)

    def quantile(self, u: np.ndarray) -> np.ndarray:
        """The untruncated distribution's inverse CDF at probabilities u (any shape): scipy's
        ``ppf`` in closed form (its own ``_ppf(u) * scale + loc``, so the same numbers), without
        scipy's ~0.1 ms of argument checks a call: the mixture proposal draws from the prior at
        every step of a kept run."""
        u = np.asarray(u, dtype=float)
        p = self.params
        if self.kind == "uniform":
            low, high = self.bounds
            return u * (high - low) + low
        if self.kind == "normal":
            return special.ndtri(u) * p["sd"] + p["mean"]
        if self.kind == "lognormal":
            return np.exp(p["sigma"] * special.ndtri(u)) * np.exp(p["mu"])
        return special.ndtri((1.0 + u) / 2.0) * p["scale"]

    def sample(self, rng: np.random.Generator, size: int) -> np.ndarray:
        """Draws from the truncated prior by inverse CDF, (size,)."""
        u = rng.uniform(*self.cdf_range(), size=size)
        return np.clip(self.quantile(u), *self.bounds)

    def to_dict(self) -> dict:
        return {"kind": self.kind, **self.params}


def prior_from_mapping(spec: Mapping | None, bounds: tuple[float, float], name: str = "") -> Prior:
    """Build a Prior from a study-file table such as ``{kind = "normal", mean = 1, sd = 0.1}``.

    ``None`` gives the uniform prior on the bounds.
    """
    if spec is None:
        return Prior("uniform", bounds, (), name)
    spec = dict(spec)
    kind = spec.pop("kind", None)
    if not isinstance(kind, str):
        raise BayesUpdateError(f"prior of {name!r}: give kind = one of {sorted(PRIOR_KEYS)}")
    args = []
    for key, value in spec.items():
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise BayesUpdateError(f"prior of {name!r}: {key} must be a number, got {value!r}")
        args.append((key, float(value)))
    return Prior(kind, bounds, tuple(args), name)


@dataclass(frozen=True)
class JointPrior:
    """Independent priors on the columns of theta (n_points, n_params), evaluated together
    (``JointPrior.of``).

    The uniform ones (the usual case) are one vectorized box check and one constant: priors are
    evaluated for every walker at every step (the likelihood's and the mixture proposal's), and
    one call per parameter costs more than the check.  uniform : (n_params,) which columns have
    a uniform prior; low, high : their bounds; uniform_log_density : the sum of their log
    densities; others : (column, Prior) of the rest.
    """

    uniform: np.ndarray
    low: np.ndarray
    high: np.ndarray
    uniform_log_density: float
    others: tuple[tuple[int, Prior], ...]

    @classmethod
    def of(cls, priors: tuple[Prior, ...]) -> "JointPrior":
        uniform = np.array([p.kind == "uniform" for p in priors], dtype=bool)
        bounds = np.array([p.bounds for p in priors], dtype=float).reshape(-1, 2)
        low, high = bounds[uniform, 0], bounds[uniform, 1]
        others = tuple((j, p) for j, p in enumerate(priors) if not uniform[j])
        return cls(uniform, low, high, -float(np.sum(np.log(high - low))), others)

    def log_density(self, theta: np.ndarray) -> np.ndarray:
        """theta (n_points, n_params) -> (n_points,) joint log prior (-inf outside a bound)."""
        theta = np.atleast_2d(theta)
        u = theta[:, self.uniform]
        inside = np.all((u >= self.low) & (u <= self.high), axis=1)
        total = np.where(inside, self.uniform_log_density, -np.inf)
        for j, prior in self.others:
            total = total + prior.logpdf(theta[:, j])
        return total
