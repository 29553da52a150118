"""Refinement of poles by nonlinear least squares on the FRFs of a window of lines (variable
projection).

Model of every FRF k on the window's lines (seed eq. 4, :mod:`bayesupdate.ema.lsfd`):
  H_k(jw) = sum_r [A_kr (jw)^p / (jw - s_r) + conj(A_kr) (jw)^p / (jw - conj s_r)]
            + LR_k (jw)^p / (jw)^2 + UR_k (jw)^p.
It is linear in the residues and residuals c_k and nonlinear in the poles s_r.  With the
design matrix D(s) (real and imaginary parts stacked, shared by all FRFs) the residues are
eliminated, c_k = D^+ y_k, and the poles minimize the projected cost
  sum_k || P_perp(s) y_k ||^2,   P_perp = I - D D^+
(variable projection: Golub & Pereyra 1973, SIAM J. Numer. Anal. 10(2) 413-432).  Its Jacobian
is taken in Kaufman's approximation (Kaufman 1975, BIT 15 49-57): J_j = -P_perp (dD/ds_j) c_k,
analytic here, as dD/ds_j touches the two columns of pole j only.  Steps are Levenberg-Marquardt
with Marquardt's diagonal scaling.

Why: LSCE (and pLSCF) fit each narrow band's poles without the flank of a strong mode just
outside it, and the constant upper residual cannot follow that flank, so a mode near the end
of the analysed range comes out biased (FE exhaust with a 176 Hz mode above the 150 Hz end:
mode 13 at 144.37 Hz 0.02-0.04 % low, noise sd ~0.006 %).  Identified poles near the window
enter the basis fixed; beyond an end of the analysed range, where no identified pole stands for
the neighbour, a free extra pole does (its residues are not reported).  A resonance that the end
cuts (its peak on the window's lines, its half-power band beyond them) is one more free pole,
allowed on the lines, with the extra pole beyond it.  Which poles are refined where:
:func:`bayesupdate.ema.identify._refine_ends`.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.ema.frf_set import KIND_POWER
from bayesupdate.ema.synthesis import frf_basis

#: largest accepted move of a refined pole, in half-power half-widths |Re s|.  The bias the
#: refinement removes is a small part of a mode's bandwidth (FE exhaust, mode 13: 0.012-0.016);
#: a larger move means the model (modes, one extra pole, residuals) does not describe the data
#: there, and the stabilized estimate is kept (real mAEWing1 GVT, top of 3-35 Hz: 0.2-0.96, the
#: 31.7 Hz mode pulled 0.23-0.36 % away from the authors' 31.78 Hz peak pick)
MAX_MOVE = 0.1


@dataclass(frozen=True)
class PoleRefinement:
    """Result of :func:`refine_poles`: poles (q,) and extra poles (e,) [rad/s] (refined, or the
    starting ones when not ``accepted``); cost (2,): projected cost before and after;
    converged_extra (e,) [rad/s]: where the extra poles converged, accepted or not (an extra
    pole that converged on the lines found a resonance that the window's end cuts)."""

    poles: np.ndarray
    extra: np.ndarray
    cost: np.ndarray
    accepted: bool
    converged_extra: np.ndarray


def _design(f: np.ndarray, poles: np.ndarray, kind: str) -> np.ndarray:
    """Real design (2 n_f, 2 m + 2): pole columns (a, b) with A = a + j b, then LR and UR."""
    pos, neg = frf_basis(f, poles, kind)
    jw = 2j * np.pi * f
    factor = jw ** KIND_POWER[kind]
    cols = np.hstack([pos + neg, 1j * (pos - neg), (factor / jw**2)[:, None], factor[:, None]])
    return np.vstack([cols.real, cols.imag])


def _project(design: np.ndarray, y: np.ndarray):
    """Orthonormal basis U of the design's range, coefficients (2m+2, n_frf) and residual."""
    scale = np.linalg.norm(design, axis=0)
    scale[scale == 0] = 1.0
    u, sv, vt = np.linalg.svd(design / scale, full_matrices=False)
    ok = sv > np.finfo(float).eps * max(design.shape) * sv[0]
    u, sv, vt = u[:, ok], sv[ok], vt[ok]
    uty = u.T @ y
    coef = (vt.T @ (uty / sv[:, None])) / scale[:, None]
    return u, coef, y - u @ uty


def _normal_equations(f, free, coef, u, resid, kind) -> tuple[np.ndarray, np.ndarray]:
    """J^T J (2q, 2q) and J^T r (2q,) of Kaufman's Jacobian J = -P_perp (dD/dtheta) c over
    theta = (Re s, Im s) of the q free poles (the first q of the basis), without forming J:
    with G = dD/dtheta c (complex, (n_f, 2q, n_frf)), J^T J = G^H G - (U^T G)^T (U^T G) and
    J^T r = -G^H r (r is already orthogonal to U); real parts of the complex products."""
    q, m, n_f = free.size, (coef.shape[0] - 2) // 2, f.size
    jw = 2j * np.pi * f[:, None]
    factor = jw ** KIND_POWER[kind]
    pos2, neg2 = factor / (jw - free) ** 2, factor / (jw - free.conj()) ** 2  # (n_f, q)
    amp = (coef[:q] + 1j * coef[m : m + q])[None]  # (1, q, n_frf)
    d_re = pos2[:, :, None] * amp + neg2[:, :, None] * amp.conj()
    g = np.concatenate([d_re, 1j * (pos2[:, :, None] * amp - neg2[:, :, None] * amp.conj())], 1)
    u_c = u[:n_f] + 1j * u[n_f:]  # stacked real inner products = Re of complex ones
    b = np.tensordot(u_c.conj(), g, axes=(0, 0)).real  # (rank, 2q, n_frf)
    gram = np.tensordot(g.conj(), g, axes=([0, 2], [0, 2])).real
    gram -= np.tensordot(b, b, axes=([0, 2], [0, 2]))
    r_c = resid[:n_f] + 1j * resid[n_f:]
    return gram, -np.tensordot(g.conj(), r_c, axes=([0, 2], [0, 1])).real


def _principal_responses(y: np.ndarray, rank: int) -> np.ndarray:
    """The FRFs y (2 n_f, n_frf) reduced to their ``rank`` strongest combinations (2 n_f, k).

    The model D c has at most rank = 2 m + 2 independent columns over the FRFs, so the
    weaker right singular directions of y hold noise only; the projected cost keeps its
    minimizer up to that noise while the work per step falls by n_frf / k (principal
    response functions: Allemang & Brown 1998, Sound Vib. 32(1), on data reduction by SVD)."""
    if y.shape[1] <= rank:
        return y
    u, sv, _ = np.linalg.svd(y, full_matrices=False)
    return u[:, :rank] * sv[:rank]


def _evaluate(theta, fixed, f, y, kind, normal=True):
    """Cost and, if ``normal``, the normal equations at theta = (Re s, Im s) of the free poles."""
    q = theta.size // 2
    free = theta[:q] + 1j * theta[q:]
    u, coef, resid = _project(_design(f, np.concatenate([free, fixed]), kind), y)
    cost = float(np.sum(resid**2))
    return cost, (_normal_equations(f, free, coef, u, resid, kind) if normal else None)


def _levenberg_marquardt(theta, fixed, f, y, kind, n_band: int, max_iter: int):
    """Minimize the projected cost from theta; returns (theta, cost at start, cost at end).

    Stops when no step lowers the cost, or when a step moves none of the first n_band poles by
    more than 1e-4 of its half-power half-width |Re s| (the extra poles, in a flat valley,
    may creep on without changing the band's poles)."""
    cost, (jtj, grad) = _evaluate(theta, fixed, f, y, kind)
    cost0, lam, q = cost, 1e-3, theta.size // 2
    for _ in range(max_iter):
        diag = np.maximum(np.diag(jtj), np.finfo(float).tiny)
        for _ in range(4):  # a step that fails 4 times shrunk: at the noise floor
            step = np.linalg.solve(jtj + lam * np.diag(diag), -grad)
            cost_new, _ = _evaluate(theta + step, fixed, f, y, kind, normal=False)
            if cost_new < cost:
                break
            lam *= 10.0
        if cost_new >= cost:
            break
        theta, cost, lam = theta + step, cost_new, max(lam / 10.0, 1e-9)
        move = np.abs(step[:n_band] + 1j * step[q : q + n_band]) / np.abs(theta[:n_band])
        if np.all(move < 1e-4):
            break
        cost, (jtj, grad) = _evaluate(theta, fixed, f, y, kind)
    return theta, cost0, cost


def refine_poles(
    frequencies_hz: np.ndarray,
    frf: np.ndarray,
    poles: np.ndarray,
    extra: np.ndarray,
    fixed: np.ndarray,
    kind: str = "accelerance",
    max_iter: int = 30,
    cut: int = 0,
    max_move: float = MAX_MOVE,
) -> PoleRefinement:
    """Refine poles (q,) and extra out-of-band poles (e,) [rad/s], Im > 0, by variable projection
    (module doc) on frf (n_frf, n_f) at frequencies_hz (n_f,) [Hz] > 0, with the poles ``fixed``
    (k,) in the basis unchanged.  The first ``cut`` extra poles stand for resonances that the
    window's end cuts: free like the others, but allowed on the lines.

    Accepted only if every refined pole moves by less than ``max_move`` (default
    ``MAX_MOVE``) of its half-power
    half-width |Re s| with Re s < 0, and every extra pole stays stable and, except the ``cut``
    ones, outside the lines' range (it stands for a mode beyond them); else the start is
    returned.
    """
    f = np.asarray(frequencies_hz, dtype=float)
    h = np.atleast_2d(frf)
    start = np.concatenate([np.asarray(poles, complex), np.asarray(extra, complex)])
    fixed = np.asarray(fixed, dtype=complex)
    y = _principal_responses(np.vstack([h.real.T, h.imag.T]), 2 * (start.size + fixed.size) + 2)
    theta0 = np.concatenate([start.real, start.imag])
    q = np.asarray(poles).size
    theta, cost0, cost1 = _levenberg_marquardt(theta0, fixed, f, y, kind, q, max_iter)
    new = theta[: start.size] + 1j * theta[start.size :]
    moved = np.abs(new[:q] - start[:q]) / np.abs(start[:q].real)
    near = np.all(moved < max_move) and np.all(new.real < 0)
    w_lo, w_hi = 2 * np.pi * f[0], 2 * np.pi * f[-1]
    beyond = new[q + cut :]
    outside = np.all((beyond.imag < w_lo) | (beyond.imag > w_hi))
    ok = bool(near and outside and np.all(np.isfinite(new)))
    out = new if ok else start
    return PoleRefinement(out[:q], out[q:], np.array([cost0, cost1]), ok, new[q:])
