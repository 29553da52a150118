"""FRF estimation from force and response time signals: H1, H2 and coherence (Bendat & Piersol).

Averaging (Welch): each repetition is cut into segments (``segment`` samples, ``overlap``
fraction), each segment windowed and Fourier transformed, and the auto/cross spectra
G_ff = <|F|^2>, G_yy = <|Y|^2>, G_fy = <conj(F) Y> averaged over all segments of all
repetitions.  H1 = G_fy / G_ff (noise on the response averages out), H2 = G_yy / conj(G_fy)
(noise on the force averages out), coherence = |G_fy|^2 / (G_ff G_yy).

Windows: ``"hann"`` for random and sweep data, ``"rect"`` for periodic or fully captured
transients, ``"impact"`` for hammer tests: a force window (1 up to ``force_window_s``, then a
short cosine taper to 0) on the force channel and an exponential window exp(-t / tau) on both
channels.  The exponential window adds 1/tau to every pole's decay rate: a measured pole
s' = s - 1/tau, so the identified damping must be corrected with
:func:`correct_exponential_window` (sigma = sigma' - 1/tau, damped frequency unchanged).
"""

import numpy as np

from bayesupdate.errors import BayesUpdateError


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
    fx = np.fft.rfft(_segments(x, segment, step) * wf, axis=-1)
    fy = np.fft.rfft(_segments(y, segment, step) * wy, axis=-1)
    gff = np.mean(np.abs(fx) ** 2, axis=-2)
    gyy = np.mean(np.abs(fy) ** 2, axis=-2)
    gfy = np.mean(fx.conj() * fy, axis=-2)
    tiny = np.finfo(float).tiny
    h1 = gfy / np.maximum(gff, tiny)
    h2 = gyy / np.where(np.abs(gfy) > 0, gfy.conj(), tiny)
    coh = np.abs(gfy) ** 2 / np.maximum(gff * gyy, tiny)
    return np.fft.rfftfreq(segment, 1 / sample_rate_hz), h1, h2, np.clip(coh, 0, 1)


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
