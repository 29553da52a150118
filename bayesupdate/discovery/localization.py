"""Localize: where on the structure the flagged modes differ from the unflagged ones.

Three views, each a ranked list:

1. **Sensitivity (score test).**  Each candidate effect is probed by one small step dz (2 % of
   its z range, ``candidates``) from its null value at the baseline optimum: g = dr/dz, the
   change of the residuals in noise units (frequencies, and the shape residuals of
   ``shape_evidence`` when the test has shapes).  Since the design variables are re-fitted with the
   effect, only the part of g outside their span counts: g_perp = (I - J_d J_d^+) g (J_d: their
   Jacobian at the optimum).  The one linear step alpha = -g_perp.r / |g_perp|^2 (clipped to the
   effect's bounds) predicts the drop in chi^2 = |r|^2 - |r + alpha g_perp|^2: the Lagrange
   multiplier (score) statistic of adding the effect (Rao 1948), computed with two model solves
   per candidate.  Large effects lie outside the linear range, so each candidate is also
   screened on a grid of magnitudes (15, 40, 100 % of the way from null to each bound) with one
   linear design-variable correction there: the candidate's score is the larger of the two
   predicted chi^2 drops, and its start value the magnitude that gave it (3-6 more solves).
2. **Modal energies.**  Strain and kinetic energy share of every part in the flagged modes minus
   the mean share in the unflagged modes (seed section 3.2): the parts the flagged modes work
   harder.
3. **COMAC** (when the test has shapes): sensor DOFs where test and model shapes disagree over
   the paired modes (Lieven & Ewins 1988).
"""

from dataclasses import dataclass, replace

import numpy as np

from bayesupdate.compute.executors import executor_or_serial
from bayesupdate.compute.progress import phase
from bayesupdate.correlation import comac
from bayesupdate.discovery.candidates import Candidate
from bayesupdate.discovery.mass_block import MassBlock
from bayesupdate.fe.reduced import ReducedFEModel
from bayesupdate.inference.parameter_space import ParameterSpec
from bayesupdate.inference.problem import build_problem

#: probe step as a fraction of the effect parameter's z range
PROBE_FRACTION = 0.02
#: grid screen magnitudes, fractions of the way from the null value to a bound
SCREEN_FRACTIONS = (0.05, 0.15, 0.3, 0.5, 0.7, 0.85, 1.0)
#: kinds whose null value reproduces the model without the effect exactly
EXACT_NULL_KINDS = ("added_mass", "boundary_spring", "bend_flexibility", "stiffness_change")
#: the progress phase of the score tests, one step per candidate effect (``compute.progress``)
CANDIDATES_PHASE = "discovery: candidates (score tests)"


@dataclass(frozen=True)
class CandidateScore:
    """Score test of one candidate.

    delta_chi2 : predicted chi^2 drop (in units of the noise: the data's, a fixed or the inferred
    robust level). step_theta : the effect parameter after the linear step (SI; a refit start).
    sensitivity : (m_used,) g_perp.
    """

    candidate: Candidate
    delta_chi2: float
    step_theta: float
    sensitivity: np.ndarray

    @property
    def label(self) -> str:
        return self.candidate.label


@dataclass(frozen=True)
class Localization:
    """Ranked views (module docstring).

    scores : CandidateScore, best first.  locations : [(location, best delta_chi2, kind)] best
    first.  part_energy : [(part, strain excess, kinetic excess)] largest first.
    comac : {sensor label: COMAC} (empty without test shapes).  positions : {location: xyz}.
    """

    scores: list
    locations: list
    part_energy: list
    comac: dict
    positions: dict


def candidate_problem(baseline_problem, design_theta, candidate: Candidate):
    """The calibration problem of ``candidate``: design variables (bounds, priors as in the
    baseline; start at the baseline optimum) plus the effect parameters (start at null)."""
    specs = (
        tuple(
            replace(p, start=float(t))
            for p, t in zip(baseline_problem.parameters, design_theta, strict=True)
        )
        + candidate.axes
    )
    # the same test modes (source numbers) and model modes as the baseline's: a candidate
    # pairs what the baseline pairs
    numbers = baseline_problem.mode_numbers
    return build_problem(
        candidate.model,
        baseline_problem.data,
        specs,
        pairing=baseline_problem.pairing.method,
        extra_modes=baseline_problem.pairing.n_model - int(numbers.max()),
        objective=baseline_problem.objective,
        test_modes=tuple(int(n) for n in numbers),
    )


def full_model(model):
    """The FE model behind a reduced one (``ReducedFEModel.fe``), else ``model`` itself."""
    return model.fe if isinstance(model, ReducedFEModel) else model


def _probe(axis: ParameterSpec, null: float) -> tuple[float, float]:
    """(z_null, dz): a step into the admissible range."""
    z_lo, z_hi = axis.z_bounds
    z0 = float(axis.to_z(null))
    dz = PROBE_FRACTION * (z_hi - z_lo)
    return z0, (dz if z0 + dz <= z_hi else -dz)


def _paired_prediction(problem, model, params) -> tuple | None:
    """(test-ordered frequencies (m,), paired model shapes (n_dof, m) on the test DOFs or None,
    the mass block's values (``mass_block.MassBlock.at``) or None) of ``model`` at ``params``
    under ``problem``'s pairing; with "order" pairing a direct solve (no calibration problem
    needed).  None where it fails."""
    n_test = problem.data.n_modes
    block = MassBlock.of(problem)
    try:
        if problem.pairing.method == "order":
            prediction = model.predict(params, n_modes=n_test)
            f = np.asarray(prediction.frequencies_hz, dtype=float)
            if not (f.size >= n_test and np.all(np.isfinite(f))):
                return None
            paired_f, shapes = f[:n_test], None
        else:
            from bayesupdate.inference.pairing import pair_modes

            prediction = model.predict(params, n_modes=problem.pairing.n_model)
            paired = pair_modes(prediction, problem.pairing)
            paired_f = np.asarray(prediction.frequencies_hz, dtype=float)[paired.model_index]
            shapes = paired.shapes
        masses = None if block is None else block.at(problem, model, params, prediction.mass_kg)
        return paired_f, shapes, masses
    except Exception:  # a failed probe scores zero; it is reported, not fatal
        return None


def _at_null(problem, candidate, design_theta, params) -> tuple | None:
    """``_paired_prediction`` at the candidate's null ``params``: the baseline model itself where
    that null reproduces it exactly (full models of ``EXACT_NULL_KINDS``), else the candidate's
    model (a joint's null only approximates it; a reduced candidate compares on its own basis)."""
    if candidate.effect.kind in EXACT_NULL_KINDS and not isinstance(
        candidate.model, ReducedFEModel
    ):
        theta = problem.as_mapping(np.asarray(design_theta, float))
        return _paired_prediction(problem, full_model(problem.model), theta)
    return _paired_prediction(problem, candidate.model, params)


def score_candidate(baseline_problem, design_theta, design_jac, residuals_fn, candidate):
    """Score test of a candidate along its first parameter (module docstring, item 1).

    residuals_fn(e, shapes, masses) -> residuals in noise units (``FitSpace.residual_vector``)
    from the relative frequency errors e (m,), the paired model shapes (or None) and the mass
    block's values (or None: the study measured no mass properties).
    design_jac : (size, d) J_d of the same residuals.
    One model solve for kinds whose null value reproduces the model exactly (added mass, spring,
    factors), two for a joint (its null only approximates two different bending stiffnesses) and
    for a candidate on a reduced basis (both ends of the difference on the same basis).
    """
    axis = candidate.axes[0]
    null = candidate.null[axis.name]
    f_test = baseline_problem.data.frequencies_hz
    params = baseline_problem.as_mapping(np.asarray(design_theta, float))
    params.update(candidate.null)

    def residuals(paired):
        f, shapes, masses = paired
        return residuals_fn((f - f_test) / f_test, shapes, masses)

    at_null = _at_null(baseline_problem, candidate, design_theta, params)
    z0, dz = _probe(axis, null)
    params[axis.name] = float(axis.from_z(z0 + dz))
    at_step = _paired_prediction(baseline_problem, candidate.model, params)
    if at_null is None or at_step is None:
        return CandidateScore(candidate, 0.0, null, np.zeros(design_jac.shape[0]))
    r0 = residuals(at_null)
    g = (residuals(at_step) - r0) / dz
    pinv = np.linalg.pinv(design_jac)
    g_perp = g - design_jac @ (pinv @ g)
    r_perp = r0 - design_jac @ (pinv @ r0)
    gg = float(g_perp @ g_perp)
    if gg <= 0 or not np.isfinite(gg):
        return CandidateScore(candidate, 0.0, null, g_perp)
    z_lo, z_hi = axis.z_bounds
    alpha = float(np.clip(-(g_perp @ r_perp) / gg, z_lo - z0, z_hi - z0))
    drop = float(r_perp @ r_perp - np.sum((r_perp + alpha * g_perp) ** 2))
    step_theta = float(axis.from_z(z0 + alpha))
    # grid screen: large effects are far outside the linear range of the score test, and the
    # baseline that absorbed them sits far from the truth.  Evaluate the effect at a few
    # magnitudes and correct the design variables by one linear least-squares step there.
    for z in screen_grid(axis, z0):
        params[axis.name] = float(axis.from_z(z))
        paired = _paired_prediction(baseline_problem, candidate.model, params)
        if paired is None:
            continue
        r = residuals(paired)
        if not np.all(np.isfinite(r)):
            continue
        r = r - design_jac @ (pinv @ r)
        grid_drop = float(r_perp @ r_perp - r @ r)
        if grid_drop > drop:
            drop, step_theta = grid_drop, float(axis.from_z(z))
    return CandidateScore(candidate, max(drop, 0.0), step_theta, g_perp)


def screen_grid(axis: ParameterSpec, z0: float) -> list[float]:
    """Magnitudes of the grid screen: ``SCREEN_FRACTIONS`` (5 % ... 100 %) of the way from the
    null value to each bound that is not the null itself (7 points one-sided, 14 two-sided).
    Dense enough that a mid-range effect (a joint at 1e3 N m/rad, 3/4 of the log range from
    rigid; a 5 kN/m spring, 5 % of its range) has a grid start in its basin: one model solve
    each (~5 ms), against local refits that stall in the baseline's basin otherwise."""
    z_lo, z_hi = axis.z_bounds
    out = []
    for bound in (z_lo, z_hi):
        if abs(bound - z0) > 1e-9 * (z_hi - z_lo):
            out.extend(z0 + f * (bound - z0) for f in SCREEN_FRACTIONS)
    return out


def _position(structure, kind: str, location: str) -> np.ndarray:
    """A representative point [m] of a location (sensor point, part, joint or bend; a deck's
    line property: the mean of its elements' nodes)."""
    s = structure
    if kind in ("added_mass", "boundary_spring"):
        for label, node in zip(s.sensor_labels, s.sensor_node, strict=True):
            if label.rstrip("VHvh") == location:
                return s.nodes[int(node)]
    if kind == "bend_flexibility" and location in s.bends:
        nodes = s.beam_nodes[s.beam_bend == s.bends.index(location)]
        return s.nodes[np.unique(nodes)].mean(axis=0)
    if location in s.parts:
        pid = s.parts.index(location)
        lines = [f.nodes[f.part == pid].ravel() for f in (s.general_beams, s.rods) if f is not None]
        nodes = np.concatenate(
            [s.beam_nodes[s.beam_part == pid].ravel(), s.spring_nodes[s.spring_part == pid].ravel()]
            + lines
        )
        nodes = nodes[nodes >= 0]
        if nodes.size:
            return s.nodes[np.unique(nodes)].mean(axis=0)
    return np.full(3, np.nan)


def energy_excess(model, design_params: dict, model_modes: np.ndarray, flagged: np.ndarray):
    """[(part, strain excess, kinetic excess)] largest strain excess first.

    model_modes : (m,) 0-based model mode paired with each test mode; flagged : (m,) bool.
    Excess = mean share over flagged modes - mean share over unflagged modes.
    """
    if not np.any(flagged) or not hasattr(model, "solve"):
        return []
    n = int(np.max(model_modes)) + 1
    energies = model.solve(design_params, n_modes=n, energies=True).energies
    strain = energies.strain_by_part[:, model_modes]
    kinetic = energies.kinetic_by_part[:, model_modes]

    def excess(share):
        rest = share[:, ~flagged].mean(axis=1) if np.any(~flagged) else 0.0
        return share[:, flagged].mean(axis=1) - rest

    s_ex, k_ex = excess(strain), excess(kinetic)
    order = np.argsort(-s_ex)
    return [(energies.parts[i], float(s_ex[i]), float(k_ex[i])) for i in order]


def shape_comac(problem, theta, evaluation) -> dict:
    """{sensor label: COMAC} of test vs paired model shapes (empty without test shapes)."""
    data = problem.data
    if data.shapes is None or evaluation.paired is None:
        return {}
    from bayesupdate.inference.pairing import shapes_at

    prediction = problem.model.predict(problem.as_mapping(theta), n_modes=problem.pairing.n_model)
    model_shapes = shapes_at(prediction, data.dof_labels, "COMAC")[:, evaluation.paired.model_index]
    values = comac(np.real(data.shapes), model_shapes)
    return dict(zip(data.dof_labels, map(float, values), strict=True))


def score_task(shared, candidate):
    """``score_candidate`` of one candidate (an executor task; shared: the baseline problem,
    design theta, design Jacobian and residuals_fn)."""
    return score_candidate(*shared, candidate)


def localize(
    baseline_problem,
    design_theta,
    design_jac,
    residuals_fn,
    candidates: list[Candidate],
    model_modes: np.ndarray,
    flagged: np.ndarray,
    executor=None,
    scored: list | None = None,
) -> Localization:
    """All three views (module docstring).  residuals_fn and design_jac are in noise units
    (``score_candidate``), so the chi^2 drops are too.  The score tests run on ``executor``
    (``compute.executors``; None: serially); residuals_fn must then be picklable.  scored : the
    candidates' ``CandidateScore`` made by the caller (then ``candidates`` is not scored)."""
    shared = (baseline_problem, design_theta, design_jac, residuals_fn)
    if scored is None:
        with phase(CANDIDATES_PHASE, len(candidates), "candidates") as shown:
            scored = executor_or_serial(executor).map(
                score_task, candidates, shared, shown.progress_callback()
            )
    scores = list(scored)
    scores.sort(key=lambda s: -s.delta_chi2)
    fe = full_model(baseline_problem.model)
    structure = fe.structure if hasattr(fe, "structure") else None
    best_at: dict[str, tuple[float, str]] = {}
    positions = {}
    for s in scores:
        loc, kind = s.candidate.effect.location, s.candidate.effect.kind
        if loc not in best_at or s.delta_chi2 > best_at[loc][0]:
            best_at[loc] = (s.delta_chi2, kind)
        if structure is not None and loc not in positions:
            positions[loc] = _position(structure, kind, loc).tolist()
    locations = sorted(((k, v[0], v[1]) for k, v in best_at.items()), key=lambda t: -t[1])
    params = baseline_problem.as_mapping(np.asarray(design_theta, float))
    part_energy = energy_excess(fe, params, model_modes, flagged)
    theta = np.asarray(design_theta, float)
    evaluation = baseline_problem.evaluate(theta)
    shape_view = shape_comac(baseline_problem, theta, evaluation)
    return Localization(scores, locations, part_energy, shape_view, positions)
