"""FRF synthesis from modal parameters (seed eqs 4-5).

Pole of mode r (seed eq. 16): s_r = -zeta_r w_r + j w_r sqrt(1 - zeta_r^2), w_r = 2 pi f_r.
Receptance (seed eq. 4):  H_ij(jw) = sum_r A_ijr / (jw - s_r) + conj(A_ijr) / (jw - conj(s_r))
                           [+ lower residual LR_ij / (jw)^2 + upper residual UR_ij].
For real mass-normalized shapes phi (proportional damping) A_ijr = phi_ir phi_jr / (2 j w_dr),
w_dr = Im(s_r).  Mobility and accelerance are receptance times (jw) and (jw)^2.
"""

import numpy as np

from bayesupdate.ema.frf_set import KIND_POWER


def poles_from_modal(frequencies_hz: np.ndarray, damping_ratio: np.ndarray) -> np.ndarray:
    """Complex poles s_r [rad/s] (m,) with positive imaginary part from f_r [Hz] and zeta_r."""
    w = 2 * np.pi * np.asarray(frequencies_hz, dtype=float)
    z = np.asarray(damping_ratio, dtype=float)
    return -z * w + 1j * w * np.sqrt(1 - z**2)


def modal_from_poles(poles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Natural frequency [Hz] and damping ratio of poles s_r (seed eq. 16-17: w_r = |s_r|)."""
    s = np.asarray(poles, dtype=complex)
    w = np.abs(s)
    return w / (2 * np.pi), -s.real / np.where(w > 0, w, 1.0)


def residues_from_shapes(
    poles: np.ndarray, shapes_response: np.ndarray, shapes_reference: np.ndarray
) -> np.ndarray:
    """Residues A_kr = phi_resp,kr phi_ref,kr / (2 j w_dr) for FRF rows k (n_frf, m).

    shapes_response, shapes_reference: (n_frf, m) real mass-normalized shape values at the
    response and reference DOF of each FRF row [1/sqrt(kg)].
    """
    wd = np.imag(poles)
    return shapes_response * shapes_reference / (2j * wd)[None, :]


def frf_basis(
    frequencies_hz: np.ndarray, poles: np.ndarray, kind: str = "receptance"
) -> tuple[np.ndarray, np.ndarray]:
    """Pole basis terms (jw)^p / (jw - s_r) and (jw)^p / (jw - conj s_r), each (n_f, m)."""
    jw = 2j * np.pi * np.asarray(frequencies_hz, dtype=float)[:, None]
    factor = jw ** KIND_POWER[kind]
    s = np.asarray(poles, dtype=complex)[None, :]
    return factor / (jw - s), factor / (jw - s.conj())


def synthesize_frf(
    frequencies_hz: np.ndarray,
    poles: np.ndarray,
    residues: np.ndarray,
    kind: str = "receptance",
    lower_residual: np.ndarray | None = None,
    upper_residual: np.ndarray | None = None,
) -> np.ndarray:
    """FRFs (n_frf, n_f) from poles (m,) and residues (n_frf, m) (seed eq. 4).

    Residuals (n_frf,) are in receptance units: LR/(jw)^2 for modes below the range (mass line),
    UR for modes above it (stiffness line); both multiplied by (jw)^p for mobility/accelerance.
    """
    f = np.asarray(frequencies_hz, dtype=float)
    a = np.atleast_2d(np.asarray(residues, dtype=complex))
    pos, neg = frf_basis(f, poles, kind)
    h = a @ pos.T + a.conj() @ neg.T
    jw = 2j * np.pi * f
    factor = jw ** KIND_POWER[kind]
    if lower_residual is not None:
        with np.errstate(divide="ignore", invalid="ignore"):
            lr_term = np.where(jw != 0, factor / np.where(jw != 0, jw, 1.0) ** 2, 0.0)
        h = h + np.asarray(lower_residual)[:, None] * lr_term[None, :]
    if upper_residual is not None:
        h = h + np.asarray(upper_residual)[:, None] * factor[None, :]
    return h


def synthesize_from_modes(
    frequencies_hz: np.ndarray,
    natural_hz: np.ndarray,
    damping_ratio: np.ndarray,
    shapes_response: np.ndarray,
    shapes_reference: np.ndarray,
    kind: str = "accelerance",
) -> np.ndarray:
    """FRFs (n_frf, n_f) of a proportionally damped model from real mass-normalized shapes.

    shapes_response / shapes_reference: (n_frf, m) shape values at each row's DOFs.
    """
    poles = poles_from_modal(natural_hz, damping_ratio)
    res = residues_from_shapes(poles, shapes_response, shapes_reference)
    return synthesize_frf(frequencies_hz, poles, res, kind)
