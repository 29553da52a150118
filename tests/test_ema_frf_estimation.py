"""FRF estimation: H1/H2/coherence and the exponential-window damping correction."""

import numpy as np
import pytest

from bayesupdate.ema.frf_estimation import correct_exponential_window, h1_h2_coherence
from bayesupdate.ema.lsce import lsce
from bayesupdate.ema.synthesis import modal_from_poles, synthesize_from_modes

FS = 1024.0


def _periodic_response(force, fn=50.0, zeta=0.02):
    n = force.shape[-1]
    f = np.fft.rfftfreq(n, 1 / FS)
    h = synthesize_from_modes(f, [fn], [zeta], np.ones((1, 1)), np.ones((1, 1)), "accelerance")
    return np.fft.irfft(np.fft.rfft(force, axis=-1) * h[0], n=n, axis=-1), f, h[0]


def test_h1_exact_for_noise_free_periodic_random():
    rng = np.random.default_rng(0)
    force = rng.standard_normal((4, 2048))
    resp, f, h_true = _periodic_response(force)
    freqs, h1, h2, coh = h1_h2_coherence(force, resp, FS, window="rect")
    assert np.allclose(freqs, f)
    # the Nyquist line of a real signal cannot carry an imaginary part: leave it out
    assert np.max(np.abs(h1[1:-1] - h_true[1:-1])) < 1e-9 * np.abs(h_true).max()
    assert np.allclose(coh[1:], 1.0, atol=1e-9)


def test_h1_h2_coherence_relation_with_response_noise():
    rng = np.random.default_rng(1)
    force = rng.standard_normal((16, 1024))
    resp, _, h_true = _periodic_response(force)
    resp = resp + 0.3 * resp.std() * rng.standard_normal(resp.shape)
    _, h1, h2, coh = h1_h2_coherence(force, resp, FS, window="rect")
    # H1 = coherence * H2 identically; response noise lowers the coherence
    assert np.allclose(h1[1:], coh[1:] * h2[1:], rtol=1e-9)
    assert np.median(coh[1:]) < 0.99
    peak = np.argmax(np.abs(h_true))
    assert abs(h1[peak] - h_true[peak]) / abs(h_true[peak]) < 0.05


def test_exponential_window_damping_correction():
    fn, zeta, tau = 40.0, 0.004, 0.5
    t = np.arange(8192) / FS
    s = -zeta * 2 * np.pi * fn + 1j * 2 * np.pi * fn * np.sqrt(1 - zeta**2)
    force = np.where(t < 0.002, np.sin(np.pi * t / 0.002), 0.0)
    # transient response to the short pulse, convolved in time (not periodic)
    irf = np.imag(np.exp(s * t)) / FS
    resp = np.convolve(force, irf)[: t.size]
    f, h1, _, _ = h1_h2_coherence(force, resp, FS, window="impact", force_window_s=0.01, tau_s=tau)
    result = lsce(f, h1[None, :], band_hz=(20.0, 60.0), max_order=8, min_order=8)
    fr, z = modal_from_poles(result.poles[0])
    k = np.argmin(np.abs(fr - fn))
    # the window adds 1/tau to the decay: zeta' = zeta + 1/(tau w)
    assert z[k] == pytest.approx(zeta + 1 / (tau * 2 * np.pi * fn), rel=0.02)
    fc, zc = correct_exponential_window(fr[k : k + 1], z[k : k + 1], tau)
    assert zc[0] == pytest.approx(zeta, rel=0.05)
    assert fc[0] == pytest.approx(fn, rel=1e-3)
