"""FRF estimation from force and response time signals: H1, H2 and coherence (Bendat & Piersol).

Averaging (Welch): each repetition is cut into segments (``segment`` samples, ``overlap``
fraction), each segment windowed and Fourier transformed, and the auto/cross spectra
G_ff = <|F|^2>, G_yy = <|Y|^2>, G_fy = <conj(F) Y> averaged over all segments of all
repetitions.  H1 = G_fy / G_ff (noise on the response averages out), H2 = G_yy / conj(G_fy)
(noise on the force averages out), coherence = |G_fy|^2 / (G_ff G_yy).

Windows: ``"hann"`` for random data, ``"rect"`` for sine sweeps (one whole-record spectrum),
periodic signals or fully captured transients, ``"impact"`` for hammer tests: a force window
(1 up to ``force_window_s``, then a short cosine taper to 0) on the force channel and an
exponential window exp(-t / tau) on both channels.  The exponential window adds 1/tau to every
pole's decay rate: a measured pole s' = s - 1/tau, so the identified damping must be corrected with
:func:`correct_exponential_window` (sigma = sigma' - 1/tau, damped frequency unchanged).
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.compute.progress import phase
from bayesupdate.ema.excitation import sine_sweep_top
from bayesupdate.errors import BayesUpdateError

#: the progress phase of ``h1_h2_coherence``, one step per response channel
#: (``compute.progress``)
FRF_PHASE = "FRF estimation"


def impact_windows(
    n_t: int, sample_rate_hz: float, force_window_s: float, tau_s: float
) -> tuple[np.ndarray, np.ndarray]:
    """Force window (n_t,) and exponential window (n_t,) for impact data (module docstring)."""
    t = np.arange(n_t) / sample_rate_hz
    taper = max(force_window_s * 0.1, 2 / sample_rate_hz)
    force_w = np.where(
        t <= force_window_s,
        1.0,
        np.where(
            t <= force_window_s + taper,
            0.5 * (1 + np.cos(np.pi * (t - force_window_s) / taper)),
            0.0,
        ),
    )
    return force_w, np.exp(-t / tau_s)


def _segments(x: np.ndarray, segment: int, step: int) -> np.ndarray:
    """(..., n_rep, n_t) -> (..., n_rep * n_seg, segment) overlapping segments."""
    view = np.lib.stride_tricks.sliding_window_view(x, segment, axis=-1)[..., ::step, :]
    return view.reshape(*x.shape[:-2], -1, segment)


def h1_h2_coherence(
    force: np.ndarray,
    response: np.ndarray,
    sample_rate_hz: float,
    segment: int | None = None,
    overlap: float = 0.5,
    window: str = "hann",
    force_window_s: float | None = None,
    tau_s: float | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """H1, H2 and coherence from force and response signals.

    force, response : (..., n_rep, n_t) or (n_t,) [N] and [response unit]; broadcast against
    each other (one force row may serve many responses).  Averages over repetitions and
    segments.  segment : samples per segment (default the whole record).  Returns
    (frequencies_hz (n_f,), h1, h2, coherence), each (..., n_f).
    """
    x = np.asarray(force, dtype=float)
    y = np.asarray(response, dtype=float)
    if x.ndim == 1:
        x = x[None, :]
    if y.ndim == 1:
        y = y[None, :]
    if x.shape[-1] != y.shape[-1]:
        raise BayesUpdateError(
            f"FRF estimation: force has {x.shape[-1]} samples, response {y.shape[-1]}; "
            "give signals of equal length"
        )
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise BayesUpdateError("FRF estimation: signals contain NaN or inf")
    n_t = x.shape[-1]
    segment = n_t if segment is None else int(segment)
    if not 8 <= segment <= n_t:
        raise BayesUpdateError(f"FRF estimation: segment {segment} must be in 8..{n_t} samples")
    step = max(1, int(round(segment * (1 - overlap))))
    wf, wy = _windows(window, segment, sample_rate_hz, force_window_s, tau_s)
    shape = np.broadcast_shapes(x.shape[:-1], y.shape[:-1])  # (..., n_rep)
    xs = np.broadcast_to(x, (*shape, n_t)).reshape(-1, shape[-1], n_t)
    ys = np.broadcast_to(y, (*shape, n_t)).reshape(-1, shape[-1], n_t)
    # one channel at a time: progress per channel, and the segments of one channel in memory
    # (a long run's segments of all channels at once are the records' size times 2 / overlap)
    shared = x.ndim == 2 or all(n == 1 for n in x.shape[:-2])  # one force row for every channel
    fx_shared = _spectra(xs[0], segment, step, wf) if shared else None
    parts = []
    with phase(FRF_PHASE, ys.shape[0], "channels") as shown:
        for k in range(ys.shape[0]):
            fx = fx_shared if shared else _spectra(xs[k], segment, step, wf)
            parts.append(_h1_h2_coherence(fx, _spectra(ys[k], segment, step, wy)))
            shown.advance()
    h1, h2, coh = (np.stack([p[i] for p in parts]).reshape(*shape[:-1], -1) for i in range(3))
    return np.fft.rfftfreq(segment, 1 / sample_rate_hz), h1, h2, coh


def _windows(window: str, segment: int, sample_rate_hz: float, force_window_s, tau_s):
    """(force window, response window), each (segment,), named as ``h1_h2_coherence`` takes
    them: "hann" (periodic), "rect" or "impact" (``impact_windows``)."""
    if window == "hann":
        wf = wy = np.hanning(segment + 1)[:-1]  # periodic Hann
    elif window == "rect":
        wf = wy = np.ones(segment)
    elif window == "impact":
        if force_window_s is None or tau_s is None:
            raise BayesUpdateError("FRF estimation: impact window needs force_window_s and tau_s")
        fw, ew = impact_windows(segment, sample_rate_hz, force_window_s, tau_s)
        wf, wy = fw * ew, ew
    else:
        raise BayesUpdateError(f"FRF estimation: window {window!r} unknown; use hann/rect/impact")
    return wf, wy


def _spectra(x: np.ndarray, segment: int, step: int, window: np.ndarray) -> np.ndarray:
    """Windowed spectra (n_rep * n_seg, segment // 2 + 1) of the segments of x (n_rep, n_t)."""
    return np.fft.rfft(_segments(x, segment, step) * window, axis=-1)


def _h1_h2_coherence(fx: np.ndarray, fy: np.ndarray) -> tuple[np.ndarray, ...]:
    """(h1, h2, coherence), each (n_f,), of one channel's force and response spectra
    (n_seg, n_f) averaged over the segments (Bendat & Piersol, Random Data, 4th ed., 9.2)."""
    gff = np.mean(np.abs(fx) ** 2, axis=0)
    gyy = np.mean(np.abs(fy) ** 2, axis=0)
    gfy = np.mean(fx.conj() * fy, axis=0)
    tiny = np.finfo(float).tiny
    h1 = gfy / np.maximum(gff, tiny)
    h2 = gyy / np.where(np.abs(gfy) > 0, gfy.conj(), tiny)
    coh = np.abs(gfy) ** 2 / np.maximum(gff * gyy, tiny)
    return h1, h2, np.clip(coh, 0, 1)


def correct_exponential_window(
    frequencies_hz: np.ndarray, damping_ratio: np.ndarray, tau_s: float
) -> tuple[np.ndarray, np.ndarray]:
    """Remove the damping an exponential window exp(-t/tau) added to identified poles.

    Measured pole s' = -zeta' w' + j w' sqrt(1 - zeta'^2); true pole s = s' + 1/tau.
    Returns corrected (natural frequency [Hz], damping ratio), each (m,).
    """
    w = 2 * np.pi * np.asarray(frequencies_hz, dtype=float)
    z = np.asarray(damping_ratio, dtype=float)
    s = -z * w + 1j * w * np.sqrt(1 - z**2) + 1.0 / tau_s
    wn = np.abs(s)
    return wn / (2 * np.pi), -s.real / wn


#: an impact starts where |force| first exceeds this fraction of the record's peak force
IMPACT_THRESHOLD = 0.1


def detect_impacts(force: np.ndarray, sample_rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """Impacts in a hammer force signal (n_t,): start samples (n_hit,) and double-hit flags.

    A hit starts where |f| rises above ``IMPACT_THRESHOLD`` of the peak after at least 20 ms
    below it; a hit whose record (up to the next hit) holds a second pulse above the threshold,
    after the force fell below it, is a double impact (the hammer bounced): its spectrum has
    notches and its FRF is biased.
    """
    above = np.abs(force) > IMPACT_THRESHOLD * np.max(np.abs(force))
    on = np.flatnonzero(above)
    if on.size == 0:
        return np.zeros(0, int), np.zeros(0, bool)
    quiet = max(int(0.02 * sample_rate_hz), 2)
    gaps = np.diff(on)
    pulse_start = np.concatenate([[on[0]], on[1:][gaps > 1]])  # every rise above threshold
    hit_start = np.concatenate([[on[0]], on[1:][gaps > quiet]])  # rises after a quiet spell
    # a second rise within the quiet spell (a bounce) or within 4 pulse lengths is a double hit
    next_hit = np.append(hit_start[1:], force.size)
    double = np.array(
        [
            np.sum((pulse_start > s) & (pulse_start < e)) > 0
            for s, e in zip(hit_start, next_hit, strict=True)
        ]
    )
    return hit_start, double


def impact_segments(
    force: np.ndarray, response: np.ndarray, sample_rate_hz: float, record_s: float | None
) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Cut a hammer test into one record per clean hit: force (n_rec, n_s), response
    (n_resp, n_rec, n_s), and notes on dropped hits.  Each record starts 5 ms (pretrigger)
    before its hit and lasts ``record_s`` (default: the shortest spacing between hits, or
    the time to the end of the signal for one hit)."""
    starts, double = detect_impacts(force, sample_rate_hz)
    if starts.size == 0:
        raise BayesUpdateError("impact test: the force channel holds no hit")
    pre = int(0.005 * sample_rate_hz)
    first = np.maximum(starts - pre, 0)
    if record_s is not None:
        n_s = int(round(record_s * sample_rate_hz))
        if n_s < 8:  # a spectrum of fewer lines resolves nothing
            raise BayesUpdateError(
                f"--record {record_s:g} s: {n_s} samples at {sample_rate_hz:g} Hz; give at least "
                f"{8 / sample_rate_hz:.3g} s"
            )
    elif starts.size > 1:
        n_s = int(np.min(np.diff(first)))
    else:
        n_s = force.size - first[0]
    notes = []
    if np.any(double):
        notes.append(
            f"impact test: {int(double.sum())} of {double.size} hits are double impacts "
            "(the hammer bounced); left out of the average"
        )
    keep = ~double & (first + n_s <= force.size)
    if not np.any(keep):
        raise BayesUpdateError(
            "impact test: no clean hit (every hit is a double impact or too close to the end); "
            "repeat the hits"
        )
    idx = first[keep][:, None] + np.arange(n_s)[None, :]
    return force[idx], response[:, idx], notes


def is_impulsive(force: np.ndarray) -> bool:
    """A hammer force: above 10 % of its peak for under 2 % of the time (a sweep, random or
    sine force is above it most of the time)."""
    return bool(np.mean(np.abs(force) > IMPACT_THRESHOLD * np.max(np.abs(force))) < 0.02)


def _impact_frf(force, response, sample_rate_hz, record_s, tau_s):
    """H1/H2/coherence of a hammer test with force and (if needed) exponential windows."""
    f_rec, y_rec, notes = impact_segments(force, response, sample_rate_hz, record_s)
    n_s = f_rec.shape[-1]
    # force window: twice the time to the last sample above 5 % of each record's peak
    mag = np.abs(f_rec) / np.max(np.abs(f_rec), axis=1, keepdims=True)
    pulse_end = max(int(np.max(np.flatnonzero(np.max(mag[:, : n_s // 2], axis=0) > 0.05))), 1)
    force_window_s = 2 * (pulse_end + 1) / sample_rate_hz
    if tau_s is None:
        # no exponential window when the response has died out by the record's end
        tail = np.sqrt(np.mean(y_rec[..., -max(n_s // 10, 1) :] ** 2))
        peak = np.sqrt(np.max(np.mean(y_rec[..., : max(n_s // 10, 1)] ** 2, axis=-1)))
        if tail > 0.01 * peak:
            tau_s = n_s / sample_rate_hz / np.log(100.0)  # the window ends at 1 %
            notes.append(
                f"impact test: the response has not died out in the {n_s / sample_rate_hz:g} s "
                f"record; exponential window tau = {tau_s:.4g} s applied: every identified "
                f"decay rate includes 1/tau = {1 / tau_s:.4g} 1/s (zeta_true = zeta - "
                f"1/(tau 2 pi f))"
            )
    win_tau = 1e12 if tau_s is None else tau_s
    spec = h1_h2_coherence(
        f_rec[None, :, :], y_rec, sample_rate_hz, segment=n_s, window="impact",
        force_window_s=force_window_s, tau_s=win_tau,
    )  # fmt: skip
    notes.append(f"impact test: {f_rec.shape[0]} hits averaged, {n_s / sample_rate_hz:g} s each")
    gff = np.mean(np.abs(np.fft.rfft(f_rec, axis=-1)) ** 2, axis=0)
    return spec, gff, notes


@dataclass(frozen=True)
class FrfEstimate:
    """FRFs of n_resp responses to one force, as :func:`frf_from_signals` returns them.

    frequencies_hz (n_f,); h1, h2 (n_resp, n_f) complex [response unit / N]; coherence
    (n_resp, n_f), or None when a single spectrum was averaged (it would be 1 everywhere);
    force_autospectrum (n_f,) [relative]; method: "impact", "sweep" or "welch"; sweep_top_hz:
    the top of a sine sweep's fundamental (:func:`~bayesupdate.ema.excitation.sine_sweep_top`)
    or None; notes: one line each, for the user.
    """

    frequencies_hz: np.ndarray
    h1: np.ndarray
    h2: np.ndarray
    coherence: np.ndarray | None
    force_autospectrum: np.ndarray
    method: str
    sweep_top_hz: float | None
    notes: tuple


def frf_from_signals(
    force: np.ndarray,
    response: np.ndarray,
    sample_rate_hz: float,
    method: str = "auto",
    segment: int | None = None,
    record_s: float | None = None,
    tau_s: float | None = None,
    window: str = "hann",
) -> FrfEstimate:
    """FRFs of responses (n_resp, n_rep, n_t) to one force (n_rep, n_t) [SI units], n_rep
    repetitions of one measurement (1-D force / 2-D response: one repetition).

    method "impact" (hits detected, one record per clean hit, force + exponential windows),
    "sweep" (one rectangular-window spectrum per repetition: a sine sweep is a transient
    wholly inside its record, so the whole-record ratio is exact for a linear structure,
    while Welch segments cut the ringing of lightly damped modes from the force that caused
    it: on the mAEWing1 GVT the 7.8 and 23.8 Hz resonances, 0.2 and 0.1 % damped, showed as
    small dips in a Welch H1),
    "welch" (``window`` segments of ``segment`` samples, default the largest power of two
    within a quarter of a repetition, 50 % overlap: random, burst, periodic chirps), or
    "auto": impact when the force is impulsive (:func:`is_impulsive`), sweep when it is a
    sine sweep (:func:`~bayesupdate.ema.excitation.sine_sweep_top`), else welch.  A given
    ``segment`` with "auto" means welch.
    """
    force = np.atleast_2d(np.asarray(force, dtype=float))
    response = np.asarray(response, dtype=float)
    response = response.reshape(-1, *force.shape)
    if method == "auto" and is_impulsive(force.reshape(-1)):
        method = "impact"
    sweep = None if method == "impact" else sine_sweep_top(force, sample_rate_hz)
    if method == "auto":
        method = "sweep" if sweep is not None and segment is None else "welch"
    if method == "impact":  # repetitions end to end: each hit makes its own record
        spec, gff, notes = _impact_frf(
            force.reshape(-1), response.reshape(response.shape[0], -1), sample_rate_hz,
            record_s, tau_s,
        )  # fmt: skip
        return FrfEstimate(*spec, gff, method, None, tuple(notes))
    if method not in ("sweep", "welch"):
        raise BayesUpdateError(f"--method {method!r}: use auto, impact, sweep or welch")
    return _averaged_frf(force, response, sample_rate_hz, method, segment, window, sweep)


def _averaged_frf(force, response, sample_rate_hz, method, segment, window, sweep):
    """:class:`FrfEstimate` of a sweep (one rectangular spectrum per repetition) or of Welch
    segments; force (n_rep, n_t), response (n_resp, n_rep, n_t)."""
    n_t = force.shape[-1]
    if method == "sweep":
        segment, window = n_t, "rect"
    elif segment is None:
        segment = 2 ** int(np.floor(np.log2(max(n_t // 4, 8))))
    if segment > n_t:
        raise BayesUpdateError(
            f"--df: a segment of {segment} samples is longer than the record ({n_t}); "
            f"the finest line spacing is {sample_rate_hz / n_t:g} Hz"
        )
    if segment < 8:  # a spectrum of fewer lines resolves nothing
        raise BayesUpdateError(
            f"--df: a segment of {segment} samples is shorter than 8; "
            f"the coarsest line spacing is {sample_rate_hz / 8:g} Hz"
        )
    f, h1, h2, coh = h1_h2_coherence(force, response, sample_rate_hz, segment, window=window)
    taper = np.hanning(segment + 1)[:-1] if window == "hann" else np.ones(segment)
    seg = _segments(force, segment, max(1, segment // 2)) * taper
    gff = np.mean(np.abs(np.fft.rfft(seg, axis=-1)) ** 2, axis=0)
    notes = [_spectra_note(method, seg.shape[0], segment / sample_rate_hz, window, sweep)]
    if seg.shape[0] == 1:
        coh = None
        notes.append("one spectrum averaged: no coherence (repeat the test to get one)")
    return FrfEstimate(f, h1, h2, coh, gff, method, sweep, tuple(notes))


def _spectra_note(method: str, n_seg: int, seg_s: float, window: str, sweep) -> str:
    if method == "sweep":
        what = "no sine sweep found" if sweep is None else f"sine sweep up to {sweep:.3g} Hz"
        return (
            f"{what}: one whole-record spectrum per repetition ({n_seg} averaged, "
            f"rectangular window, {seg_s:g} s)"
        )
    return f"Welch: {n_seg} {window} segments of {seg_s:g} s, 50 % overlap"
