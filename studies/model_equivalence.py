"""How far apart two explanations of a test are, in units of the test noise (identifiability).

Given a *true* structure's noise-free modes (frequencies f (m,) [Hz] and shapes T (n, m) at the
test DOFs) and a model (the baseline, or the baseline extended by one library effect), fit the
model's parameters theta (design variables plus the effect's parameters) to the truth by least
squares on the whitened residual of the discovery likelihood:

    r_f,i = (f_model,i - f_i) / (f_i sigma_f)                      frequencies, relative sd sigma_f
    r_s,i = (t_i - a_i p_i) / (sigma_s / sqrt(n))                  shapes (``shape_residuals``)

with sigma_s the shape noise as a fraction of a shape's RMS amplitude (so a unit-norm shape's
components carry sd sigma_s / sqrt(n) and noise alone gives 1 - MAC ~ sigma_s^2, as
``modal_data.noisy_modes``).  The minimum D = min_theta |r|^2 / 2 is, for equal noise covariances,
the Kullback-Leibler divergence from the truth's test distribution to the model's best member:
the expected log-likelihood ratio, truth against the model's best fit, that one noisy test
carries.  When D is a nat or two, no test at that noise level can tell the model from the truth,
however the evidence is computed; when D of the baseline is large and D of a candidate is small,
every such test prefers the candidate: an out-of-library truth is then *observationally
equivalent* to that library effect, and naming it is not a failure of the decision rule but a
limit of the data.

A study helper (``hidden_effect_study.divergences``; checked by
tests/test_discovery_equivalence.py): it composes the package's discovery likelihood
(``discovery.evidence.FitSpace``) but no command or pipeline uses it.
"""

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from bayesupdate.discovery.candidates import make_candidate
from bayesupdate.discovery.effects import Effect
from bayesupdate.discovery.evidence import FitSpace
from bayesupdate.discovery.localization import candidate_problem
from bayesupdate.discovery.shape_evidence import unit_real_shapes
from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.likelihood_blocks import NoiseModel, ShapeBlock
from bayesupdate.inference.parameter_space import EvaluationCount
from bayesupdate.inference.problem import build_problem
from bayesupdate.modal_data import ModalData


@dataclass(frozen=True)
class EquivalenceFit:
    """Best fit of one model to a noise-free truth (module docstring).

    names / theta : fitted parameters (SI).  frequency_z : (m,) frequency residuals in noise
    units.  mac_deficit : (m,) 1 - MAC of the fitted model shapes against the truth's.
    shape_chi2 : sum of the whitened shape residuals squared.
    """

    label: str
    names: tuple[str, ...]
    theta: np.ndarray
    frequency_z: np.ndarray
    mac_deficit: np.ndarray
    shape_chi2: float

    @property
    def divergence(self) -> float:
        """D = chi^2_min / 2 [nats]: the expected log-likelihood ratio per test."""
        return 0.5 * (float(np.sum(self.frequency_z**2)) + self.shape_chi2)


def noise_free_modes(prediction, source: str = "noise-free truth") -> ModalData:
    """ModalData of a ``Prediction``'s frequencies and shapes, listed by frequency, no noise."""
    f = np.asarray(prediction.frequencies_hz, dtype=float)
    order = np.argsort(f)
    return ModalData(
        f[order],
        shapes=np.asarray(prediction.shapes, dtype=float)[:, order],
        dof_labels=tuple(prediction.dof_labels),
        source=source,
    )


def _truth_starts(
    model, problem, design: np.ndarray, effect: Effect | None, effect_starts: int
) -> tuple[object, str, list[np.ndarray]]:
    """The problem to fit (extended by ``effect`` when given), its label and its starts (each
    (d,), SI): the design (d_design,) alone for the baseline; with an effect, the design with the
    effect on an ``effect_starts``-per-axis grid inside its z range, then at its null value."""
    if effect is None:
        return problem, "baseline", [design]
    candidate = make_candidate(model, effect)
    problem = candidate_problem(problem, design, candidate)
    grids = [np.linspace(*a.z_bounds, effect_starts + 2)[1:-1] for a in candidate.axes]
    mesh = np.meshgrid(*grids, indexing="ij")
    starts = [
        np.append(design, [a.from_z(z) for a, z in zip(candidate.axes, point, strict=True)])
        for point in zip(*(m.ravel() for m in mesh), strict=True)
    ]
    # the effect at its null value: the baseline's own fit is reachable, so D(candidate)
    # <= D(baseline) up to the optimizer, as it must be for a nested model
    starts.append(np.append(design, [candidate.null[a.name] for a in candidate.axes]))
    return problem, effect.tag, starts


def _truth_likelihood(
    truth: ModalData, frequency_noise: float, shape_noise: float
) -> tuple[NoiseModel, ShapeBlock]:
    """The discovery likelihood's own whitening for the m modes of ``truth``: fixed relative
    frequency sd ``frequency_noise`` [-], and a shape block with the stated level
    ``shape_noise`` / sqrt(n) per component of a unit-norm shape (``shape_evidence``)."""
    m = truth.n_modes
    noise = NoiseModel(np.full(m, frequency_noise), np.ones(m), False, "fixed", frequency_noise)
    test_unit = unit_real_shapes(np.asarray(truth.shapes))
    shape_sd = shape_noise / np.sqrt(test_unit.shape[0])
    return noise, ShapeBlock(np.arange(m), test_unit, np.full(m, shape_sd))


def _best_least_squares(space: FitSpace, starts: list[np.ndarray]):
    """The ``scipy.optimize.least_squares`` result (in the unit box) with the smallest cost
    over the starts (each (d,), SI); the first start wins ties."""
    # a failed solve: a 1000 % error in noise units (parameter_space.FAILED_RELATIVE_ERROR)
    residual = space.unit_box_residuals(EvaluationCount())
    best = None
    for theta0 in starts:
        u0 = np.clip(space.u_from_theta(theta0), 0.0, 1.0)
        fit = least_squares(residual, u0, bounds=(0.0, 1.0), x_scale=0.1)
        if best is None or fit.cost < best.cost:
            best = fit
    return best


def fit_to_truth(
    model,
    truth: ModalData,
    design_start: dict,
    effect: Effect | None = None,
    frequency_noise: float = 0.003,
    shape_noise: float = 0.03,
    effect_starts: int = 7,
) -> EquivalenceFit:
    """Fit ``model`` (extended by ``effect`` when given: its parameters are fitted too) to the
    noise-free ``truth`` (ModalData with shapes), design variables started at ``design_start``
    {name: SI value}, the effect at ``effect_starts`` points spread over its axis (log axes in
    log) and at its null value.  Returns the best of these least-squares fits (module
    docstring)."""
    if truth.shapes is None:
        raise BayesUpdateError("equivalence: the truth needs mode shapes")
    if not (frequency_noise > 0 and shape_noise > 0):
        raise BayesUpdateError("equivalence: frequency_noise and shape_noise must be > 0")
    problem = build_problem(model, truth, None, pairing="mac")
    design = np.array([design_start[p.name] for p in problem.parameters], dtype=float)
    problem, label, starts = _truth_starts(model, problem, design, effect, effect_starts)
    noise, shapes = _truth_likelihood(truth, frequency_noise, shape_noise)
    space = FitSpace(problem, problem.parameters, noise, shapes)
    best = _best_least_squares(space, starts)
    theta = space.parameter_space.theta_from_u(best.x)
    r = best.fun
    m = truth.n_modes
    return EquivalenceFit(
        label=label,
        names=tuple(problem.names),
        theta=theta,
        frequency_z=r[:m],
        mac_deficit=shapes.rss(r[m:]),  # |d_i|^2 = 1 - MAC_i
        shape_chi2=float(np.sum(r[m:] ** 2)),
    )
