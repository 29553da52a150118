"""Name: refit a model (baseline or baseline + one effect) and compute its evidence.

The likelihood is ``inference.likelihood_blocks.FixedNoiseLikelihood``: the relative frequency
errors e_i with noise s_i from ``likelihood_blocks.NoiseModel`` (the data's sd, a fixed level, or
the robust level of the frequency-only baseline's residuals), and the shape block when the test
has shapes:

    log L = -1/2 sum r_i^2 - sum log s_i - m/2 log 2 pi,   r_i = e_i / s_i.

Every level is fixed before any fit: an inferred frequency level is the empirical-Bayes plug-in
of the frequency-only baseline (Vanik, Beck & Au 2000 estimate the prediction-error variances
alongside the parameters; here they are estimated once, where only the frequencies chose the
design), and each shape level is fixed the same way (``shape_evidence``).  A level integrated out
at every point instead (a log-uniform prior on sigma, as this module once did) makes the frequency
block scale-invariant: moving all twelve identified frequencies 0.08 % off, 8 times their robust
level, then cost only m/2 ln 64 = 25 nats, less than a few shape blocks could gain, and the
baseline of an identified null test was dragged that far (``tests/test_discovery_cli.py``,
``test_user_path_null_case_names_nothing``).

Evidence by the Laplace approximation (MacKay 2003 ch. 27; Kass & Raftery 1995 eq. 4) in the fit
coordinates z (the axis coordinates of ``inference.parameter_space``):

    log Z = log L(z*) + log p(z*) + d/2 log 2 pi - 1/2 log det H + sum_j log T_j,

H = J^T J + diag(prior curvature) the Gauss-Newton Hessian of the negative log posterior
(J: Jacobian of r in z), and
T_j = Phi((z_hi - z*_j)/s_j) - Phi((z_lo - z*_j)/s_j), s_j^2 = (H^-1)_jj, the Gaussian mass
inside the prior box (so a parameter at its bound, or one the data do not constrain, is not
over-counted).  Starts that end in distinct optima (Mahalanobis distance > 3 under H) have their
evidences summed (log-sum-exp); the same optimum found twice counts once.

When the test has shapes, the residual vector also holds the shape residuals
(``likelihood_blocks.ShapeBlock``, each mode with its own level fixed before the fit by
``shape_evidence``), and H sums J_b^T J_b over the blocks.  When the study measured mass
properties (weight, CG, inertia), their residuals follow (``mass_block``: the terms ``calibrate``'s
likelihood has), so an effect that adds mass is judged against the weight too.

PSIS-LOO (Vehtari, Gelman & Gabry 2017) with per-mode log-likelihoods (a mode's frequency and
shape together), via ``arviz_stats.loo_approximate_posterior``: draws from the Laplace
Gaussian (truncated to the box), residuals linearized with the same Jacobian (r = r* + J (z - z*),
the approximation the Laplace evidence already makes; no extra model solves), importance-corrected
with log p - log q.
"""

import time
import warnings
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from scipy import optimize, special, stats

from bayesupdate.discovery.mass_block import MassBlock, WithMassBlock
from bayesupdate.discovery.settings import MIN_LOO_DRAWS
from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.likelihood_blocks import (
    LOG_2PI,
    FixedNoiseLikelihood,
    NoiseModel,
    ShapeBlock,
    relative_errors,
)
from bayesupdate.inference.parameter_space import (
    EvaluationCount,
    ParameterSpace,
    ParameterSpec,
    failed_residuals,
    screened_residuals,
)


@dataclass(frozen=True)
class FitSpace:
    """What a fit needs: the calibration problem of the (extended) model, its parameters
    (problem order, each on its axis), the frequency noise and the shape block (``likelihood``)."""

    problem: object
    axes: tuple[ParameterSpec, ...]
    noise: NoiseModel
    shapes: ShapeBlock | None = None
    mass: MassBlock | None = None

    @property
    def likelihood(self) -> "FixedNoiseLikelihood | WithMassBlock":
        inner = FixedNoiseLikelihood(self.noise, self.shapes)
        return inner if self.mass is None else WithMassBlock(inner, self.mass)

    def shape_residuals(self, r: np.ndarray) -> np.ndarray:
        """The shape block's part of a residual vector r (size,) (empty without shapes)."""
        n = self.n_frequency
        return r[n : n + (0 if self.shapes is None else self.shapes.size)]

    @property
    def n_frequency(self) -> int:
        """Residuals of the frequency block (the used modes)."""
        return self.likelihood.n_frequency

    @property
    def size(self) -> int:
        """Length of the residual vector: frequencies, then shapes mode after mode."""
        return self.likelihood.size

    @cached_property
    def parameter_space(self) -> ParameterSpace:
        """The coordinates theta, z (axis) and u (unit box) of the fit (``parameter_space``)."""
        return ParameterSpace(self.axes)

    @property
    def z_low(self) -> np.ndarray:
        return self.parameter_space.z_low

    @property
    def z_high(self) -> np.ndarray:
        return self.parameter_space.z_high

    def z_from_u(self, u):
        return self.parameter_space.z_from_u(u)

    def u_from_theta(self, theta) -> np.ndarray:
        return self.parameter_space.u_from_theta(theta)

    def theta_from_z(self, z) -> np.ndarray:
        return self.parameter_space.theta_from_z(z)

    def log_prior_z(self, z: np.ndarray) -> np.ndarray:
        """z (n, d) -> (n,) joint log prior density in z coordinates."""
        return self.parameter_space.log_prior_z(z)

    @property
    def residual_units(self) -> np.ndarray:
        """(size,) the noise sd each component of ``residual_vector`` is measured in: the
        frequency levels, then each mode's shape level once per DOF."""
        units = [self.noise.scale[self.noise.used]]
        if self.shapes is not None:
            units.append(np.repeat(self.shapes.scale, self.shapes.n_dof))
        if self.mass is not None:
            units.append(self.mass.scale)
        return np.concatenate(units)

    def unit_box_residuals(self, count: EvaluationCount):
        """r(u) (size,): ``residual_vector`` at theta(u) for a least-squares fit in the unit box,
        with the failure convention of ``parameter_space.unit_box_residuals``
        (``screened_residuals``).  The function is built here, not handed down to
        ``parameter_space``, so the solver's calls stay in discovery's code.

        Each distinct u is solved once per function (``count`` counts solves): a fit asks
        for the same points again, the chosen start (``_pick_starts``, then the solver's
        first call) and the forward-difference points at the end point (TRF's last
        Jacobian, then ``_forward_jacobian``'s, the same steps: 1e-4, flipped at the upper
        bound), so a solve there would give the same bits again."""
        failed = failed_residuals(self.residual_units)
        theta_from_u = self.parameter_space.theta_from_u
        solved: dict[bytes, np.ndarray] = {}

        def residuals(u: np.ndarray) -> np.ndarray:
            key = np.asarray(u, dtype=float).tobytes()
            if key not in solved:
                r = self._residuals_at(theta_from_u(u))
                solved[key] = screened_residuals(r, failed, count)
            return solved[key].copy()

        return residuals

    def _residuals_at(self, theta) -> np.ndarray | None:
        """``residual_vector`` (size,) at theta, None where the model failed."""
        e, evaluation = self.relative_errors(theta)
        if not evaluation.ok:
            return None
        shapes = None if evaluation.paired is None else evaluation.paired.shapes
        return self.residual_vector(e, shapes, self.mass_values(evaluation))

    def mass_values(self, evaluation) -> np.ndarray | None:
        """(k,) the mass block's model values of a problem ``Evaluation`` (its total mass and
        measured CG / inertia components); None without a mass block."""
        if self.mass is None:
            return None
        return self.mass.values(evaluation.mass_kg, evaluation.mass_properties)

    def relative_errors(self, theta) -> tuple[np.ndarray, object]:
        """e (m,) at theta and the problem's Evaluation (e NaN where the model failed)."""
        evaluation = self.problem.evaluate(np.asarray(theta, dtype=float))
        return relative_errors(
            evaluation.frequencies_hz, self.problem.data.frequencies_hz
        ), evaluation

    def residual_vector(
        self, e: np.ndarray, model_shapes: np.ndarray | None, mass_values=None
    ) -> np.ndarray:
        """(size,) residuals in noise units (``FixedNoiseLikelihood.residual_vector``), then
        the mass block's of ``mass_values`` (``MassBlock.values``) when there is one."""
        if self.mass is None:
            return self.likelihood.residual_vector(e, model_shapes)
        return self.likelihood.residual_vector(e, model_shapes, mass_values)


@dataclass
class Optimum:
    """One end point of a fit: z (d,), normalized residuals r (m_used,), Jacobian J (m_used, d)."""

    z: np.ndarray
    r: np.ndarray
    jac_z: np.ndarray
    log_like: float
    log_prior: float
    log_evidence: float
    hessian: np.ndarray


def laplace(space: FitSpace, z: np.ndarray, r: np.ndarray, jac_z: np.ndarray) -> Optimum:
    """Laplace log-evidence around one optimum (module docstring)."""
    d = z.size
    span = space.z_high - space.z_low
    likelihood = space.likelihood
    log_like = likelihood.log_likelihood(r)
    log_prior = float(space.log_prior_z(z[None])[0])
    h = 1e-4 * span
    curv = np.zeros(d)
    for j in range(d):  # priors are closed-form; a 3-point second difference per axis is exact
        zp, zm = z.copy(), z.copy()
        zp[j] = min(z[j] + h[j], space.z_high[j])
        zm[j] = max(z[j] - h[j], space.z_low[j])
        lp = space.log_prior_z(np.vstack([zm, z, zp]))
        step = 0.5 * (zp[j] - zm[j])
        if np.all(np.isfinite(lp)) and step > 0:
            curv[j] = max(-(lp[0] - 2 * lp[1] + lp[2]) / step**2, 0.0)
    hessian = jac_z.T @ (likelihood.curvature_weights(r)[:, None] * jac_z) + np.diag(curv)
    # a direction the data do not see: a tiny curvature (1e-8 per prior width^2) keeps H
    # invertible; the box truncation below then caps its contribution at the prior volume
    hessian = hessian + np.diag(1e-8 / span**2)
    sign, logdet = np.linalg.slogdet(hessian)
    cov = np.linalg.inv(hessian)
    sd = np.sqrt(np.maximum(np.diag(cov), 1e-300))
    inside = stats.norm.cdf((space.z_high - z) / sd) - stats.norm.cdf((space.z_low - z) / sd)
    log_trunc = float(np.sum(np.log(np.maximum(inside, 1e-300))))
    log_z = log_like + log_prior + 0.5 * d * LOG_2PI - 0.5 * logdet + log_trunc
    return Optimum(z, r, jac_z, log_like, log_prior, float(log_z), hessian)


@dataclass(frozen=True)
class ModelFit:
    """A fitted model (baseline or one candidate) with its evidence.

    label : "baseline" or ``KIND@LOCATION``.  theta : best parameters (SI), ``names`` order.
    residual_rel : (m,) relative errors at theta (test order).  optima : distinct optima found,
    best fit (smallest chi^2) first; theta is that optimum.
    log_evidence : Laplace log Z summed over the distinct optima.  loo : PSIS-LOO elpd (None
    unless computed).  mac : (m,) MAC of the paired shapes at theta (None without test shapes).
    model_error : largest relative frequency error of a reduced model at theta against a full
    solve (``reduced_candidates.certified_fit``; None: fitted on full solves).
    """

    label: str
    kind: str | None
    location: str | None
    names: tuple[str, ...]
    theta: np.ndarray
    residual_rel: np.ndarray
    frequencies_hz: np.ndarray
    expr: float
    optima: list
    log_evidence: float
    evaluations: int
    wall_s: float
    space: FitSpace = field(repr=False)
    loo: dict | None = None
    stage: str = "full"
    mac: np.ndarray | None = None
    model_error: float | None = None

    @property
    def best(self) -> Optimum:
        return self.optima[0]

    @property
    def parameters(self) -> dict[str, float]:
        return dict(zip(self.names, map(float, self.theta), strict=True))

    @property
    def effect_parameters(self) -> dict[str, float]:
        """The effect's own parameters, by short name (``m``, ``k_rot``...)."""
        if self.kind is None:
            return {}
        prefix = f"{self.kind}@{self.location}:"
        return {k[len(prefix) :]: v for k, v in self.parameters.items() if k.startswith(prefix)}

    @property
    def chi2(self) -> float:
        return float(np.sum(self.best.r**2))


def _forward_jacobian(fun, u: np.ndarray, r0: np.ndarray, step: float = 1e-4) -> np.ndarray:
    """dr/du (m, d) by forward differences, each step pointing into the unit box."""
    jac = np.empty((r0.size, u.size))
    for j in range(u.size):
        h = step if u[j] + step <= 1.0 else -step
        up = u.copy()
        up[j] += h
        jac[:, j] = (fun(up) - r0) / h
    return jac


def _pick_starts(
    fun, space: FitSpace, starts_theta: list[np.ndarray], best_start_only: bool
) -> list[np.ndarray]:
    """Starts (each (d,), SI) -> unit-box starts (each (d,) in [0, 1]); with
    ``best_start_only`` only the one with the smallest chi^2 (one model solve per start)."""
    u_starts = [np.clip(space.u_from_theta(t), 0.0, 1.0) for t in starts_theta]
    if best_start_only and len(u_starts) > 1:
        u_starts = [min(u_starts, key=lambda u: float(np.sum(fun(u) ** 2)))]
    return u_starts


def _optimum_from(fun, space: FitSpace, u0: np.ndarray, span: np.ndarray, max_nfev: int) -> Optimum:
    """Bounded TRF least squares of r(u) from the unit-box start u0 (d,), then the Laplace
    evidence at its end point (``laplace``).  span : (d,) z range of each axis."""
    fit = optimize.least_squares(
        fun,
        u0,
        bounds=(np.zeros(u0.size), np.ones(u0.size)),
        method="trf",
        diff_step=1e-4,
        xtol=1e-7,
        ftol=1e-7,
        gtol=1e-8,
        max_nfev=max_nfev,
    )
    u = np.clip(fit.x, 0.0, 1.0)
    r = np.asarray(fit.fun)
    # our own Jacobian: TRF's ``fit.jac`` is rescaled near the bounds (zero at a bound)
    jac_z = _forward_jacobian(fun, u, r) / span
    return laplace(space, space.z_from_u(u), r, jac_z)


def _distinct_optima(ends: list[Optimum], span: np.ndarray) -> list[Optimum]:
    """The distinct optima among ``ends``, highest evidence first: an end point within
    Mahalanobis distance 3 (under its Hessian) of a kept one, or within 2 % of every axis's z
    range (span (d,)), is the same optimum found again and is dropped."""
    distinct: list[Optimum] = []
    for o in sorted(ends, key=lambda o: -o.log_evidence):
        same = False
        for kept in distinct:
            dz = o.z - kept.z
            if float(dz @ kept.hessian @ dz) < 9.0 or np.max(np.abs(dz / span)) < 0.02:
                same = True
                break
        if not same:
            distinct.append(o)
    return distinct


def fit_model(
    space: FitSpace,
    starts_theta: list[np.ndarray],
    label: str = "baseline",
    kind: str | None = None,
    location: str | None = None,
    max_nfev: int = 30,
    stage: str = "full",
    best_start_only: bool = False,
) -> ModelFit:
    """Bounded least squares (TRF, unit-box coordinates, forward-difference Jacobians with step
    1e-4, recomputed at each end point; a failed model as ``FitSpace.unit_box_residuals``) from
    each start, then the Laplace evidence of the distinct optima (module doc).

    best_start_only : evaluate every start once and fit from the one with the smallest chi^2
    only (the cheap quick tier)."""
    t0 = time.perf_counter()
    count = EvaluationCount()
    span = space.z_high - space.z_low
    fun = space.unit_box_residuals(count)
    u_starts = _pick_starts(fun, space, starts_theta, best_start_only)
    ends = [_optimum_from(fun, space, u0, span, max_nfev) for u0 in u_starts]
    distinct = _distinct_optima(ends, span)
    log_z = float(special.logsumexp([o.log_evidence for o in distinct]))
    # report the best-fitting optimum (the calibrated point; also the centre of the LOO draws);
    # the evidence is the sum over all distinct optima either way
    distinct.sort(key=lambda o: float(np.sum(o.r**2)))
    theta = space.theta_from_z(distinct[0].z)
    e, evaluation = space.relative_errors(theta)
    count.evaluations += 1
    return ModelFit(
        label=label,
        kind=kind,
        location=location,
        names=tuple(a.name for a in space.axes),
        theta=theta,
        residual_rel=e,
        frequencies_hz=evaluation.frequencies_hz,
        expr=float(space.problem.expr(evaluation.frequencies_hz)),
        optima=distinct,
        log_evidence=log_z,
        evaluations=count.evaluations,
        wall_s=time.perf_counter() - t0,
        space=space,
        stage=stage,
        mac=None
        if space.shapes is None or evaluation.paired is None
        else np.asarray(evaluation.paired.mac, dtype=float),
    )


def laplace_loo(fit: ModelFit, draws: int = 400, seed: int = 0) -> dict:
    """PSIS-LOO elpd of ``fit`` from Laplace draws (module docstring).

    Returns {"elpd", "se", "p_loo", "pareto_k_max", "draws", "method"}.
    """
    import arviz_base
    import arviz_stats

    if draws < MIN_LOO_DRAWS:
        raise BayesUpdateError(f"laplace_loo: draws must be >= {MIN_LOO_DRAWS}, got {draws}")
    space, best = fit.space, fit.best
    rng = np.random.default_rng(seed)
    cov = np.linalg.inv(best.hessian)
    cov = 0.5 * (cov + cov.T)
    d = best.z.size
    # rejection to the box: keep the first ``draws`` inside (the box holds most of the mass
    # unless a parameter sits at its bound, where about half is kept)
    z = np.empty((0, d))
    for _ in range(20):
        more = rng.multivariate_normal(best.z, cov, size=4 * draws, method="cholesky")
        ok = np.all((more >= space.z_low) & (more <= space.z_high), axis=1)
        z = np.vstack([z, more[ok]])
        if z.shape[0] >= draws:
            break
    method = "Laplace draws, linearized residuals, PSIS-LOO (approximate posterior)"
    if z.shape[0] < draws:
        # the box holds little of the Gaussian (an unconstrained parameter): clip instead
        more = rng.multivariate_normal(best.z, cov, size=draws, method="cholesky")
        z = np.vstack([z, np.clip(more, space.z_low, space.z_high)])
        method += "; draws clipped to the bounds"
    z = z[:draws]
    n = z.shape[0]
    r_all = best.r[None, :] + (z - best.z) @ best.jac_z.T  # (n, size) linearized residuals
    log_q = stats.multivariate_normal(best.z, cov, allow_singular=True).logpdf(z)
    log_q = np.atleast_1d(log_q)
    pointwise = space.likelihood.pointwise_by_mode(r_all)
    log_p = pointwise.sum(axis=1) + space.log_prior_z(z)
    tree = arviz_base.from_dict(
        {"posterior": {"z": z[None]}, "log_likelihood": {"f": pointwise[None]}},
        dims={"f": ["mode"], "z": ["parameter"]},
    )
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = arviz_stats.loo_approximate_posterior(
                tree, log_p[None], log_q[None], pointwise=True, var_name="f"
            )
    except ValueError as exc:  # no tail to smooth: draws clipped to the bounds, all alike
        return dict.fromkeys(("elpd", "se", "p_loo", "pareto_k_max")) | {
            "draws": int(n),
            "method": f"{method}; not available: PSIS found no tail to smooth ({exc})",
        }
    return {
        "elpd": float(result.elpd),
        "se": float(result.se),
        "p_loo": float(result.p),
        "pareto_k_max": float(np.max(result.pareto_k.values)),
        "draws": int(n),
        "method": method,
    }
