"""Mode shapes as evidence: how discovery sets the level of each mode in the shape block
(``inference.likelihood_blocks.ShapeBlock``) before any fit, so that no single mode can drag the
design variables away from what the frequencies say, and how it counts modes off their stated
level.

Test mode i has the real, unit-norm shape t_i (n,) on the test's sensor DOFs (complex identified
shapes are rotated to their best-fit real line first, ``ema.lsfd.realize``; ``unit_real_shapes``).
The block's residual is d_i = t_i - a_i p_i, |d_i|^2 = 1 - MAC(t_i, p_i), with independent
N(0, sigma_i^2) components (``ShapeBlock``, after Vanik, Beck & Au 2000 and Yuen 2010 ch. 6), and
its level is held fixed:

    sigma_i = s_i,  s_i = max(sd_i, SHAPE_SD_FLOOR_REL) / sqrt(n),  unless R_i / s_i^2 rejects
    chi^2(n - 1) at level ``STATED_REJECTION`` (1 %); then sigma_i = sqrt(R_i / (n - 1)),

* sd_i is the data's ``shape_sd_rel`` (identification estimates it from the LSFD fit; a virtual
  test states it), floored at ``SHAPE_SD_FLOOR_REL`` = 1 % of the shape's RMS amplitude: sensor
  sensitivity and orientation errors of about 1 % (the calibration uncertainty of ordinary
  accelerometers) and the FE discretization of a shape leave no test-model difference below it
  that is physics.  Without it a near-perfect mode (1 - MAC ~ 1e-6 on the virtual test) gets a
  level so small that a 0.04 % frequency shift of all modes buys a better shape fit of it: that is
  how the former per-mode integrated level dragged the baseline on identified data (the null case
  of ``tests/test_discovery_cli.py``);
* R_i = |d_i|^2 at the frequency-only baseline calibration (the eq. 19 optimum, which shapes have
  not touched): a mode whose misfit there rejects its stated level carries identification bias the
  stated sd does not cover (on the virtual roving-hammer test, modes whose reference accelerometer
  barely moves: their V and H sets cannot be scaled to each other; 1 - MAC ~ 6e-3 to 8e-3, tens to
  hundreds of times the LSFD estimate).  Its level becomes its own misfit (the plug-in estimate of
  that mode's prediction-error variance at a point the shapes did not choose), so its chi^2 at the
  baseline is n - 1 and any model, an effect included, gains at most (n - 1) / 2 nats from it,
  however large the bias.  Modes the stated level covers keep it, and a misfit elsewhere (an
  effect the frequencies alone cannot see) counts in full against it.

With the level fixed, c_i = R_i / sigma_i^2 ~ chi^2(n - 1) under a model that fits (one degree of
freedom goes to the fitted scale factor), and the adequacy check (``flagging.flag_modes``) tests it.
Raising hides a mode's misfit from that per-mode test, so the check also counts the modes whose
misfit rejects their *stated* level: identification fails for a few modes (those its reference
barely sees; ``FAILURE_RATE`` = 10 % is our stated prior rate), while a change the model lacks (a
longer pipe) puts most shapes off at once.  More rejections than that rate explains (binomial
tail below the adequacy level) flags them all: physics, not identification.
"""

from dataclasses import dataclass

import numpy as np
from scipy import stats

from bayesupdate.ema.lsfd import realize
from bayesupdate.inference.likelihood_blocks import ShapeBlock, shape_residuals

#: smallest shape noise as a fraction of a shape's RMS amplitude [-] (module docstring)
SHAPE_SD_FLOOR_REL = 0.01
#: a misfit "rejects its stated level" when P(chi^2(n - 1) > R / s^2) is below this: at the
#: frequency-only baseline it raises the level to the misfit, at a fit it counts towards the
#: adequacy check (module docstring); 1 %: raising only ever costs evidence, so err towards it
STATED_REJECTION = 0.01
#: the rate at which identification misses a mode shape's stated accuracy (module docstring)
FAILURE_RATE = 0.1


def unit_real_shapes(shapes: np.ndarray) -> np.ndarray:
    """(n_dof, m) real or complex shapes -> real shapes with unit Euclidean norm per column."""
    real = realize(shapes) if np.iscomplexobj(shapes) else np.asarray(shapes, dtype=float)
    norm = np.linalg.norm(real, axis=0)
    return real / np.where(norm > 0, norm, 1.0)[None, :]


@dataclass(frozen=True)
class ShapeEvidence(ShapeBlock):
    """The shape block of a discovery fit with the record of how its levels were set.

    modes, test_unit, scale : as ``ShapeBlock`` (scale: each mode's fixed level, module
    docstring).  stated : (k,) the stated (floored) level before any raise (None: ``scale``).
    source : what the stated level came from ("data sd" or "floor" when the data give none).
    """

    stated: np.ndarray | None = None
    source: str = "data sd"

    @property
    def raised(self) -> np.ndarray:
        """(k,) bool: the modes whose level was raised to their baseline misfit."""
        if self.stated is None:
            return np.zeros(self.scale.size, dtype=bool)
        return self.scale > self.stated

    def stated_rejections(self, r: np.ndarray) -> np.ndarray:
        """(..., k) bool: each mode's misfit in the residuals r rejects its stated level."""
        stated = self.scale if self.stated is None else self.stated
        return rejects_stated(self.rss(r), stated, self.dof)


def shape_evidence(data, baseline_model_shapes: np.ndarray, used: np.ndarray):
    """ShapeEvidence of ``data`` (ModalData with shapes) or None without shapes.

    baseline_model_shapes : (n_dof, m) the paired model shapes on ``data.dof_labels`` at the
    frequency-only baseline calibration; used : (m,) bool modes that count.  Each mode's level
    is the larger of its stated level and its misfit there (module docstring)."""
    if data.shapes is None or baseline_model_shapes is None:
        return None
    test = unit_real_shapes(np.asarray(data.shapes))
    finite = np.all(np.isfinite(test), axis=0) & (np.linalg.norm(test, axis=0) > 0)
    modes = np.flatnonzero(np.asarray(used, dtype=bool) & finite)
    if modes.size == 0 or test.shape[0] < 3:
        return None
    n = test.shape[0]
    stated = np.zeros(modes.size) if data.shape_sd_rel is None else data.shape_sd_rel[modes]
    floor = np.maximum(stated, SHAPE_SD_FLOOR_REL) / np.sqrt(n)
    d = shape_residuals(test[:, modes], np.asarray(baseline_model_shapes)[:, modes])
    rss = np.sum(d**2, axis=0)
    rss = np.where(np.isfinite(rss), rss, 0.0)  # a missing model shape: keep the stated level
    level = np.where(rejects_stated(rss, floor, n - 1), np.sqrt(rss / (n - 1)), floor)
    source = "data sd" if data.shape_sd_rel is not None else "floor"
    return ShapeEvidence(modes, test[:, modes], level, stated=floor, source=source)


def rejects_stated(rss: np.ndarray, stated: np.ndarray, dof: int) -> np.ndarray:
    """(..., k) bool: R / s^2 rejects chi^2(dof) at ``STATED_REJECTION``; rss (..., k) = |d|^2,
    stated (k,) the per-component level."""
    return stats.chi2.sf(rss / stated**2, dof) < STATED_REJECTION
