"""Piecewise Chebyshev interpolation in barycentric form (Berrut & Trefethen, SIAM Rev. 46, 2004).

The reduced model interpolates the element matrices of parameters that do not enter K or M
linearly (wall thickness, bend factor) in log(value), on Chebyshev points of the second kind,
piecewise between breakpoints (the kinks of the B31.3 elbow factor) and tensor-product when
several such parameters act on the same beams.  The weights are linear in the interpolated
values, so projecting the node matrices once gives the reduced matrices for every theta.
"""

import numpy as np


def chebyshev_nodes(low: float, high: float, degree: int) -> np.ndarray:
    """(degree + 1,) Chebyshev points of the second kind on [low, high], ascending."""
    k = np.arange(degree + 1)
    return low + (high - low) * 0.5 * (1.0 - np.cos(np.pi * k / degree))


def piecewise_nodes(pieces: np.ndarray, degree: int) -> np.ndarray:
    """(P * (degree + 1),) the nodes of every piece of the breakpoints ``pieces`` (P + 1,), in
    piece order (the column order of ``barycentric_weights``)."""
    return np.concatenate(
        [chebyshev_nodes(pieces[k], pieces[k + 1], degree) for k in range(pieces.size - 1)]
    )


def barycentric_weights(x: np.ndarray, pieces: np.ndarray, degree: int) -> np.ndarray:
    """Lagrange basis values of a piecewise Chebyshev interpolant.

    x : (B,) points; pieces : (P + 1,) ascending breakpoints.  Returns (B, P * (degree + 1)): the
    weight of each piece's node values, zero outside the piece holding x (Berrut & Trefethen 2004,
    eq. 4.2 with the second-kind weights (-1)^j, halved at the ends).
    """
    x = np.asarray(x, dtype=float).reshape(-1, 1)
    return barycentric_weights_columns(x, np.asarray(pieces, dtype=float)[None, :], degree)[:, 0]


def barycentric_weights_columns(x: np.ndarray, pieces: np.ndarray, degree: int) -> np.ndarray:
    """``barycentric_weights`` for G interpolants of the same degree and piece count at once:
    x (B, G), pieces (G, P + 1) -> (B, G, P * (degree + 1)).  Vectorized over points, columns
    and pieces: it runs in every likelihood call."""
    B, G = x.shape
    n = degree + 1
    P = pieces.shape[1] - 1
    w = (-1.0) ** np.arange(n)
    w[0] *= 0.5
    w[-1] *= 0.5
    which = np.empty((B, G), dtype=int)
    for g in range(G):  # G is the number of interpolated parameters (a handful)
        which[:, g] = np.searchsorted(pieces[g], x[:, g], side="right") - 1
    np.clip(which, 0, P - 1, out=which)
    cols = np.arange(G)[None, :]
    low, high = pieces[cols, which], pieces[cols, which + 1]
    unit = 0.5 * (1.0 - np.cos(np.pi * np.arange(n) / degree))
    d = x[..., None] - (low[..., None] + (high - low)[..., None] * unit)  # (B, G, n)
    exact = d == 0.0
    q = w / np.where(exact, 1.0, d)
    lag = q / q.sum(axis=-1, keepdims=True)
    hit = exact.any(axis=-1)
    if np.any(hit):
        lag[hit] = exact[hit].astype(float)
    out = np.zeros((B, G, P * n))
    np.put_along_axis(out, which[..., None] * n + np.arange(n), lag, axis=-1)
    return out


def tensor_weights(values: np.ndarray, log_pieces, degrees) -> np.ndarray:
    """Tensor-product weights of an interpolant in log(value): values (B, k) > 0, one column per
    axis with breakpoints ``log_pieces[i]`` (in log) and degree ``degrees[i]``.  Returns
    (B, prod_i P_i (d_i + 1)), the last axis varying fastest (the order of
    ``np.meshgrid(..., indexing="ij")`` of the per-axis nodes); k = 0 gives (B, 1) ones."""
    if len(log_pieces) == 0:
        return np.ones((values.shape[0], 1))
    w = None
    for i, p in enumerate(log_pieces):
        wi = barycentric_weights(np.log(values[:, i]), p, degrees[i])
        w = wi if w is None else np.einsum("bi,bj->bij", w, wi).reshape(wi.shape[0], -1)
    return w
