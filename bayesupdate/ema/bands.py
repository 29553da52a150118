"""Automatic consecutive narrow analysis bands (seed section 4.1 advice).

The seed advises several consecutive narrow bands instead of one wide one, each with a
power-of-two number of lines (for the FFT to the IRF) and limits where the FRFs are small (local
minima of the sum-FRF), so out-of-band modes disturb little.  Both cannot hold exactly at once, so
each band holds 2^k + 1 lines (an IRF of 2^(k+1) samples), starts at a sum-FRF minimum (the
first starts at the data's start) and reaches past the start of the next band; the next band
starts at the deepest sum-FRF minimum in the upper part of the current one.  Each band *owns* the
range from its start to the next band's start (a minimum, where no mode sits); modes found in the
overlap are owned by the next band, where they are far from the edges.
"""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Band:
    """Line indices of one analysis band: lines lo..hi analysed, modes kept in own_lo..own_hi."""

    lo: int
    hi: int
    own_lo: int
    own_hi: int


def sum_frf(frf: np.ndarray) -> np.ndarray:
    """Sum over FRFs of the FRF magnitude, (n_f,)."""
    return np.sum(np.abs(np.atleast_2d(frf)), axis=0)


def default_band_lines(n_lines: int) -> int:
    """Power of two near a quarter of the lines, between 64 and 2048."""
    k = int(np.round(np.log2(max(n_lines, 4) / 4)))
    return int(np.clip(2**k, 64, 2048))


#: complex FRF values per estimated polynomial coefficient a band must hold at least
MIN_VALUES_PER_COEFFICIENT = 16


def min_band_lines(n_frf: int, order: int) -> int:
    """Power of two at or above MIN_VALUES_PER_COEFFICIENT * order / n_frf lines.

    The estimators fit order coefficients to n_frf x lines values; with few values per
    coefficient the spare poles of a band holding one or two modes fit the data's coherent
    ripple (a sweep's leakage) and stabilize.  Real plate, one FRF, order 40: 256-line bands
    gave 10 such poles in 60-500 Hz, 512 lines 3, 1024 lines 0; the GVT (10 FRFs) and the FE
    exhaust (40 FRFs) are not affected (64 and 16 lines).
    """
    need = MIN_VALUES_PER_COEFFICIENT * max(int(order), 1) / max(int(n_frf), 1)
    return int(2 ** np.ceil(np.log2(max(need, 1.0))))


def automatic_bands(
    frf: np.ndarray,
    start: int = 0,
    stop: int | None = None,
    band_lines: int | None = None,
    order: int = 0,
) -> list[Band]:
    """Consecutive overlapping bands over lines start..stop (inclusive) (module docstring).

    frf : (n_frf, n_f).  band_lines : lines per band minus one (a power of two); default
    :func:`default_band_lines`, raised to :func:`min_band_lines` for the model ``order``.
    """
    frf = np.atleast_2d(frf)
    n_f = frf.shape[1]
    stop = n_f - 1 if stop is None else int(stop)
    n_lines = stop - start + 1
    if band_lines is None:
        width = max(default_band_lines(n_lines), min_band_lines(frf.shape[0], order))
    else:
        width = int(band_lines)
    if n_lines <= width + 1:
        return [Band(start, stop, start, stop)]
    # smooth over 3 lines so single noisy lines do not fake a minimum
    s = np.convolve(sum_frf(frf), np.ones(3) / 3, mode="same")
    bands = []
    lo = start
    while True:
        if lo + width >= stop:
            first = max(start, stop - width)
            bands.append(Band(first, stop, lo, stop))
            return bands
        nxt = _deepest_minimum(s, lo + width // 2, lo + (7 * width) // 8)
        bands.append(Band(lo, lo + width, lo, nxt - 1))
        lo = nxt


def _deepest_minimum(s: np.ndarray, first: int, last: int) -> int:
    """Index of the deepest local minimum of s in first..last (the window minimum if none)."""
    k = np.arange(max(first, 1), min(last, s.size - 2) + 1)
    local = k[(s[k] <= s[k - 1]) & (s[k] <= s[k + 1])]
    if local.size:
        return int(local[np.argmin(s[local])])
    return first + int(np.argmin(s[first : last + 1]))
