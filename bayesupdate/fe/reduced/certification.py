"""Certification of a reduced basis against full solves, and its enrichment.

Reduced frequencies are Rayleigh-Ritz values, hence upper bounds of the full ones
(Courant-Fischer); the relative error is one-sided, so a reduced value *below* a full one can only
come from the interpolation of the affine terms, and is treated as such (an error asking for a
finer interpolation).  Fresh seeded validation points are solved in full; while the largest
relative frequency error exceeds ``tol`` the validation shapes join the snapshots, the POD
threshold is lowered and a new validation set is drawn.  If ``max_size`` is reached first, the
model warns and falls back to full solves.  Extra points (e.g. an optimum) are checked the same
way (``certify_points``); a miss there enriches the basis with their shapes.
"""

import warnings
from dataclasses import dataclass, replace

import numpy as np
from scipy.stats import qmc

from bayesupdate import __version__
from bayesupdate.compute.cache import ArrayStore, content_key
from bayesupdate.compute.progress import phase
from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.reduced.affine import (
    check_separable,
    coefficient_arrays,
    coefficient_map,
    decompose,
)
from bayesupdate.fe.reduced.basis import ReducedBasis, full_solves, pod_basis
from bayesupdate.fe.reduced.estimator import ResidualIndicator

# ``model`` below is a ``fe.reduced.model.ReducedFEModel``: not imported, not even for type
# checking, since that module imports this one (tests/test_no_import_cycle.py)


@dataclass(frozen=True)
class Certificate:
    """What the certification found: largest relative frequency error over ``n_points`` full solves
    (validation set plus checked points), the smallest signed error (>= ~0 by Rayleigh-Ritz)."""

    max_rel_error: float
    min_signed_error: float
    n_points: int


@dataclass(frozen=True)
class BuildRound:
    """One round of the build: basis size, error on its validation set, POD threshold."""

    round: int
    size: int
    max_rel_error: float
    pod_tol: float


@dataclass(frozen=True, eq=False)
class Certification:
    """A basis and what its certification found (a ``ReducedFEModel`` holds one).

    basis : None before the build.  certified : False -> every prediction is a full solve.
    max_rel_error : certified relative frequency error.  history : the build's rounds.
    checked : (theta (k, n_params), full frequencies (k, n_modes) [Hz]) of every point set the
    basis was certified on, re-verified when the basis is enriched.
    """

    basis: ReducedBasis | None
    certificate: Certificate
    certified: bool
    max_rel_error: float
    history: tuple[BuildRound, ...] = ()
    checked: tuple[tuple[np.ndarray, np.ndarray], ...] = ()


#: a model not built yet
UNBUILT = Certification(None, Certificate(np.inf, 0.0, 0), False, np.inf)


def compare(basis: ReducedBasis, theta: np.ndarray, f_full: np.ndarray, n_modes: int):
    """``Certificate`` of the basis at theta (k, n_params) against full frequencies f_full
    (k, n_modes) [Hz]; rows with a failed full solve (NaN) are left out."""
    ok = np.all(np.isfinite(f_full), axis=1)
    lam = basis.eigen(theta[ok], n_modes)
    f_rom = np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)
    signed = f_rom / f_full[ok] - 1.0
    return Certificate(float(np.max(np.abs(signed))), float(np.min(signed)), int(ok.sum()))


def build(model, executor=None, store: ArrayStore | None = None) -> Certification:
    """Decompose, snapshot, compress, certify, enrich (module docstring) over ``model``'s box
    with its settings; warns and returns an uncertified result when ``max_size`` is reached.
    The snapshot and validation solves run on ``executor`` (None: in this process).  A certified
    basis is kept in ``store`` (``compute.cache``; None: the environment's) under the content of
    the model's terms, box and settings (``_cache_key``), and a later build of the same content
    reads the projected terms and their coefficient map back, neither decomposing nor projecting
    again, and re-certifies them at ``RECHECK_POINTS`` fresh points (full solves)."""
    fe, st = model.fe, model.settings
    centre = model.mapping(model.centre())
    _check_free_free(fe, centre)
    store = ArrayStore.from_environment() if store is None else store
    key = _cache_key(model, centre) if store.enabled else ""
    cached = _load(model, store.load(key), executor) if key else None
    if cached is not None:
        return cached
    decomposition = decompose(fe, model.bounds, st.interp_tol)
    result = _build(model, decomposition, centre, executor)
    if key and result.certified:
        store.save(key, _arrays(result))
    return result


def _build(model, decomposition, centre, executor) -> Certification:
    fe, names = model.fe, model.parameter_names
    st = model.settings.resolved(fe.structure.n_dof)
    dim = len(names)
    snap_theta = model.scale(qmc.Sobol(dim, scramble=True, seed=st.seed).random(st.n_snapshots))
    n_snap = st.n_modes + st.extra_modes
    what = "reduced basis: snapshots"
    sens = decomposition if st.sensitivities else None
    snaps = _snapshots(fe, names, snap_theta, n_snap, (executor, what, sens))[1]
    pod_tol = (SENSITIVE_POD if st.sensitivities else 0.5) * st.tol
    if st.greedy_train:
        snaps, pod_tol = _greedy(model, st, decomposition, (centre, snaps, pod_tol), executor)
    history = []
    certificate = UNBUILT.certificate
    for rnd in range(st.max_rounds):
        basis = pod_basis(fe, decomposition, centre, snaps, pod_tol, st.n_modes)
        if basis.size > st.max_size:
            break
        sobol = qmc.Sobol(dim, scramble=True, seed=st.seed + 1000 + rnd)
        theta_v = model.scale(sobol.random(st.n_validation))
        what = f"reduced basis: certification (round {rnd + 1})"
        f_full, shapes_v = full_solves(fe, names, theta_v, st.n_modes, executor, what)
        certificate = compare(basis, theta_v, f_full, st.n_modes)
        history.append(BuildRound(rnd, basis.size, certificate.max_rel_error, pod_tol))
        _check_upper_bound(certificate, st.tol)
        if certificate.max_rel_error <= st.tol:
            checked = ((theta_v, f_full),)
            err = certificate.max_rel_error
            return Certification(basis, certificate, True, err, tuple(history), checked)
        snaps = np.concatenate([snaps, shapes_v], axis=1)
        pod_tol *= 0.25
    err = certificate.max_rel_error
    failed = Certification(basis, certificate, False, err, tuple(history))
    _warn_failed(model, failed, stacklevel=5)  # the caller of ReducedFEModel.build
    return failed


#: first POD threshold / tol with sensitivities: the threshold bounds the discarded energy per
#: snapshot column on average, and each mode then brings n_params + 1 columns, so the plain
#: 0.5 x tol admits several times more discarded energy per mode.  Measured on the shell
#: exhaust at density 16: with 0.5 the first validation round failed (9.9e-4), with 0.125 it
#: passed (7.1e-5), 40 full solves in all against 72 (``docs/validation/shells-reduced.md``)
SENSITIVE_POD = 0.125


def _snapshots(fe, names, theta, n_modes: int, how):
    """``full_solves`` at snapshot points; how: (executor, progress name, decomposition for
    sensitivities or None).  Without sensitivities the call is the plain one."""
    executor, what, sens = how
    if sens is None:
        return full_solves(fe, names, theta, n_modes, executor, what)
    return full_solves(fe, names, theta, n_modes, executor, what, sensitivities=sens)


#: points full-solved per greedy step (where the residual indicator is largest)
GREEDY_BATCH = 4
#: the greedy stops when the error at those points is below this fraction of tol
GREEDY_MARGIN = 0.5


def _greedy(model, st, decomposition, start, executor):
    """Enrich the snapshots where the residual indicator (``reduced.estimator``) is largest on
    ``greedy_train`` seeded training points, ``GREEDY_BATCH`` full solves (with sensitivities)
    per step, until the error at the chosen points is below ``GREEDY_MARGIN`` x tol (at most
    ``max_rounds`` steps): the validation rounds that follow, which certify, then rarely fail.
    st : the resolved settings; start : (centre, snapshots (n_dof, k), POD threshold).
    Returns (snapshots, POD threshold)."""
    fe, names = model.fe, model.parameter_names
    centre, snaps, pod_tol = start
    sobol = qmc.Sobol(len(names), scramble=True, seed=st.seed + 500)
    train = model.scale(sobol.random(st.greedy_train))
    indicator = ResidualIndicator(fe, centre)
    sens = decomposition if st.sensitivities else None
    for step in range(st.max_rounds):
        basis = pod_basis(fe, decomposition, centre, snaps, pod_tol, st.n_modes)
        if basis.size > st.max_size or train.shape[0] < GREEDY_BATCH:
            break
        with phase(f"reduced basis: residual indicator (step {step + 1})", None, "points"):
            eta = indicator(basis, train, names, st.n_modes)
        worst = np.argsort(eta)[::-1][:GREEDY_BATCH]
        what = f"reduced basis: greedy snapshots (step {step + 1})"
        n_snap = st.n_modes + st.extra_modes
        f_full, shapes = _snapshots(fe, names, train[worst], n_snap, (executor, what, sens))
        err = compare(basis, train[worst], f_full[:, : st.n_modes], st.n_modes).max_rel_error
        snaps = np.concatenate([snaps, shapes], axis=1)
        train = np.delete(train, worst, axis=0)
        if err <= GREEDY_MARGIN * st.tol:
            break
        pod_tol *= 0.25
    return snaps, pod_tol


#: fresh points a basis loaded from the cache is checked at before use (full solves).  The
#: entry's checksum has matched (``compute.cache``: a truncated or altered file is refused
#: before this), and its key holds the assembled K, M at the centre and ``_KEY_POINTS`` other
#: points (``_cache_key``), so the check guards a model that differs only away from those: one
#: fresh point sees any element, material or parameter action such a change touches, as the
#: key's own points do.  A stored basis whose terms or vectors are off is refused there
#: (``tests/test_reduced_recheck.py``: a 0.2 % scaled stiffness term, a basis cut to 6 vectors).
#: One point, not 4: each is a full solve, ~1.5 s of CPU on the shell exhaust's 28,386 DOFs
RECHECK_POINTS = 1
#: the seed offset of those points (the build's validation sets use seed + 1000 + round)
_RECHECK_SEED = 7919
#: format of a cached basis; bump when the stored arrays change meaning
_CACHE_FORMAT = "reduced-basis-2"
#: seed of the box points whose assembled K, M join the key (besides the centre)
_KEY_SEED = 3571
#: how many such points
_KEY_POINTS = 2


def basis_key(model) -> str:
    """The key a certified basis of ``model`` (built or not) is kept under by ``build``: the
    content of everything it depends on (``_cache_key``), without building it.  Raises
    ``BayesUpdateError`` for a model without a reduced form (``affine.check_separable``)."""
    return _cache_key(model, model.mapping(model.centre()))


def _cache_key(model, centre) -> str:
    """Everything the basis depends on, without decomposing: the package version and the entry
    format; the parameter names, box and settings (``interp_tol`` included); the model's term
    description ``fe.affine_terms()`` (which elements each parameter acts on, how it enters, the
    element properties at the defaults and at unit values), its bindings (a deck binding names
    its cards, fields, factor and line elements) and defaults; the assembled K, M at the centre
    and at ``_KEY_POINTS`` seeded points of the box, which see every element, material and deck
    value and the parameters' non-linear action on them (what the interpolated groups and a
    deck's line fields are built from); the rigid motions and the sensors.  The fresh-point
    check of a loaded basis (``_load``) guards the rest: a model that differs only away from
    those points gives frequencies the stored basis misses, and is rebuilt."""
    fe = model.fe
    terms = fe.affine_terms()
    check_separable(fe, terms)  # a model without a reduced form has no key (as no basis)
    u = qmc.Sobol(len(model.parameter_names), scramble=True, seed=_KEY_SEED).random(_KEY_POINTS)
    probes = [centre, *(model.mapping(row) for row in model.scale(u))]
    matrices = [fe.matrices(p) for p in probes]
    return content_key(
        _CACHE_FORMAT, __version__, type(fe).__qualname__, model.parameter_names, model.bounds,
        model.settings, terms, dict(getattr(fe, "bindings", {})),
        fe.default_parameters(), matrices, fe.rigid_motions(), tuple(fe.structure.sensor_labels),
    )  # fmt: skip


def _arrays(c: Certification) -> dict[str, np.ndarray]:
    """What a load needs: the basis and its sensor read-out, the projected compressed terms and
    their coefficient map (``affine.coefficient_arrays``), the certificate, rounds, checked sets."""
    cert, basis = c.certificate, c.basis
    history = [(h.round, h.size, h.max_rel_error, h.pod_tol) for h in c.history]
    arrays = {
        "V": basis.V,
        "V_sensor": basis.V_sensor,
        "n_rigid": np.array(basis.n_rigid),
        "rigid_energy": np.array(basis.rigid_energy),
        "K_C": basis.K_terms[0],
        "K_B": basis.K_terms[1],
        "M_C": basis.M_terms[0],
        "M_B": basis.M_terms[1],
        "certificate": np.array([cert.max_rel_error, cert.min_signed_error, cert.n_points]),
        "history": np.array(history, float).reshape(-1, 4),
    }
    arrays.update({f"map_{k}": v for k, v in coefficient_arrays(basis.decomposition).items()})
    for i, (theta, f) in enumerate(c.checked):
        arrays[f"checked_theta_{i}"], arrays[f"checked_f_{i}"] = theta, f
    return arrays


def _stored(model, arrays) -> tuple[ReducedBasis, tuple, tuple]:
    """(basis, history, checked sets) of a stored entry; KeyError / ValueError when malformed.
    The basis holds the stored coefficient map, without term stacks (``AffineDecomposition``
    ``.has_terms``)."""
    decomposition = coefficient_map({k[4:]: v for k, v in arrays.items() if k.startswith("map_")})
    if decomposition.names != tuple(model.parameter_names):
        raise ValueError(f"parameters {decomposition.names}, not {model.parameter_names}")
    V, nr = arrays["V"], int(arrays["n_rigid"])
    coupled = bool(arrays["rigid_energy"])
    K_terms, M_terms = (arrays["K_C"], arrays["K_B"]), (arrays["M_C"], arrays["M_B"])
    r_k = V.shape[1] if coupled else V.shape[1] - nr
    if K_terms[1].shape[1] != r_k**2 or M_terms[1].shape[1] != V.shape[1] ** 2:
        raise ValueError(f"stored terms do not fit a basis of size {V.shape[1]}")
    basis = ReducedBasis(decomposition, V, arrays["V_sensor"], nr, K_terms, M_terms, coupled)
    history = tuple(BuildRound(int(r), int(z), float(x), float(p)) for r, z, x, p in
                    arrays["history"])  # fmt: skip
    checked = tuple(
        (arrays[f"checked_theta_{i}"], arrays[f"checked_f_{i}"])
        for i in range(sum(k.startswith("checked_theta_") for k in arrays))
    )
    return basis, history, checked


def _load(model, arrays, executor) -> Certification | None:
    """The stored certification read back (no decomposition, no projection) and checked at
    fresh points; None (with a note when the entry is unreadable or the check fails) when
    there is nothing usable."""
    if arrays is None:
        return None
    st = model.settings
    try:
        basis, history, checked = _stored(model, arrays)
        e, s, n = arrays["certificate"]
    except (KeyError, ValueError) as exc:
        warnings.warn(f"cached reduced basis unreadable ({exc}); rebuilding", RuntimeWarning,
                      stacklevel=4)  # fmt: skip
        return None
    sobol = qmc.Sobol(len(model.parameter_names), scramble=True, seed=st.seed + _RECHECK_SEED)
    theta = model.scale(sobol.random(RECHECK_POINTS))
    what = "reduced basis: cached, checked"
    f_full = full_solves(model.fe, model.parameter_names, theta, st.n_modes, executor, what)[0]
    recheck = compare(basis, theta, f_full, st.n_modes)
    if recheck.max_rel_error > st.tol or recheck.min_signed_error < -0.1 * st.tol:
        warnings.warn(
            f"cached reduced basis of {model.fe.name} misses its tolerance at fresh points "
            f"({recheck.max_rel_error:.1e} > {st.tol:g}); rebuilding",
            RuntimeWarning,
            stacklevel=4,
        )
        return None
    worst = max(float(e), recheck.max_rel_error)
    certificate = Certificate(worst, min(float(s), recheck.min_signed_error),
                              int(n) + recheck.n_points)  # fmt: skip
    return Certification(basis, certificate, True, worst, history, (*checked, (theta, f_full)))


def _check_free_free(fe, centre) -> None:
    K0 = fe.matrices(centre)[0]
    R = fe.rigid_motions()
    if R.shape[1] and np.abs(K0 @ R).max() > 1e-8 * np.abs(K0.data).max():
        raise BayesUpdateError(
            "reduced model: rigid motions the supports allow strain the structure (e.g. "
            "springs to ground); use the full model (--full)"
        )


def _check_upper_bound(certificate: Certificate, tol: float) -> None:
    if certificate.min_signed_error < -0.1 * tol:
        raise BayesUpdateError(
            f"reduced model: reduced frequencies fall {-certificate.min_signed_error:.1e} below "
            "full ones (Rayleigh-Ritz forbids it): the parameter interpolation is too "
            "coarse (lower interp_tol), or DOFs without mass (a lumped-mass beam's rotations) "
            "move with the parameters; use the full model (--full)"
        )


def _warn_failed(model, failed: Certification, stacklevel: int) -> None:
    st = model.settings
    warnings.warn(
        f"reduced model of {model.fe.name}: tolerance {st.tol:g} not reached within size "
        f"{st.max_size} (best {failed.max_rel_error:.2e} at size {failed.basis.size}); "
        "falling back to full solves",
        RuntimeWarning,
        stacklevel=stacklevel,
    )


def certify_points(
    model, theta: np.ndarray, enrich: bool = True, enrich_above=None, solved=None
) -> tuple[Certification, float]:
    """``model``'s certification checked at theta (k, n_params) inside its box (all parameters,
    SI): (new certification, largest relative frequency error at the points; NaN, and the
    certification unchanged, when no full solve there succeeds).  A miss (error > tol, or >
    ``enrich_above`` when that is smaller) with ``enrich``: their shapes join the basis and every
    checked point is re-verified; if the tolerance still fails or the size limit is hit, the
    result is uncertified (a warning).  One full solve per point: with ``enrich`` it gives the
    ``extra_modes`` the enrichment needs as well (Lanczos's lowest modes do not depend on how
    many more are asked for, to its tolerance).  solved : those full solves when the caller has
    made them (``solve_count`` modes each): ((k, n) frequencies [Hz], NaN rows where a solve
    failed; (n_dof, n x the points that solved) their shapes side by side, as ``full_solves``
    gives them), so that a caller that needs the solution itself (its mass, its shapes at the
    sensors) solves once."""
    c, st = model.certification, model.settings
    n_solve = solve_count(model, enrich)
    if solved is None:
        solved = full_solves(model.fe, model.parameter_names, theta, n_solve)
    f_all, shapes = solved
    if f_all.shape != (theta.shape[0], n_solve):
        raise ValueError(f"certify_points: {f_all.shape} frequencies for {theta.shape[0]} points")
    ok = np.all(np.isfinite(f_all), axis=1)
    if not np.any(ok):
        return c, float("nan")
    theta, f_full = theta[ok], f_all[ok, : st.n_modes]
    cert = compare(c.basis, theta, f_full, st.n_modes)
    threshold = st.tol if enrich_above is None else min(st.tol, float(enrich_above))
    if cert.max_rel_error > threshold and enrich:
        return _enriched(model, theta, f_full, shapes)
    max_err = max(c.max_rel_error, cert.max_rel_error)
    return _with_checked(c, c.basis, max_err, cert, (theta, f_full)), cert.max_rel_error


def solve_count(model, enrich: bool = True) -> int:
    """Modes per full solve of ``certify_points``: the certified ones, with ``enrich`` the
    ``extra_modes`` its enrichment adds too."""
    st = model.settings
    return st.n_modes + (st.extra_modes if enrich else 0)


def _enriched(model, theta: np.ndarray, f_full: np.ndarray, extra: np.ndarray):
    """``certify_points``' enrichment: the shapes ``extra`` (n_dof, k) of the full solves at
    theta (frequencies f_full) join the basis, and every checked point is re-verified."""
    c, st, fe = model.certification, model.settings, model.fe
    snaps = np.concatenate([c.basis.V[:, c.basis.n_rigid :], extra], axis=1)
    centre = model.mapping(model.centre())
    decomposition = c.basis.decomposition
    if not decomposition.has_terms:  # a basis read from the cache holds its coefficients only
        decomposition = decompose(fe, model.bounds, st.interp_tol)
    basis = pod_basis(fe, decomposition, centre, snaps, 0.0, st.n_modes)
    errors = [compare(basis, t, f, st.n_modes) for t, f in [*c.checked, (theta, f_full)]]
    cert = errors[-1]
    worst = max(e.max_rel_error for e in errors)
    if worst > st.tol or basis.size > st.max_size:
        # the reported error stays the last certificate's (as before the enrichment)
        failed = replace(c, basis=basis, certified=False, max_rel_error=c.certificate.max_rel_error)
        _warn_failed(model, failed, stacklevel=5)  # the caller of ReducedFEModel.certify_at
        return failed, cert.max_rel_error
    return _with_checked(c, basis, worst, cert, (theta, f_full)), cert.max_rel_error


def _with_checked(c: Certification, basis, max_err: float, cert: Certificate, point_set):
    certificate = Certificate(
        max_err,
        min(c.certificate.min_signed_error, cert.min_signed_error),
        c.certificate.n_points + cert.n_points,
    )
    return replace(
        c,
        basis=basis,
        certificate=certificate,
        max_rel_error=max_err,
        checked=(*c.checked, point_set),
    )
