"""Least-squares complex exponential (LSCE) pole estimation (seed eqs 7-17; Brown et al. 1979).

Band handling (why the band's lower limit does not bias the frequencies): the N lines of the band
f_lo..f_hi (step df) are treated as a base-band spectrum, the line f_lo + k df becoming line k.
Its inverse real FFT is an IRF with M = 2 (N - 1) samples at the band's own time step
dt = 1 / (M df) = 1 / (2 (f_hi - f_lo)).  A mode term A / (jw - s_r) of the band becomes
A / (jw' - (s_r - j w_lo)) with w' = w - w_lo, so the IRF holds exponentials with poles
s'_r = s_r - j w_lo: same decay, damped frequency lowered by w_lo.  After the roots z_r of the
Prony polynomial (seed eq. 10) give s'_r = ln(z_r) / dt (seed eq. 15), the pole is shifted back,
s_r = s'_r + j w_lo, and only then are w_r = |s_r| and zeta_r = -Re(s_r) / |s_r| formed (seed eqs
16-17).  Applying eq. 17 to s'_r directly, or sampling the band's IRF with the full-band time
step, gives wrong frequencies for any band not starting at 0 Hz.

Global least squares (seed eq. 14): the Hankel rows of all FRFs' IRFs are stacked into one
over-determined system.  Model orders are nested: with a fixed number of rows, the system of
order p uses the first p + 1 columns of the system of the highest order, and the R factor of a
QR decomposition of those columns is the leading (p + 1) x (p + 1) block of the full R factor.
One QR (by Cholesky-QR, see :func:`hankel_r_factor`) of the largest Hankel matrix therefore
solves every order of the stabilization diagram.
"""

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from bayesupdate.errors import BayesUpdateError


@dataclass(frozen=True)
class LsceResult:
    """Poles of every model order of one band.

    orders : (n_o,) int, polynomial orders 2n (number of poles incl. conjugates).
    poles : tuple of (m_o,) complex arrays [rad/s], Im > 0, damped frequency inside the band.
    vectors : tuple of (n_frf, m_o) complex arrays, IRF residue of each pole per FRF (pole vector).
    band_hz : (f_lo, f_hi) of the band.
    dt : IRF time step of the band [s].
    """

    orders: np.ndarray
    poles: tuple
    vectors: tuple
    band_hz: tuple
    dt: float


def band_irf(band_frf: np.ndarray, df_hz: float) -> tuple[np.ndarray, float]:
    """IRFs (n_frf, M) of band FRFs (n_frf, N) shifted to base band, and their step dt [s].

    M = 2 (N - 1), dt = 1 / (M df).  A band with N = 2^k + 1 lines gives a power-of-two IRF.
    """
    n_lines = band_frf.shape[-1]
    m = 2 * (n_lines - 1)
    return np.fft.irfft(band_frf, n=m, axis=-1), 1.0 / (m * df_hz)


def _hankel_blocks(irf: np.ndarray, n_cols: int, first: int, n_rows: int):
    """Yield chunks of the stacked Hankel matrix X (row k of IRF f: h_f[first+k : +n_cols])."""
    windows = np.lib.stride_tricks.sliding_window_view(irf, n_cols, axis=1)
    windows = windows[:, first : first + n_rows, :]
    chunk = max(1, int(4e6 // max(1, n_rows * n_cols)))
    for start in range(0, irf.shape[0], chunk):
        yield windows[start : start + chunk].reshape(-1, n_cols)


def hankel_r_factor(irf: np.ndarray, n_cols: int, first: int, n_rows: int) -> np.ndarray:
    """R factor (n_cols, n_cols) of the stacked Hankel matrix X of all IRFs (seed eq. 14).

    Cholesky-QR2 (Yamamoto et al. 2015): R1 = chol(X^T X), R = chol((X R1^-1)^T (X R1^-1)) R1,
    as accurate as Householder QR while X is not too ill-conditioned (kappa < ~1e7, the case
    for measured, noisy data), and every pass is one matrix product over chunks of FRFs - about
    20x faster for 40 FRFs x 4000 rows.  Near-singular X (noise-free synthetic data, orders
    above the data's own order) falls back to Householder QR of the chunks (tall-skinny QR).
    The leading (p + 1) x (p + 1) block of R is the R factor of order p (module docstring).
    """
    gram = np.zeros((n_cols, n_cols))
    for block in _hankel_blocks(irf, n_cols, first, n_rows):
        gram += block.T @ block
    try:
        r = scipy.linalg.cholesky(gram, lower=False, check_finite=False)
        diag = np.abs(np.diag(r))
        if diag.min() > 1e-7 * diag.max():
            gram = np.zeros((n_cols, n_cols))
            for block in _hankel_blocks(irf, n_cols, first, n_rows):
                q = scipy.linalg.solve_triangular(r, block.T, trans="T", check_finite=False)
                gram += q @ q.T
            return scipy.linalg.cholesky(gram, lower=False, check_finite=False) @ r
    except np.linalg.LinAlgError:
        pass
    rs = [
        scipy.linalg.qr(block, mode="r", check_finite=False)[0][:n_cols]
        for block in _hankel_blocks(irf, n_cols, first, n_rows)
    ]
    if len(rs) == 1:
        return rs[0]
    return scipy.linalg.qr(np.vstack(rs), mode="r", check_finite=False)[0][:n_cols]


def prony_coefficients(r_factor: np.ndarray, order: int) -> np.ndarray:
    """Monic Prony coefficients beta_0..beta_{p-1} (beta_p = 1) of order p (seed eqs 13-14)."""
    a = r_factor[:order, :order]
    b = -r_factor[:order, order]
    diag = np.abs(np.diag(a))
    if diag.min() > 1e-10 * diag.max():
        return scipy.linalg.solve_triangular(a, b, check_finite=False)
    # rank-deficient (order above the data's own order, noise-free data): minimum-norm solution
    return scipy.linalg.lstsq(a, b, check_finite=False)[0]


def lsce(
    frequencies_hz: np.ndarray,
    frf: np.ndarray,
    band_hz: tuple[float, float] | None = None,
    max_order: int = 40,
    min_order: int = 2,
    first_sample: int = 1,
    n_samples: int | None = None,
    with_vectors: bool = True,
) -> LsceResult:
    """Global LSCE over all FRFs for polynomial orders min_order..max_order (even).

    frequencies_hz : (n_f,) uniform axis [Hz]; frf : (n_frf, n_f) complex (any kind: the
    (jw)^p factor of mobility/accelerance only adds terms at the first IRF samples, skipped by
    ``first_sample``).  band_hz : (f_lo, f_hi) or None for the whole axis.  n_samples : IRF
    samples used (default: half the band's IRF).  Returns an :class:`LsceResult`.
    """
    f = np.asarray(frequencies_hz, dtype=float)
    h = np.atleast_2d(np.asarray(frf))
    lo_i, hi_i = band_indices(f, band_hz)
    max_order = int(max_order) + int(max_order) % 2
    min_order = max(2, int(min_order) + int(min_order) % 2)
    irf, dt, n_use, n_rows = _band_system(f, h, (lo_i, hi_i), max_order, first_sample, n_samples)
    r = hankel_r_factor(irf, max_order + 1, first_sample, n_rows)
    w_lo, w_hi = 2 * np.pi * f[lo_i], 2 * np.pi * f[hi_i]
    orders = np.arange(min_order, max_order + 1, 2)
    poles_out, vectors_out = [], []
    n_vec = min(n_use, 2 * max_order + 64)
    t_index = np.arange(first_sample, first_sample + n_vec)
    for p in orders:
        z, pick, poles = _order_poles(r, int(p), dt, (w_lo, w_hi))
        poles_out.append(poles)
        if with_vectors:
            vectors_out.append(_pole_vectors(z, irf, t_index)[pick].T)
        else:
            vectors_out.append(np.zeros((h.shape[0], pick.size), complex))
    return LsceResult(
        orders=orders,
        poles=tuple(poles_out),
        vectors=tuple(vectors_out),
        band_hz=(float(f[lo_i]), float(f[hi_i])),
        dt=float(dt),
    )


def _band_system(f, h, band, max_order, first_sample, n_samples):
    """The band's IRFs (n_frf, M) and step dt [s], the IRF samples used and the Hankel rows
    per FRF; BayesUpdateError when the band holds too few lines for ``max_order``.
    f (n_f,) [Hz], h (n_frf, n_f), band (lo, hi) line indices (inclusive)."""
    lo_i, hi_i = band
    n_lines = hi_i - lo_i + 1
    df = (f[-1] - f[0]) / (f.size - 1)
    irf, dt = band_irf(h[:, lo_i : hi_i + 1], df)
    n_irf = irf.shape[1]
    n_use = n_irf // 2 if n_samples is None else min(int(n_samples), n_irf)
    n_rows = n_use - first_sample - max_order
    # rows per FRF times FRFs must exceed the unknowns, or the system is under-determined
    if n_rows < 1 or n_rows * h.shape[0] < 2 * max_order:
        raise BayesUpdateError(
            f"band {f[lo_i]:g}-{f[hi_i]:g} Hz: {n_lines} lines are too few for model order "
            f"{max_order}; widen the band or lower --max-order"
        )
    return irf, dt, n_use, n_rows


def _order_poles(r_factor, order, dt, w_band):
    """Prony roots z (n_z,) of one order (seed eqs 10, 15), the indices (m,) into z of its
    physical poles, and those poles (m,) [rad/s]: decaying, Im > 0, shifted back by the band's
    lower limit (module docstring), inside w_band = (w_lo, w_hi) [rad/s], by frequency."""
    w_lo, w_hi = w_band
    beta = prony_coefficients(r_factor, order)
    z = np.roots(np.concatenate(([1.0], beta[::-1])))
    z = z[np.isfinite(z) & (np.abs(z) > 0)]
    s_base = np.log(z.astype(complex)) / dt
    keep = (s_base.imag > 0) & (s_base.real < 0)
    s = s_base[keep] + 1j * w_lo
    inside = (s.imag >= w_lo) & (s.imag <= w_hi)
    order_idx = np.argsort(s[inside].imag)
    pick = np.flatnonzero(keep)[inside][order_idx]
    return z, pick, s[inside][order_idx]


def _pole_vectors(z, irf, t_index):
    """IRF residues (n_z, n_frf) of the roots z (n_z,) (seed eq. 18) by least squares over the
    IRF samples t_index of irf (n_frf, M); zero for growing roots, which would overflow z^k
    and carry no physical residue."""
    decaying = np.abs(z) < 1
    vander = z[decaying][None, :] ** t_index[:, None]
    # normal equations of the small Vandermonde system (p x p): the vectors only feed the MAC
    # stability check, and this avoids a LAPACK least-squares call per order
    normal = vander.conj().T @ vander
    normal += 1e-12 * np.trace(normal).real * np.eye(normal.shape[0])
    coef = np.linalg.solve(normal, vander.conj().T @ irf[:, t_index].T)
    full = np.zeros((z.size, irf.shape[0]), complex)
    full[decaying] = coef
    return full


def band_indices(frequencies_hz: np.ndarray, band_hz: tuple[float, float] | None) -> tuple:
    """First and last line index of a band (inclusive); BayesUpdateError if outside the data."""
    f = np.asarray(frequencies_hz, dtype=float)
    if band_hz is None:
        return 0, f.size - 1
    lo, hi = float(band_hz[0]), float(band_hz[1])
    df = (f[-1] - f[0]) / (f.size - 1)
    if not (np.isfinite(lo) and np.isfinite(hi)) or hi <= lo:
        raise BayesUpdateError(f"band {lo:g}:{hi:g} Hz: give LO:HI with LO < HI")
    if lo < f[0] - 0.5 * df or hi > f[-1] + 0.5 * df:
        raise BayesUpdateError(
            f"band {lo:g}:{hi:g} Hz lies outside the data ({f[0]:g}-{f[-1]:g} Hz); "
            "choose a band inside it"
        )
    lo_i = int(np.clip(np.round((lo - f[0]) / df), 0, f.size - 1))
    hi_i = int(np.clip(np.round((hi - f[0]) / df), 0, f.size - 1))
    if hi_i - lo_i < 8:
        raise BayesUpdateError(
            f"band {lo:g}:{hi:g} Hz holds only {hi_i - lo_i + 1} lines; widen it"
        )
    return lo_i, hi_i
