"""The Jacobian of the fit residuals on a certified reduced basis from design derivatives.

On a reduced basis the pencil is K_r(theta) = sum_t c_t(theta) K_t, M_r likewise
(``fe.reduced.basis.ReducedBasis``), so an eigenvalue's design derivative needs no second solve:
for a simple eigenvalue lambda_k with mass-normalized reduced vector y_k (Fox & Kapoor, AIAA J. 6
(1968) 2426; Nelson, AIAA J. 14 (1976) 1201)

    d lambda_k / d theta_j = y_k^T (dK_r/dtheta_j - lambda_k dM_r/dtheta_j) y_k,

and f_k = sqrt(lambda_k) / (2 pi) gives d f_k = d lambda_k / (8 pi^2 f_k).  The coefficients c_t
(monomials and, for non-affine fields, interpolation weights in log theta) are differentiated by
central differences of the coefficients alone (microseconds; no eigen-solve), so a Jacobian costs
one eigen-solve with vectors instead of the d + 1 of a forward difference.  The pairing is held
at the point (the residual's branch: on a kink the one-sided derivative, as a difference would
give from one side), and the mass term's derivative is a forward difference of the masses
(``optimize._masses``: the verified polynomial when there is one).  Other extra terms (MAC,
measured CG / inertia) or points the basis does not cover: None, and the caller differences.

The basis is reached through the reduced model's attributes (``certification.basis``: its
``eigen``, ``matrices``' affine terms and ``decomposition.coefficients``), not imported:
inference imports no fe (the layer contract); these functions belong beside
``ReducedBasis.eigen`` in ``fe.reduced`` when that module next changes.
"""

import numpy as np

from bayesupdate.inference.problem import CalibrationProblem

#: relative step of the coefficients' central differences: their truncation error ~ step^2
STEP = 1e-6
#: y_m^T A_p y_m for every mode m and parameter p
_QUADRATIC_FORMS = "im,pij,jm->mp"


def reduced_basis_of(problem: CalibrationProblem):
    """(the reduced model, its basis) when ``problem`` is on a certified reduced basis whose
    stiffness is on the elastic block (no rigid-body energy) and every extra term is
    differentiable here (module docstring); else None."""
    model, spec = problem.model, problem.objective
    certification = getattr(model, "certification", None)
    basis = getattr(certification, "basis", None)
    if basis is None or not getattr(model, "certified", False) or basis.rigid_energy:
        return None
    if spec.mac_weight > 0 or spec.mass_properties is not None:
        return None
    if problem.pairing.n_model > model.n_modes:
        return None
    return model, basis


def eigen_derivatives(
    basis, full: np.ndarray, columns: list[int], n_modes: int, solved=None, paths=None
):
    """At one point full (1, P) of the basis's parameters (SI): (lambda (m,) [rad^2/s^2], y
    (r, m) mass-normalized reduced vectors, d lambda / d theta (m, len(columns)) for the
    parameters at ``columns``).  solved : ``basis.eigen(full, n_modes, vectors=True)`` when
    the caller has it (``LastSolve``), else it is solved here.  paths : the two contractions'
    ``contraction_paths`` (None: numpy searches them on each call)."""
    lam, y = basis.eigen(full, n_modes, vectors=True) if solved is None else solved
    lam, y = lam[0], y[0]
    h = STEP * np.abs(full[0, columns])
    steps = np.zeros((len(columns), full.shape[1]))
    steps[np.arange(len(columns)), columns] = h
    cK_plus, cM_plus = basis.decomposition.coefficients(full + steps)
    cK_minus, cM_minus = basis.decomposition.coefficients(full - steps)
    dcK = (cK_plus - cK_minus) / (2 * h[:, None])
    dcM = (cM_plus - cM_minus) / (2 * h[:, None])
    r, nr = basis.size, basis.n_rigid
    dK = ((dcK @ basis.K_terms[0]) @ basis.K_terms[1]).reshape(-1, r - nr, r - nr)
    dM = ((dcM @ basis.M_terms[0]) @ basis.M_terms[1]).reshape(-1, r, r)
    b = y[nr:]
    k_path, m_path = (True, True) if paths is None else paths
    k_part = np.einsum(_QUADRATIC_FORMS, b, dK, b, optimize=k_path)
    m_part = np.einsum(_QUADRATIC_FORMS, y, dM, y, optimize=m_path)
    return lam, y, k_part - lam[:, None] * m_part


def contraction_paths(basis, n_modes: int, n_params: int) -> tuple[list, list]:
    """The contraction orders ``np.einsum(..., optimize=True)`` finds for ``eigen_derivatives``'
    stiffness and mass forms on ``basis`` with ``n_modes`` modes and ``n_params`` parameters,
    found once: the order depends on the shapes alone, so given back to ``einsum`` it makes the
    same products (the same bits) without the search, which cost 0.6 of its 1.75 ms a call on
    the shell exhaust's basis (r = 97, 14 modes, 5 parameters; process_time over 2,000 calls)."""
    r, re = basis.size, basis.size - basis.n_rigid
    paths = []
    for n in (re, r):
        vectors, forms = np.zeros((n, n_modes)), np.zeros((n_params, n, n))
        paths.append(np.einsum_path(_QUADRATIC_FORMS, vectors, forms, vectors, optimize=True)[0])
    return paths[0], paths[1]


class LastSolve:
    """A reduced model's sensor predictions (``predict_batch_with_shapes``) that keep the
    reduced eigen-solve of their last one-point call, so that the Jacobian at that point
    (``eigen_derivatives(..., solved=...)``) does not solve it again.  scipy's trust-region
    least squares asks for J(x) right after r(x) at every accepted step, so each Jacobian was a
    second eigen-solve of a point just solved: on the shell exhaust's basis (r = 97) 382 of a
    calibration's 1,244.  A point inside the basis's box is solved as
    ``ReducedFEModel.predict_batch_with_shapes`` solves it (the same calls, the same bits);
    any other call is that method's.  The one mutable record of a least-squares run: made per
    start (``optimize._fit_start``), never shared between starts or processes.
    """

    def __init__(self, model, basis):
        self.model, self.basis = model, basis
        self._last: tuple = ()

    def predict_batch_with_shapes(self, theta: np.ndarray, names: tuple[str, ...], n_modes: int):
        """(frequencies (B, n_modes) [Hz], sensor shapes (B, n_sensors, n_modes)) at theta
        (B, len(names)) (SI): ``ReducedFEModel.predict_batch_with_shapes``."""
        model = self.model
        full = model._theta_full(np.atleast_2d(np.asarray(theta, dtype=float)), tuple(names))
        if full.shape[0] != 1 or not (model._usable(n_modes) and model._inside(full)[0]):
            return model.predict_batch_with_shapes(theta, names, n_modes)
        lam, y = self.basis.eigen(full, n_modes, vectors=True)
        self._last = (full.tobytes(), n_modes, (lam, y))
        return np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi), self.basis.V_sensor @ y

    def solved(self, full: np.ndarray, n_modes: int):
        """(lambda (1, n_modes), y (1, r, n_modes)) of the last one-point call when it was at
        ``full`` (1, P) (the basis's parameters, bit for bit) with ``n_modes``; else None."""
        if self._last and self._last[:2] == (full.tobytes(), n_modes):
            return self._last[2]
        return None
