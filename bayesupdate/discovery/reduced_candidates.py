"""Discovery on reduced models: a large FE model's baseline and candidates on certified bases.

A full solve of the shell exhaust takes ~0.5 s wall (9,426 DOFs, mesh density 16), and
discovery on full solves makes one per evaluation: the baseline's multi-start calibration, the
score tests and magnitude grids of 59 candidates, ~40 per quick refit, the full refits (253 on
a three-candidate library with one design variable; docs/guide/exhaust-shell.md).  For an FE
model of at least ``REDUCED_MIN_DOF`` DOFs with shells (``use_reduced``) every phase runs on
reduced models:

1. the design variables get the certified reduced basis of calibration and sampling
   (``fe.reduced.reduced_model_for`` over the problem's box, its modes those the pairing needs,
   tolerance ``TOL`` on seeded validation points);
2. each candidate's extended model gets that basis enriched by the attachment vectors of its
   effect at the baseline optimum (``fe.reduced.enrichment``), projected on the extended model's
   own affine terms: exact in the design variables and the effect's value wherever the span is;
3. every fit whose evidence is compared (baseline, quick and full tiers, the winner's polish)
   is checked by one full solve at its optimum (``certified_fit``): the largest relative
   frequency error there is the fit's ``model_error``; above ``TOL`` the full solve's shapes join
   the basis and the fit is repeated from that point on the enriched basis.

A candidate whose extended model is not free-free (a spring to ground: ``boundary_spring``)
has no reduced form (``fe.reduced``) and keeps full solves.  The score tests and magnitude grids
(a ranking, no evidence) run on the enriched bases without a check of their own.
"""

import warnings
from dataclasses import dataclass, replace

import numpy as np

from bayesupdate.discovery.candidates import Candidate
from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.model import FEModel
from bayesupdate.fe.reduced import ReducedFEModel, ReducedSettings, reduced_model_for
from bayesupdate.fe.reduced.enrichment import (
    ShiftedSolver,
    attachment_vectors,
    effect_change,
    enriched_model,
)

#: FE models with shells and at least this many DOFs run discovery on reduced models
REDUCED_MIN_DOF = 5000
#: relative frequency tolerance of every reduced model discovery uses (as calibration's)
TOL = 1e-4
#: shift s = (2 pi SHIFT_HZ)^2 of the attachment vectors' (K + s M)^-1 (any s > 0 is exact in
#: span for a low-rank change; a few Hz keeps the matrix well conditioned)
SHIFT_HZ = 5.0
#: relative widening of a reduced model's box beyond the parameters' bounds (``widened``)
WIDEN = 1e-9


def use_reduced(model) -> bool:
    """Whether discovery runs ``model`` on reduced models (module docstring)."""
    return (
        isinstance(model, FEModel)
        and model.structure.shells is not None
        and model.structure.n_dof >= REDUCED_MIN_DOF
    )


def widened(bounds: tuple[float, float]) -> tuple[float, float]:
    """(low, high) widened by ``WIDEN`` of the range on each side (a low of 0 stays 0): a start
    on a bound of a log axis comes back from exp(log(x)) a rounding error outside it, where the
    reduced model would hand the point to a full solve."""
    lo, hi = map(float, bounds)
    pad = WIDEN * (hi - lo)
    return (lo if lo == 0 else lo - min(pad, 0.5 * abs(lo)), hi + pad)


def design_box(problem) -> dict[str, tuple[float, float]]:
    """Bounds [SI] of the reduced basis: the calibrated parameters' bounds (``widened``), fixed
    parameters a +-0.1 % box around their value (as ``pipelines.surrogates.sampling_problem``)."""
    bounds = {p.name: widened(p.bounds) for p in problem.parameters}
    for name, value in problem.fixed.items():
        if name in problem.model.parameter_names and value > 0:
            bounds[name] = (value * (1 - 1e-3), value * (1 + 1e-3))
    return bounds


def snapshot_count(n_free: int) -> int:
    """Snapshot and validation points of the design basis for ``n_free`` calibrated
    parameters: 8 + 6 per parameter, at most the reduced model's default 32 (reached at 4); a
    box of one or two thicknesses needs fewer points to be covered as densely."""
    return int(min(32, 8 + 6 * n_free))


def reduced_problem(problem, executor=None):
    """(the problem on the design variables' certified basis, the basis); (problem, None) when
    no certified basis exists (a warning says full solves are used)."""
    points = snapshot_count(len(problem.parameters))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        rom = reduced_model_for(
            problem.model, design_box(problem), tol=TOL, n_modes=problem.pairing.n_model,
            executor=executor, n_snapshots=points, n_validation=points,
        )  # fmt: skip
    if not isinstance(rom, ReducedFEModel) or not rom.certified:
        for w in caught:
            warnings.warn(str(w.message), RuntimeWarning, stacklevel=2)
        return problem, None
    return replace(problem, model=rom), rom


@dataclass(frozen=True, eq=False)
class CandidateReducer:
    """Builds each candidate's enriched reduced model (module docstring, item 2).

    rom : the design variables' basis.  params : the full parameters at the baseline optimum
    (SI).  solver : (K + s M)^-1 there.  modes : (n_dof, n_modes) the baseline's reduced modes
    there."""

    rom: ReducedFEModel
    params: dict
    solver: ShiftedSolver
    modes: np.ndarray

    @classmethod
    def at(cls, rom: ReducedFEModel, problem, theta: np.ndarray) -> "CandidateReducer":
        """The reducer around the baseline optimum theta (d,) of ``problem``."""
        params = rom.fe.full_parameters(problem.as_mapping(theta))
        row = np.array([[params[k] for k in rom.parameter_names]])
        basis = rom.certification.basis
        _, y = basis.eigen(row, rom.n_modes, vectors=True)
        solver = ShiftedSolver(rom.fe, params, (2 * np.pi * SHIFT_HZ) ** 2)
        return cls(rom, params, solver, basis.V @ y[0])

    def reduce(self, candidate: Candidate) -> Candidate:
        """``candidate`` with its extended model on the enriched basis; unchanged (full solves)
        when the extended model has no reduced form (not free-free)."""
        fe, axis = candidate.model, candidate.axes[0]
        params = {**self.params, **candidate.null}
        lo, hi = axis.bounds
        # half the range, into it: the secant of an affine effect is its derivative
        inward = 1.0 if params[axis.name] - lo <= hi - params[axis.name] else -1.0
        step = 0.5 * (hi - lo) * inward
        dK, dM = effect_change(fe, params, axis.name, step)
        basis = self.rom.certification.basis
        vectors = np.concatenate(
            [basis.V[:, basis.n_rigid :], attachment_vectors(self.solver, dK, dM, self.modes)],
            axis=1,
        )
        bounds = {**self.rom.bounds, **{a.name: widened(a.bounds) for a in candidate.axes}}
        settings = ReducedSettings(n_modes=self.rom.n_modes, tol=TOL)
        try:
            reduced = enriched_model(fe, bounds, settings, vectors)
        except BayesUpdateError:  # not free-free (a spring to ground): full solves
            return candidate
        return replace(candidate, model=reduced)


@dataclass(frozen=True)
class Stripped:
    """What remains of a scored candidate's model once it cannot be refitted any more (the
    score keeps its numbers): whether it was on an enriched basis."""

    reduced: bool


def stripped(score):
    """``score`` (a ``localization.CandidateScore``) with its candidate's model replaced by a
    ``Stripped`` marker (frees the extended FE model and its basis, ~60 MB on the shell
    exhaust)."""
    if isinstance(score.candidate.model, Stripped):
        return score
    marker = Stripped(isinstance(score.candidate.model, ReducedFEModel))
    return replace(score, candidate=replace(score.candidate, model=marker))


def on_reduced_basis(model) -> bool:
    """Whether a candidate's model is (or was, before ``stripped``) on an enriched basis."""
    return isinstance(model, ReducedFEModel) or (isinstance(model, Stripped) and model.reduced)


def model_error(problem, theta: np.ndarray):
    """(the problem with its reduced model checked at theta (d,) by a full solve, the largest
    relative frequency error there); (problem, None) on full solves.  A miss (> ``TOL``)
    enriches the basis (``ReducedFEModel.certify_at``)."""
    rom = problem.model
    if not isinstance(rom, ReducedFEModel):
        return problem, None
    params = rom.fe.full_parameters(problem.as_mapping(theta))
    row = np.array([[params[k] for k in rom.parameter_names]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a failed enrichment is reported through the error
        checked, err = rom.certify_at(row)
    return replace(problem, model=checked), float(err)


def certified_fit(fit, refit, rounds: int = 2):
    """``fit`` (a ``ModelFit``) with its ``model_error`` at its optimum (module docstring, item
    3).  refit(space, theta) -> ModelFit fits again from theta on ``space`` after a miss.  On
    full solves the fit is returned as it is."""
    for _ in range(rounds):
        problem, err = model_error(fit.space.problem, fit.theta)
        if err is None:
            return fit
        space = replace(fit.space, problem=problem)
        if not err > TOL or not np.isfinite(err):
            return replace(fit, space=space, model_error=err)
        fit = refit(space, fit.theta)
    problem, err = model_error(fit.space.problem, fit.theta)
    return replace(fit, space=replace(fit.space, problem=problem), model_error=err)
