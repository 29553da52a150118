"""LSCE (seed eqs 7-17): exact recovery on noise-free data and unbiased narrow bands."""

import numpy as np
import pytest

from bayesupdate.ema.lsce import band_irf, lsce
from bayesupdate.ema.synthesis import modal_from_poles, poles_from_modal, synthesize_from_modes
from bayesupdate.errors import BayesUpdateError

FN = np.array([20.0, 45.0, 47.0, 80.0])
ZETA = np.array([0.01, 0.02, 0.005, 0.03])


def _exact_discrete_frf(n_lines=1025, df=0.25, seed=0):
    """FRF lines whose inverse FFT is exactly a sum of 4 damped exponential pairs (eq. 9)."""
    s = poles_from_modal(FN, ZETA)
    m = 2 * (n_lines - 1)
    dt = 1 / (m * df)
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(5, 4)) + 1j * rng.normal(size=(5, 4))
    n = np.arange(m)
    irf = 2 * np.real(a[:, :, None] * np.exp(s[None, :, None] * n * dt)).sum(axis=1)
    return np.arange(n_lines) * df, np.fft.rfft(irf, axis=1), s


def test_noise_free_exponentials_recovered_to_1e_6():
    f, h, s_true = _exact_discrete_frf()
    result = lsce(f, h, max_order=8, min_order=8)
    s = result.poles[0]
    assert s.size == 4
    assert np.max(np.abs(s - s_true) / np.abs(s_true)) < 1e-6


def test_band_irf_time_step_is_the_bands_own():
    # 257 lines at 0.5 Hz span 128 Hz: IRF of 512 samples at 1 / (2 * 128) s
    irf, dt = band_irf(np.ones((1, 257)), 0.5)
    assert irf.shape == (1, 512)
    assert dt == pytest.approx(1 / 256)


@pytest.mark.parametrize("band", [(0.0, 120.0), (30.0, 100.0), (35.3, 60.1)])
def test_band_with_lower_limit_is_unbiased(band):
    f = np.arange(0, 128.0001, 0.125)
    rng = np.random.default_rng(1)
    h = synthesize_from_modes(f, FN, ZETA, rng.normal(size=(6, 4)), rng.normal(size=(6, 4)))
    result = lsce(f, h, band_hz=band, max_order=40)
    fr, z = modal_from_poles(result.poles[-1])
    inside = FN[(FN > band[0]) & (FN < band[1])]
    for target, zt in zip(inside, ZETA[np.isin(FN, inside)], strict=True):
        k = np.argmin(np.abs(fr - target))
        assert abs(fr[k] - target) / target < 1e-6
        assert abs(z[k] - zt) / zt < 1e-4


def test_unshifted_band_formula_would_be_biased():
    """The check above can fail: eq. 17 on the base-band poles (no shift back) is far off."""
    f = np.arange(0, 128.0001, 0.125)
    rng = np.random.default_rng(1)
    h = synthesize_from_modes(f, FN, ZETA, rng.normal(size=(6, 4)), rng.normal(size=(6, 4)))
    result = lsce(f, h, band_hz=(35.0, 60.0), max_order=40)
    s_base = result.poles[-1] - 2j * np.pi * 35.0
    fr_biased, _ = modal_from_poles(s_base)
    assert np.min(np.abs(fr_biased - 45.0)) / 45.0 > 0.2


def test_too_few_lines_for_order_is_a_user_error():
    f = np.arange(0, 100.0, 0.5)
    h = np.ones((1, f.size), complex)
    with pytest.raises(BayesUpdateError, match="too few"):
        lsce(f, h, band_hz=(10.0, 30.0), max_order=60)


def test_band_outside_data_is_a_user_error():
    f = np.arange(0, 100.0, 0.5)
    h = np.ones((1, f.size), complex)
    with pytest.raises(BayesUpdateError, match="outside"):
        lsce(f, h, band_hz=(50.0, 200.0))
