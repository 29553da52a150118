"""Least-squares frequency-domain (LSFD) residues, mode shapes and modal phase collinearity.

With the poles s_r fixed (from LSCE), every FRF is linear in its residues (seed eq. 4):
  H_k(jw) = sum_r [A_kr (jw)^p / (jw - s_r) + conj(A_kr) (jw)^p / (jw - conj s_r)]
            + LR_k (jw)^p / (jw)^2 + UR_k (jw)^p,
p = 0, 1, 2 for receptance, mobility, accelerance; LR (lower residual: modes below the range)
and UR (upper residual: modes above it) are real.  Writing A = a + j b keeps the conjugate pair
structure with real unknowns; one real least-squares solve serves all FRFs (shared basis).

Mode shapes: for a fixed DOF q of a test set and roving DOFs i, A_iqr = psi_ir psi_qr / (2 j
w_dr) for mass-normalized (unit modal-A) scaling, so with the driving point i = q,
psi_qr = sqrt(2 j w_dr A_qqr) and psi_ir = 2 j w_dr A_iqr / psi_qr.
"""

from dataclasses import dataclass

import numpy as np
import scipy.fft

from bayesupdate.ema.frf_set import KIND_POWER
from bayesupdate.ema.synthesis import frf_basis


@dataclass(frozen=True)
class LsfdFit:
    """LSFD result for n_frf FRFs and m poles.

    residues (n_frf, m) complex; lower, upper (n_frf,) real residuals (receptance units);
    residue_var (n_frf, m): variance of each complex residue, E|A - A_hat|^2 = var(a) + var(b),
    from the least-squares covariance cov = s^2 (D^T D)^-1 per FRF row (Pintelon & Schoukens
    2012, sec. 7.2), with s^2 the residual variance near each pole (:func:`lsfd`);
    local_sd (n_frf, m): that s, the fit residual's sd per real part near each pole.
    """

    residues: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    residue_var: np.ndarray
    local_sd: np.ndarray


def lsfd(
    frequencies_hz: np.ndarray,
    frf: np.ndarray,
    poles: np.ndarray,
    kind: str = "accelerance",
    residuals: bool = True,
) -> LsfdFit:
    """Residues, residuals and residue variances by one real least-squares solve (module doc).

    frequencies_hz (n_f,) [Hz], frf (n_frf, n_f), poles (m,) [rad/s] with Im > 0.  Lines at
    0 Hz are left out (the lower-residual term is singular there).
    """
    f = np.asarray(frequencies_hz, dtype=float)
    keep = f > 0
    f = f[keep]
    h = np.atleast_2d(frf)[:, keep]
    poles = np.asarray(poles, dtype=complex)
    m = poles.size
    pos, neg = frf_basis(f, poles, kind)
    cols = [pos + neg, 1j * (pos - neg)]
    if residuals:
        jw = 2j * np.pi * f
        factor = jw ** KIND_POWER[kind]
        cols += [(factor / jw**2)[:, None], factor[:, None]]
    basis = np.hstack(cols)
    scale = np.linalg.norm(basis, axis=0)
    scale[scale == 0] = 1.0
    design = np.vstack([basis.real, basis.imag]) / scale
    rhs = np.vstack([h.real.T, h.imag.T])
    # one SVD gives the solution and diag((D^T D)^-1); directions the data do not fix (tiny
    # singular values) are left at zero and get a huge variance
    u, sv, vt = np.linalg.svd(design, full_matrices=False)
    ok = sv > np.finfo(float).eps * max(design.shape) * sv[0]  # lstsq's default cut-off
    inv_sv = np.where(ok, 1.0 / np.where(ok, sv, 1.0), 0.0)
    coef_s = vt.T @ (inv_sv[:, None] * (u.T @ rhs))
    coef = coef_s / scale[:, None]
    n_f = f.size
    resid = rhs - design @ coef_s  # (2 n_f, n_frf): real parts, then imaginary parts
    power = resid[:n_f] ** 2 + resid[n_f:] ** 2  # (n_f, n_frf)
    # the residue of a mode is fixed by the lines around its resonance, and FRF noise is not
    # white (H1 error grows with |H|): the residual variance is taken there, over the lines
    # within 3 half-power bandwidths (at least 3 lines) of each pole, per FRF
    width = np.maximum(3 * np.abs(poles.real), 3 * 2 * np.pi * (f[-1] - f[0]) / max(n_f - 1, 1))
    near = np.abs(2 * np.pi * f[:, None] - poles.imag[None, :]) <= width[None, :]  # (n_f, m)
    count = np.maximum(near.sum(axis=0), 1)
    s2_local = (near.T.astype(float) @ power) / (2 * count[:, None])  # (m, n_frf)
    diag = np.sum(vt**2 * np.where(ok, inv_sv**2, 1e24)[:, None], axis=0) / scale**2
    s2_local = s2_local * _correlation_inflation(resid[:n_f] + 1j * resid[n_f:], near)[:, None]
    var_a = s2_local * diag[:m, None]
    var_b = s2_local * diag[m : 2 * m, None]
    residues = (coef[:m] + 1j * coef[m : 2 * m]).T
    residue_var = (var_a + var_b).T
    if residuals:
        lower, upper = coef[2 * m], coef[2 * m + 1]
    else:
        lower = upper = np.zeros(h.shape[0])
    return LsfdFit(residues, lower, upper, residue_var, np.sqrt(s2_local.T))


def _correlation_inflation(resid: np.ndarray, near: np.ndarray) -> np.ndarray:
    """Variance inflation (m,) >= 1 of a residue for a fit residual correlated across lines.

    The least-squares covariance s^2 (D^T D)^-1 assumes residuals independent from line to
    line; model error (leakage, aliasing, modes outside the basis) is smooth in frequency and
    moves a residue by about the residual itself, not by its mean over many lines.  Near each
    pole (mask ``near`` (n_f, m)) the residual's autocorrelation rho_k over the lines, pooled
    over FRFs, gives the variance factor of a mean of correlated samples,
    g = 1 + 2 sum_k (1 - k/L) rho_k (Bartlett weights over the L lines), clipped to [1, L].
    resid (n_f, n_frf) complex.
    """
    out = np.ones(near.shape[1])
    for r in range(near.shape[1]):  # a few poles, each an FFT over its own lines
        seg = resid[near[:, r]]
        n = seg.shape[0]
        if n < 3:
            continue
        # any length >= 2n - 1 gives the linear autocorrelation: take a fast one
        spec = scipy.fft.fft(seg, scipy.fft.next_fast_len(2 * n), axis=0)
        acf = np.sum(scipy.fft.ifft(np.abs(spec) ** 2, axis=0).real[:n], axis=1)
        if acf[0] <= 0:
            continue
        k = np.arange(1, n)
        out[r] = np.clip(1 + 2 * np.sum((1 - k / n) * acf[1:] / acf[0]), 1.0, n)
    return out


def lsfd_residues(
    frequencies_hz: np.ndarray,
    frf: np.ndarray,
    poles: np.ndarray,
    kind: str = "accelerance",
    residuals: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Residues (n_frf, m) complex and real lower/upper residuals (n_frf,) (see :func:`lsfd`)."""
    fit = lsfd(frequencies_hz, frf, poles, kind, residuals)
    return fit.residues, fit.lower, fit.upper


def mpc(shapes: np.ndarray) -> np.ndarray:
    """Modal phase collinearity (Pappa et al. 1993) of each column of (n_dof, m) shapes, in [0, 1].

    MPC = ((l1 - l2) / (l1 + l2))^2 with l1 >= l2 the eigenvalues of the 2x2 covariance of the
    real and imaginary parts; 1 for a real (normal) mode, 0 for a circularly spread one.
    """
    x = np.atleast_2d(np.asarray(shapes, dtype=complex))
    # scale-free: an unscaled shape (no driving point) may be far from unit size
    peak = np.max(np.abs(x), axis=0)
    x = x / np.where(peak > 0, peak, 1.0)
    re, im = x.real, x.imag
    sxx = np.sum(re * re, axis=0)
    syy = np.sum(im * im, axis=0)
    sxy = np.sum(re * im, axis=0)
    tr = sxx + syy
    det = sxx * syy - sxy**2
    disc = np.sqrt(np.maximum(tr**2 / 4 - det, 0.0))
    l1, l2 = tr / 2 + disc, tr / 2 - disc
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(tr > 0, ((l1 - l2) / np.where(tr > 0, tr, 1.0)) ** 2, 0.0)


def realize(shapes: np.ndarray) -> np.ndarray:
    """Real shapes (n_dof, m): each column rotated to its best-fit real line, real part kept."""
    x = np.asarray(shapes, dtype=complex)
    # the angle maximizing sum Re(e^{-j t} x)^2 is half the angle of sum x^2
    theta = 0.5 * np.angle(np.sum(x**2, axis=0))
    return np.real(x * np.exp(-1j * theta)[None, :])


@dataclass(frozen=True)
class ScaledShapes:
    """Shapes assembled from the residues of all test sets (:func:`shapes_from_residues`).

    labels (n_dof,) str; shapes (n_dof, m) complex; mass_normalized (m,) bool: the anchor set
    had a driving point; error_var (n_dof, m): expected |psi_i - psi_i_true|^2 of each value
    up to the shape's common scale (0 when no residue variances were given); weak_part (m,)
    bool: some DOFs come only from a set too weak to be scaled against the others.
    """

    labels: tuple
    shapes: np.ndarray
    mass_normalized: np.ndarray
    error_var: np.ndarray
    weak_part: np.ndarray


def _link_scale(col, col_var, shared_rows, psi_other, var_other):
    """Complex factor scaling a set's column onto a scaled set through shared DOFs, and its
    variance: fac = sum conj(a) b / sum |a|^2 (least squares), var(fac) to first order in the
    errors of a (this set) and b (the scaled set); (None, None) without usable shared DOFs."""
    a, va = col[shared_rows[0]], col_var[shared_rows[0]]
    b, vb = psi_other[shared_rows[1]], var_other[shared_rows[1]]
    den = np.sum(np.abs(a) ** 2)
    if a.size == 0 or den <= 0:
        return None, None
    fac = np.sum(a.conj() * b) / den
    return fac, float(np.sum(np.abs(a) ** 2 * (vb + abs(fac) ** 2 * va)) / den**2)


def _own_scale(dp: complex, dp_var: float) -> tuple[complex, float]:
    """1 / psi_q from a driving-point value psi_q^2 (sign: driving point positive), and the
    variance of that factor: var(1/sqrt(x)) = var(x) / (4 |x|^3)."""
    root = np.sqrt(complex(dp))
    root = -root if root.real < 0 else root
    return 1.0 / root, dp_var / (4 * abs(dp) ** 3)


def _scale_mode(prod, prod_var, sets, dp, weak, common):
    """Per-set factors (n_set,) complex, their variances (n_set,), the anchor's having a driving
    point (bool) and per-set flags 'scaled by an arbitrary factor' (n_set,) for one mode."""
    order = sorted(range(len(sets)), key=lambda k: -abs(dp[k]))
    fac, fvar = np.zeros(len(sets), complex), np.zeros(len(sets))
    arbitrary = np.zeros(len(sets), bool)
    # the factor (and its variance) a weak or unlinked set would have had: its error
    alt, alt_var = np.full(len(sets), np.nan + 0j), np.zeros(len(sets))
    done: list[int] = []
    massnorm, anchor_relvar = False, 0.0
    for k in order:
        rows, has_dp = sets[k]["rows"], sets[k]["driving_row"] is not None and abs(dp[k]) > 0
        own = _own_scale(dp[k], prod_var[sets[k]["driving_row"]]) if has_dp else (None, None)
        if not done:  # the anchor: its overall scale does not change any MAC (variance 0)
            fac[k] = own[0] if has_dp else 1.0 / common
            massnorm = has_dp
            anchor_relvar = own[1] / abs(own[0]) ** 2 if has_dp else 0.0
            done.append(k)
            continue
        link = (None, None)
        for other in done:
            shared = [lab for lab in sets[k]["roving"] if lab in sets[other]["roving"]]
            if shared:
                pos = ([sets[k]["roving"].index(x) for x in shared],
                       [sets[other]["roving"].index(x) for x in shared])  # fmt: skip
                psi_o = prod[sets[other]["rows"]] * fac[other]
                var_o = prod_var[sets[other]["rows"]] * abs(fac[other]) ** 2
                var_o = var_o + np.abs(psi_o) ** 2 * fvar[other] / max(abs(fac[other]) ** 2, 1e-300)
                link = _link_scale(prod[rows], prod_var[rows], pos, psi_o, var_o)
                break
        if link[0] is not None and not weak[k]:
            fac[k], fvar[k] = link
        elif has_dp and not weak[k]:  # independent driving point: both sets' errors count
            fac[k], fvar[k] = own
            fvar[k] += abs(own[0]) ** 2 * anchor_relvar
        else:  # weak or unlinked: a common factor that need not fit this set
            fac[k], arbitrary[k] = 1.0 / common, True
            best = link if link[0] is not None else own
            if best[0] is not None:
                alt[k], alt_var[k] = best
        done.append(k)
    return fac, fvar, massnorm, arbitrary, (alt, alt_var)


def _residue_products(residues, poles, residue_var, sets):
    """Per mode, from residues (n_frf, m) and poles (m,) [rad/s]: the products psi_i psi_q =
    2 j w_d A_iq (n_frf, m), their variances (n_frf, m) (zero without ``residue_var``), the
    driving-point products (n_set, m) (zero for a set without one) and the common scale (m,)
    of a set that is not scaled by its own data."""
    wd = np.imag(poles)
    prod = residues * (2j * wd)[None, :]  # psi_i psi_q
    prod_var = np.zeros(prod.shape) if residue_var is None else residue_var * (2 * wd) ** 2
    n_modes = prod.shape[1]
    dp = np.array(
        [
            prod[s["driving_row"]] if s["driving_row"] is not None else np.zeros(n_modes)
            for s in sets
        ]
    )
    # without any driving point a mode cannot be mass-normalized: its shape is left unscaled,
    # at unit largest component (dividing by a vanishing driving point would overflow)
    peak = np.max(np.abs(prod), axis=0)
    dp_max = np.max(np.abs(dp), axis=0)
    common = np.where(dp_max > 0, np.sqrt(dp_max), np.where(peak > 0, peak, 1.0))
    return prod, prod_var, dp, common


def _value_var(col, cvar, fac, fvar, arbitrary, alt):
    """Error variance (n_rows,) of a set's values psi = fac col of one mode (col, cvar
    (n_rows,): products and their variances; fac, fvar: the set's factor and its variance;
    alt: the (factor, variance) the set would have had if ``arbitrary``; docstring of
    :func:`shapes_from_residues`)."""
    psi = col * fac
    var = cvar * abs(fac) ** 2 + np.abs(psi) ** 2 * fvar / abs(fac) ** 2
    if arbitrary and np.isfinite(alt[0]):
        a, a_var = alt
        var = np.abs(col) ** 2 * (abs(a - fac) ** 2 + a_var) + cvar * abs(a) ** 2
    elif arbitrary:
        var = var + np.abs(psi) ** 2
    return var


def _assemble_mode(prod_r, prod_var_r, sets, index, scaling, weak_r):
    """One mode's shape (n_dof,) complex and error variance (n_dof,) at the labels of
    ``index``: the sets' scaled values averaged where sets share a label, a weak set
    (weak_r (n_set,) bool) weighted 1e-6 so it only fills DOFs no other set has.
    prod_r, prod_var_r (n_frf,); scaling: (fac, fvar, arbitrary, alt) of :func:`_scale_mode`."""
    fac, fvar, arbitrary, alt = scaling
    total = np.zeros(len(index), complex)
    count = np.zeros(len(index))
    var_sum = np.zeros(len(index))
    for k, st in enumerate(sets):
        col, cvar = prod_r[st["rows"]], prod_var_r[st["rows"]]
        psi = col * fac[k]
        var = _value_var(col, cvar, fac[k], fvar[k], arbitrary[k], (alt[0][k], alt[1][k]))
        weight = 1e-6 if weak_r[k] else 1.0
        rows = [index[lab] for lab in st["roving"]]
        np.add.at(total, rows, weight * psi)
        np.add.at(count, rows, weight)
        np.add.at(var_sum, rows, weight**2 * var)
    return total / np.where(count > 0, count, 1.0), var_sum / np.where(count > 0, count, 1.0) ** 2


def shapes_from_residues(
    residues: np.ndarray,
    poles: np.ndarray,
    sets: list[dict],
    residue_var: np.ndarray | None = None,
    reliable_fraction: float = 0.02,
) -> ScaledShapes:
    """Mode shapes (n_dof, m) at the roving DOFs of all sets, scaled consistently, with their
    errors propagated from the residue variances (n_frf, m) when given (:class:`LsfdFit`).

    residues (n_frf, m), poles (m,), sets from :meth:`FrfSet.sets`.  For each mode the set whose
    driving point sees the mode most strongly is the anchor, mass-normalized by its driving
    point (psi_q = sqrt(2 j w_d A_qq)).  Every other set is scaled onto the already scaled sets
    through their shared DOF labels (complex least squares: magnitude and sign), because a set
    whose own driving point barely moves in this mode would give a noisy sqrt; only a set that
    shares no label with a scaled set uses its own driving point.  A weak set (norm below
    ``reliable_fraction`` of the strongest) only holds noise for this mode: it keeps the common
    scale and only fills DOFs no other set has.  Shared labels are averaged over the sets.
    Without any driving point a mode is left unscaled (unit largest component).

    Errors: value psi_i = fac_k 2 j w_d A_ik has var |fac_k 2 w_d|^2 var(A_ik) (noise) plus
    |psi_i|^2 var(fac_k) / |fac_k|^2 (the set's scale, relative to the anchor, whose own scale
    changes no MAC).  The part of a weak or unlinked set is scaled by a factor that need not
    fit it: its error is the difference to the best other factor (shared DOFs or its own
    driving point) plus that factor's variance, or its whole size when there is none.
    """
    prod, prod_var, dp, common = _residue_products(residues, poles, residue_var, sets)
    n_modes = prod.shape[1]
    set_norm = np.array([np.linalg.norm(prod[s["rows"]], axis=0) for s in sets])  # (n_set, m)
    labels = tuple(dict.fromkeys(lab for s in sets for lab in s["roving"]))
    index = {lab: i for i, lab in enumerate(labels)}
    shapes = np.zeros((len(labels), n_modes), complex)
    error_var = np.zeros((len(labels), n_modes))
    massnorm = np.zeros(n_modes, bool)
    weak_part = np.zeros(n_modes, bool)
    weak = set_norm < reliable_fraction * set_norm.max(axis=0)
    for r in range(n_modes):  # a few modes: the per-mode anchor logic reads best as a loop
        fac, fvar, massnorm[r], arbitrary, alt = _scale_mode(
            prod[:, r], prod_var[:, r], sets, dp[:, r], weak[:, r], common[r]
        )
        shapes[:, r], error_var[:, r] = _assemble_mode(
            prod[:, r], prod_var[:, r], sets, index, (fac, fvar, arbitrary, alt), weak[:, r]
        )
        weak_part[r] = bool(np.any(arbitrary & weak[:, r]))
    return ScaledShapes(labels, shapes, massnorm, error_var, weak_part)
