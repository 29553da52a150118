"""Aligning a test geometry with a model: a rigid transform, optionally with a uniform scale.

x_model = s R x_test + t, held as a 4x4 matrix [[s R, t], [0, 1]] (test to model, model length
unit).  Three ways (``PairingSettings.align``):

- named node pairs (>= 3, not collinear): the least-squares similarity transform of Umeyama
  (1991, "Least-squares estimation of transformation parameters between two point patterns",
  IEEE TPAMI 13(4) 376-380, eqs 34-43), which without scale is Kabsch's (1976, Acta Cryst. A32
  922) rotation;
- iterative closest point (Besl & McKay 1992, IEEE TPAMI 14(2) 239-256) onto the model's nodes,
  seeded by a principal-axes guess under each of the 24 proper rotations that map the test's
  principal axes onto the model's (the cube's rotation group); the best end wins, and a second
  end about as good with another pose is an error (a symmetric layout: give pairs);
- an explicit 3x4 matrix [s R | t], checked to be a rotation (times a scale where allowed)
  within 1 %.
"""

import itertools
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from bayesupdate.errors import BayesUpdateError

#: relative tolerance of "rigid": singular values of the 3x3 part within 1 % of each other
#: (and of 1 without scale), a pair fit's rms residual within 1 % of the pairs' spread
RIGID_TOL = 0.01


@dataclass(frozen=True)
class Transform:
    """matrix (4, 4) test to model (model length unit); scale s; residuals (n,) per aligned
    test point [model length unit]; rms of them; method: 'pairs', 'icp', 'none' or 'matrix';
    iterations of ICP (0 otherwise)."""

    matrix: np.ndarray
    scale: float
    residuals: np.ndarray
    rms: float
    method: str
    iterations: int = 0

    def apply(self, points) -> np.ndarray:
        """Model coordinates (n, 3) of test points (n, 3) in the model's length unit."""
        p = np.atleast_2d(np.asarray(points, dtype=float))
        return p @ self.matrix[:3, :3].T + self.matrix[:3, 3]

    @property
    def rotation(self) -> np.ndarray:
        """The rotation R (3, 3) (the 3x3 part over the scale)."""
        return self.matrix[:3, :3] / self.scale


def homogeneous(R, t, s: float = 1.0) -> np.ndarray:
    """[[s R, t], [0, 0, 0, 1]] (4, 4)."""
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = s * np.asarray(R), np.asarray(t)
    return m


def umeyama(src, dst, with_scale: bool = False) -> tuple[np.ndarray, np.ndarray, float]:
    """(R (3, 3), t (3,), s) minimizing sum |s R src_i + t - dst_i|^2 (Umeyama 1991 eqs 40-42;
    s = 1 without scale).  src, dst : (n, 3), n >= 3."""
    src, dst = np.asarray(src, float), np.asarray(dst, float)
    mu_s, mu_d = src.mean(axis=0), dst.mean(axis=0)
    a, b = src - mu_s, dst - mu_d
    U, D, Vt = np.linalg.svd(b.T @ a / len(src))
    S = np.eye(3)
    if np.linalg.det(U) * np.linalg.det(Vt) < 0:
        S[2, 2] = -1.0  # a reflection is the best fit: take the best proper rotation
    R = U @ S @ Vt
    var = (a**2).sum() / len(src)
    s = float(np.trace(np.diag(D) @ S) / var) if with_scale and var > 0 else 1.0
    return R, mu_d - s * R @ mu_s, s


def fit_pairs(test_xyz, model_xyz, with_scale: bool, names=()) -> Transform:
    """Transform from named pairs (test points (n, 3), their model points (n, 3), model unit);
    errors: fewer than 3 or collinear pairs, a scale off 1 by > 1 % without ``with_scale``, or
    pairs that no rigid transform relates (rms residual > 1 % of their spread)."""
    src, dst = np.asarray(test_xyz, float), np.asarray(model_xyz, float)
    if len(src) < 3:
        raise BayesUpdateError(
            f"test.pairs: {len(src)} node pairs; an alignment needs at least three "
            "(not on one line), or align = 'none' or a 3x4 matrix"
        )
    spread = np.sqrt(((dst - dst.mean(axis=0)) ** 2).sum(axis=1).mean())
    if np.linalg.svd(src - src.mean(axis=0), compute_uv=False)[1] < 1e-9 * max(spread, 1e-300):
        raise BayesUpdateError("test.pairs: the test points are on one line; add a pair off it")
    R, t, s = umeyama(src, dst, True)
    if not with_scale:
        if abs(s - 1.0) > RIGID_TOL:
            raise BayesUpdateError(
                f"test.pairs: the best fit scales the test by {s:.4g} (more than 1 % from 1): "
                "check length_unit and the pairs, or set scale = true"
            )
        R, t, s = umeyama(src, dst, False)
    res = np.linalg.norm(src @ (s * R).T + t - dst, axis=1)
    rms = float(np.sqrt(np.mean(res**2)))
    if rms > RIGID_TOL * spread:
        worst = int(np.argmax(res))
        name = names[worst] if len(names) > worst else worst
        raise BayesUpdateError(
            f"test.pairs: not a rigid transform: rms residual {rms:.4g} is over 1 % of the "
            f"pairs' spread {spread:.4g} (worst: pair {name}, {res[worst]:.4g}); check the pairs"
        )
    return Transform(homogeneous(R, t, s), s, res, rms, "pairs")


def from_matrix(matrix, with_scale: bool) -> Transform:
    """Transform of an explicit 3x4 [s R | t]; an error when the 3x3 part is not a proper
    rotation (times one scale if ``with_scale``) within 1 %."""
    m = np.asarray(matrix, dtype=float)
    if m.shape != (3, 4) or not np.all(np.isfinite(m)):
        raise BayesUpdateError("test.align: give a 3x4 matrix [[R | t] rows] of numbers")
    sv = np.linalg.svd(m[:, :3], compute_uv=False)
    s = float(sv.mean())
    bad = sv.max() / sv.min() - 1 > RIGID_TOL if sv.min() > 0 else True
    if bad or np.linalg.det(m[:, :3]) <= 0 or (not with_scale and abs(s - 1) > RIGID_TOL):
        raise BayesUpdateError(
            f"test.align: the 3x3 part is not a rotation within 1 % (singular values "
            f"{np.round(sv, 5).tolist()}, determinant {np.linalg.det(m[:, :3]):.4g}); "
            "give [R | t] with R a rotation (scale = true allows one uniform scale)"
        )
    U, _, Vt = np.linalg.svd(m[:, :3])
    return Transform(homogeneous(U @ Vt, m[:, 3], s), s, np.zeros(0), 0.0, "matrix")


def _proper_axis_maps() -> list[np.ndarray]:
    """The 24 signed permutation matrices with determinant +1."""
    out = []
    for perm in itertools.permutations(range(3)):
        for signs in itertools.product((1.0, -1.0), repeat=3):
            P = np.zeros((3, 3))
            P[range(3), perm] = signs
            if np.linalg.det(P) > 0:
                out.append(P)
    return out


def _principal_axes(points) -> np.ndarray:
    """(3, 3) columns = principal axes, largest spread first, right-handed."""
    _, _, Vt = np.linalg.svd(points - points.mean(axis=0), full_matrices=False)
    V = Vt.T
    if np.linalg.det(V) < 0:
        V[:, 2] *= -1
    return V


@dataclass(frozen=True)
class IcpSettings:
    """ICP knobs: iterations per seed, relative rms change that ends a run on the nodes and
    one on the elements (``icp``'s ``refine``), the ratio of a
    second pose's rms to the best under which the alignment is ambiguous, and the change
    (moving some test point by this fraction of the model's size) that makes two poses
    different."""

    max_iterations: int = 200
    tolerance: float = 1e-10
    refine_tolerance: float = 1e-3
    ambiguity_ratio: float = 2.0
    distinct_size: float = 0.05


def _icp_run(closest, src, start, with_scale, cfg) -> tuple:
    """(matrix, rms, residuals, iterations, converged) of ICP from ``start`` (4, 4);
    ``closest(points)`` -> (distances (n,), model points (n, 3))."""
    m, previous = start, np.inf
    for it in range(1, cfg.max_iterations + 1):
        dist, target = closest(src @ m[:3, :3].T + m[:3, 3])
        rms = float(np.sqrt(np.mean(dist**2)))
        if previous - rms <= cfg.tolerance * max(rms, 1e-300):
            return m, rms, dist, it, True
        previous = rms
        R, t, s = umeyama(src, target, with_scale)
        m = homogeneous(R, t, s)
    return m, rms, dist, cfg.max_iterations, False


def _rodrigues(w) -> np.ndarray:
    """Rotation matrix of the rotation vector w (3,) (Rodrigues' formula)."""
    angle = float(np.linalg.norm(w))
    if angle < 1e-300:
        return np.eye(3)
    k = w / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _surface_step(moved, dist, target) -> tuple[np.ndarray, np.ndarray]:
    """(rotation vector about the points' centroid, translation): the Gauss-Newton step on the
    distances to the surface, d_i + n_i . (w x (p_i - c) + tau) = 0 with n_i the unit vector
    from the foot to the point (Chen & Medioni 1992, "Object modelling by registration of
    multiple range images", Image Vis. Comput. 10(3) 145-155: point-to-plane ICP)."""
    c = moved.mean(axis=0)
    n = np.zeros_like(moved)
    off = dist > 1e-12 * max(float(np.ptp(moved)), 1e-300)
    n[off] = (moved[off] - target[off]) / dist[off, None]
    A = np.column_stack([np.cross(moved - c, n), n])
    x = np.linalg.lstsq(A, -dist * off, rcond=1e-10)[0]
    return x[:3], x[3:]


def _surface_run(closest, src, start, cfg) -> tuple:
    """``_icp_run`` by Gauss-Newton steps on the point-to-surface distances (``_surface_step``)
    with step halving, for the polish onto elements (rigid: no scale)."""
    m = start
    dist, target = closest(src @ m[:3, :3].T + m[:3, 3])
    rms = float(np.sqrt(np.mean(dist**2)))
    for it in range(1, cfg.max_iterations + 1):
        moved = src @ m[:3, :3].T + m[:3, 3]
        w, tau = _surface_step(moved, dist, target)
        c = moved.mean(axis=0)
        for _ in range(8):
            dR = _rodrigues(w)
            trial = homogeneous(dR, c - dR @ c + tau) @ m
            d_new, t_new = closest(src @ trial[:3, :3].T + trial[:3, 3])
            rms_new = float(np.sqrt(np.mean(d_new**2)))
            if rms_new <= rms:
                break
            w, tau = w / 2, tau / 2
        else:
            return m, rms, dist, it, True  # no step lowers the rms: a minimum
        done = rms - rms_new <= cfg.refine_tolerance * max(rms, 1e-300)
        m, rms, dist, target = trial, rms_new, d_new, t_new
        if done:
            return m, rms, dist, it, True
    return m, rms, dist, cfg.max_iterations, False


def _distinct(a, b, src, size, cfg) -> bool:
    """True if poses a and b (4, 4) put some test point (src (n, 3)) farther apart than
    ``cfg.distinct_size`` of the model's size."""
    pa, pb = src @ a[:3, :3].T + a[:3, 3], src @ b[:3, :3].T + b[:3, 3]
    return bool(np.linalg.norm(pa - pb, axis=1).max() > cfg.distinct_size * size)


def _poses(runs, src, size, cfg, keep: int = 3) -> list:
    """The best converged run of each distinct pose, best first, at most ``keep``."""
    out = []
    for r in sorted((r for r in runs if r[4]), key=lambda r: r[1]):
        if all(_distinct(r[0], o[0], src, size, cfg) for o in out):
            out.append(r)
    return out[:keep]


def icp(test_xyz, model_xyz, with_scale: bool = False, cfg: IcpSettings = IcpSettings(),
        refine=None) -> Transform:  # fmt: skip
    """Transform from iterative closest point of the test points (n, 3) onto the model's nodes
    (N, 3) (module docstring); ``refine(points)`` -> (distances, model points), e.g. the nearest
    element points, then polishes the best distinct poses.  Errors when no run converges or two
    distinct poses fit about as well."""
    src, dst = np.asarray(test_xyz, float), np.asarray(model_xyz, float)
    if len(src) < 3:
        raise BayesUpdateError(
            f"test.align = 'auto': {len(src)} test points; iterative closest point needs at "
            "least three, or give align = 'none' or a 3x4 matrix"
        )
    tree = cKDTree(dst)
    nodes = lambda p: (lambda d, i: (d, dst[i]))(*tree.query(p))  # noqa: E731
    size = float(np.ptp(dst, axis=0).max())
    Vt, Vm = _principal_axes(src), _principal_axes(dst)
    runs = []
    for P in _proper_axis_maps():
        R0 = Vm @ P @ Vt.T
        start = homogeneous(R0, dst.mean(axis=0) - R0 @ src.mean(axis=0))
        runs.append(_icp_run(nodes, src, start, with_scale, cfg))
    poses = _poses(runs, src, size, cfg)
    if refine is not None:
        polish = (lambda r: _icp_run(refine, src, r[0], True, cfg)) if with_scale else (
            lambda r: _surface_run(refine, src, r[0], cfg))  # fmt: skip
        poses = _poses([polish(r) for r in poses], src, size, cfg)
    if not poses:
        raise BayesUpdateError(
            f"test.align = 'auto': iterative closest point did not converge in "
            f"{cfg.max_iterations} iterations; give at least three pairs = [[test, model], ...]"
        )
    best = poses[0]
    if len(poses) > 1 and poses[1][1] < cfg.ambiguity_ratio * best[1] + 1e-12 * size:
        raise BayesUpdateError(
            f"test.align = 'auto': ambiguous: two poses fit the model about as well (rms "
            f"{best[1]:.4g} and {poses[1][1]:.4g}; a symmetric test layout); give at least "
            "three pairs = [[test node, model node], ...] or a 3x4 matrix"
        )
    scale = float(np.cbrt(np.linalg.det(best[0][:3, :3])))
    return Transform(best[0], scale, best[2], best[1], "icp", best[3])
