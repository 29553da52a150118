"""Which lines a measured force excites: its level (:func:`excited_band`) and, for a sine sweep,
the top its fundamental reaches (:func:`sine_sweep_top`).

A shaker's sine sweep also pushes at 2x, 3x ... the swept frequency (armature and stinger
distortion; mAEWing1 GVT: the force at 35-70 Hz, above a 1-35 Hz sweep, only 6-15 dB below its
in-band level, with coherence 0.97-0.99, as the distortion is as deterministic as the sweep).
Those lines are no excitation of the structure's FRF: a resonance passed by the fundamental
rings with harmonics whose ratio to the force harmonics peaks at multiples of the resonance
(GVT: stable poles at 39.6, 47.4, 55.2 Hz, 5, 6 and 7 x 7.9 Hz).  The force level cannot tell
them from the sweep, but time can: at each moment a sweep's energy sits in one line, its
fundamental, and a harmonic dominates only while the structure absorbs the fundamental at a
resonance (force drop-out), for a few moments off the sweep's smooth track.
"""

import numpy as np
from scipy.ndimage import median_filter

from bayesupdate.errors import BayesUpdateError

#: short spectra per record in the sweep test: fine enough in time that a sweep over the whole
#: record crosses under one line per spectrum ((f_hi - f_lo) n_t / fs < 64^2 lines), fine
#: enough in frequency (fs 64 / n_t) to place its top within a line
SWEEP_SEGMENTS = 64
#: a force is a sine sweep when, in the median short spectrum, this share of the energy lies
#: within +-2 lines of the strongest line (GVT 0.85, real plate 0.997, white noise 0.03)
SWEEP_CONCENTRATION = 0.5
#: short spectra over which the sweep's track is smoothed (a running median): harmonic
#: excursions at force drop-outs last a few spectra (GVT: at most 3 of 58)
TRACK_SMOOTHING = 9


def sine_sweep_top(force: np.ndarray, sample_rate_hz: float) -> float | None:
    """Highest frequency [Hz] a sine sweep's fundamental reaches, or None for any other force.

    force (n_rep, n_t) or (n_t,).  Each repetition is cut into ``SWEEP_SEGMENTS`` Hann-windowed
    short spectra (mean removed, DC line ignored); spectra above 1 % of the median energy are
    active.  The force is a sweep when the median share of energy within +-2 lines of each
    spectrum's strongest line is at least ``SWEEP_CONCENTRATION``.  The track is the strongest
    line of each active spectrum; those within 2 lines of its running median over
    ``TRACK_SMOOTHING`` spectra are the fundamental (module docstring); the top is theirs
    plus one short-spectrum line (the sweep moves within a spectrum).  (Its bottom is not
    returned: where a shaker cannot push, at the lowest frequencies, the harmonics dominate
    the whole time; the force level decides there, :func:`excited_band`.)
    """
    x = np.atleast_2d(np.asarray(force, dtype=float))
    n_t = x.shape[-1]
    seg = 2 ** int(np.round(np.log2(max(n_t / SWEEP_SEGMENTS, 16))))
    if n_t < 8 * seg:
        return None
    segs = np.lib.stride_tricks.sliding_window_view(x, seg, axis=-1)[:, ::seg]  # (n_rep, n_s, seg)
    segs = segs - segs.mean(axis=-1, keepdims=True)
    spec = np.abs(np.fft.rfft(segs * np.hanning(seg + 1)[:-1], axis=-1)) ** 2
    spec[..., 0] = 0.0
    energy = spec.sum(axis=-1)
    active = energy > 0.01 * np.median(energy)
    peak = np.argmax(spec, axis=-1)  # (n_rep, n_s)
    lines = np.clip(peak[..., None] + np.arange(-2, 3), 0, spec.shape[-1] - 1)
    near = np.take_along_axis(spec, lines, axis=-1).sum(axis=-1)
    share = near / np.where(energy > 0, energy, 1.0)
    if not np.any(active) or np.median(share[active]) < SWEEP_CONCENTRATION:
        return None
    on_track = []
    for k, a in zip(peak, active, strict=True):  # per repetition: a track runs in time
        k = k[a].astype(float)
        if k.size >= 3:
            smooth = median_filter(k, size=min(TRACK_SMOOTHING, k.size), mode="nearest")
            on_track.append(k[np.abs(k - smooth) <= 2])
    track = np.concatenate(on_track) if on_track else np.zeros(0)
    if track.size == 0:
        return None
    return float((track.max() + 1) * sample_rate_hz / seg)


def excited_band(
    frequencies_hz: np.ndarray,
    gff: np.ndarray,
    floor: float = 1e-3,
    sweep_top_hz: float | None = None,
) -> tuple[float, float]:
    """(lo, hi) [Hz]: the contiguous lines around the force autospectrum's peak where its
    envelope stays at least ``floor`` (-30 dB) of its in-band level (the median over the lines
    within 10 dB of its peak), and, for a sine sweep, not above its fundamental's top
    (``sweep_top_hz`` from :func:`sine_sweep_top`: the lines above hold its harmonics).

    The envelope is the running maximum over +-10 % of each line's frequency: a shaker's force
    drops out by 20-30 dB at the structure's own resonances (GVT near 7.8 Hz, plate near 350
    and 450 Hz), which must not end the band.  Outside, the FRF holds noise (or a DC drift's
    leakage, which a gap separates from the excited band).
    """
    f = np.asarray(frequencies_hz, dtype=float)
    g = np.where(f > 0, gff, 0.0)
    df = f[1] - f[0]
    half = np.maximum(np.rint(0.1 * f / df).astype(int), 2)
    idx = np.arange(f.size)
    lo_i, hi_i = np.maximum(idx - half, 0), np.minimum(idx + half + 1, f.size)
    # a running maximum over windows growing with frequency: a cumulative maximum would need
    # a sparse table; once per command over n_f lines is cheap
    env = np.array([g[a:b].max() for a, b in zip(lo_i, hi_i, strict=True)])
    level = np.median(g[g >= 0.1 * np.max(g)])
    low = env < floor * level
    if sweep_top_hz is not None:
        low |= f > sweep_top_hz
    top = int(np.argmax(np.where(low, 0.0, g)))
    below, above = np.flatnonzero(low[:top]), np.flatnonzero(low[top:])
    lo = below[-1] + 1 if below.size else 1
    hi = top + above[0] - 1 if above.size else f.size - 1
    if hi - lo < 3:
        raise BayesUpdateError("FRF estimation: the force excites fewer than 4 lines")
    return float(f[lo]), float(f[hi])
