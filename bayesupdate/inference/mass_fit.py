"""A model's total mass over the parameter box as a polynomial, verified before use.

Why: a likelihood with a mass term takes each point's mass from the model (``likelihood.
mass_function``: per-term masses, no solve, but one Python call per point, ~0.2 ms).  The
delayed-acceptance screen (``inference.delayed_acceptance``) evaluates every proposal, and on the
exhaust (seed Table 2 with the weighed mass, 32 walkers) its per-point masses were 38 % of a
screened batch's cost (7.3 of 19.2 ms for 32 points, ``benchmarks/likelihood_speed.py``).

The total mass of the library's models is a low-degree polynomial in the parameters: rho A(t) L
with a tube area quadratic in its wall thickness t, point-mass factors and densities linear,
shell groups rho sum_p theta^p m_p (``fe.reduced.mass``).  So the mass is fitted once by least
squares on the monomials of total degree <= ``DEGREE`` in the box coordinates u in [-1, 1]^d
(u = 2 (theta - low) / (high - low) - 1), at ``FIT_FACTOR`` x (number of monomials) points
drawn uniformly in the box, and used only when, at ``CHECK_POINTS`` fresh points, it matches the
model to ``REL_TOL`` relative: a polynomial of higher degree, or a mass that is not a
polynomial, fails the check and the caller keeps the model's own per-point masses.

The screen uses it (``LogPosterior.with_fitted_mass``): delayed acceptance leaves the chain's
target the exact posterior whatever the surrogate is (Christen & Fox 2005), so even a fit that
were off somewhere between the check points would cost acceptance, never accuracy.  The exact
posterior of a sampling run uses it only when it reproduces the model to round-off
(``LogPosterior.use_fitted_mass``, ``likelihood.EXACT_MASS_REL_TOL``: 1e-10; the exhaust's
1.3e-12), far below the reduced basis's own error in the target.
"""

import itertools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bayesupdate.compute.batch_rows import row_product
from bayesupdate.errors import BayesUpdateError

#: total degree of the fitted monomials (a shell's rho theta^3 is degree 4)
DEGREE = 4
#: fitting points per monomial
FIT_FACTOR = 3
#: fresh points at which the fit is checked against the model
CHECK_POINTS = 64
#: largest relative difference from the model accepted at the check points
REL_TOL = 1e-9
#: no fit above this many monomials (d = 8 at degree 4 has 495): the fit would cost more
#: model calls than a screened run saves
MAX_TERMS = 500


def monomial_exponents(d: int, degree: int = DEGREE) -> np.ndarray:
    """(n_terms, d) exponents of every monomial of total degree <= ``degree`` in d variables,
    constant first."""
    rows = [
        np.bincount(np.array(c, dtype=int), minlength=d)
        for k in range(degree + 1)
        for c in itertools.combinations_with_replacement(range(d), k)
    ]
    return np.array(rows, dtype=int).reshape(-1, d)


@dataclass(frozen=True)
class MassPolynomial:
    """Total mass [kg] = sum_k coef_k prod_j u_j^exponents_kj, u the box coordinates of theta.

    low, high : (d,) the box [parameter units]; exponents : (n_terms, d); coef : (n_terms,) [kg].
    max_rel_error : the largest relative difference from the model at the check points.
    """

    low: np.ndarray
    high: np.ndarray
    exponents: np.ndarray
    coef: np.ndarray
    max_rel_error: float

    def design(self, theta: np.ndarray) -> np.ndarray:
        """(n, n_terms) monomials at theta (n, d)."""
        u = 2.0 * (np.atleast_2d(theta) - self.low) / (self.high - self.low) - 1.0
        # each u_j^k once, then gathered: the same powers as u ** exponents term by term (to the
        # bit), five times fewer of them (32 points, 126 monomials: 0.11 against 0.57 ms)
        powers = u[:, :, None] ** np.arange(int(self.exponents.max(initial=0)) + 1)
        return np.prod(powers[:, np.arange(u.shape[1]), self.exponents], axis=2)

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        """(n,) total masses [kg] at theta (n, d), each point's the same bits in any batch
        (``compute.batch_rows``)."""
        return row_product(self.design(theta), self.coef)


def _masses(mass_of: Callable[[np.ndarray], float], theta: np.ndarray) -> np.ndarray | None:
    """The model's masses at the rows of theta, None when it rejects any of them."""
    out = np.empty(theta.shape[0])
    for k, row in enumerate(theta):
        try:
            out[k] = mass_of(row)
        except BayesUpdateError:
            return None
    return out if np.all(np.isfinite(out)) else None


def fit_mass_polynomial(
    mass_of: Callable[[np.ndarray], float],
    low: np.ndarray,
    high: np.ndarray,
    seed: int = 0,
) -> MassPolynomial | None:
    """The verified polynomial of ``mass_of`` (theta (d,) -> total mass [kg]) over the box
    [low, high] (module docstring), or None when it does not reproduce the model to
    ``REL_TOL`` at the check points, the box is not finite, it has too many monomials, or the
    model rejects a point of the box.  seed : the fitting and check points' generator."""
    low, high = np.asarray(low, dtype=float), np.asarray(high, dtype=float)
    if not (np.all(np.isfinite(low)) and np.all(np.isfinite(high)) and np.all(high > low)):
        return None
    exponents = monomial_exponents(low.size)
    n_terms = exponents.shape[0]
    if n_terms > MAX_TERMS:
        return None
    rng = np.random.default_rng(seed)
    points = low + (high - low) * rng.uniform(size=(FIT_FACTOR * n_terms + CHECK_POINTS, low.size))
    masses = _masses(mass_of, points)
    if masses is None:
        return None
    fit, check = slice(0, FIT_FACTOR * n_terms), slice(FIT_FACTOR * n_terms, None)
    shell = MassPolynomial(low, high, exponents, np.zeros(n_terms), np.inf)
    coef = np.linalg.lstsq(shell.design(points[fit]), masses[fit], rcond=None)[0]
    fitted = MassPolynomial(low, high, exponents, coef, np.inf)
    error = float(np.max(np.abs(fitted(points[check]) - masses[check]) / np.abs(masses[check])))
    if not error <= REL_TOL:
        return None
    return MassPolynomial(low, high, exponents, coef, error)


def fit_problem_masses(
    mass_of: Callable[[dict[str, float]], float],
    names: tuple[str, ...],
    fixed_values,
    low: np.ndarray,
    high: np.ndarray,
    seed: int = 0,
) -> MassPolynomial | None:
    """``fit_mass_polynomial`` of a problem's total mass over its free parameters' box [low,
    high] with its fixed parameters held: ``mass_of`` takes {name: value} over ``names`` (the
    free parameters, then the fixed ones, whose values are ``fixed_values``)."""
    held = np.asarray(fixed_values, dtype=float)

    def mass_at(row: np.ndarray) -> float:
        return mass_of(dict(zip(names, map(float, np.concatenate([row, held])), strict=True)))

    return fit_mass_polynomial(mass_at, low, high, seed)
