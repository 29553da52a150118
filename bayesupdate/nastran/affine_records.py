"""Records read from a deck's cards as affine (or bilinear) functions of the parameters, found
from the reader itself.

A parameter bound to a card field (a PBEAM's A, a MAT1's RHO, a CBEAM's W1A, a CONM2's X1)
changes numbers the reader derives from the card: a beam's area, its end offset in basic
axes, a point mass's offset.  Most of those are affine in the field (the reader scales it by
WTMASS, rotates it by a fixed frame, adds it to the others); a product of two bound fields
(rho A, the mass per length) is bilinear in them.  ``fit_records`` finds the map once from the
reader's own records at the deck's values and one step per parameter,

    r(theta) = r(theta0) + sum_j dr_j (theta_j - theta0_j)
               + sum_{i<j} d2r_ij (theta_i - theta0_i)(theta_j - theta0_j),

the cross terms only where the affine part misses, and only of parameters that move one
record of one element, each from one more reading at theta0 + step_i e_i + step_j e_j.  It
checks the result at seeded points of the box against fresh readings to ``RECORD_TOL`` of each
record's largest value: it holds exactly there, or the caller keeps reading the cards.
"""

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np

#: relative miss allowed between the fitted records and the reader's (exact: ~1e-16)
RECORD_TOL = 1e-12
#: the seeded points of the box where the fitted records are checked
CHECK_SEED, CHECK_POINTS = 0, 3

#: a reading: the records {key: array} at a point theta (p,), or None where the parameters
#: change which elements there are (nodes, element count), so no record map exists
Reading = Callable[[np.ndarray], "dict[str, np.ndarray] | None"]


@dataclass(frozen=True, eq=False)
class AffineRecords:
    """Records as functions of the parameters (module docstring).

    names : the parameters (``theta`` order); theta0 : (p,) their deck values; at0 : {key:
    array} the records at theta0; slopes : {key: (..., p) d r / d theta} of the records that
    move; pairs : {key: (..., q) d^2 r / d theta_i d theta_j} of the q pairs ``pair_index``
    ((i, j), i < j) where a record is a product of two fields."""

    names: tuple[str, ...]
    theta0: np.ndarray
    at0: dict
    slopes: dict
    pairs: dict
    pair_index: tuple = ()

    @cached_property
    def moving(self) -> frozenset[str]:
        """The keys of the records that move with the parameters (found once: a solve asks
        for them per family)."""
        return frozenset(self.slopes) | frozenset(self.pairs)

    def at(self, theta: np.ndarray) -> dict:
        """{key: array} the records at ``theta`` (p,)."""
        step = np.asarray(theta, float) - self.theta0
        out = dict(self.at0)
        for key, slope in self.slopes.items():
            out[key] = self.at0[key] + slope @ step
        if self.pairs:
            both = np.array([step[i] * step[j] for i, j in self.pair_index])
            for key, pair in self.pairs.items():
                out[key] = out[key] + pair @ both
        return out


def steps(theta0: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """(p,) the step of each parameter for its slope: to the far bound (the upper one unless
    theta0 sits on it), so that the slope is exact for an affine record and large enough not to
    lose digits."""
    return np.where(high > theta0, high, low) - theta0


def fit_records(read: Reading, names, theta0, low, high) -> tuple[AffineRecords | None, str]:
    """(``AffineRecords``, "") of the reading ``read`` over the box [low, high] (p,), or (None,
    the reason) where the records are not affine or bilinear in the parameters there.

    read : the reader's records at a point (``Reading``); names, theta0 : the parameters and
    their deck values (p,)."""
    names, theta0 = tuple(names), np.asarray(theta0, float)
    at0 = read(theta0)
    if at0 is None:
        return None, "the deck's values change which elements there are"
    step = steps(theta0, low, high)
    slopes = {}
    for j in range(len(names)):
        at = read(theta0 + step[j] * (np.arange(len(names)) == j))
        if at is None:
            return None, f"{names[j]} changes which elements or masses there are"
        for key, r0 in at0.items():
            d = (at[key] - r0) / step[j]
            if np.any(d != 0):
                slopes.setdefault(key, np.zeros((*d.shape, len(names))))[..., j] = d
    fit = AffineRecords(names, theta0, at0, slopes, {})
    reason = _miss(read, fit, low, high)
    if reason and len(names) > 1:
        fit = _with_pairs(read, fit, step)
        if fit is None:
            return None, "a parameter changes which elements or masses there are"
        reason = _miss(read, fit, low, high)
    return (None, reason) if reason else (fit, "")


def _with_pairs(read: Reading, fit: AffineRecords, step: np.ndarray) -> AffineRecords | None:
    """``fit`` with the cross terms of every pair of parameters, each from one reading at
    theta0 + step_i e_i + step_j e_j (the single steps are the slopes' own points); None where
    a reading changes the elements."""
    p = len(fit.names)
    index = _sharing(fit.slopes, p)
    pairs = {}
    for q, (i, j) in enumerate(index):
        theta = fit.theta0 + step * np.isin(np.arange(p), (i, j))
        at = read(theta)
        if at is None:
            return None
        affine = fit.at(theta)
        for key, exact in at.items():
            d = exact - affine[key]
            d = np.where(np.abs(d) > RECORD_TOL * _scale(exact), d, 0.0)
            if np.any(d != 0):
                pairs.setdefault(key, np.zeros((*d.shape, len(index))))[..., q] = d / (
                    step[i] * step[j]
                )
    return AffineRecords(fit.names, fit.theta0, fit.at0, fit.slopes, pairs, index)


def _sharing(slopes: dict, p: int) -> tuple[tuple[int, int], ...]:
    """The pairs (i, j), i < j, of parameters that move one and the same record of one element
    (a record's first axis is its elements): the only products a reading can hold where each
    factor moves it alone.  Any other product is caught by ``_miss``."""
    index = set()
    for slope in slopes.values():
        moves = slope.reshape(slope.shape[0], -1, p) if slope.ndim > 1 else slope[None]
        moves = np.any(moves != 0, axis=1)  # (elements, p)
        for row in np.unique(moves, axis=0):
            both = np.flatnonzero(row)
            index.update((int(i), int(j)) for k, i in enumerate(both) for j in both[k + 1 :])
    return tuple(sorted(index))


def _miss(read: Reading, fit: AffineRecords, low, high) -> str:
    """ "" when ``fit`` equals fresh readings at the seeded points of the box (``CHECK_SEED``,
    ``CHECK_POINTS``) to ``RECORD_TOL``, else the reason."""
    rng = np.random.default_rng(CHECK_SEED)
    for u in rng.uniform(size=(CHECK_POINTS, len(fit.names))):
        theta = low + u * (high - low)
        at = read(theta)
        if at is None:
            return "a parameter changes which elements or masses there are"
        mine = fit.at(theta)
        for key, exact in at.items():
            if exact.size and np.abs(exact - mine[key]).max() > RECORD_TOL * _scale(exact):
                field = key.split(".", 1)[-1]
                return f"the elements' {field} is not affine in {', '.join(fit.names)}"
    return ""


def _scale(x: np.ndarray) -> float:
    return max(float(np.abs(x).max(initial=0.0)), 1e-300)
