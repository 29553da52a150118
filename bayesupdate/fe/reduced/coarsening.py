"""Smaller reduced models made from a certified one: a coarser basis inside it (for screening
proposals in delayed-acceptance sampling) and a model localized on a sub-box (e.g. a pilot
chain's)."""

from dataclasses import replace

import numpy as np
from scipy.stats import qmc

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.reduced.basis import ReducedBasis
from bayesupdate.fe.reduced.certification import UNBUILT
from bayesupdate.fe.reduced.settings import ReducedSettings

# ``model`` below is a ``fe.reduced.model.ReducedFEModel``: not imported, not even for type
# checking, since that module imports this one (tests/test_no_import_cycle.py)


def coarsened(
    model,
    tol: float = 5e-3,
    n_train: int = 128,
    n_check: int = 64,
    min_size: int | None = None,
):
    """A smaller reduced model for screening proposals (delayed-acceptance sampling), built
    without any full solve: a second Rayleigh-Ritz level inside ``model``'s basis.

    Elastic reduced eigenvectors of ``model`` at ``n_train`` seeded Sobol points of the box,
    each scaled to unit strain energy at the box centre, are compressed by POD in that energy
    norm; the smallest rank whose frequencies stay within ``tol`` (relative) of ``model``'s on
    ``n_check`` fresh points is kept (``min_size`` elastic vectors at least, default
    ``n_modes``).  The affine terms are projected once more, so an evaluation costs an
    eigen-solve of size 6 + m.  Its values are Rayleigh-Ritz values of ``model``'s pencils:
    upper bounds of its frequencies, hence of the full ones.  ``max_rel_error`` of the result is
    the measured error against ``model`` (its own error against full solves adds to it).
    Raises ``BayesUpdateError`` on an uncertified model."""
    if not model.certified:
        raise BayesUpdateError("coarsened: the reduced model is not certified")
    st, basis = model.settings, model.certification.basis
    dim = len(model.parameter_names)
    train = model.scale(qmc.Sobol(dim, scramble=True, seed=st.seed + 77).random(n_train))
    check = model.scale(qmc.Sobol(dim, scramble=True, seed=st.seed + 78).random(n_check))
    G, U = _energy_directions(basis, train, model.centre(), st.n_modes)
    lam_check = basis.eigen(check, st.n_modes)
    start = st.n_modes if min_size is None else int(min_size)
    coarse, err = _smallest_rank(basis, G, U, (check, lam_check), start, tol, st.n_modes)
    return replace(
        model,
        settings=replace(st, tol=float(tol)),
        name=f"{model.fe.name} (reduced, screening)",
        certification=replace(model.certification, basis=coarse, max_rel_error=err),
    )


def _energy_directions(basis: ReducedBasis, train: np.ndarray, centre: np.ndarray, n_modes: int):
    """(G, U): G the Cholesky factor of the reduced elastic K at ``centre`` (energy norm
    ||x||^2 = |G^T x|^2) and U (r_e, k) the POD directions, in that norm, of the elastic reduced
    eigenvectors at ``train`` (B, n_params) scaled to unit energy."""
    nr, re = basis.n_rigid, basis.size - basis.n_rigid
    _, y = basis.eigen(train, n_modes, vectors=True)
    Y = np.moveaxis(y[:, nr:, :], 1, 0).reshape(re, -1)  # (r_e, n_train * n_modes)
    Kc = basis.matrices(centre[None, :])[0][0]
    G = np.linalg.cholesky(0.5 * (Kc + Kc.T))
    Z = G.T @ Y
    Z = Z / np.linalg.norm(Z, axis=0)
    return G, np.linalg.svd(Z, full_matrices=False)[0]


def _smallest_rank(basis: ReducedBasis, G, U, check_set, start: int, tol: float, n_modes: int):
    """(restricted basis, error): the first rank from ``start`` in steps of 2 whose frequencies
    at the check points stay within ``tol`` of the basis's eigenvalues ``check_set``
    (theta (k, n_params), lambda (k, n_modes)); the full rank if none does."""
    check, lam_check = check_set
    re = basis.size - basis.n_rigid
    for m in range(min(start, re), re + 1, 2):
        Q = np.linalg.qr(np.linalg.solve(G.T, U[:, :m]))[0]  # same span, orthonormal
        coarse = basis.restricted(Q)
        lam = coarse.eigen(check, n_modes)
        err = float(np.max(np.abs(np.sqrt(lam / lam_check) - 1.0)))
        if err <= tol:
            break
    return coarse, err


def localized(
    model,
    samples: np.ndarray,
    names: tuple[str, ...] | None = None,
    widen: float = 0.5,
    **settings,
):
    """A smaller, faster certified model on the box of ``samples`` (k, len(names)) (e.g. a
    pilot chain), widened by ``widen`` times its width on each side and clipped to ``model``'s
    box; points outside it are predicted by ``model`` (``outer``).  Parameters not in ``names``
    keep ``model``'s bounds.  Same tol, seed and n_modes unless given in ``settings`` (other
    ``ReducedSettings`` fields, or ``outer``)."""
    names = tuple(model.parameter_names if names is None else names)
    samples = np.atleast_2d(np.asarray(samples, dtype=float))
    bounds = dict(model.bounds)
    for c, n in enumerate(names):
        lo, hi = np.min(samples[:, c]), np.max(samples[:, c])
        pad = widen * max(hi - lo, 1e-6 * abs(hi))
        bounds[n] = (max(lo - pad, model.bounds[n][0]), min(hi + pad, model.bounds[n][1]))
    outer = settings.pop("outer", model)
    st = model.settings
    options = {"n_modes": st.n_modes, "tol": st.tol, "seed": st.seed, **settings}
    local = replace(
        model,
        bounds=bounds,
        settings=ReducedSettings(**options),
        outer=outer,
        name=None,
        certification=UNBUILT,
    )
    return local.build()
