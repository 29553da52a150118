"""Least-squares frequency-domain (LSFD) residues, mode shapes and modal phase collinearity.

With the poles s_r fixed (from LSCE), every FRF is linear in its residues (seed eq. 4):
  H_k(jw) = sum_r [A_kr (jw)^p / (jw - s_r) + conj(A_kr) (jw)^p / (jw - conj s_r)]
            + LR_k (jw)^p / (jw)^2 + UR_k (jw)^p,
p = 0, 1, 2 for receptance, mobility, accelerance; LR (lower residual: modes below the range)
and UR (upper residual: modes above it) are real.  Writing A = a + j b keeps the conjugate pair
structure with real unknowns; one real least-squares solve serves all FRFs (shared basis).

Mode shapes: for a fixed DOF q of a test set and roving DOFs i, A_iqr = psi_ir psi_qr / (2 j
w_dr) for mass-normalised (unit modal-A) scaling, so with the driving point i = q,
psi_qr = sqrt(2 j w_dr A_qqr) and psi_ir = 2 j w_dr A_iqr / psi_qr.
"""

from dataclasses import dataclass

import numpy as np

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
    var_a = s2_local * diag[:m, None]
    var_b = s2_local * diag[m : 2 * m, None]
    residues = (coef[:m] + 1j * coef[m : 2 * m]).T
    residue_var = (var_a + var_b).T
    if residuals:
        lower, upper = coef[2 * m], coef[2 * m + 1]
    else:
        lower = upper = np.zeros(h.shape[0])
    return LsfdFit(residues, lower, upper, residue_var, np.sqrt(s2_local.T))


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


def realise(shapes: np.ndarray) -> np.ndarray:
    """Real shapes (n_dof, m): each column rotated to its best-fit real line, real part kept."""
    x = np.asarray(shapes, dtype=complex)
    # the angle maximising sum Re(e^{-j t} x)^2 is half the angle of sum x^2
    theta = 0.5 * np.angle(np.sum(x**2, axis=0))
    return np.real(x * np.exp(-1j * theta)[None, :])


def shapes_from_residues(
    residues: np.ndarray,
    poles: np.ndarray,
    sets: list[dict],
    reliable_fraction: float = 0.02,
) -> tuple[tuple[str, ...], np.ndarray, np.ndarray]:
    """Mode shapes (n_dof, m) at the roving DOFs of all sets, scaled consistently.

    residues (n_frf, m), poles (m,), sets from :meth:`FrfSet.sets`.  For each mode the set whose
    driving point sees the mode most strongly is the anchor: it is mass-normalised by its driving
    point (psi_q = sqrt(2 j w_d A_qq)).  Every other set is scaled onto the already scaled sets
    through their shared DOF labels (complex least squares: magnitude and sign), because a set
    whose own driving point barely moves in this mode would give a noisy sqrt; only a set that
    shares no label with a scaled set uses its own driving point.  A weak set (norm below
    ``reliable_fraction`` of the strongest) only holds noise for this mode: it keeps the common
    scale and only fills DOFs no other set has.  Shared labels are averaged over the sets.
    Without any driving point a mode is left unscaled (unit largest component) and
    mass_normalised is False.  Returns (labels, shapes, mass_normalised (m,) bool: the anchor had
    a driving point, row_scale (n_frf, m) complex: the factor that turned row k's
    2 j w_d A_kr into its shape value, for propagating residue variances).
    """
    wd = np.imag(poles)
    prod = residues * (2j * wd)[None, :]  # psi_i psi_q
    n_modes = prod.shape[1]
    set_norm = np.array([np.linalg.norm(prod[s["rows"]], axis=0) for s in sets])  # (n_set, m)
    dp = np.array(
        [
            prod[s["driving_row"]] if s["driving_row"] is not None else np.zeros(n_modes)
            for s in sets
        ]
    )
    # without any driving point a mode cannot be mass-normalised: its shape is left unscaled,
    # at unit largest component (dividing by a vanishing driving point would overflow)
    peak = np.max(np.abs(prod), axis=0)
    dp_max = np.max(np.abs(dp), axis=0)
    common = np.where(dp_max > 0, np.sqrt(dp_max), np.where(peak > 0, peak, 1.0))
    labels = tuple(dict.fromkeys(lab for s in sets for lab in s["roving"]))
    index = {lab: i for i, lab in enumerate(labels)}
    shapes = np.zeros((len(labels), n_modes), complex)
    massnorm = np.zeros(n_modes, bool)
    row_scale = np.zeros(prod.shape, complex)
    weak = set_norm < reliable_fraction * set_norm.max(axis=0)

    def own_scale(k, r):
        root = np.sqrt(complex(dp[k, r]))
        return -root if root.real < 0 else root  # sign convention: driving point positive

    for r in range(n_modes):  # a few modes: the per-mode anchor logic reads best as a loop
        order = sorted(range(len(sets)), key=lambda k: -abs(dp[k, r]))
        scaled: dict[int, np.ndarray] = {}
        total = np.zeros(len(labels), complex)
        count = np.zeros(len(labels))
        for k in order:
            col = prod[sets[k]["rows"], r]
            if not scaled:
                has_dp = sets[k]["driving_row"] is not None and abs(dp[k, r]) > 0
                fac = 1.0 / (own_scale(k, r) if has_dp else common[r])
                massnorm[r] = has_dp
            else:
                fac = None
                for other, psi_other in scaled.items():
                    shared = [lab for lab in sets[k]["roving"] if lab in sets[other]["roving"]]
                    if not shared:
                        continue
                    a = col[[sets[k]["roving"].index(lab) for lab in shared]]
                    b = psi_other[[sets[other]["roving"].index(lab) for lab in shared]]
                    den = np.sum(np.abs(a) ** 2)
                    if den > 0 and not weak[k, r]:
                        fac = np.sum(a.conj() * b) / den
                    break
                if fac is None:  # no link to a scaled set (or too weak to scale through it)
                    has_dp = sets[k]["driving_row"] is not None and abs(dp[k, r]) > 0
                    fac = 1.0 / (own_scale(k, r) if has_dp and not weak[k, r] else common[r])
            psi = col * fac
            row_scale[sets[k]["rows"], r] = fac
            scaled[k] = psi
            weight = 1e-6 if weak[k, r] else 1.0
            for j, lab in enumerate(sets[k]["roving"]):
                total[index[lab]] += weight * psi[j]
                count[index[lab]] += weight
        shapes[:, r] = total / np.where(count > 0, count, 1.0)
    return labels, shapes, massnorm, row_scale
