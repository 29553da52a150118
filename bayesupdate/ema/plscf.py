"""Least-squares complex frequency-domain (LSCF) pole estimation: the common-denominator model
of PolyMAX (Guillaume et al. 2003; Peeters, Van der Auweraer, Guillaume, Leuridan 2004, "The
PolyMAX frequency-domain method: a new standard for modal parameter estimation?", Shock and
Vibration 11:395-409, eqs 1-12).

Model: every FRF o of the band is H_o(w) = B_o(z) / A(z) with z = exp(j w dt), the common
denominator A(z) = sum_r alpha_r z^r of order p and numerators B_o(z) = sum_r beta_or z^r,
real coefficients.  The linearized least-squares error B_o - A H_o, stacked over the lines,
gives normal equations with R = Re(X^H X), S_o = Re(X^H Y_o), T_o = Re(Y_o^H Y_o) (X the
(N, p+1) basis z^r, Y_o = -diag(H_o) X); eliminating the numerators leaves the reduced normal
equations M alpha = 0, M = sum_o (T_o - S_o^T R^-1 S_o) (Peeters et al. eq. 9), solved with
alpha_p = 1.  The poles are the roots z_r of A: s_r = ln(z_r) / dt.  With one reference (the
FRF rows of a roving or SIMO test) the poly-reference right matrix-fraction model reduces to
this scalar denominator; its participation factors are then 1, and the pole vector (one value
per FRF, for the stabilization MAC) is the residue B_o(z_r) / A'(z_r).

Band handling as in :mod:`bayesupdate.ema.lsce`: the band's lines are a base-band spectrum
(w - w_lo), dt = 1 / (2 (f_hi - f_lo)), poles shifted back by j w_lo.  Orders are nested: the
basis of order n is the first n + 1 columns of the highest order's, so R, S_o and T are formed
once (Toeplitz blocks, from one FFT per FRF) and each order uses their leading blocks, reduced
through the leading block of one Cholesky factor of R (:func:`_nested_reduction`).  Each FRF
row is weighted by 1 / its RMS over the band, so weak FRFs count as much as strong ones (the
PolyMAX weighting W_o).
"""

import numpy as np
import scipy.linalg

from bayesupdate.ema.lsce import LsceResult, band_indices
from bayesupdate.errors import BayesUpdateError


def _normal_blocks(h: np.ndarray, n_basis: int):
    """R (n, n), S (n_o, n, n), T (n, n) of the reduced normal equations (module docstring) for
    the band's N uniform lines h (n_o, N).

    On the base-band grid z_k = exp(j w_k dt) = exp(j 2 pi k / M), M = 2 (N - 1), every block is
    Toeplitz: (X^H diag(g) X)_rs = sum_k g_k z_k^(s - r), a DFT of g at lag s - r.  One FFT per
    FRF gives all lags, O(n_o M log M), instead of the products over lines, O(n_o N n^2)
    (40 FRFs x 4096 lines, order 60: 0.57 s -> a few ms).
    """
    m = 2 * (h.shape[1] - 1)
    lag = (np.arange(n_basis)[None, :] - np.arange(n_basis)[:, None]) % m  # s - r
    moments = np.fft.ifft(h, n=m, axis=-1) * m  # (n_o, M): sum_k h_k z_k^d, d = 0..M-1
    r = (np.fft.ifft(np.ones(h.shape[1]), n=m) * m)[lag].real
    s = -moments[:, lag].real
    t = (np.fft.ifft(np.sum(np.abs(h) ** 2, axis=0), n=m) * m)[lag].real
    return r, s, t


def _nested_reduction(r: np.ndarray, s: np.ndarray):
    """Cholesky factor L (n, n) of R, Q = L^-1 S_o stacked as (n, n_o, n) (row, FRF, column),
    and the cumulative Gram blocks G (n, n, n) with G[k - 1, :k, :k] = sum_o S_o^T R^-1 S_o of
    the order with k coefficients.

    L of a leading block of R is the leading block of L, and the first k rows of L^-1 S_o
    involve only those, so Q_o[:k, :k] = L_k^-1 S_o[:k, :k] and S^T R^-1 S = Q^T Q for every
    order from one factorization: G[k - 1] = sum_(i < k) sum_o Q_o[i]^T Q_o[i].
    """
    n = r.shape[0]
    chol = scipy.linalg.cholesky(r, lower=True)
    s_wide = np.ascontiguousarray(np.moveaxis(s, 0, 1)).reshape(n, -1)  # (n, n_o n)
    q = scipy.linalg.solve_triangular(chol, s_wide, lower=True).reshape(n, -1, n)
    gram = np.cumsum(np.einsum("ioj,iok->ijk", q, q), axis=0)
    return chol, q, gram


def _poles_and_vectors(alpha, beta, dt, w_lo, w_hi):
    """Poles (m,) [rad/s] inside w_lo..w_hi, sorted, and their vectors B_o(z_r) / A'(z_r)
    (n_o, m) of the denominator alpha (n,) and numerators beta (n_o, n) of one order."""
    n = alpha.size
    z = np.roots(alpha[::-1])
    z = z[np.isfinite(z) & (np.abs(z) > 0)]
    s_base = np.log(z.astype(complex)) / dt
    keep = (s_base.imag > 0) & (s_base.real < 0)
    poles = s_base[keep] + 1j * w_lo
    inside = (poles.imag >= w_lo) & (poles.imag <= w_hi)
    zk = z[keep][inside]
    order_idx = np.argsort(poles[inside].imag)
    powers = zk[None, :] ** np.arange(n)[:, None]  # (n, m)
    d_alpha = (alpha[1:] * np.arange(1, n)) @ (zk[None, :] ** np.arange(n - 1)[:, None])
    vectors = (beta @ powers) / np.where(d_alpha != 0, d_alpha, 1.0)[None, :]
    return poles[inside][order_idx], vectors[:, order_idx]


def plscf(
    frequencies_hz: np.ndarray,
    frf: np.ndarray,
    band_hz: tuple[float, float] | None = None,
    max_order: int = 40,
    min_order: int = 2,
) -> LsceResult:
    """Common-denominator LSCF over all FRFs for orders min_order..max_order (even).

    frequencies_hz (n_f,) uniform [Hz]; frf (n_frf, n_f) complex, any kind.  Returns an
    :class:`~bayesupdate.ema.lsce.LsceResult` (poles [rad/s] with Im > 0 inside the band,
    pole vectors B_o(z_r) / A'(z_r) per FRF), so stabilization and selection are shared.
    """
    f = np.asarray(frequencies_hz, dtype=float)
    h_all = np.atleast_2d(np.asarray(frf))
    lo_i, hi_i = band_indices(f, band_hz)
    h = h_all[:, lo_i : hi_i + 1]
    n_lines = h.shape[1]
    max_order = int(max_order) + int(max_order) % 2
    min_order = max(2, int(min_order) + int(min_order) % 2)
    if n_lines < max_order + 2:
        raise BayesUpdateError(
            f"band {f[lo_i]:g}-{f[hi_i]:g} Hz: {n_lines} lines are too few for model order "
            f"{max_order}; widen the band or lower --max-order"
        )
    rms = np.sqrt(np.mean(np.abs(h) ** 2, axis=1, keepdims=True))
    h = h / np.where(rms > 0, rms, 1.0)
    dt = 1.0 / (2 * (f[hi_i] - f[lo_i]))
    r_full, s_full, t_full = _normal_blocks(h, max_order + 1)
    w_lo, w_hi = 2 * np.pi * f[lo_i], 2 * np.pi * f[hi_i]
    orders = np.arange(min_order, max_order + 1, 2)
    chol, q, gram = _nested_reduction(r_full, s_full)
    poles_out, vectors_out = [], []
    for p in orders:
        n = int(p) + 1
        m = t_full[:n, :n] - gram[n - 1, :n, :n]
        alpha = np.append(np.linalg.lstsq(m[:-1, :-1], -m[:-1, -1], rcond=None)[0], 1.0)
        # numerator coefficients beta_o = -R^-1 S_o alpha = -L^-T (Q_o alpha), (n_o, n)
        q_alpha = np.einsum("ioj,j->io", q[:n, :, :n], alpha)
        beta = -scipy.linalg.solve_triangular(chol[:n, :n], q_alpha, lower=True, trans="T").T
        poles, vectors = _poles_and_vectors(alpha, beta, dt, w_lo, w_hi)
        poles_out.append(poles)
        vectors_out.append(vectors * rms)
    return LsceResult(
        orders=orders,
        poles=tuple(poles_out),
        vectors=tuple(vectors_out),
        band_hz=(float(f[lo_i]), float(f[hi_i])),
        dt=float(dt),
    )
