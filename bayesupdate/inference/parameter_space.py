"""One parameter space: each parameter's bounds, prior and axis, and the coordinates fits use.

A ``ParameterSpec`` is one calibrated parameter: SI bounds, a prior truncated to them
(``priors.Prior``), an optional start value and its *axis*, linear or log.  A positive
parameter whose bounds span two decades or more (``LOG_AXIS_RATIO``, e.g. a joint stiffness in
[1e2, 1e6] N m/rad) is on a log axis unless told otherwise.

A ``ParameterSpace`` over d such parameters maps between four coordinates, each (..., d):

- theta: the SI values;
- z, the axis coordinates: z = theta on a linear axis, z = log theta on a log axis (the
  coordinates of discovery's Laplace evidence and its score test);
- u, the unit box u in [0, 1]^d over z: z = z_low + clip(u, 0, 1) (z_high - z_low) (the
  coordinates of every bounded least-squares fit and of the optimizer's space-filling starts;
  thicknesses of 1e-3 m and densities of 1e4 kg/m^3 are then equally scaled);
- y, the unconstrained sampler coordinates (Stan Reference Manual, "Constraint transforms"):
  both bounds finite -> theta = lo + (hi - lo) logistic(y); lower bound only ->
  theta = lo + exp(y); upper only -> theta = hi - exp(-y); none -> theta = y.  A density in y
  adds log |d theta / d y| = log(hi - lo) + log s + log(1 - s) (logit), y (lower), -y (upper).

The log prior is given in theta, z (with the Jacobian z of a log axis) and y.

Least squares over the unit box (``unit_box_residuals``) has one failure convention: where the
model fails (an exception, a missing or non-finite frequency) or its residual is not finite,
each residual component is that of a relative error of ``FAILED_RELATIVE_ERROR`` (1000 %) in
that component's units, and the failure is counted.
"""

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from bayesupdate.inference.priors import JointPrior, Prior

#: bounds ratio high / low from which a positive parameter is on a log axis
LOG_AXIS_RATIO = 100.0
AXIS_KINDS = ("linear", "log")

#: relative error given to every residual component where the model failed, in the component's
#: units: FAILED_RELATIVE_ERROR / unit, unit = 1 for a relative error (seed eq. 19 and its mass
#: and MAC terms, ``optimize``) and the noise sd s for an error in noise units (discovery's
#: refits and equivalence).  A working model's frequencies are positive and not 11 times the
#: test's (-1 < e < 10), and a residual of unit-norm shapes is at most 1 per component, so a
#: failure is worse than any working point in every component whatever the noise level (a fixed
#: value is not: with the frequency noise at its 1e-4 floor a 10 % error is 1,000 noise sd).
#: Finite, so a solver's finite differences stay numbers and it moves away from the failure.
FAILED_RELATIVE_ERROR = 10.0


def logistic(y) -> np.ndarray:
    """1 / (1 + exp(-y)), elementwise, without overflow (as 0.5 (1 + tanh(y / 2)))."""
    return 0.5 * (1.0 + np.tanh(0.5 * np.asarray(y, dtype=float)))


def natural_axis(bounds: tuple[float, float]) -> str:
    """The axis for these bounds: log when positive and high / low >= ``LOG_AXIS_RATIO``."""
    low, high = bounds
    return "log" if low > 0 and high / low >= LOG_AXIS_RATIO else "linear"


@dataclass(frozen=True)
class ParameterSpec:
    """One calibrated parameter: SI bounds, prior (truncated to the bounds), start value (None
    where the parameter has none, e.g. a sampled noise level) and axis ("linear", "log", or
    "auto" for ``natural_axis``)."""

    name: str
    bounds: tuple[float, float]
    prior: Prior
    start: float | None = None
    axis: str = "auto"

    def __post_init__(self):
        if self.axis == "auto":
            object.__setattr__(self, "axis", natural_axis(self.bounds))
        if self.axis not in AXIS_KINDS:
            raise ValueError(f"parameter {self.name!r}: axis {self.axis!r}; use {AXIS_KINDS}")

    @property
    def log(self) -> bool:
        return self.axis == "log"

    @property
    def z_bounds(self) -> tuple[float, float]:
        low, high = self.bounds
        return (np.log(low), np.log(high)) if self.log else (low, high)

    def to_z(self, theta):
        return np.log(theta) if self.log else np.asarray(theta, dtype=float)

    def from_z(self, z):
        return np.exp(z) if self.log else np.asarray(z, dtype=float)

    def log_prior_z(self, z):
        """Log density of the prior in z, including |d theta / d z| = theta on a log axis."""
        z = np.asarray(z, dtype=float)
        value = self.prior.logpdf(self.from_z(z))
        return value + z if self.log else value


@dataclass(frozen=True)
class ParameterSpace:
    """The coordinates of d parameters (module docstring).  Arrays are (d,) in ``parameters``
    order; every map takes points (..., d)."""

    parameters: tuple[ParameterSpec, ...]
    lower: np.ndarray = field(init=False, repr=False, compare=False)
    upper: np.ndarray = field(init=False, repr=False, compare=False)
    is_log: np.ndarray = field(init=False, repr=False, compare=False)
    z_low: np.ndarray = field(init=False, repr=False, compare=False)
    z_high: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        params = tuple(self.parameters)
        arrays = {
            "parameters": params,
            "lower": np.array([p.bounds[0] for p in params], dtype=float),
            "upper": np.array([p.bounds[1] for p in params], dtype=float),
            "is_log": np.array([p.log for p in params], dtype=bool),
            "z_low": np.array([p.z_bounds[0] for p in params], dtype=float),
            "z_high": np.array([p.z_bounds[1] for p in params], dtype=float),
        }
        for name, value in arrays.items():
            if isinstance(value, np.ndarray):
                value.setflags(write=False)  # shared by every caller: read-only
            object.__setattr__(self, name, value)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.parameters)

    @property
    def ndim(self) -> int:
        return len(self.parameters)

    def linear(self) -> "ParameterSpace":
        """The same parameters, every axis linear (the optimizer's box: u is linear in theta)."""
        return ParameterSpace(tuple(replace(p, axis="linear") for p in self.parameters))

    # -- axis coordinates z and the unit box u ------------------------------------------------
    def z_from_theta(self, theta) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        z = theta.copy()
        z[..., self.is_log] = np.log(theta[..., self.is_log])
        return z

    def theta_from_z(self, z) -> np.ndarray:
        z = np.asarray(z, dtype=float)
        theta = z.copy()
        theta[..., self.is_log] = np.exp(z[..., self.is_log])
        return theta

    def z_from_u(self, u) -> np.ndarray:
        return self.z_low + np.clip(u, 0.0, 1.0) * (self.z_high - self.z_low)

    def u_from_theta(self, theta) -> np.ndarray:
        """Unit-box coordinates of theta (not clipped: a theta outside the bounds is outside)."""
        return (self.z_from_theta(theta) - self.z_low) / (self.z_high - self.z_low)

    def theta_from_u(self, u) -> np.ndarray:
        """theta at u, u clipped to the box: low + clip(u) (high - low) on a linear axis."""
        return self.theta_from_z(self.z_from_u(u))

    # -- priors -------------------------------------------------------------------------------
    @cached_property
    def joint_prior(self) -> JointPrior:
        """The parameters' priors evaluated together (made once: the mixture proposal asks at
        every step)."""
        return JointPrior.of(tuple(p.prior for p in self.parameters))

    def log_prior(self, theta) -> np.ndarray:
        """theta (n, d) -> (n,) joint log prior density in theta (-inf outside the bounds)."""
        return self.joint_prior.log_density(theta)

    def log_prior_z(self, z) -> np.ndarray:
        """z (n, d) -> (n,) joint log prior density in z coordinates."""
        z = np.atleast_2d(z)
        return sum(p.log_prior_z(z[:, j]) for j, p in enumerate(self.parameters))

    def log_prior_y(self, y) -> np.ndarray:
        """y (n, d) -> (n,) joint log prior density in the unconstrained coordinates y."""
        y = np.atleast_2d(y)
        return self.log_prior(self.theta_from_y(y)) + self.log_jacobian_y(y)

    # -- unconstrained sampler coordinates y --------------------------------------------------
    @property
    def _both(self) -> np.ndarray:
        return np.isfinite(self.lower) & np.isfinite(self.upper)

    @property
    def _lower_only(self) -> np.ndarray:
        return np.isfinite(self.lower) & ~np.isfinite(self.upper)

    @property
    def _upper_only(self) -> np.ndarray:
        return ~np.isfinite(self.lower) & np.isfinite(self.upper)

    def theta_from_y(self, y) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        both = self._both
        s = logistic(y)
        span = np.where(both, self.upper - self.lower, 0.0)
        theta = np.where(both, self.lower + span * s, y)
        theta = np.where(self._upper_only, self.upper - np.exp(np.minimum(-y, 700.0)), theta)
        return np.where(self._lower_only, self.lower + np.exp(np.minimum(y, 700.0)), theta)

    def log_jacobian_y(self, y) -> np.ndarray:
        """(n,) log |d theta / d y| summed over the columns of y (n, d)."""
        y = np.asarray(y, dtype=float)
        both = self._both
        # log s + log(1 - s) = -|y| - 2 log(1 + exp(-|y|)), stable for large |y|
        logit_part = np.log(np.where(both, self.upper - self.lower, 1.0)) - np.abs(y)
        logit_part = logit_part - 2.0 * np.log1p(np.exp(-np.abs(y)))
        one_sided = np.where(self._lower_only, y, np.where(self._upper_only, -y, 0.0))
        return np.where(both, logit_part, one_sided).sum(axis=-1)

    def y_from_theta(self, theta, margin: float = 1e-3) -> np.ndarray:
        """Inverse of ``theta_from_y``; a point on a finite bound of a two-sided parameter is
        moved ``margin`` (of the width) inside it."""
        theta = np.asarray(theta, dtype=float)
        with np.errstate(invalid="ignore", divide="ignore"):
            u = np.clip((theta - self.lower) / (self.upper - self.lower), margin, 1 - margin)
            logit = np.log(u) - np.log1p(-u)
            log_above = np.log(np.maximum(theta - self.lower, 1e-300))
            log_below = -np.log(np.maximum(self.upper - theta, 1e-300))
        one_sided = np.where(self._upper_only, log_below, theta)
        return np.where(self._both, logit, np.where(self._lower_only, log_above, one_sided))


# -- least squares over the unit box ----------------------------------------------------------
@dataclass
class EvaluationCount:
    """Model evaluations and failures of one fit (mutable; local to that fit)."""

    evaluations: int = 0
    failed: int = 0


def unit_box_residuals(
    space: ParameterSpace,
    residuals_at: Callable[[np.ndarray], np.ndarray | None],
    units: np.ndarray,
    count: EvaluationCount,
) -> Callable[[np.ndarray], np.ndarray]:
    """r(u) (size,) for a bounded least-squares fit in the unit box of ``space``.

    residuals_at(theta (d,)) -> the residual vector (size,), or None where the model failed.
    units : (size,) each component's unit as a relative error (1, or its noise sd).  A failure
    or a non-finite residual gives FAILED_RELATIVE_ERROR / units (module docstring); ``count``
    counts evaluations and failures.
    """
    failed = failed_residuals(units)

    def residuals(u: np.ndarray) -> np.ndarray:
        return screened_residuals(residuals_at(space.theta_from_u(u)), failed, count)

    return residuals


def failed_residuals(units: np.ndarray) -> np.ndarray:
    """(size,) the residual of a failed evaluation: FAILED_RELATIVE_ERROR / units (module
    docstring), units (size,) each component's unit as a relative error."""
    return FAILED_RELATIVE_ERROR / np.asarray(units, dtype=float)


def screened_residuals(
    r: np.ndarray | None, failed: np.ndarray, count: EvaluationCount
) -> np.ndarray:
    """One evaluation of a unit-box fit under the failure convention (module docstring): r
    (size,), or a copy of ``failed`` (``failed_residuals``) where r is None or not finite.
    Counts the evaluation, and the failure, in ``count``.  A caller that evaluates its own
    model (discovery's ``FitSpace``) builds its r(u) from this and ``theta_from_u``, so the
    fit's function stays in the caller's room."""
    count.evaluations += 1
    if r is None or not np.all(np.isfinite(r)):
        count.failed += 1
        return failed.copy()
    return r
