"""The Gaussian likelihood blocks that calibration (``inference.likelihood``) and discovery
(``discovery.evidence``, ``studies/model_equivalence.py``) compose: frequencies, shapes and mass.

Each block turns a prediction into residuals r in noise units and the Gaussian log-density

    log L = -1/2 sum_i r_i^2 - sum_i log s_i - n/2 log 2 pi,     r_i = (y_i - y_Ti) / s_i.   (1)

Blocks
------
* Frequencies: the relative errors e_i = (f_i - f_Ti) / f_Ti [-] of the modes with eq. 19 weight
  w_i > 0 (``relative_errors``).
* Shapes (``ShapeBlock``): per test mode i the residual d_i = t_i - a_i p_i of the unit-norm real
  test shape t_i (n_dof,) against the paired model shape p_i scaled by its modal scale factor
  a_i = p_i.t_i / p_i.p_i (Allemang 2003, "The modal assurance criterion - twenty years of use
  and abuse", eq. 3): |d_i|^2 = 1 - MAC(t_i, p_i) exactly for real shapes, the MAC deficit
  spread over the sensors with a sign and a location, which is what a sensitivity (Jacobian)
  needs.  The n_dof components are independent N(0, sigma_i^2), one level per mode (the
  eigenvector prediction-error model of Vanik, Beck & Au 2000, J. Eng. Mech. 126:738; Yuen
  2010, "Bayesian Methods for Structural Dynamics and Civil Engineering", ch. 6), and the block
  counts n_dof - 1 terms per mode (the scale factor is fitted).  How the levels are chosen (the
  stated sd, its floor, the raise rule) is discovery's decision (``discovery.shape_evidence``).
* Mass: e_m = (m - m_T) / m_T ~ N(0, sd_rel^2) (``mass_log_likelihood``).

Noise of the frequency block
----------------------------
* known: the data's sd, s_i = (sd_i / f_Ti) / sqrt(w_i) (``NoiseModel`` source "data sd");
* fixed: s_i = sigma / sqrt(w_i) with sigma stated ("fixed"), or the empirical-Bayes plug-in of a
  frequency-only baseline fit, a robust scale of its residuals, held fixed ("inferred (robust)",
  ``noise_model``; Vanik, Beck & Au 2000 estimate the prediction-error variances from the data);
* sampled: s_i^2(sigma) = sigma^2 / w_i + (sd_i / f_Ti)^2, sigma one more parameter of the
  posterior with its own prior, integrated out by the sampler; a known sd is added in quadrature
  (``SampledNoise``).  A fixed sigma in calibration is this form at one value.
The known sd enters the two forms differently: the fixed form divides it by sqrt(w_i), the
sampled form does not (both as before this module; equal when all weights are 1).

Two known sds.  ``frequency_sd_hz`` is a frequency's whole error (a stated sd, or virtual data
drawn with it): it replaces the level in the fixed form.  ``identification_sd_hz`` (written by
``identify``, ``ema.frequency_sd``) is only the test's part: the model's error, of unknown level
sigma, comes on top, so it never replaces sigma.  It is added in quadrature in both forms,
s_i^2 = sigma^2 / w_i + (sd_id_i / f_Ti)^2 (``SampledNoise``), with sigma inferred as
before ("inferred (robust) + identification sd"): a mode the test fixes poorly (the FEMAP
deck's damped 110.4 Hz mode, sd 1e-4 against 1e-5 for its neighbours) weighs less, and no
mode's scale falls below the inferred level, so discovery sees no misfit that was not there.

Arithmetic
----------
(1) is evaluated in two spellings, each kept as its callers always computed it so that seeded
results stay bit-identical: the residual form (``gaussian_log_likelihood``, per residual
``gaussian_pointwise``) for fixed levels and the variance form
-1/2 sum_i (e_i^2 / v_i + log v_i + log 2 pi) (``gaussian_log_likelihood_var``) for a sampled sigma.
"""

from dataclasses import dataclass

import numpy as np

LOG_2PI = float(np.log(2.0 * np.pi))

#: smallest relative noise level inferred (0.01 %): below it frequencies are not reproducible
SIGMA_FLOOR = 1e-4


def relative_errors(f: np.ndarray, f_test: np.ndarray) -> np.ndarray:
    """e = (f - f_T) / f_T [-]; f (..., m) model frequencies [Hz], f_test (m,) [Hz]."""
    return (f - f_test) / f_test


def gaussian_log_likelihood(r: np.ndarray, scale: np.ndarray) -> float:
    """Eq. (1), residual form: r (n,) residuals in noise units, scale (n,) their levels s_i."""
    return float(-0.5 * np.sum(r * r) - np.sum(np.log(scale)) - 0.5 * r.size * LOG_2PI)


def gaussian_pointwise(r: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Eq. (1) per residual: r (..., n), scale (n,) -> (..., n) log-densities."""
    return -0.5 * r**2 - np.log(scale)[None, :] - 0.5 * LOG_2PI


def gaussian_log_likelihood_var(e: np.ndarray, var: np.ndarray) -> np.ndarray:
    """Eq. (1), variance form: e (k, n) raw errors, var (k, n) their variances s_i^2 -> (k,)."""
    return -0.5 * np.sum(e * e / var + np.log(var) + LOG_2PI, axis=1)


@dataclass(frozen=True)
class NoiseModel:
    """Fixed relative noise of the frequency block, per test mode.

    scale : (m,) s_i (inf where w_i = 0).  weights_sqrt : (m,) sqrt(w_i) (0 drops a mode).
    inferred : the level is the plug-in estimate from baseline residuals.  source : "data sd" |
    "fixed" | "inferred (robust)".  sigma : the level quoted (the median for "data sd").
    """

    scale: np.ndarray
    weights_sqrt: np.ndarray
    inferred: bool
    source: str
    sigma: float

    @property
    def used(self) -> np.ndarray:
        return self.weights_sqrt > 0

    def residuals(self, e: np.ndarray) -> np.ndarray:
        """r = e_i / s_i of the used modes; e (m,) relative errors -> (m_used,)."""
        used = self.used
        return e[used] / self.scale[used]

    def log_likelihood(self, r: np.ndarray) -> float:
        """Eq. (1) of the used modes' residuals r (m_used,)."""
        return gaussian_log_likelihood(r, self.scale[self.used])

    def pointwise(self, r: np.ndarray) -> np.ndarray:
        """(n, m_used) per-mode log-densities of residual draws r (n, m_used)."""
        return gaussian_pointwise(r, self.scale[self.used])


def noise_model(data, residual_rel: np.ndarray, n_params: int, sigma: float | None = None):
    """NoiseModel of ``data`` (``ModalData``): a fixed ``sigma`` if given, else the data's
    frequency sd if every used mode has one, else the robust plug-in level of the baseline
    residuals residual_rel (m,): sigma = 1.4826 MAD(e sqrt(w)) sqrt(m / (m - d)) (median absolute
    deviation about zero, corrected for the d = n_params fitted parameters; Huber 1981), floored
    at ``SIGMA_FLOOR``.  A discrepancy confined to a few modes then stands out instead of
    inflating the level.  The data's identification sd, if any, is added in quadrature to the
    inferred level (module docstring), s_i^2 = (sigma^2 + (sd_id_i / f_Ti)^2) / w_i."""
    w = np.ones(data.n_modes) if data.weights is None else np.asarray(data.weights, float)
    sw = np.sqrt(np.maximum(w, 0.0))
    inv = np.where(sw > 0, 1.0 / np.where(sw > 0, sw, 1.0), np.inf)
    if sigma is not None:
        return NoiseModel(sigma * inv, sw, False, "fixed", float(sigma))
    sd = data.frequency_sd_hz
    if sd is not None and np.all(sd[sw > 0] > 0):
        rel = sd / data.frequencies_hz
        return NoiseModel(rel * inv, sw, False, "data sd", float(np.median(rel[sw > 0])))
    used = sw > 0
    m = int(np.sum(used))
    e = np.abs(residual_rel[used] * sw[used])
    dof_factor = np.sqrt(m / max(m - n_params, 1))
    robust = 1.4826 * float(np.median(e)) * dof_factor
    level = max(robust, SIGMA_FLOOR)
    sd_id = data.identification_sd_hz
    if sd_id is None:
        return NoiseModel(level * inv, sw, True, "inferred (robust)", level)
    scale = np.sqrt(level**2 + (sd_id / data.frequencies_hz) ** 2) * inv
    return NoiseModel(scale, sw, True, "inferred (robust) + identification sd", level)


@dataclass(frozen=True)
class SampledNoise:
    """Frequency noise with a free level sigma (module docstring, "sampled"), used modes only.

    inv_w : (n,) 1 / w_i.  sd_rel2 : (n,) the known relative variance (sd_i / f_Ti)^2 (zeros
    when the data give no sd).
    """

    inv_w: np.ndarray
    sd_rel2: np.ndarray

    @classmethod
    def of(cls, f_test: np.ndarray, weights: np.ndarray, sd_hz, identification_sd_hz=None):
        """From the used modes' f_test (n,) [Hz], weights (n,) > 0, stated sd (n,) [Hz] or None
        and identification sd (n,) [Hz] or None (module docstring: both add in quadrature)."""
        sd_rel2 = np.zeros(f_test.size) if sd_hz is None else (sd_hz / f_test) ** 2
        if identification_sd_hz is not None:
            sd_rel2 = sd_rel2 + (identification_sd_hz / f_test) ** 2
        return cls(1.0 / weights, sd_rel2)

    def variance(self, sigma: np.ndarray) -> np.ndarray:
        """s_i^2 (k, n) for sigma (k,)."""
        return sigma[:, None] ** 2 * self.inv_w + self.sd_rel2

    def log_likelihood(self, e: np.ndarray, sigma: np.ndarray) -> np.ndarray:
        """Eq. (1) of relative errors e (k, n) at levels sigma (k,) -> (k,)."""
        return gaussian_log_likelihood_var(e, self.variance(sigma))


def mass_log_likelihood(mass: np.ndarray, target_kg: float, sd_rel: float) -> np.ndarray:
    """Mass block: masses (k,) [kg] against the measured target [kg], relative sd sd_rel -> (k,)."""
    em = (mass - target_kg) / target_kg
    s2 = sd_rel**2
    return -0.5 * (em * em / s2 + np.log(s2) + LOG_2PI)


def shape_residuals(test_unit: np.ndarray, model_shapes: np.ndarray) -> np.ndarray:
    """d (n_dof, m) = t - a p with the modal scale factor a (module docstring).

    test_unit : (n_dof, m) unit-norm real test shapes; model_shapes : (n_dof, m) paired model
    shapes on the same DOFs (any scaling).  A zero model shape leaves d = t (MAC 0)."""
    p = np.asarray(model_shapes, dtype=float)
    pp = np.sum(p * p, axis=0)
    a = np.sum(p * test_unit, axis=0) / np.where(pp > 0, pp, 1.0)
    return test_unit - p * a[None, :]


@dataclass(frozen=True)
class ShapeBlock:
    """The shape block (module docstring) with each mode's level fixed.

    modes : (k,) 0-based test modes whose shapes count.  test_unit : (n_dof, k) their unit-norm
    real shapes.  scale : (k,) sigma_i, each mode's per-component level [-].
    """

    modes: np.ndarray
    test_unit: np.ndarray
    scale: np.ndarray

    @property
    def n_dof(self) -> int:
        return int(self.test_unit.shape[0])

    @property
    def dof(self) -> int:
        """Degrees of freedom per mode: n_dof less the fitted scale factor."""
        return self.n_dof - 1

    @property
    def size(self) -> int:
        return int(self.test_unit.size)

    def residuals(self, model_shapes: np.ndarray) -> np.ndarray:
        """(k n_dof,) scaled residuals d_i / sigma_i, mode after mode.  model_shapes :
        (n_dof, m_test) paired model shapes of all test modes."""
        d = shape_residuals(self.test_unit, np.asarray(model_shapes)[:, self.modes])
        return (d / self.scale[None, :]).T.reshape(-1)

    def chi2(self, r: np.ndarray) -> np.ndarray:
        """(..., k) c_i = R_i / sigma_i^2 (~ chi^2(dof) per mode under a fitting model)."""
        blocks = np.asarray(r).reshape(*np.shape(r)[:-1], self.scale.size, self.n_dof)
        return np.sum(blocks**2, axis=-1)

    def rss(self, r: np.ndarray) -> np.ndarray:
        """(..., k) R_i = |d_i|^2 = 1 - MAC_i from the scaled residuals r (..., k n_dof)."""
        return self.chi2(r) * self.scale**2

    def log_likelihood(self, r: np.ndarray) -> np.ndarray:
        """(..., k) per-mode Gaussian log-density of the scaled residuals r (..., k n_dof), on
        dof terms per mode (the scale factor is fitted)."""
        return -0.5 * self.chi2(r) - self.dof * (np.log(self.scale) + 0.5 * LOG_2PI)


@dataclass(frozen=True)
class FixedNoiseLikelihood:
    """Frequencies, then (when the test has shapes) the shape block, all levels fixed: what a
    least-squares fit, its Laplace evidence and its LOO see.

    The residual vector (size,) is r = [e_i / s_i of the used modes, shape residuals mode after
    mode]; every entry is in noise units, so the Gauss-Newton Hessian is J^T J.
    """

    noise: NoiseModel
    shapes: ShapeBlock | None = None

    @property
    def n_frequency(self) -> int:
        """Residuals of the frequency block (the used modes)."""
        return int(np.sum(self.noise.used))

    @property
    def size(self) -> int:
        return self.n_frequency + (0 if self.shapes is None else self.shapes.size)

    def residual_vector(self, e: np.ndarray, model_shapes: np.ndarray | None) -> np.ndarray:
        """(size,) from relative errors e (m,) and paired model shapes (n_dof, m) on the test
        DOFs (None: the shape residuals are NaN)."""
        r = self.noise.residuals(e)
        if self.shapes is None:
            return r
        if model_shapes is None:
            return np.concatenate([r, np.full(self.shapes.size, np.nan)])
        return np.concatenate([r, self.shapes.residuals(model_shapes)])

    def log_likelihood(self, r: np.ndarray) -> float:
        """log L of the residual vector r (size,): frequencies + the shape block."""
        n_f = self.n_frequency
        value = self.noise.log_likelihood(r[:n_f])
        if self.shapes is not None:
            value += float(np.sum(self.shapes.log_likelihood(r[n_f:])))
        return value

    def pointwise_by_mode(self, r: np.ndarray) -> np.ndarray:
        """(n, m_used) log-likelihood per used mode, its frequency and shape together, of
        residual draws r (n, size) (the observations PSIS-LOO leaves out)."""
        n_f = self.n_frequency
        pointwise = self.noise.pointwise(r[:, :n_f])
        if self.shapes is not None:
            column = np.searchsorted(np.flatnonzero(self.noise.used), self.shapes.modes)
            pointwise = pointwise.copy()
            pointwise[:, column] += self.shapes.log_likelihood(r[:, n_f:])  # modes are distinct
        return pointwise

    def curvature_weights(self, r: np.ndarray) -> np.ndarray:
        """(size,) w with H = J^T diag(w) J: 1 everywhere, every residual is in noise units."""
        return np.ones(r.size)
