"""Standard deviation of each identified natural frequency, from the FRFs around its resonance.

For mode r, the FRFs on the lines within ``WINDOW_WIDTHS`` half-power half-widths |Re s_r| of
its damped frequency are modelled as in :mod:`bayesupdate.ema.pole_refinement` (seed eq. 4; the
residues and residuals eliminated by variable projection).  The poles on those lines are free,
theta = (Re s, Im s); the identified poles within a window's width of it enter fixed.  Two
parts, added as variances:

1. The linearized covariance of a least-squares pole fit (Pintelon, Guillaume & Schoukens
   2007, "Uncertainty calculation in (operational) modal analysis", MSSP 21, 2359-2373: the
   pole covariance from the Jacobian of the fit, propagated to f_n), in its sandwich form

       cov(theta) = A^-1 B A^-1,   A = J^T J,   B = sum_l sum_|d|<=L w_d g_l g_(l+d)^T,

   with J = -P_perp (dD/dtheta) c Kaufman's Jacobian (:mod:`pole_refinement`), g_l = J_l^T r_l
   the score of line l (over the FRFs) and Bartlett weights w_d = 1 - |d| / (L + 1), L =
   ``LAG_LINES`` (Newey & West 1987, Econometrica 55, 703-708).  The plain s^2 (J^T J)^-1
   assumes white noise of one level; H1 noise grows with |H| at a resonance (input noise) and
   windowing and model error correlate neighbouring lines, and on the FE exhaust's virtual
   tests (1 % noise, seeds 1-6, 72 modes) the plain form gave standardized errors with RMS
   4.2, the sandwich 2.2.
2. The estimator's own bias: the reported pole (the band's LSCE, or the end refinement) is not
   the window's least-squares optimum, whose covariance part 1 is.  The window is refined by
   variable projection (:func:`~bayesupdate.ema.pole_refinement.refine_poles`); the squared
   move of f_n is added (0 when the refinement is rejected).  With it the RMS above is 1.04
   (seeds 7-14, run once: 0.89; ``tests/test_ema_frequency_sd.py``).

f_n = |s| / 2 pi, var f_n = grad^T cov grad with grad = (Re s, Im s) / (2 pi |s|) (first-order
propagation).  What it does not hold: a bias the window's data share with the
estimate (a neighbour beyond the range whose flank no pole models).
"""

import numpy as np

from bayesupdate.ema.frf_set import KIND_POWER
from bayesupdate.ema.pole_refinement import _design, _project, refine_poles
from bayesupdate.ema.synthesis import modal_from_poles

#: half-width of each mode's window, in half-power half-widths |Re s| (at least ``MIN_LINES``
#: lines each side): the resonance and its flanks, where the data fix the pole
WINDOW_WIDTHS = 5.0
MIN_LINES = 5
#: lines of residual correlation the sandwich's middle term counts (Bartlett weights)
LAG_LINES = 3


def mode_window(f: np.ndarray, everything: np.ndarray, r: int, lo: int, hi: int) -> tuple:
    """(line indices (n,), free poles (q,) with pole r first, fixed poles (k,)) of the window
    of pole r of ``everything`` [rad/s] within lines lo..hi (module docstring)."""
    pole = everything[r]
    half = max(WINDOW_WIDTHS * abs(pole.real), MIN_LINES * 2 * np.pi * (f[1] - f[0]))
    idx = np.flatnonzero(np.abs(2 * np.pi * f - pole.imag) <= half)
    idx = idx[(idx >= lo) & (idx <= hi)]
    if idx.size == 0:
        return idx, everything[[r]], everything[:0]
    w_lo, w_hi = 2 * np.pi * f[idx[0]], 2 * np.pi * f[idx[-1]]
    span = w_hi - w_lo
    others = np.arange(everything.size) != r
    on = others & (everything.imag >= w_lo) & (everything.imag <= w_hi)
    near = others & ~on & (everything.imag > w_lo - span) & (everything.imag < w_hi + span)
    return idx, np.concatenate([[pole], everything[on]]), everything[near]


def _jacobian(f: np.ndarray, free: np.ndarray, coef: np.ndarray, u: np.ndarray, kind: str):
    """Kaufman's Jacobian J (2 n_f, 2q, n_frf) of the projected residuals over theta =
    (Re s, Im s) of the q free poles (the first q of the basis; coef, u from ``_project``)."""
    q, m = free.size, (coef.shape[0] - 2) // 2
    jw = 2j * np.pi * f[:, None]
    factor = jw ** KIND_POWER[kind]
    pos2, neg2 = factor / (jw - free) ** 2, factor / (jw - free.conj()) ** 2  # (n_f, q)
    amp = (coef[:q] + 1j * coef[m : m + q])[None]  # (1, q, n_frf)
    d_re = pos2[:, :, None] * amp + neg2[:, :, None] * amp.conj()
    d_im = 1j * (pos2[:, :, None] * amp - neg2[:, :, None] * amp.conj())
    g = np.concatenate([d_re, d_im], axis=1)
    g = np.concatenate([g.real, g.imag], axis=0)  # stacked as the design's rows
    return -(g - np.einsum("ia,ajk->ijk", u, np.einsum("ia,ijk->ajk", u, g)))


def _sandwich(jac: np.ndarray, resid: np.ndarray) -> np.ndarray:
    """A^-1 B A^-1 (2q, 2q) of J (2 n_f, 2q, n_frf) and residuals (2 n_f, n_frf): B counts the
    scores' correlation up to ``LAG_LINES`` lines, and between a line's real and imaginary
    parts (module docstring)."""
    n_f = jac.shape[0] // 2
    a = np.einsum("ijk,ilk->jl", jac, jac)
    scores = jac * resid[:, None, :]
    parts = (scores[:n_f], scores[n_f:])
    cross = np.einsum("ijk,ilk->jl", *parts)
    b = cross + cross.T
    for s in parts:
        b += np.einsum("ijk,ilk->jl", s, s)
        for d in range(1, min(LAG_LINES, n_f - 1) + 1):
            c = np.einsum("ijk,ilk->jl", s[:-d], s[d:])
            b += (1 - d / (LAG_LINES + 1)) * (c + c.T)
    a_inv = np.linalg.pinv(a)
    return a_inv @ b @ a_inv


def _mode_variance(f, frf, free, fixed, kind) -> float:
    """var f_n [Hz^2] of the first free pole on lines f (n_f,) of frf (n_frf, n_f): parts 1 and
    2 of the module docstring."""
    y = np.vstack([frf.real.T, frf.imag.T])
    u, coef, resid = _project(_design(f, np.concatenate([free, fixed]), kind), y)
    cov = _sandwich(_jacobian(f, free, coef, u, kind), resid)
    pole = free[0]
    grad = np.array([pole.real, pole.imag]) / (2 * np.pi * abs(pole))
    block = cov[np.ix_([0, free.size], [0, free.size])]
    ref = refine_poles(f, frf, free, np.zeros(0, complex), fixed, kind)
    move = modal_from_poles(ref.poles[:1])[0][0] - abs(pole) / (2 * np.pi) if ref.accepted else 0
    return float(max(grad @ block @ grad, 0.0) + move**2)


def frequency_sd(
    frequencies_hz: np.ndarray,
    frf: np.ndarray,
    poles: np.ndarray,
    other_poles: np.ndarray,
    kind: str = "accelerance",
    lines: tuple[int, int] | None = None,
) -> np.ndarray:
    """sd [Hz] (m,) of the natural frequency of each mode's pole (module docstring).

    frequencies_hz (n_f,) [Hz], frf (n_frf, n_f); poles (m,) [rad/s] the modes, other_poles
    (k,) [rad/s] more poles in the identification's basis (residual poles, cut resonances);
    lines (first, last) line indices the windows stay within (default: all lines above 0 Hz).
    NaN where a window holds too few lines for its basis.
    """
    f = np.asarray(frequencies_hz, dtype=float)
    h = np.atleast_2d(frf)
    poles = np.asarray(poles, dtype=complex)
    everything = np.concatenate([poles, np.asarray(other_poles, dtype=complex)])
    first = int(np.searchsorted(f, 0.0, side="right"))
    lo, hi = (first, f.size - 1) if lines is None else (max(lines[0], first), lines[1])
    out = np.full(poles.size, np.nan)
    for r in range(poles.size):  # one small window per mode
        idx, free, fixed = mode_window(f, everything, r, lo, hi)
        unknowns = 2 * (free.size + fixed.size) + 2 + 2 * free.size
        if 2 * idx.size > unknowns:
            out[r] = np.sqrt(_mode_variance(f[idx], h[:, idx], free, fixed, kind))
    return out
