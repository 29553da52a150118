"""Free-free bending frequencies of a uniform beam (a test and study helper).

Used by tests/test_ema_real_data.py and studies/beam_frf_poles.py to ask whether poles found on
the measured LADISK beam FRF above its authors' 10-5000 Hz band are its bending modes 8, 9, ...
The beam's geometry is not given with the data (../shared/data/beam_frf_sdpy/README.md), so
both models are scaled to the authors' 7 frequencies and only then extrapolated:

- Euler-Bernoulli: f_n = c (beta_n L)^2, beta_n L = 4.7300, 7.8532, 10.9956, 14.1372,
  17.2788, 20.4204, 23.5619, then (2n + 1) pi / 2; c by least squares on log f.
- Timoshenko (shear and rotary inertia): a free-free beam of 100 elements of
  ``bayesupdate.fe.elements.beam`` (Przemieniecki 1968, eqs 5.116, 11.41-11.42; at s -> 0 modes 1-12
  are within 2e-5 of the exact roots above), eigenvalues omega^2 rho A L^4 / EI
  (L = 1, I / A = s^2, E / (kappa G) = 2 (1 + nu) / kappa with Cowper's
  kappa = 10 (1 + nu) / (12 + 11 nu) for a rectangle, nu = 0.3); the slenderness s = r / L
  (r = radius of gyration) and the scale by least squares on log f over the 7 references.
"""

import numpy as np
from scipy.linalg import eigh
from scipy.optimize import minimize_scalar

from bayesupdate.fe.elements.beam import local_beam_matrices

#: the data authors' 7 frequencies [Hz] (sdypy-EMA tests/test_data.py nat_freq_true)
BEAM_REFERENCE_HZ = np.array(
    [176.07332578, 476.4634351, 932.28540465, 1534.78951957, 2286.31989538, 3162.15866336,
     4181.71710178]
)  # fmt: skip
_BETA_L = np.array([4.7300408, 7.8532046, 10.9956078, 14.1371655, 17.2787597, 20.4203522])
#: (v, rz) bending DOFs of the 12-DOF element of bayesupdate.fe.elements.beam
_PLANE = np.array([1, 5, 7, 11])
_NU = 0.3
_N_ELEMENTS = 100


def beta_l(n: np.ndarray) -> np.ndarray:
    """Free-free beta_n L (n 1-based, flexible modes), exact roots then (2n + 1) pi / 2."""
    n = np.asarray(n)
    tail = (2 * n + 1) * np.pi / 2
    return np.where(n <= _BETA_L.size, _BETA_L[np.minimum(n, _BETA_L.size) - 1], tail)


def euler_bernoulli_hz(n: np.ndarray, reference_hz: np.ndarray = BEAM_REFERENCE_HZ) -> np.ndarray:
    """Euler-Bernoulli frequencies [Hz] of modes n, c fitted to modes 1..len(reference_hz)."""
    b2 = beta_l(np.arange(1, reference_hz.size + 1)) ** 2
    c = np.exp(np.mean(np.log(reference_hz / b2)))
    return c * beta_l(np.asarray(n)) ** 2


def timoshenko_eigenvalues(slenderness: float, n_modes: int) -> np.ndarray:
    """Nondimensional omega^2 rho A L^4 / EI (n_modes,) of the first flexible free-free modes."""
    ne = _N_ELEMENTS
    le = np.full(ne, 1.0 / ne)
    kappa = 10 * (1 + _NU) / (12 + 11 * _NU)
    one = np.ones(ne)
    # E = rho = A = 1, I = s^2, kappa G = kappa E / (2 (1 + nu)) on A_s = A
    g = kappa / (2 * (1 + _NU)) * one
    ke, me = local_beam_matrices(le, one, g, one, one, one, slenderness**2 * one, one, one, one)
    ke, me = ke[:, _PLANE[:, None], _PLANE], me[:, _PLANE[:, None], _PLANE]
    dof = 2 * np.arange(ne)[:, None] + np.arange(4)[None, :]
    k = np.zeros((2 * ne + 2, 2 * ne + 2))
    m = np.zeros_like(k)
    np.add.at(k, (dof[:, :, None], dof[:, None, :]), ke)
    np.add.at(m, (dof[:, :, None], dof[:, None, :]), me)
    omega2 = eigh(k, m, eigvals_only=True, subset_by_index=[2, n_modes + 1])
    return omega2 / slenderness**2  # E I = s^2 here


def timoshenko_fit(reference_hz: np.ndarray = BEAM_REFERENCE_HZ) -> tuple[float, float, float]:
    """(slenderness r / L, scale [Hz], rms log misfit) fitted to modes 1..len(reference_hz)."""

    def misfit(log_s: float) -> tuple[float, float]:
        root = np.sqrt(timoshenko_eigenvalues(np.exp(log_s), reference_hz.size))
        resid = np.log(reference_hz / root)
        return float(np.sqrt(np.mean((resid - resid.mean()) ** 2))), float(np.exp(resid.mean()))

    best = minimize_scalar(lambda x: misfit(x)[0], bounds=(np.log(1e-4), np.log(0.05)))
    rms, scale = misfit(best.x)
    return float(np.exp(best.x)), scale, rms


def timoshenko_hz(n: np.ndarray, fit: tuple[float, float, float]) -> np.ndarray:
    """Timoshenko frequencies [Hz] of modes n (1-based) with ``fit`` from :func:`timoshenko_fit`."""
    n = np.asarray(n)
    root = np.sqrt(timoshenko_eigenvalues(fit[0], int(n.max())))
    return fit[1] * root[n - 1]
