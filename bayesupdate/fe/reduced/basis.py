"""The reduced basis: snapshots, POD in the energy norm, projection of the affine terms.

Elastic mode shapes at parameter points (snapshots), rigid-body part removed, are compressed by
POD in the energy (K) norm of the box centre with each snapshot scaled to unit strain energy: the
discarded POD energy then estimates the relative eigenvalue error of Rayleigh-Ritz (Quarteroni,
Manzoni & Negri, *Reduced Basis Methods for PDEs*, 2016, ch. 6).  The six rigid-body motions are
kept exactly as the first basis vectors.

Online: reduced K and M for all points by matrix products over the projected affine terms
(``compute.batch_rows.row_product``, so that a point's matrices are the same bits in any
batch), the rigid-body coordinates eliminated exactly (K R = 0 for a free body, so the elastic
pencil is K_ww x = lambda (M_ww - M_wr M_rr^-1 M_rw) x), then stacked Cholesky + ``eigvalsh``
for all points, the batch split over threads (``fe.batched_eigen``).
"""

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from bayesupdate.compute.batch_rows import row_product
from bayesupdate.compute.executors import executor_or_serial
from bayesupdate.compute.progress import phase
from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.batched_eigen import batched_elastic_eigenvalues
from bayesupdate.fe.model import FEModel
from bayesupdate.fe.reduced.affine import AffineDecomposition
from bayesupdate.fe.reduced.rigid import compressed_stiffness, rigid_energy
from bayesupdate.fe.reduced.sensitivity import SHIFT, static_corrections
from bayesupdate.fe.sparse_modal import ModalSettings, factorize, solve_reduced_modes


@dataclass(frozen=True, eq=False)
class ReducedBasis:
    """A basis V and the affine terms projected on it.

    V : (n_dof, r) basis: the first ``n_rigid`` columns the rigid-body motions, the rest elastic,
    all orthonormal in the mass matrix at the box centre.  V_sensor : (n_sensors, r) its sensor
    read-out (shapes at the sensors of a reduced solution y are V_sensor @ y).  K_terms /
    M_terms : (C (n_terms, k), B (k, r_e^2) or (k, r^2)) with the projected terms ~= C @ B
    (``compress_terms``), K on the elastic block only (K R = 0) unless ``rigid_energy`` (the
    rigid motions carry strain energy: springs to ground under a SUPORT), then on all r
    coordinates, compressed onto the elastic ones at each point (``reduced.rigid``).
    decomposition : the affine terms the coefficients come from.
    """

    decomposition: AffineDecomposition
    V: np.ndarray
    V_sensor: np.ndarray
    n_rigid: int
    K_terms: tuple[np.ndarray, np.ndarray]
    M_terms: tuple[np.ndarray, np.ndarray]
    rigid_energy: bool = False

    @property
    def size(self) -> int:
        """Basis vectors (rigid included)."""
        return self.V.shape[1]

    def matrices(self, theta_full: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Reduced pencils at theta_full (B, n_params) (all parameters, SI): the elastic block of
        K (B, r_e, r_e) and the whole M (B, r, r), the first ``n_rigid`` coordinates being the
        rigid-body motions.  Matrix products over the projected affine terms, each point's the
        same bits in any batch (``compute.batch_rows``)."""
        cK, cM = self.decomposition.coefficients(theta_full)
        r, nr = self.size, self.n_rigid
        M = self.combined(cM, self.M_terms).reshape(-1, r, r)
        if self.rigid_energy:
            K = self.combined(cK, self.K_terms).reshape(-1, r, r)
            return compressed_stiffness(K, M, nr), M
        K = self.combined(cK, self.K_terms).reshape(-1, r - nr, r - nr)
        return K, M

    @staticmethod
    def combined(coefficients: np.ndarray, terms: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
        """The projected terms ~= C @ B (``terms``) combined with ``coefficients`` (B, n_terms):
        (B, B.shape[1]) flattened matrices, each row independent of the batch (``row_product``)."""
        return row_product(row_product(coefficients, terms[0]), terms[1])

    def eigen(self, theta_full: np.ndarray, n_modes: int, vectors: bool = False):
        """(B, n_modes) elastic eigenvalues [rad^2/s^2] at theta_full (B, n_params) and, with
        ``vectors``, the (B, r, n_modes) reduced eigenvectors (``batched_elastic_eigenvalues``)."""
        K, M = self.matrices(theta_full)
        return batched_elastic_eigenvalues(K, M, self.n_rigid, n_modes, vectors=vectors)

    def restricted(self, Q: np.ndarray) -> "ReducedBasis":
        """The basis restricted to the elastic subspace Q (r_e, m) of this one (rigid kept): a
        second Rayleigh-Ritz level, without re-projecting the element matrices."""
        nr, re = self.n_rigid, self.size - self.n_rigid
        m = Q.shape[1]
        Qf = np.zeros((self.size, nr + m))
        Qf[:nr, :nr] = np.eye(nr)
        Qf[nr:, nr:] = Q
        BM = self.M_terms[1].reshape(-1, self.size, self.size)
        if self.rigid_energy:
            BK = self.K_terms[1].reshape(-1, self.size, self.size)
            K_terms = (self.K_terms[0], (Qf.T @ BK @ Qf).reshape(BK.shape[0], -1))
        else:
            BK = self.K_terms[1].reshape(-1, re, re)
            K_terms = (self.K_terms[0], (Q.T @ BK @ Q).reshape(BK.shape[0], -1))
        return ReducedBasis(
            self.decomposition,
            self.V @ Qf,
            self.V_sensor @ Qf,
            nr,
            K_terms,
            (self.M_terms[0], (Qf.T @ BM @ Qf).reshape(BM.shape[0], -1)),
            self.rigid_energy,
        )


def _solve_point(shared: tuple, row: np.ndarray):
    """(frequencies (n_modes,) [Hz], shapes (n_dof, k)) of one full solve, None where it fails
    (an executor task; shared: (fe, names, n_modes, decomposition)).  The shapes are the
    n_modes modes, followed, when ``decomposition`` is not None, by their design-sensitivity
    vectors (``reduced.sensitivity``)."""
    fe, names, n_modes, decomposition = shared
    params = dict(zip(names, map(float, row), strict=True))
    try:
        if decomposition is not None and _shares_factorization(fe):
            return _snapshot(fe, decomposition, params, n_modes)
        sol = fe.solve(params, n_modes).modes
        if decomposition is None:
            return sol.frequencies_hz, sol.shapes
        extra = static_corrections(fe, decomposition, params, sol.eigenvalues, sol.shapes)
    except (BayesUpdateError, np.linalg.LinAlgError):
        return None
    return sol.frequencies_hz, np.concatenate([sol.shapes, extra], axis=1)


def _modal_settings(fe: FEModel, n_modes: int) -> ModalSettings:
    """The ``ModalSettings`` of ``FEModel.solve`` on the sparse path (a SUPORT deck's rigid
    set from the structure's metadata)."""
    rigid_set = fe.structure.metadata.get("rigid_set", "zero_energy")
    return ModalSettings(n_modes=n_modes, rigid_set=rigid_set)


def _shares_factorization(fe: FEModel) -> bool:
    """Whether a snapshot of ``fe`` is solved by shift-invert Lanczos (the sparse path, above
    ``dense_below`` independent DOFs) with the sensitivities' shift, so that both can use one
    factorization of K - sigma M."""
    g = fe.general
    settings = ModalSettings()
    return (
        g is not None
        and settings.shift == SHIFT
        and g.transform.independent.size >= settings.dense_below
    )


def _snapshot(fe: FEModel, decomposition: AffineDecomposition, params, n_modes: int):
    """(frequencies (n_modes,) [Hz], [modes, design-sensitivity vectors] (n_dof, k)) at
    ``params``: the modes of ``FEModel.solve`` (same assembly, constraints and solver) and
    ``static_corrections`` from the one factorization of T^T (K - sigma M) T the Lanczos
    iteration made, instead of a second assembly and factorization."""
    g = fe.general
    tr = g.transform
    K, M = fe.matrices(params)
    Kf, Mf = tr.reduce(K), tr.reduce(M)
    settings = _modal_settings(fe, n_modes)
    solve = factorize((Kf - settings.shift * Mf).tocsc(), settings.factorization)
    lam, phi = solve_reduced_modes(Kf, Mf, g.rigid, settings, tr.independent, solve)[:2]
    shapes = np.asarray(tr.expand(phi))
    extra = static_corrections(fe, decomposition, params, lam, shapes, solve=solve)
    freqs = np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)
    return freqs, np.concatenate([shapes, extra], axis=1)


def full_solves(
    fe: FEModel,
    names: tuple[str, ...],
    theta: np.ndarray,
    n_modes: int,
    executor=None,
    what: str = "full solves",
    sensitivities: AffineDecomposition | None = None,
):
    """Full solves at theta (B, len(names)) (SI), one task per point on ``executor``
    (``compute.executors``; None: in this process), shown as the progress phase ``what``
    (``compute.progress``): (B, n_modes) frequencies [Hz] (NaN rows on failure) and the
    (n_dof, k) mode shapes of the points that solved, side by side, each point's modes followed
    by their design-sensitivity vectors when ``sensitivities`` (the model's decomposition) is
    given (``reduced.sensitivity``); (n_dof, 0) when no point solved."""
    shared = (fe, names, n_modes, sensitivities)
    with phase(what, theta.shape[0], "solves") as running:
        solved = executor_or_serial(executor).map(
            _solve_point, list(theta), shared, running.progress_callback()
        )
    freqs = np.full((theta.shape[0], n_modes), np.nan)
    shapes = []
    for i, point in enumerate(solved):
        # a snapshot whose eigen-solve fails is left out (its row stays NaN); the
        # certification then runs on the points that solved
        if point is not None:
            freqs[i] = point[0]
            shapes.append(point[1])
    if not shapes:
        return freqs, np.zeros((fe.structure.n_dof, 0))
    return freqs, np.concatenate(shapes, axis=1)


def pod_basis(
    fe: FEModel,
    decomposition: AffineDecomposition,
    centre: Mapping[str, float],
    snaps: np.ndarray,
    pod_tol: float,
    n_modes: int,
) -> ReducedBasis:
    """POD of the rigid-free snapshots (n_dof, k) in the K-norm at ``centre`` (unit strain energy
    each), then the affine terms projected on [rigid motions, POD vectors].  Keeps the smallest
    rank whose discarded energy per snapshot (on average) is <= pod_tol: that is about the
    relative eigenvalue error, twice the relative frequency error; at least ``n_modes``."""
    K0, M0 = fe.matrices(centre)
    R = fe.rigid_motions()
    MR = M0 @ R
    Rr = R @ np.linalg.inv(np.linalg.cholesky(R.T @ MR)).T  # M0-orthonormal rigid motions
    Y = snaps - Rr @ (Rr.T @ (M0 @ snaps))
    W = _energy_pod(Y, K0, pod_tol, n_modes)
    # M0-orthonormal elastic basis (well-conditioned reduced M)
    W = W - Rr @ (Rr.T @ (M0 @ W))
    g = W.T @ (M0 @ W)
    s, Q = np.linalg.eigh(0.5 * (g + g.T))
    if not s.min() > 0:
        # combinations that move only DOFs without mass (a lumped-mass beam's rotations, whose
        # static response to the others changes with the parameters): no mass norm, dropped;
        # the certification's full solves judge what remains
        keep = s > 0
        s, Q = s[keep], Q[:, keep]
    W = W @ (Q / np.sqrt(s))
    return projected_basis(fe, decomposition, np.concatenate([Rr, W], axis=1), Rr.shape[1])


def _energy_pod(Y: np.ndarray, K0, pod_tol: float, n_modes: int) -> np.ndarray:
    """(n_dof, rank) leading POD vectors of the snapshots Y (n_dof, k) in the K0 energy norm."""
    energy = np.einsum("ik,ik->k", Y, K0 @ Y)
    Y = Y / np.sqrt(energy)
    G = Y.T @ (K0 @ Y)
    w, U = np.linalg.eigh(0.5 * (G + G.T))
    w, U = w[::-1], U[:, ::-1]
    tail = np.concatenate([np.cumsum(w[::-1])[::-1][1:], [0.0]])
    numerical = int(np.sum(w > 1e-10 * w[0]))
    rank = int(np.argmax(tail <= pod_tol * Y.shape[1])) + 1
    rank = min(max(rank, n_modes), numerical)
    return Y @ U[:, :rank]


def projected_basis(
    fe: FEModel, decomposition: AffineDecomposition, V: np.ndarray, n_rigid: int
) -> ReducedBasis:
    """The ``ReducedBasis`` of V (n_dof, r), its first ``n_rigid`` columns rigid motions."""
    # sensor read-out is linear in the shape: sensor shapes of a reduced solution y are
    # V_sensor @ y, so a batch of shapes costs (n_sensors x r x n_modes) per point
    nr = n_rigid
    Kt = decomposition.project(V, decomposition.k_stacks)
    coupled = rigid_energy(Kt, nr)
    if not coupled:
        Kt = Kt[:, nr:, nr:]
    Mt = decomposition.project(V, decomposition.m_stacks)
    return ReducedBasis(
        decomposition,
        V,
        fe.sensor_shapes(V),
        nr,
        compress_terms(Kt.reshape(Kt.shape[0], -1)),
        compress_terms(Mt.reshape(Mt.shape[0], -1)),
        coupled,
    )


def compress_terms(terms: np.ndarray, rel: float = 1e-14) -> tuple[np.ndarray, np.ndarray]:
    """(n_terms, r*r) projected terms -> (C (n_terms, k), B (k, r*r)) with terms ~= C @ B.

    The interpolation nodes of one part give nearly dependent matrices (smooth in the
    parameter): on the mAEWing1 deck's line group 3,758 terms have rank 16 (K) and 6 (M) to
    ``rel``.  What is dropped has spectral norm <= ``rel`` times the largest singular value,
    which changes reduced entries by < 1e-14 ||K_r||, far below the certified tolerance (and the
    certification is run on the compressed terms).  The low rank is found by a randomized range
    finder (Halko, Martinsson & Tropp, SIAM Rev. 53, 2011, alg. 4.2 and sec. 4.3) whose
    residual is measured exactly (``_range_finder``); the plain SVD (O(n_terms^2 r^2)) is kept
    for small term sets and as the fallback when the rank is not low."""
    found = _range_finder(terms, 0.5 * rel)
    if found is None:
        U, sv, Vt = np.linalg.svd(terms, full_matrices=False)
        k = max(1, int(np.sum(sv > rel * sv[0])))
        return U[:, :k] * sv[:k], Vt[:k]
    Q, U, sv, Vt = found
    # the residual's Frobenius norm is <= rel / 2 x s0 and the truncation below drops singular
    # values <= rel / 2 x s0: together no more than the plain SVD's truncation at rel x s0
    k = max(1, int(np.sum(sv > 0.5 * rel * sv[0])))
    return (Q @ U[:, :k]) * sv[:k], Vt[:k]


#: columns of the first random sketch of ``_range_finder`` (doubled until the residual passes)
SKETCH = 32
#: seed of its Gaussian test matrix (fixed: the build is deterministic)
_SKETCH_SEED = 0


def _range_finder(terms: np.ndarray, rel: float):
    """(Q (n, s), U (s, s), sv (s,), Vt (s, m)) with Q orthonormal, Q^T terms = U diag(sv) Vt,
    and ||terms - Q Q^T terms||_F <= rel x sv[0], for terms (n, m); None when the sketch would
    reach half of min(n, m) first (then the plain SVD is as cheap).  Gaussian sketches of
    ``SKETCH`` columns, doubled until that exact residual passes."""
    n, m = terms.shape
    rng = np.random.default_rng(_SKETCH_SEED)
    s = SKETCH
    while 2 * s <= min(n, m):
        Q = np.linalg.qr(terms @ rng.standard_normal((m, s)))[0]
        small = Q.T @ terms
        U, sv, Vt = np.linalg.svd(small, full_matrices=False)
        if sv[0] > 0 and np.linalg.norm(terms - Q @ small) <= rel * sv[0]:
            return Q, U, sv, Vt
        s *= 2
    return None
