"""The calibration posterior: the frequency block (and optionally the mass block) of
``likelihood_blocks`` with a sampled or fixed level sigma, times the parameter priors, vectorized
over walkers.

For paired frequencies f_i(theta) and test values f_Ti:

    e_i = (f_i - f_Ti) / f_Ti,   e_i ~ N(0, s_i^2),   s_i^2 = sigma^2 / w_i + (sd_i / f_Ti)^2,

with w_i the eq. 19 weights (w_i = 0 drops mode i) and sd_i the test's own frequency standard
deviation if the data give one (added in quadrature; zero otherwise): ``SampledNoise``.  sd_i^2
is the sum of the data's stated ``frequency_sd_hz``^2 and its ``identification_sd_hz``^2 (the
identification's part, ``identify``; ``likelihood_blocks`` module docstring).  So
-2 log L is sum_i e_i^2 / s_i^2 + const: with equal s_i it is seed eq. 19 divided by sigma^2.
sigma is fixed or sampled as one more parameter (named ``sigma``) with its own prior (e.g.
halfnormal).  Optional mass term: (m - m_T)/m_T ~ N(0, mass_sd_rel^2) (``mass_log_likelihood``).
Measured CG / inertia components (the problem's ``objective.mass_properties``) add their own
Gaussian block with their stated sds (``mass_properties.MassPropertyTargets.log_likelihood``),
each point's values from the model's ``mass_properties`` (one mass-matrix assembly, no solve).

``LogPosterior`` maps walkers (n_walkers, d) to (n_walkers,) log-posterior values.  Three ways
to get the paired frequencies (``mode``):

* ``"shape-batch"``: the problem pairs by shape (tracked against the reference design, or MAC to
  test shapes) and the model gives frequencies *and sensor shapes* for a whole batch
  (``predict_batch_with_shapes``, e.g. the reduced FE model): one batched solve, then a batched
  MAC assignment (``pairing.pair_batch``).  Default for such models: a posterior never compares
  swapped modes silently.  ``pair_differs / pair_checked`` is the share of evaluated points whose
  pairing differs from the order pairing.
* ``"order-batch"``: frequencies in order from ``predict_frequencies_batch`` (the problem pairs by
  order, or ``pairing="order"`` was asked for).
* ``"points"``: one ``problem.evaluate`` per point (the problem's pairing, models without batch
  support, a mass term on a model that cannot give its mass without a solve).  Given an
  executor (``LogPosterior(..., executor=...)``), the points of each call are evaluated on it
  (``parallel.PointEvaluator``: the problem sent to each worker once; evaluations back in point
  order, so the chain is the serial one bit for bit).  The batched modes run here: one batched
  solve beats shipping points to workers one by one; a sampler may split a large batch in two
  with a worker (``evaluators.split_densities``), the same bits.

With a mass term the batched modes take each point's mass from ``mass_function`` (the FE
model's ``total_mass``, no solve; the reduced model's own predictions take it from there too):
on the demo's seed case (Table 2 with the weighed mass, reduced basis) a batch of 16 walkers
costs ~0.6 ms a point against ~1.9 ms a point through ``problem.evaluate``.  A sampling run
takes them from a polynomial verified to round-off instead (``LogPosterior.use_fitted_mass``).

A point where the model raises or returns NaN gets -inf and is counted in ``failed``.
"""

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.evaluators import PointEvaluator
from bayesupdate.inference.likelihood_blocks import (
    SampledNoise,
    mass_log_likelihood,
    relative_errors,
)
from bayesupdate.inference.mass_properties import mass_properties_function
from bayesupdate.inference.pairing import pair_batch
from bayesupdate.inference.priors import JointPrior, Prior
from bayesupdate.inference.problem import CalibrationProblem
from bayesupdate.model_protocol import BatchParametricModel

PAIRING_CHOICES = ("auto", "tracked", "problem", "order")
#: the exact posterior's masses come from the verified mass polynomial (``inference.mass_fit``)
#: only when it reproduces the model to this relative error (``LogPosterior.use_fitted_mass``)
EXACT_MASS_REL_TOL = 1e-10


@dataclass(frozen=True)
class LikelihoodSpec:
    """sigma : fixed relative noise level, or None to infer it with ``sigma_prior``.

    mass_sd_rel : relative sd of the mass observation (None: mass not in the likelihood).
    pairing : "auto" (default: the problem's pairing, batched when the model gives batch shapes,
    else per point; batched in order when the problem pairs by order), "tracked" (same as auto),
    "problem" (the problem's pairing, per-point predictions when it needs shapes) or "order"
    (frequencies in order; batch predictions; swaps are only checked on draws afterwards).
    """

    sigma: float | None = 0.05
    sigma_prior: Prior | None = None
    mass_sd_rel: float | None = None
    pairing: str = "auto"

    def __post_init__(self):
        if self.sigma is None and self.sigma_prior is None:
            raise BayesUpdateError("likelihood: give sigma = value or sigma_prior = {kind = ...}")
        if self.sigma is not None and self.sigma_prior is not None:
            raise BayesUpdateError("likelihood: give either sigma or sigma_prior, not both")
        if self.sigma is not None and not (np.isfinite(self.sigma) and self.sigma > 0):
            raise BayesUpdateError(f"likelihood.sigma: must be > 0, got {self.sigma}")
        if self.sigma_prior is not None and self.sigma_prior.bounds[0] < 0:
            raise BayesUpdateError("likelihood.sigma_prior: bounds must be >= 0")
        if self.mass_sd_rel is not None and not self.mass_sd_rel > 0:
            raise BayesUpdateError("likelihood.mass_sd: must be > 0")
        if self.pairing not in PAIRING_CHOICES:
            raise BayesUpdateError(f"likelihood.pairing: use one of {list(PAIRING_CHOICES)}")

    @property
    def infer_sigma(self) -> bool:
        return self.sigma is None


class LogPosterior:
    """Vectorized log-posterior over walkers; counts evaluations and failures.

    Call with theta (n_walkers, d) where d = number of parameters (+1 for sigma, last column).
    """

    def __init__(self, problem: CalibrationProblem, spec: LikelihoodSpec, executor=None):
        self.problem = problem
        self.spec = spec
        self.priors = tuple(p.prior for p in problem.parameters)
        f_test = problem.data.frequencies_hz
        w = problem.weights
        self.mask = w > 0
        self.f_test = f_test[self.mask]
        data = problem.data
        sd, sd_id = data.frequency_sd_hz, data.identification_sd_hz
        self.noise = SampledNoise.of(
            self.f_test,
            w[self.mask],
            None if sd is None else sd[self.mask],
            None if sd_id is None else sd_id[self.mask],
        )
        self.mode = likelihood_mode(problem, spec)
        self.batched = self.mode != "points"
        self._remote = None  # points mode on an executor (module docstring)
        if not self.batched and executor is not None and executor.kind != "serial":
            self._remote = PointEvaluator(problem, executor)
        if self.mode == "shape-batch":
            pairing = problem.pairing
            self._reference = (
                pairing.test_shapes if pairing.method == "mac" else pairing.reference_shapes
            )
            rows = {label: i for i, label in enumerate(problem.model.sensor_labels)}
            self._shape_rows = np.array([rows[label] for label in pairing.dof_labels], dtype=int)
        self.pair_checked = 0
        self.pair_differs = 0
        # fixed (not calibrated) parameters go to the batch call too: its defaults may differ
        self.fixed_names = tuple(k for k in problem.fixed if k in problem.model.parameter_names)
        self._mass_fit = None  # a verified mass polynomial (``with_fitted_mass``)
        self.fixed_values = np.array([problem.fixed[k] for k in self.fixed_names], dtype=float)
        self.evaluations = 0
        self.failed = 0
        self.last_error = ""
        self._joint_prior = JointPrior.of(self.priors)
        self.mass_targets = problem.objective.mass_properties

    @property
    def on_executor(self) -> bool:
        """Whether its points go to an executor already ("points" mode given one)."""
        return self._remote is not None

    @property
    def names(self) -> tuple[str, ...]:
        return self.problem.names + (("sigma",) if self.spec.infer_sigma else ())

    @property
    def ndim(self) -> int:
        return len(self.names)

    def predict_frequencies(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Paired frequencies (n, n_test) [Hz] and masses (n,) [kg] (NaN where failed)."""
        theta = np.atleast_2d(theta)
        n_test = self.problem.data.n_modes
        if self.batched:
            if self.fixed_names:
                full_theta = np.hstack([theta, np.tile(self.fixed_values, (theta.shape[0], 1))])
            else:
                full_theta = theta
            names = self.problem.names + self.fixed_names
            try:
                if self.mode == "shape-batch":
                    freqs = self._shape_paired(full_theta, names)
                else:
                    order = self.problem.pairing.expected
                    freqs = np.asarray(
                        self.problem.model.predict_frequencies_batch(
                            full_theta, names, n_modes=int(order.max()) + 1
                        ),
                        dtype=float,
                    )[:, order]
            except Exception as exc:  # a failing batch: fall back to points to find the culprits
                self.last_error = f"{type(exc).__name__}: {exc}"
                freqs = None
            if freqs is not None and freqs.shape == (theta.shape[0], n_test):
                return freqs, self._masses(full_theta, names)
        freqs = np.full((theta.shape[0], n_test), np.nan)
        mass = np.full(theta.shape[0], np.nan)
        use_order = self.spec.pairing == "order"
        if self._remote is not None:
            evaluations = self._remote(theta)
        else:
            evaluations = (self.problem.evaluate(point) for point in theta)
        for k, evaluation in enumerate(evaluations):
            if not evaluation.ok:
                self.last_error = evaluation.error
                continue
            freqs[k] = (
                evaluation.all_frequencies_hz[self.problem.pairing.expected]
                if use_order
                else evaluation.frequencies_hz
            )
            if not use_order and self.problem.pairing.method != "order":
                self.pair_checked += 1
                self.pair_differs += int(evaluation.paired.swapped)
            mass[k] = np.nan if evaluation.mass_kg is None else evaluation.mass_kg
        return freqs, mass

    def _masses(self, theta: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
        """(n,) total masses [kg] at theta (n, len(names)) when the likelihood has a mass term
        (NaN where the model rejects the values), else NaN."""
        masses = np.full(theta.shape[0], np.nan)
        if self.spec.mass_sd_rel is None:
            return masses
        rows = np.arange(theta.shape[0])
        fit = self._mass_fit
        if fit is not None:
            d = fit.low.size
            inside = np.all((theta[:, :d] >= fit.low) & (theta[:, :d] <= fit.high), axis=1)
            masses[inside] = fit(theta[inside, :d])
            rows = np.flatnonzero(~inside)
        mass_of = mass_function(self.problem.model)
        for k in rows:
            row = theta[k]
            try:
                masses[k] = mass_of(dict(zip(names, map(float, row), strict=True)))
            except BayesUpdateError:
                continue
        return masses

    def with_fitted_mass(self, seed: int = 0) -> "LogPosterior":
        """This posterior with its mass term's masses from a verified polynomial over the
        parameter box (``inference.mass_fit``; the model's own masses outside the box), or
        itself when there is no mass term, the masses come per point anyway (``mode``
        "points") or the fit does not verify.  For a delayed-acceptance screen: the chain's
        target stays exact whatever the screen is (``inference.mass_fit`` module docstring)."""
        import copy

        fit = self._fitted_mass(seed)
        if fit is None:
            return self
        fitted = copy.copy(self)
        fitted._mass_fit = fit
        return fitted

    def use_fitted_mass(self, seed: int = 0) -> bool:
        """Take this posterior's own masses (the mass term's, in place) from the verified
        polynomial of ``with_fitted_mass`` when it reproduces the model's masses to
        ``EXACT_MASS_REL_TOL`` at its check points; True when it does.

        Why: the model's masses come one Python call per point (~0.1-0.2 ms), about an eighth
        of an exact batch's cost on the exhaust (seed Table 2 with the weighed mass, 16 points:
        14.3 against 12.6 ms on the loaded 2-core machine), the polynomial's in one array
        product.  ``sample --model exhaust --data paper:ema`` gives the same chain to the bit
        with either (seed 1).  Why the target does not move: a relative mass error
        e changes the mass block's log-likelihood by |z| e / mass_sd_rel (z the standardized
        mass residual), < 3e-8 at e = 1e-10, |z| < 3 and the weighed 1 %, against the reduced
        basis's certified frequency error (1e-4 relative, |z| 1e-4 / sigma per mode) that the
        target already carries.  The exhaust's fit: 1.3e-12 at its check points, 2.3e-12 at
        2000 fresh points of the box (its oval sections' area is not a polynomial in t)."""
        fit = self._fitted_mass(seed)
        if fit is None or not fit.max_rel_error <= EXACT_MASS_REL_TOL:
            return False
        self._mass_fit = fit
        return True

    def _fitted_mass(self, seed: int):
        """The verified ``inference.mass_fit.MassPolynomial`` of this posterior's masses, None
        when there is no mass term, the masses come per point, or the fit does not verify."""
        from bayesupdate.inference.mass_fit import fit_problem_masses

        mass_of = mass_function(self.problem.model)
        if self.spec.mass_sd_rel is None or not self.batched or mass_of is None:
            return None
        names, p = self.problem.names + self.fixed_names, self.problem
        return fit_problem_masses(mass_of, names, self.fixed_values, p.lower, p.upper, seed)

    def _shape_paired(self, theta: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
        """Frequencies (B, n_test) paired by batched MAC against the reference shapes."""
        pairing = self.problem.pairing
        freqs, shapes = self.problem.model.predict_batch_with_shapes(
            theta, names, n_modes=pairing.n_model
        )
        window = None if pairing.window is None else (pairing.test_hz, freqs, pairing.window)
        index, _ = pair_batch(self._reference, shapes[:, self._shape_rows, :], window)
        ok = np.all(np.isfinite(freqs), axis=1)
        self.pair_checked += int(ok.sum())
        self.pair_differs += int(np.sum(np.any(index != pairing.expected, axis=1) & ok))
        return np.take_along_axis(freqs, index, axis=1)

    @property
    def pair_differs_fraction(self) -> float:
        """Share of evaluated points whose shape pairing differs from the order pairing (NaN if
        the likelihood does not pair by shape)."""
        return self.pair_differs / self.pair_checked if self.pair_checked else float("nan")

    def mass_property_values(self, theta: np.ndarray) -> np.ndarray | None:
        """(n, k) the model's values of the measured CG / inertia components at theta (n, d)
        (NaN rows where the model rejects the values); None when none are measured."""
        if self.mass_targets is None:
            return None
        function = mass_properties_function(self.problem.model)
        out = np.full((theta.shape[0], len(self.mass_targets.names)), np.nan)
        for k, row in enumerate(theta):
            try:
                out[k] = self.mass_targets.predicted(function(self.problem.as_mapping(row)))
            except BayesUpdateError:
                continue
        return out

    def log_likelihood(
        self, freqs: np.ndarray, sigma: np.ndarray, mass: np.ndarray, props=None
    ) -> np.ndarray:
        """freqs (n, n_test) [Hz], sigma (n,), mass (n,), props (n, k) or None (the measured
        CG / inertia components' model values) -> (n,) log-likelihood (NaN -> -inf)."""
        ll = self.noise.log_likelihood(relative_errors(freqs[:, self.mask], self.f_test), sigma)
        if self.spec.mass_sd_rel is not None:
            target = self.problem.objective.mass_target_kg
            if target is None:
                raise BayesUpdateError("likelihood.mass_sd needs objective.mass_kg")
            ll = ll + mass_log_likelihood(mass, target, self.spec.mass_sd_rel)
        if props is not None and self.mass_targets is not None:
            ll = ll + self.mass_targets.log_likelihood(props)
        return np.where(np.isfinite(ll), ll, -np.inf)

    def log_prior(self, theta: np.ndarray) -> np.ndarray:
        """Joint log prior of the model parameters, theta (n, d) -> (n,) (``JointPrior``)."""
        return self._joint_prior.log_density(theta)

    def __call__(self, theta: np.ndarray) -> np.ndarray:
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        d = len(self.priors)
        # a proposal far out (an overflowing z^2) or at sigma = 0 has density 0: -inf by intent
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            lp = self.log_prior(theta[:, :d])
            if self.spec.infer_sigma:
                sigma = theta[:, d]
                lp = lp + self.spec.sigma_prior.logpdf(sigma)
            else:
                sigma = np.full(theta.shape[0], self.spec.sigma)
        inside = np.isfinite(lp)
        out = np.full(theta.shape[0], -np.inf)
        if not np.any(inside):
            return out
        freqs, mass = self.predict_frequencies(theta[inside, :d])
        props = self.mass_property_values(theta[inside, :d])
        self.evaluations += int(np.sum(inside))
        failed = ~np.all(np.isfinite(freqs), axis=1)
        self.failed += int(np.sum(failed))
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            out[inside] = lp[inside] + self.log_likelihood(freqs, sigma[inside], mass, props)
        return out


def mass_function(model) -> Callable[[dict], float] | None:
    """params -> total mass [kg] without a solve: a reduced model's ``mass_kg`` (per-term masses,
    the same its ``predict`` reports, no K, M assembly), else ``total_mass`` of an FE model or
    of the FE model a model wraps (its ``fe``); None for other models."""
    if callable(getattr(model, "mass_kg", None)):
        return model.mass_kg
    for candidate in (model, getattr(model, "fe", None)):
        total_mass = getattr(candidate, "total_mass", None)
        if callable(total_mass):
            return lambda params: float(total_mass(params)[0])
    return None


def likelihood_mode(problem: CalibrationProblem, spec: LikelihoodSpec) -> str:
    """ "shape-batch", "order-batch" or "points" for this problem and spec (module docstring)."""
    model = problem.model
    if spec.mass_sd_rel is not None and mass_function(model) is None:
        return "points"
    if spec.pairing == "order" or problem.pairing.method == "order":
        return "order-batch" if isinstance(model, BatchParametricModel) else "points"
    if spec.pairing in ("auto", "tracked") and hasattr(model, "predict_batch_with_shapes"):
        labels = set(getattr(model, "sensor_labels", ()))
        # no test DOFs (a deck without test points): nothing to pair shapes on
        if problem.pairing.dof_labels and set(problem.pairing.dof_labels) <= labels:
            return "shape-batch"
    return "points"
