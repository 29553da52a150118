"""Mode shapes as evidence: per-mode shape residuals, each with its own integrated noise level.

Test mode i has the real, unit-norm shape t_i (n,) on the test's sensor DOFs (complex identified
shapes are rotated to their best-fit real line first, ``ema.lsfd.realise``); p_i is the paired model
shape on the same DOFs.  The modal scale factor a_i = p_i.t_i / p_i.p_i (Allemang 2003, "The modal
assurance criterion - twenty years of use and abuse", eq. 3) fits the model shape to the test shape
and leaves the residual

    d_i = t_i - a_i p_i,        |d_i|^2 = 1 - MAC(t_i, p_i)   (exactly, for real shapes),

so this is the MAC deficit spread over the sensors, with a sign and a location, which is what a
sensitivity (Jacobian) needs.  The components of d_i are modelled as independent N(0, sigma_i^2)
with one level sigma_i *per mode*: identification quality varies from mode to mode (a mode with
little motion at the reference sensor is identified worse; on the virtual test 1 - MAC of the
identified against the true shapes is ~1e-5 for most modes and ~2e-2 for three of twelve).  Each
sigma_i is integrated out under a log-uniform prior on [``SHAPE_SIGMA_FLOOR``, ``SHAPE_SIGMA_MAX``]
with the closed form of ``evidence.inferred_block_log_likelihood`` on n - 1 degrees of freedom (the
scale factor is fitted).  A model that explains a shape discrepancy therefore gains about
(n - 1)/2 ln(R_before / R_after) for that mode, R = |d_i|^2; one that cannot, gains nothing, however
large the identification error of that mode.

The optimiser sees d_i / s_i with s_i the level fitted at the baseline (held fixed: one
reweighting of an iteratively reweighted least-squares fit of the integrated likelihood, whose
gradient (n - 1)/R_i d_i.dd_i it matches at the baseline).

*Known* shape noise: when the data give ``ModalData.shape_sd_rel`` (each shape's component sd as
a fraction of its RMS amplitude; a unit-norm shape on n DOFs has RMS amplitude 1/sqrt(n)), the
level is sigma_i = shape_sd_rel_i / sqrt(n), fixed, and the block is Gaussian with that sd, as
frequencies are with a known sd.  Then a shape misfit that no model removes is not absorbed
into an inflated noise level: R_i / sigma_i^2 ~ chi^2(n - 1) under a model that fits, and the
adequacy check (``flagging.flag_modes``) sees it.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.ema.lsfd import realise

#: smallest per-component noise level of a unit-norm shape (1 - MAC ~ 4e-7 on 40 DOFs)
SHAPE_SIGMA_FLOOR = 1e-4
#: largest: a unit-norm shape on n DOFs has components ~ 1/sqrt(n); 0.5 is pure noise for n >= 4
SHAPE_SIGMA_MAX = 0.5


def unit_real_shapes(shapes: np.ndarray) -> np.ndarray:
    """(n_dof, m) real or complex shapes -> real shapes with unit Euclidean norm per column."""
    real = realise(shapes) if np.iscomplexobj(shapes) else np.asarray(shapes, dtype=float)
    norm = np.linalg.norm(real, axis=0)
    return real / np.where(norm > 0, norm, 1.0)[None, :]


def shape_residuals(test_unit: np.ndarray, model_shapes: np.ndarray) -> np.ndarray:
    """d (n_dof, m) = t - a p with the modal scale factor a (module docstring).

    test_unit : (n_dof, m) unit-norm real test shapes; model_shapes : (n_dof, m) paired model
    shapes on the same DOFs (any scaling).  A zero model shape leaves d = t (MAC 0)."""
    p = np.asarray(model_shapes, dtype=float)
    pp = np.sum(p * p, axis=0)
    a = np.sum(p * test_unit, axis=0) / np.where(pp > 0, pp, 1.0)
    return test_unit - p * a[None, :]


@dataclass(frozen=True)
class ShapeEvidence:
    """The shape block of a fit's residual vector.

    modes : (k,) 0-based test modes whose shapes count (the modes with weight > 0).
    test_unit : (n_dof, k) their unit-norm real shapes.  scale : (k,) s_i, the optimiser's fixed
    per-mode level (module docstring).  known : s_i is the data's known noise level (not
    integrated out).
    """

    modes: np.ndarray
    test_unit: np.ndarray
    scale: np.ndarray
    known: bool = False

    @property
    def n_dof(self) -> int:
        return int(self.test_unit.shape[0])

    @property
    def dof(self) -> int:
        """Degrees of freedom per mode: n_dof less the fitted scale factor."""
        return self.n_dof - 1

    @property
    def size(self) -> int:
        return int(self.test_unit.size)

    def residuals(self, model_shapes: np.ndarray) -> np.ndarray:
        """(k n_dof,) scaled residuals d_i / s_i, mode after mode.  model_shapes : (n_dof, m_test)
        paired model shapes of all test modes."""
        d = shape_residuals(self.test_unit, np.asarray(model_shapes)[:, self.modes])
        return (d / self.scale[None, :]).T.reshape(-1)

    def rss(self, r: np.ndarray) -> np.ndarray:
        """(k,) R_i = |d_i|^2 from the scaled residuals r (..., k n_dof) -> (..., k)."""
        blocks = np.asarray(r).reshape(*np.shape(r)[:-1], self.scale.size, self.n_dof)
        return np.sum(blocks**2, axis=-1) * self.scale**2

    def fitted_level(self, r: np.ndarray) -> np.ndarray:
        """(k,) the profile noise level sqrt(R_i / dof), floored; the known level if known."""
        if self.known:
            return np.broadcast_to(self.scale, np.shape(r)[:-1] + self.scale.shape)
        return np.maximum(np.sqrt(self.rss(r) / self.dof), SHAPE_SIGMA_FLOOR)

    def chi2(self, r: np.ndarray) -> np.ndarray:
        """(k,) R_i / s_i^2 (with known noise ~ chi^2(dof) per mode under a fitting model)."""
        return self.rss(r) / self.scale**2


def shape_evidence(data, baseline_model_shapes: np.ndarray, used: np.ndarray):
    """ShapeEvidence of ``data`` (ModalData with shapes) or None without shapes.

    baseline_model_shapes : (n_dof, m) the baseline's paired model shapes on ``data.dof_labels``;
    used : (m,) bool modes that count.  s_i = the data's known level (``shape_sd_rel``), else
    the baseline's fitted level of mode i."""
    if data.shapes is None or baseline_model_shapes is None:
        return None
    test = unit_real_shapes(np.asarray(data.shapes))
    finite = np.all(np.isfinite(test), axis=0) & (np.linalg.norm(test, axis=0) > 0)
    modes = np.flatnonzero(np.asarray(used, dtype=bool) & finite)
    if modes.size == 0 or test.shape[0] < 3:
        return None
    if data.shape_sd_rel is not None:
        known = np.asarray(data.shape_sd_rel, dtype=float)[modes] / np.sqrt(test.shape[0])
        return ShapeEvidence(modes, test[:, modes], known, known=True)
    unscaled = ShapeEvidence(modes, test[:, modes], np.ones(modes.size))
    scale = unscaled.fitted_level(unscaled.residuals(baseline_model_shapes))
    return ShapeEvidence(modes, test[:, modes], scale)
