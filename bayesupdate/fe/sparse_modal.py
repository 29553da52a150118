"""Sparse assembly and sparse modal solution for large models (1e4 - 1e6 DOFs).

Assembly: element matrices (n_e, d, d) with DOF maps (n_e, d) are summed into a fixed CSR pattern
(``SparsePattern``: COO rows/cols made unique once, then every re-assembly is one ``np.bincount``).

Modal solution (``solve_sparse_modes``): K u = lambda M u on the free DOFs (single-point
constraints eliminated), by shift-invert Lanczos (ARPACK through ``scipy.sparse.linalg.eigsh``;
Ericsson & Ruhe, Math. Comp. 35 (1980) 1251) with a *negative* shift sigma, so that K - sigma M is
positive definite even for a free or partly supported structure.  The rigid-body modes are not
left to the iteration: the rigid motions that the constraints allow (null space of the
constraint rows of the 6 rigid motions) and that carry no strain energy are the exact rigid
modes; the Lanczos operator is restricted to their M-orthogonal complement
(P (K - sigma M)^-1 with P = I - R R^T M), so only elastic modes come out.  A further eigenvalue
below ``zero_tol`` x its own diagonal energy sum_i K_ii x_i^2 (x mass-normalized: the value its
eigenvalue would have without any cancellation between DOFs) is a mechanism and is reported with
the DOFs
that move.  Small models (below ``ModalSettings.dense_below`` DOFs) use dense LAPACK on the same
complement, or (``ModalSettings.small_method`` "krylov") a banded shift-invert block Krylov
on it (``fe.eigen_small``, residual-checked).

Springs to ground: the allowed rigid motions then carry energy and come out of the iteration as
low modes.  They are *suspension* modes and, as on the beam path (``fe.eigensolve``), elastic
modes numbered with the others: only the zero-energy combinations are rigid (a frame on vertical
bungees has four rigid modes and its bounce and pitch as elastic modes 1-2).  "Zero" is the
sparse path's ``zero_tol`` test against the diagonal energy: a spring so soft that its mode's
energy is below 1e-10 of sum_i K_ii x_i^2 counts as free (a 0.1 lbf in/rad rotational spring on
a 40 in aluminium frame: 2.4e-11, at 0.04 Hz under a first bending mode of 54 Hz).  MSC Nastran's
SUPORT makes the rigid-body motions of its reference DOFs the rigid set instead, whatever the
springs store (Quick Reference Guide, SUPORT; the eigenvalue table prints them as 0.0):
``ModalSettings.rigid_set = "rigid_motions"`` takes every allowed rigid motion as a rigid mode
(reported with its Rayleigh quotient) and solves the elastic modes on their M-orthogonal
complement, exactly: the Lanczos operator is then the constrained inverse
x = (K - sigma M)^-1 (b - M Rm mu), Rm^T M x = 0, i.e. the inverse of the compressed pencil
(a bordered solve; P (K - sigma M)^-1 alone is exact only when Rm are eigenvectors).

Factorization of K - sigma M: CHOLMOD (supernodal Cholesky, Chen et al., ACM TOMS 35 (2008) 22,
through scikit-sparse, the optional extra ``bayesupdate[fast]``) where it is installed, else
SuperLU (``ModalSettings.factorization``).
"""

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.eigen_small import KrylovSettings, krylov_modes, worthwhile
from bayesupdate.fe.eigensolve import ModalSolution
from bayesupdate.fe.node_pattern import NODE_DOF, node_blocks, node_pattern

COMPONENTS = ("ux", "uy", "uz", "rx", "ry", "rz")
FACTORIZATIONS = ("auto", "cholmod", "superlu")
#: which modes are rigid: the zero-energy ones, or every allowed rigid motion (SUPORT)
RIGID_SETS = ("zero_energy", "rigid_motions")
#: solvers of a pencil below ``ModalSettings.dense_below`` DOFs
SMALL_METHODS = ("krylov", "dense")


def sorted_unique(keys: np.ndarray) -> np.ndarray:
    """Sorted distinct values of an integer array (as ``np.unique``, whose hash path is ~30x
    slower than a sort on the millions of (row, col) keys of a shell pattern)."""
    k = np.sort(keys)
    return k[np.concatenate([[True], k[1:] != k[:-1]])] if k.size else k


def element_dofs(connectivity: np.ndarray, dof_per_node: int = 6) -> np.ndarray:
    """(n_e, k * dof_per_node) global DOF numbers of elements with node lists (n_e, k)."""
    c = np.asarray(connectivity)
    return (dof_per_node * c[:, :, None] + np.arange(dof_per_node)).reshape(len(c), -1)


class SparsePattern:
    """Fixed CSR pattern of a sum of element matrices.

    blocks : DOF maps (n_e, d) of each element family; ``data(mats_list)`` sums element matrices
    (same order) into the (nnz,) CSR data; ``csr(data)`` wraps it.  Every DOF gets a diagonal.
    Keeps cols, indptr and the element positions; ``rows`` is derived from indptr when asked
    (it is only needed to merge patterns, and takes nnz x 4 bytes: 0.2 GiB at 1e6 DOFs).
    """

    def __init__(self, n_dof: int, blocks: list[np.ndarray]):
        self.n_dof = n_dof
        maps = [node_blocks(d) for d in blocks] if n_dof % NODE_DOF == 0 else [None]
        if blocks and all(m is not None for m in maps):
            n_entries = sum(d.shape[0] * d.shape[1] ** 2 for d in blocks) + n_dof
            index = np.int32 if n_entries < 2**31 else np.int64  # nnz <= n_entries
            pattern = node_pattern(n_dof, maps, index)
        else:
            pattern = dof_pattern(n_dof, blocks)
        _, self.cols, self.indptr, self.positions = pattern
        self.nnz = self.cols.size

    @property
    def rows(self) -> np.ndarray:
        """(nnz,) row of every CSR entry."""
        return np.repeat(np.arange(self.n_dof, dtype=self.indptr.dtype), np.diff(self.indptr))

    def data(self, mats: list[np.ndarray]) -> np.ndarray:
        """(nnz,) sum of the element stacks ``mats`` (one per block, (n_e, d, d))."""
        out = np.zeros(self.nnz)
        for b, m in enumerate(mats):
            if m is None or m.size == 0:
                continue
            out += np.bincount(self.positions[b], m.ravel(), self.nnz)
        return out

    def csr(self, data: np.ndarray) -> sp.csr_matrix:
        return sp.csr_matrix((data, self.cols, self.indptr), shape=(self.n_dof, self.n_dof))


def dof_pattern(n_dof: int, blocks: list[np.ndarray]):
    """(rows, cols, indptr, positions) of the CSR pattern of element DOF maps ``blocks`` (n_e, d)
    plus every diagonal, from the DOF-pair keys (any DOF maps; ``node_pattern`` gives the same
    for whole 6-DOF node blocks at a fraction of the cost)."""
    rows = [np.repeat(d, d.shape[1], axis=1).ravel() for d in blocks]
    cols = [np.tile(d, (1, d.shape[1])).ravel() for d in blocks]
    rows.append(np.arange(n_dof))
    cols.append(np.arange(n_dof))
    key = np.concatenate(rows).astype(np.int64) * n_dof + np.concatenate(cols)
    uniq = sorted_unique(key)
    inverse = np.searchsorted(uniq, key)
    r = (uniq // n_dof).astype(np.int32)
    indptr = np.searchsorted(r, np.arange(n_dof + 1)).astype(np.int32)
    sizes = [d.shape[0] * d.shape[1] ** 2 for d in blocks]
    positions = np.split(inverse[: sum(sizes)], np.cumsum(sizes)[:-1])
    return r, (uniq % n_dof).astype(np.int32), indptr, positions


def assemble_coo(n_dof: int, dofs: np.ndarray, mats: np.ndarray) -> sp.csr_matrix:
    """One-shot assembly: CSR (n_dof, n_dof) sum of element matrices mats (n_e, d, d) at
    DOF maps dofs (n_e, d) (COO with duplicates summed)."""
    d = dofs.shape[1]
    rows = np.repeat(dofs, d, axis=1).ravel()
    cols = np.tile(dofs, (1, d)).ravel()
    return sp.coo_matrix((mats.ravel(), (rows, cols)), shape=(n_dof, n_dof)).tocsr()


def rigid_motions(nodes: np.ndarray) -> np.ndarray:
    """(6N, 6) rigid-body motions of nodes (N, 3): 3 translations, 3 rotations about the
    centroid (small rotation theta: u = theta x (x - c))."""
    n = nodes.shape[0]
    r = nodes - nodes.mean(axis=0)
    R = np.zeros((n, 6, 6))
    R[:, :3, :3] = np.eye(3)
    R[:, 3:, 3:] = np.eye(3)
    # theta x r: columns 3..5 are rotations about x, y, z
    R[:, 0, 4], R[:, 0, 5] = r[:, 2], -r[:, 1]
    R[:, 1, 3], R[:, 1, 5] = -r[:, 2], r[:, 0]
    R[:, 2, 3], R[:, 2, 4] = r[:, 1], -r[:, 0]
    return R.reshape(6 * n, 6)


@dataclass(frozen=True)
class ModalSettings:
    """Settings of ``solve_sparse_modes``.

    n_modes : elastic modes wanted; shift : sigma [rad^2/s^2] (< 0); zero_tol : a mode x
    (mass-normalized) with eigenvalue below zero_tol x sum_i K_ii x_i^2 counts as a zero mode
    (rigid or mechanism).  A scale per mode, not max(K_ii / M_ii): the small rotary inertia of a
    thin shell makes that ratio ~1e12 and flagged the first bending mode of a 30 mm plate as a
    mechanism; a true zero mode cancels to round-off (~1e-16) and a thin plate's bending mode
    to ~1e-7 of its diagonal energy.  dense_below :
    free-DOF count under which dense LAPACK is used; tol : ARPACK relative tolerance; seed : start
    vector; factorization : "auto" (CHOLMOD if scikit-sparse is installed, else SuperLU),
    "cholmod" (an error without scikit-sparse) or "superlu"; rigid_set : "zero_energy" (the
    default: suspension modes on springs to ground are elastic modes) or "rigid_motions" (every
    allowed rigid motion is a rigid mode, as MSC Nastran's SUPORT makes it; module docstring);
    small_method : below dense_below, "dense" (LAPACK) or "krylov" (banded shift-invert block
    Krylov, ``fe.eigen_small``, residual-checked; dense LAPACK where the pencil is too small for
    it or it does not converge; ``NastranModel``'s choice).
    """

    n_modes: int = 20
    shift: float = -((2 * np.pi * 1.0) ** 2)
    zero_tol: float = 1e-10
    dense_below: int = 1200
    tol: float = 1e-12
    seed: int = 0
    factorization: str = "auto"
    rigid_set: str = "zero_energy"
    small_method: str = "dense"

    def __post_init__(self):
        if not (self.shift < 0 and np.isfinite(self.shift)):
            raise BayesUpdateError(f"modal settings: shift must be < 0, got {self.shift}")
        if self.n_modes < 1:
            raise BayesUpdateError(f"modal settings: n_modes must be >= 1, got {self.n_modes}")
        if self.factorization not in FACTORIZATIONS:
            raise BayesUpdateError(
                f"modal settings: factorization must be one of {FACTORIZATIONS}, "
                f"got {self.factorization!r}"
            )
        if self.small_method not in SMALL_METHODS:
            raise BayesUpdateError(
                f"modal settings: small_method must be one of {SMALL_METHODS}, "
                f"got {self.small_method!r}"
            )
        if self.rigid_set not in RIGID_SETS:
            raise BayesUpdateError(
                f"modal settings: rigid_set must be one of {RIGID_SETS}, got {self.rigid_set!r}"
            )


@dataclass(frozen=True)
class SparseModes:
    """Elastic and rigid-body modes.

    frequencies_hz, eigenvalues (m,) [Hz, rad^2/s^2]; shapes (n_dof, m) mass-normalized, zero on
    constrained DOFs; rigid_shapes (n_dof, r) mass-normalized rigid-body modes allowed by the
    constraints (``ModalSettings.rigid_set``); rigid_eigenvalues (r,) their eigenvalues (round-off
    ~0 for zero-energy rigid modes, the Rayleigh quotient for a SUPORT's rigid motions).
    """

    frequencies_hz: np.ndarray
    eigenvalues: np.ndarray
    shapes: np.ndarray
    rigid_shapes: np.ndarray
    rigid_eigenvalues: np.ndarray

    @property
    def n_rigid(self) -> int:
        return self.rigid_shapes.shape[1]


def _diagonal_energy(kd, x):
    """(m,) sum_i K_ii x_i^2 of mass-normalized columns x (n, m)."""
    return np.einsum("i,im->m", kd, x**2)


def _rigid_modes(K, M, R, zero_tol, rigid_set="zero_energy"):
    """M-orthonormal zero-energy combinations of the allowed rigid motions R (n, 6), or all of
    them for ``rigid_set`` "rigid_motions", with their Rayleigh quotients."""
    if R.shape[1] == 0:
        return R, np.zeros(0)
    KR, MR = K @ R, M @ R
    lam, C = sl.eigh(R.T @ KR, R.T @ MR)
    keep = np.abs(lam) < zero_tol * _diagonal_energy(K.diagonal(), R @ C)
    if rigid_set == "rigid_motions":
        keep[:] = True
    return R @ C[:, keep], lam[keep]


def _allowed_rigid(nodes, n_dof, fixed):
    """Rigid motions (n_dof, r) that vanish on the constrained DOFs ``fixed``."""
    R = rigid_motions(nodes)
    if R.shape[0] != n_dof:
        raise BayesUpdateError("rigid motions need 6 DOFs per node")
    if fixed.size == 0:
        return R
    s, v = np.linalg.svd(R[fixed], full_matrices=True)[1:]
    rank = int(np.sum(s > 1e-9 * max(1.0, np.abs(R).max())))
    return R @ v[rank:].T


def solve_sparse_modes(K, M, nodes, settings: ModalSettings, fixed_dofs=()) -> SparseModes:
    """First ``settings.n_modes`` elastic modes of K u = lambda M u, constraints eliminated.

    K, M : (n_dof, n_dof) sparse, 6 DOFs per node; nodes : (N, 3) [m] (for the rigid motions);
    fixed_dofs : global DOF numbers held at zero.  Raises
    BayesUpdateError for a mechanism (naming the moving DOFs) or a singular K - sigma M.
    """
    n_dof = K.shape[0]
    fixed = np.unique(np.asarray(fixed_dofs, dtype=np.int64))
    free = np.setdiff1d(np.arange(n_dof), fixed)
    Kf = sp.csr_matrix(K)[free][:, free]
    Mf = sp.csr_matrix(M)[free][:, free]
    R = _allowed_rigid(nodes, n_dof, fixed)[free]
    lam, phi, Rm, lam_r = solve_reduced_modes(Kf, Mf, R, settings, free)
    shapes = np.zeros((n_dof, phi.shape[1]))
    shapes[free] = phi
    rigid = np.zeros((n_dof, Rm.shape[1]))
    rigid[free] = Rm
    return SparseModes(np.sqrt(np.maximum(lam, 0)) / (2 * np.pi), lam, shapes, rigid, lam_r)


def constrained_modes(Kf, Mf, R, settings: ModalSettings, dof_ids, T) -> ModalSolution:
    """``solve_reduced_modes`` of the constrained K, M (n_ind, n_ind) as a ``ModalSolution``
    with full-DOF shapes T @ phi (T (n_dof, n_ind): the constraint transform)."""
    lam, phi, Rm, lam_r = solve_reduced_modes(Kf, Mf, R, settings, dof_ids)
    return ModalSolution(
        frequencies_hz=np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi),
        eigenvalues=lam,
        shapes=T @ phi,
        n_rigid=Rm.shape[1],
        rigid_frequencies_hz=np.sqrt(np.abs(lam_r)) / (2 * np.pi),
    )


def solve_reduced_modes(Kf, Mf, R, settings: ModalSettings, dof_ids, solve=None):
    """Elastic and rigid modes of a reduced pencil (Kf, Mf) (n, n) sparse whose allowed rigid
    motions are the columns of R (n, r); dof_ids (n,) global DOF number of each coordinate (for
    mechanism messages).  solve : a factorization of Kf - shift Mf (``factorize``) the caller
    made and uses again (e.g. for design sensitivities, ``fe.reduced.sensitivity``); None: made
    here when the Lanczos path needs one.  Returns (lam (m,), phi (n, m), rigid modes (n, r')
    and their eigenvalues (r',)), all mass-normalized; raises BayesUpdateError for a
    mechanism."""
    Rm, lam_r = _rigid_modes(Kf, Mf, R, settings.zero_tol, settings.rigid_set)
    Rm = Rm / np.sqrt(np.einsum("ij,ij->j", Rm, Mf @ Rm))
    _check_mode_count(settings.n_modes, Mf, Rm.shape[1])
    if Kf.shape[0] < settings.dense_below:
        lam, phi = _small_modes(Kf, Mf, Rm, settings)
    else:
        bordered = settings.rigid_set == "rigid_motions"
        lam, phi = _lanczos_modes(Kf, Mf, Rm, settings, bordered, solve)
    zero = settings.zero_tol * _diagonal_energy(Kf.diagonal(), phi)
    _check_mechanism(lam, phi, zero, np.asarray(dof_ids))
    idx = np.argmax(np.abs(phi), axis=0)  # deterministic sign
    phi = phi * np.sign(phi[idx, np.arange(phi.shape[1])])
    return lam, phi, Rm, lam_r


def _check_mode_count(n_modes: int, Mf, n_rigid: int) -> None:
    """Raise if fewer than ``n_modes`` elastic modes exist: a DOF whose row of M (n, n) is
    empty carries no mass and so no mode (it follows the others statically), so the pencil has
    at most n - (massless DOFs) - n_rigid elastic modes.  Asking for more would return
    eigenvectors of zero mass, whose infinite eigenvalues, rounded, look like zero-energy modes."""
    Mf = Mf if getattr(Mf, "format", None) == "csr" else sp.csr_matrix(Mf)
    n = Mf.shape[0]
    # explicit zeros (K and M may share one pattern, ``general_plan``) and the 1e-300 a deck
    # reader puts for a zero RHO count as no mass: 1e-100 of the largest entry is none
    mass = np.abs(Mf.data)
    has_mass = np.zeros(n, bool)
    rows = np.repeat(np.arange(n), np.diff(Mf.indptr))
    has_mass[rows[mass > 1e-100 * mass.max(initial=0.0)]] = True
    massless = n - int(np.count_nonzero(has_mass))
    n_el = n - massless - n_rigid
    if n_modes > n_el:
        detail = f" ({massless} of its {n} DOFs carry no mass)" if massless else ""
        raise BayesUpdateError(
            f"asked for {n_modes} modes but the model has only {n_el} elastic modes{detail}; "
            f"ask for at most {n_el}"
        )


class MechanismError(BayesUpdateError):
    """The modal solve found ``count`` zero-energy modes beyond the rigid-body modes the
    supports allow; the first moves the global DOFs ``dofs`` (k,) (6 per node), largest first.
    The message names nodes by ``node_names`` (node index -> its name, e.g. a deck's "GRID
    12"; None: "node 3"), so that a model read from a file can name them its own way
    (``named``)."""

    def __init__(self, count: int, dofs, node_names=None):
        self.count, self.dofs = int(count), np.asarray(dofs, dtype=np.int64)
        name = node_names or (lambda node: f"node {node}")
        moving = ", ".join(f"{name(int(d) // 6)} {COMPONENTS[d % 6]}" for d in self.dofs)
        super().__init__(
            f"the model is a mechanism: {self.count} zero-energy mode(s) beyond the rigid-body "
            f"modes the supports allow; the first moves {moving}; connect or support these DOFs"
        )

    def named(self, node_names) -> "MechanismError":
        """The same error with its nodes named by ``node_names`` (node index -> name)."""
        return MechanismError(self.count, self.dofs, node_names)

    def __reduce__(self):
        # raised in a worker process: it crosses back pickled, its message as it was worded
        return _restored_mechanism, (str(self), self.count, self.dofs)


def _restored_mechanism(message: str, count: int, dofs) -> MechanismError:
    """A ``MechanismError`` with its message as worded where it was raised (unpickling)."""
    err = MechanismError.__new__(MechanismError)
    BayesUpdateError.__init__(err, message)
    err.count, err.dofs = count, dofs
    return err


def _check_mechanism(lam, phi, zero, free):
    bad = np.flatnonzero(np.abs(lam) < zero)
    if bad.size:
        mode = phi[:, bad[0]]
        moving = np.flatnonzero(np.abs(mode) > 0.1 * np.abs(mode).max())
        order = moving[np.argsort(-np.abs(mode[moving]))][:8]
        raise MechanismError(bad.size, free[order])


def _small_modes(Kf, Mf, Rm, settings: ModalSettings):
    """Below ``dense_below``: dense LAPACK, or for ``small_method`` "krylov" the banded block
    Krylov (``fe.eigen_small``; ~3x faster than LAPACK at 350 DOFs) where the pencil is large
    enough for it, with LAPACK where it does not converge (LAPACK also reports a singular
    K - sigma M)."""
    ks = KrylovSettings()
    n_rigid = Rm.shape[1]
    if settings.small_method == "krylov" and worthwhile(Kf.shape[0], settings.n_modes, n_rigid, ks):
        out = krylov_modes(Kf, Mf, Rm, settings.n_modes, settings.shift, ks)
        if out is not None:
            return out
    return _dense_modes(Kf, Mf, Rm, settings.n_modes, settings.shift)


def _dense_modes(Kf, Mf, Rm, n_modes, sigma):
    """Dense LAPACK on the M-orthogonal complement of Rm, as M x = mu (K - sigma M) x
    (mu = 1 / (lambda - sigma)) so that a semi-definite M (massless DOFs) is allowed.

    The complement's basis Q is the last n - r columns of the Householder factor H of
    M Rm = H [R; 0] (Golub & Van Loan, *Matrix Computations*, 4th ed., sec. 5.2): Q^T X Q is the
    trailing block of H^T X H, applied as r reflections (LAPACK ormqr, O(r n^2)) instead of the
    explicit products with an n x (n - r) Q (O(n^3), the larger part of the solve before)."""
    Kd, Md = Kf.toarray(), Mf.toarray()
    r = Rm.shape[1]
    if r:
        (h, tau), _ = sl.qr(Md @ Rm, mode="raw")

        def reflect(side, trans, X):
            return sl.lapack.dormqr(side, trans, h, tau, X, lwork=max(1, 64 * X.shape[0]))[0]

        def project(X):
            return reflect("R", "N", reflect("L", "T", X))[r:, r:]

        A, B = project(Md), project(Kd - sigma * Md)
    else:
        A, B = Md, Kd - sigma * Md
    m = A.shape[0]
    try:
        mu, y = sl.eigh(A, B, subset_by_index=[m - n_modes, m - 1])
    except np.linalg.LinAlgError as exc:
        raise BayesUpdateError(
            "K - sigma M is singular: some DOFs have neither stiffness nor mass; "
            "support them or give them mass"
        ) from exc
    mu, y = mu[::-1], y[:, ::-1]
    phi = reflect("L", "N", np.vstack([np.zeros((r, y.shape[1])), y])) if r else y
    phi = phi / np.sqrt(np.einsum("ij,ij->j", phi, Md @ phi))
    return sigma + 1.0 / mu, phi


def cholmod_available() -> bool:
    """True if scikit-sparse's CHOLMOD can be imported (the optional extra ``fast``)."""
    try:
        import sksparse.cholmod  # noqa: F401
    except ImportError:
        return False
    return True


def _singular(detail: str) -> BayesUpdateError:
    return BayesUpdateError(
        f"K - sigma M is singular ({detail}): some DOFs have neither stiffness nor mass; "
        "support them or give them mass"
    )


def factorize(A, kind: str = "auto"):
    """solve(b) -> (K - sigma M)^-1 b for the symmetric positive definite A (n, n) sparse.

    kind "auto": CHOLMOD (supernodal Cholesky, AMD ordering) if scikit-sparse is installed,
    else SuperLU with a symmetric minimum-degree ordering and diagonal pivots; "cholmod" or
    "superlu" force one (a BayesUpdateError if CHOLMOD is asked for but not installed).
    """
    if kind not in FACTORIZATIONS:
        raise BayesUpdateError(f"factorization must be one of {FACTORIZATIONS}, got {kind!r}")
    if kind != "superlu":
        try:
            from sksparse.cholmod import CholmodNotPositiveDefiniteError, cholesky
        except ImportError:
            if kind == "cholmod":
                raise BayesUpdateError(
                    "factorization 'cholmod' needs scikit-sparse: pip install "
                    "'bayesupdate[fast]' (it builds against libsuitesparse-dev), or use 'auto'"
                ) from None
        else:
            try:
                return cholesky(sp.csc_matrix(A), ordering_method="amd")
            except CholmodNotPositiveDefiniteError as exc:
                raise _singular("CHOLMOD: not positive definite") from exc
    try:
        lu = spla.splu(
            sp.csc_matrix(A),
            permc_spec="MMD_AT_PLUS_A",
            diag_pivot_thresh=0.0,
            options={"SymmetricMode": True},
        )
    except RuntimeError as exc:
        raise _singular(str(exc)) from exc
    return lu.solve


def _lanczos_modes(Kf, Mf, Rm, settings: ModalSettings, bordered: bool = False, solve=None):
    """Shift-invert Lanczos on the complement of the rigid modes Rm (M-orthonormal).

    bordered : Rm need not be eigenvectors (a SUPORT's rigid motions on springs): the operator is
    the constrained inverse (module docstring), from Z = A^-1 M Rm and S = Rm^T M Z made once.
    solve : the factorization of Kf - shift Mf (None: made here)."""
    n = Kf.shape[0]
    sigma = settings.shift
    if solve is None:
        solve = factorize((Kf - sigma * Mf).tocsc(), settings.factorization)
    MR = Mf @ Rm

    def project(x):
        return x - Rm @ (MR.T @ x)

    if bordered and Rm.shape[1]:
        Z = np.column_stack([solve(np.ascontiguousarray(c)) for c in MR.T])
        S = MR.T @ Z

        def op(b):
            y = solve(np.asarray(b, dtype=float).ravel())
            return y - Z @ np.linalg.solve(S, MR.T @ y)
    else:

        def op(b):
            return project(solve(np.asarray(b, dtype=float).ravel()))

    OPinv = spla.LinearOperator((n, n), matvec=op, dtype=float)
    v0 = project(np.random.default_rng(settings.seed).standard_normal(n))
    k = settings.n_modes
    ncv = min(n, max(2 * k + 1, k + 20))
    mu, phi = spla.eigsh(
        Kf, k=k, M=Mf, sigma=sigma, which="LM", OPinv=OPinv, v0=v0, ncv=ncv, tol=settings.tol
    )
    order = np.argsort(mu)
    phi = phi[:, order]
    phi = phi / np.sqrt(np.einsum("ij,ij->j", phi, Mf @ phi))
    return mu[order], phi
