"""The measured mass properties as data in discovery: the same Gaussian terms ``calibrate``'s
likelihood has (``inference.likelihood.LogPosterior``), as residuals in noise units so that the
least-squares fits, their Laplace evidence and their PSIS-LOO see them like the frequencies.

Two kinds of component, both from the calibration problem's objective (``ObjectiveSpec``, built
from the study's ``[data] mass / mass_sd / cg / inertia`` as ``calibrate`` builds it):

* the total mass m against the measured m_T with relative sd s_rel (the data's
  ``mass_sd_rel``): r = ((m - m_T) / m_T) / s_rel, log-density -r^2/2 - log s_rel - log(2 pi)/2
  (``likelihood_blocks.mass_log_likelihood``);
* each measured CG or inertia component p_T with sd s (model units):
  r = (p - p_T) / s, log-density -r^2/2 - log s - log(2 pi)/2
  (``mass_properties.MassPropertyTargets.log_likelihood``).

An effect that adds mass (a point mass at a test point) then pays for the weight it adds: the
frequencies alone cannot tell a missing mass from a missing stiffness elsewhere, a scale can.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.inference.likelihood_blocks import LOG_2PI
from bayesupdate.inference.mass_properties import MassPropertyTargets, mass_properties_function


@dataclass(frozen=True)
class MassBlock:
    """Measured mass properties as likelihood terms (module docstring).

    mass_target : measured total mass [model mass unit] or None; mass_sd_rel : its relative sd
    (None: no mass term).  targets : measured CG / inertia components or None."""

    mass_target: float | None
    mass_sd_rel: float | None
    targets: MassPropertyTargets | None

    @classmethod
    def of(cls, problem) -> "MassBlock | None":
        """The block of a calibration problem: its objective's mass target with the data's
        relative sd (``ModalData.mass_sd_rel``) and its measured CG / inertia; None when
        nothing is measured (or the mass has no sd, as ``calibrate`` leaves it out then)."""
        objective = problem.objective
        target = objective.mass_target_kg
        sd_rel = problem.data.mass_sd_rel if target is not None else None
        if sd_rel is None:
            target = None
        if target is None and objective.mass_properties is None:
            return None
        return cls(target, sd_rel, objective.mass_properties)

    @property
    def has_mass(self) -> bool:
        return self.mass_target is not None

    @property
    def size(self) -> int:
        return int(self.has_mass) + (0 if self.targets is None else len(self.targets.names))

    @property
    def names(self) -> tuple[str, ...]:
        """(size,) component names: "mass", then the CG / inertia components."""
        return ("mass",) * self.has_mass + (() if self.targets is None else self.targets.names)

    @property
    def scale(self) -> np.ndarray:
        """(size,) the sd each residual is measured in (the mass's relative, the others in
        model units): the ``- sum log s`` of the log-density."""
        sd = [self.mass_sd_rel] if self.has_mass else []
        if self.targets is not None:
            sd += list(self.targets.sd)
        return np.asarray(sd, dtype=float)

    def values(self, mass: float | None, properties: np.ndarray | None) -> np.ndarray:
        """(size,) the model's values of the measured components (NaN where not given): its
        total mass and ``MassPropertyTargets.predicted`` values."""
        out = []
        if self.has_mass:
            out.append(np.nan if mass is None else float(mass))
        if self.targets is not None:
            k = len(self.targets.names)
            out += list(np.full(k, np.nan) if properties is None else properties)
        return np.asarray(out, dtype=float)

    def residuals(self, values: np.ndarray | None) -> np.ndarray:
        """(size,) residuals in noise units of the model's ``values`` (None: NaN)."""
        if values is None:
            return np.full(self.size, np.nan)
        v = np.asarray(values, dtype=float)
        out = []
        if self.has_mass:
            out.append((v[0] - self.mass_target) / self.mass_target / self.mass_sd_rel)
        if self.targets is not None:
            out += list((v[int(self.has_mass) :] - self.targets.values) / self.targets.sd)
        return np.asarray(out, dtype=float)

    def pointwise(self, r: np.ndarray) -> np.ndarray:
        """(..., size) Gaussian log-density of each residual r (..., size)."""
        return -0.5 * np.asarray(r) ** 2 - np.log(self.scale) - 0.5 * LOG_2PI

    def log_likelihood(self, r: np.ndarray) -> float:
        """Sum of ``pointwise`` of the residuals r (size,)."""
        return float(np.sum(self.pointwise(r)))

    def at(self, problem, model, params: dict, mass: float | None) -> np.ndarray:
        """(size,) the values of ``model`` (an extended candidate's too) at ``params`` (all its
        parameters) with total mass ``mass`` from its prediction: the CG / inertia from the
        model's own mass properties (``mass_properties_function``; NaN where it fails)."""
        props = None
        if self.targets is not None:
            function = mass_properties_function(model)
            try:
                props = self.targets.predicted(function(params))
            except Exception:  # a failed evaluation scores NaN, as a failed solve does
                props = None
        return self.values(mass, props)


@dataclass(frozen=True)
class WithMassBlock:
    """A frequency / shape likelihood (``likelihood_blocks.FixedNoiseLikelihood``) followed
    by a ``MassBlock``: the residual vector is [inner residuals, mass residuals]."""

    inner: object
    mass: MassBlock

    @property
    def n_frequency(self) -> int:
        return self.inner.n_frequency

    @property
    def size(self) -> int:
        return self.inner.size + self.mass.size

    def residual_vector(self, e, model_shapes, mass_values=None) -> np.ndarray:
        """(size,) the inner residuals of e (m,) and the shapes, then the mass block's of
        ``mass_values`` (``MassBlock.values``; None: NaN)."""
        inner = self.inner.residual_vector(e, model_shapes)
        return np.concatenate([inner, self.mass.residuals(mass_values)])

    def log_likelihood(self, r: np.ndarray) -> float:
        n = self.inner.size
        return self.inner.log_likelihood(r[:n]) + self.mass.log_likelihood(r[n:])

    def pointwise_by_mode(self, r: np.ndarray) -> np.ndarray:
        """(n, m_used + size of the mass block): each used mode's log-likelihood, then each
        measured mass property's, as the observations PSIS-LOO leaves out one at a time."""
        n = self.inner.size
        return np.hstack([self.inner.pointwise_by_mode(r[:, :n]), self.mass.pointwise(r[:, n:])])

    def curvature_weights(self, r: np.ndarray) -> np.ndarray:
        return np.ones(np.asarray(r).size)
