"""Find: which modes miss by more than the noise (and the posterior predictive) allow.

Residuals are relative frequency errors e_i = (f_i - f_Ti) / f_Ti. The noise of mode i is s_i =
sigma_i / sqrt(w_i) with w_i the eq. 19 weights (w_i = 0 drops the mode), where

* sigma_i = sd_i / f_Ti when the data give frequency standard deviations sd_i, or
* sigma_i = sigma, a relative level fixed by the user, or
* sigma is *inferred*: a robust scale of the baseline residuals, floored (the plug-in level of
  ``inference.likelihood_blocks.noise_model``).  A discrepancy confined to a few modes then stands
  out instead of inflating the noise level; the evidence uses the same level, fixed
  (``evidence``).

z_i = e_i / sqrt(s_i^2 + v_i) with v_i the posterior-predictive variance of the relative frequency
(when a posterior is given), two-sided p_i = 2 Phi(-|z_i|). Mode i is flagged when p_i < alpha / T
(Bonferroni over the T per-mode tests made, family-wise level alpha: T = m, or 2m with shape tests)
or, where shapes exist, when its MAC is below ``mac_threshold``, or, where the test has shapes,
when its shape misfit c_i at its level (``shape_evidence``) has P(chi^2(n - 1) > c_i) < alpha / T,
or when more modes reject their *stated* shape level (at 1 %) than identification failures explain
(binomial tail < ``COUNT_LEVEL``): then all of those modes are flagged, since many shapes off at
once is physics, not identification. The global misfit test is chi^2 = sum z_i^2 on m - d degrees
of freedom (known frequency noise only)."""

from dataclasses import dataclass

import numpy as np
from scipy import stats

from bayesupdate.inference.likelihood_blocks import NoiseModel

#: level of the count test of shapes off their stated accuracy, in finding and adequacy alike: a
#: model check (discovery's adequacy level), not a search for a discrepancy in one mode
COUNT_LEVEL = 1e-3


@dataclass(frozen=True)
class ShapeTests:
    """Shape tests of one fit, per test mode (m,): ``p_value`` of its chi^2 at its level (NaN: no
    shape term), ``rejected`` (the misfit rejects the stated level at 1 %), and ``count_p``, the
    binomial tail probability of that many rejections at the identification failure rate."""

    p_value: np.ndarray
    rejected: np.ndarray
    count_p: float


@dataclass(frozen=True)
class ModeFlags:
    """Per mode (test order): z-score, two-sided p-value, MAC (NaN: no shapes), flagged.

    chi2 / chi2_dof / chi2_p : global misfit test (NaN for inferred noise).  shape_p_value :
    (m,) p-value of each mode's shape misfit at its fixed level (NaN: not tested).
    """

    residual_rel: np.ndarray
    z: np.ndarray
    p_value: np.ndarray
    mac: np.ndarray
    flagged: np.ndarray
    alpha: float
    chi2: float
    chi2_dof: int
    chi2_p: float
    shape_p_value: np.ndarray | None = None

    @property
    def flagged_modes(self) -> list[int]:
        """1-based numbers of the flagged modes."""
        return [int(i) + 1 for i in np.flatnonzero(self.flagged)]


def flag_modes(
    residual_rel: np.ndarray,
    noise: NoiseModel,
    n_params: int,
    predictive_rel_var: np.ndarray | None = None,
    mac: np.ndarray | None = None,
    alpha: float = 0.05,
    mac_threshold: float = 0.8,
    shapes: ShapeTests | None = None,
) -> ModeFlags:
    """Flag modes (module docstring).  residual_rel : (m,) e_i; predictive_rel_var : (m,) v_i;
    shapes : the shape tests of the fit (``ShapeTests``), or None."""
    e = np.asarray(residual_rel, dtype=float)
    var = noise.scale**2 + (0.0 if predictive_rel_var is None else predictive_rel_var)
    used = noise.used
    z = np.where(used, e / np.sqrt(np.where(used, var, 1.0)), 0.0)
    p = np.where(used, 2.0 * stats.norm.sf(np.abs(z)), 1.0)
    m = int(np.sum(used))
    mac = np.full(e.size, np.nan) if mac is None else np.asarray(mac, dtype=float)
    low_mac = np.nan_to_num(mac, nan=1.0) < mac_threshold
    shape_p = None
    n_tests = m
    shape_flag = np.zeros(e.size, dtype=bool)
    if shapes is not None:
        tested = used & np.isfinite(shapes.p_value)
        shape_p = shapes.p_value
        n_tests += int(np.sum(tested))
        shape_flag = tested & (np.nan_to_num(shape_p, nan=1.0) < alpha / n_tests)
        if shapes.count_p < COUNT_LEVEL:  # too many shapes off at once: physics, flag them all
            shape_flag |= tested & shapes.rejected
    # Bonferroni over every per-mode test made (frequencies, and shapes when tested)
    flagged = used & ((p < alpha / max(n_tests, 1)) | low_mac | shape_flag)
    dof = max(m - n_params, 1)
    if noise.inferred:
        chi2 = chi2_p = float("nan")
    else:
        chi2 = float(np.sum(z[used] ** 2))
        chi2_p = float(stats.chi2.sf(chi2, dof))
    return ModeFlags(e, z, p, mac, flagged, alpha, chi2, dof, chi2_p, shape_p)
