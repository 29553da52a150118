"""Virtual roving-hammer impact test by modal superposition (for tests, demos and ``simulate``).

Independent of any FE model: give natural frequencies, damping ratios and real mass-normalized
shapes at named sensor DOFs.  Default layout = the seed's test (section 4): 20 sensor points; a
vertical set with the accelerometer fixed at ``1V`` and the hammer roving over ``1V..19V``
(19 FRFs, driving point ``1V/1V``), and a horizontal set with the accelerometer at ``1H`` and the
hammer over ``1H..20H`` (20 FRFs, driving point ``1H/1H``) plus one hit at ``1V`` read by the
``1H`` accelerometer, which ties the sign of the H part of each shape to the V part (without a
cross FRF it is unobservable).

Signals: the hammer force is a half-sine pulse; the record is periodic (the pulse repeats every
record length T), so the steady response is exactly y = IFFT(H(jw) F(jw)) with the analytic
accelerance H of seed eq. 4.  Noise is added to the *time signals*: Gaussian, independent per
hit and channel, with standard deviation ``noise`` times the RMS of the noise-free channel.
FRFs are then estimated with H1 averaged over ``n_averages`` hits (rectangular window; the
periodic record has no leakage), so noise is the only error source.
"""

from dataclasses import dataclass, replace

import numpy as np

from bayesupdate.ema.frf_estimation import h1_h2_coherence
from bayesupdate.ema.frf_set import FrfSet
from bayesupdate.ema.synthesis import synthesize_from_modes
from bayesupdate.errors import BayesUpdateError


def seed_layout(
    n_points: int = 20, reference_v: int = 1, reference_h: int = 1
) -> list[tuple[str, str]]:
    """(response, reference) pairs of the seed's layout: 19 V + 20 H + 1 cross FRF = 40 FRFs.

    The V accelerometer sits at point ``reference_v`` and the hammer roves over 19 of the points
    (all but the last one that is not the reference point, so the driving point is included);
    the H accelerometer at ``reference_h`` sees hammer hits at all points; the cross FRF
    (H accelerometer, V hit at ``reference_v``) ties the signs of the two sets.
    """
    skip_v = n_points if reference_v != n_points else n_points - 1
    pairs = [(f"{reference_v}V", f"{k}V") for k in range(1, n_points + 1) if k != skip_v]
    pairs += [(f"{reference_h}H", f"{k}H") for k in range(1, n_points + 1)]
    pairs.append((f"{reference_h}H", f"{reference_v}V"))
    return pairs


def best_reference_points(
    shapes: np.ndarray, dof_labels: tuple[str, ...], n_points: int = 20, significant: float = 0.05
) -> tuple[int, int]:
    """Pre-test analysis: the accelerometer points (V, H) from which every mode is best seen.

    A roving-hammer set measures psi_i psi_ref, so its reference must move in every mode that has
    motion in the set's direction.  For the V set, the modes whose V part holds at least
    ``significant`` of the shape's norm count; the point maximizing the worst |phi_ref| / max|phi|
    (V part) over those modes wins.  Likewise for H.  shapes : (n_dof, m) at ``dof_labels``.
    """
    index = {lab: i for i, lab in enumerate(dof_labels)}
    total = np.linalg.norm(shapes, axis=0)

    def best(direction):
        rows = [
            index[f"{k}{direction}"] for k in range(1, n_points + 1) if f"{k}{direction}" in index
        ]
        points = [k for k in range(1, n_points + 1) if f"{k}{direction}" in index]
        part = np.abs(shapes[rows])  # (n_points, m)
        matters = np.linalg.norm(part, axis=0) >= significant * np.where(total > 0, total, 1.0)
        if not np.any(matters):
            return points[0]
        vis = part[:, matters] / np.max(part[:, matters], axis=0)
        return points[int(np.argmax(vis.min(axis=1)))]

    return best("V"), best("H")


def half_sine_pulse(t: np.ndarray, duration_s: float, peak_n: float = 100.0) -> np.ndarray:
    """Hammer force [N] (n_t,): peak * sin(pi t / duration) for 0 <= t < duration, else 0."""
    on = (t >= 0) & (t < duration_s)
    return np.where(on, peak_n * np.sin(np.pi * t / duration_s), 0.0)


@dataclass(frozen=True)
class ImpactTestSettings:
    """Knobs of :func:`virtual_impact_test`, validated once here.

    f_max_hz : top of the returned FRFs [Hz], below half the sample rate.  sample_rate_hz [Hz],
    duration_s : record length T [s].  pulse_s : hammer pulse length [s], spanning at least 4
    samples and exciting up to 1.2 f_max_hz (the half-sine spectrum's first zero is at
    1.5 / pulse_s).  noise : relative time-signal noise (module docstring).  n_averages : hits
    averaged per FRF.
    """

    f_max_hz: float = 150.0
    sample_rate_hz: float = 1024.0
    duration_s: float = 16.0
    pulse_s: float = 0.004
    noise: float = 0.01
    n_averages: int = 5

    def __post_init__(self):
        if self.f_max_hz >= self.sample_rate_hz / 2:
            raise BayesUpdateError("virtual test: f_max_hz must be below half the sample rate")
        if self.pulse_s * self.sample_rate_hz < 4:
            raise BayesUpdateError(
                f"virtual test: hammer pulse of {self.pulse_s:g} s spans under 4 samples at "
                f"{self.sample_rate_hz:g} Hz; lengthen the pulse or raise the sample rate"
            )
        if 1.5 / self.pulse_s < 1.2 * self.f_max_hz:
            raise BayesUpdateError(
                f"virtual test: a {self.pulse_s:g} s pulse does not excite up to "
                f"{self.f_max_hz:g} Hz; shorten the pulse"
            )


def _checked_modes(natural_hz, damping_ratio, shapes, dof_labels, layout):
    """The modes as float arrays (m,), (m,), (n_dof, m), the labels (n_dof,) and the layout
    (default :func:`seed_layout`); BayesUpdateError for mismatched sizes or layout DOFs
    without shape values."""
    natural_hz = np.asarray(natural_hz, dtype=float)
    damping_ratio = np.asarray(damping_ratio, dtype=float)
    shapes = np.asarray(shapes, dtype=float)
    labels = tuple(dof_labels)
    if shapes.shape != (len(labels), natural_hz.size) or damping_ratio.shape != natural_hz.shape:
        raise BayesUpdateError(
            f"virtual test: shapes {shapes.shape} must be (n_dof={len(labels)}, "
            f"n_modes={natural_hz.size}) and damping must have one value per mode"
        )
    layout = seed_layout() if layout is None else list(layout)
    missing = sorted({lab for pair in layout for lab in pair} - set(labels))
    if missing:
        raise BayesUpdateError(f"virtual test: layout DOFs {missing} have no shape values")
    return natural_hz, damping_ratio, shapes, labels, layout


def _noisy_signals(h_true, settings: ImpactTestSettings, n_t: int, rng):
    """Time t (n_t,) [s] and the noisy hammer forces [N] and accelerations [m/s^2], each
    (n_frf, n_averages, n_t), of the periodic record for accelerances h_true (n_frf, n_t//2+1)
    on the rfft lines; noise is drawn for the forces first, then the accelerations."""
    t = np.arange(n_t) / settings.sample_rate_hz
    force = half_sine_pulse(t, settings.pulse_s)
    accel = np.fft.irfft(h_true * np.fft.rfft(force)[None, :], n=n_t, axis=1)  # (n_frf, n_t)
    shape = (h_true.shape[0], settings.n_averages, n_t)
    force_rms = np.sqrt(np.mean(force**2))
    accel_rms = np.sqrt(np.mean(accel**2, axis=1))[:, None, None]
    force_n = force[None, None, :] + settings.noise * force_rms * rng.standard_normal(shape)
    accel_n = accel[:, None, :] + settings.noise * accel_rms * rng.standard_normal(shape)
    return t, force_n, accel_n


def virtual_impact_test(
    natural_hz: np.ndarray,
    damping_ratio: np.ndarray,
    shapes: np.ndarray,
    dof_labels: tuple[str, ...],
    layout: list[tuple[str, str]] | None = None,
    settings: ImpactTestSettings | None = None,
    seed: int | np.random.Generator | None = 0,
    return_signals: bool = False,
    **options,
):
    """Simulate the test; returns an accelerance :class:`FrfSet` on 0..f_max_hz.

    natural_hz (m,) [Hz], damping_ratio (m,), shapes (n_dof, m) real mass-normalized
    [1/sqrt(kg)] at ``dof_labels``; layout: (response, reference) label pairs (default
    :func:`seed_layout`).  settings : :class:`ImpactTestSettings` (default: its defaults);
    options : fields of it to set or override, for calls without a record
    (``noise=0.0``).  With ``return_signals`` also returns (t (n_t,), force (n_frf, n_avg,
    n_t), accel (same)).
    """
    settings = ImpactTestSettings(**options) if settings is None else replace(settings, **options)
    natural_hz, damping_ratio, shapes, labels, layout = _checked_modes(
        natural_hz, damping_ratio, shapes, dof_labels, layout
    )
    rng = np.random.default_rng(seed)
    n_t = int(round(settings.duration_s * settings.sample_rate_hz))
    f_all = np.fft.rfftfreq(n_t, 1 / settings.sample_rate_hz)
    index = {lab: i for i, lab in enumerate(labels)}
    resp = shapes[[index[a] for a, _ in layout]]
    ref = shapes[[index[b] for _, b in layout]]
    h_true = synthesize_from_modes(f_all, natural_hz, damping_ratio, resp, ref, "accelerance")
    t, force_n, accel_n = _noisy_signals(h_true, settings, n_t, rng)
    freqs, h1, _, coh = h1_h2_coherence(
        force_n, accel_n, settings.sample_rate_hz, segment=n_t, window="rect"
    )
    keep = freqs <= settings.f_max_hz + 1e-9
    frfs = FrfSet(
        frequencies_hz=freqs[keep],
        frf=h1[:, keep],
        response_labels=tuple(a for a, _ in layout),
        reference_labels=tuple(b for _, b in layout),
        kind="accelerance",
        coherence=coh[:, keep],
        source="virtual impact test",
    )
    if return_signals:
        return frfs, (t, force_n, accel_n)
    return frfs
