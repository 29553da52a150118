"""Indicators (CMIF, FRAC), automatic bands, MPC, synthesis identities."""

import numpy as np
import pytest

from bayesupdate.ema.bands import automatic_bands, sum_frf
from bayesupdate.ema.frf_set import FrfSet
from bayesupdate.ema.indicators import cmif, frf_correlation
from bayesupdate.ema.lsfd import lsfd_residues, mpc
from bayesupdate.ema.synthesis import (
    poles_from_modal,
    residues_from_shapes,
    synthesize_frf,
    synthesize_from_modes,
)


def test_accelerance_equals_minus_omega_squared_receptance():
    f = np.linspace(1, 100, 200)
    phi = np.array([[1.0, 0.5], [0.3, -0.8]])
    rec = synthesize_from_modes(f, [20, 60], [0.01, 0.02], phi, phi, "receptance")
    acc = synthesize_from_modes(f, [20, 60], [0.01, 0.02], phi, phi, "accelerance")
    assert np.allclose(acc, -((2 * np.pi * f) ** 2) * rec, rtol=1e-12)
    # at resonance a single mode's receptance is phi^2 / (2 j zeta w^2)
    one = synthesize_from_modes(
        np.array([20.0]), [20], [0.01], np.ones((1, 1)), np.ones((1, 1)), "receptance"
    )
    w = 2 * np.pi * 20
    assert one[0, 0] == pytest.approx(1 / (2j * 0.01 * w**2), rel=1e-12)


def test_cmif_rank_one_at_isolated_mode_and_two_curves_for_a_pair():
    f = np.arange(0, 100.0, 0.05)
    labels_out = ("1V", "2V")
    labels_in = ("1V", "2V", "3V")
    phi = {"1V": [1.0, 0.2], "2V": [0.4, 1.0], "3V": [-0.7, 0.6]}
    rows = [(o, i) for o in labels_out for i in labels_in]
    resp = np.array([phi[o] for o, _ in rows])
    ref = np.array([phi[i] for _, i in rows])
    h = synthesize_from_modes(f, [30.0, 30.6], [0.002, 0.002], resp, ref)
    frfs = FrfSet(f, h, tuple(o for o, _ in rows), tuple(i for _, i in rows))
    sv = cmif(frfs)
    assert sv.shape == (2, f.size)
    k1, k2 = np.argmin(np.abs(f - 30.0)), np.argmin(np.abs(f - 30.6))
    # each mode dominates the first singular value at its own peak; at the pair both curves are
    # large, far from the pair the second one is far below the first
    assert sv[1, k1] > 0.05 * sv[0, k1] and sv[1, k2] > 0.05 * sv[0, k2]
    far = np.argmin(np.abs(f - 80.0))
    assert sv[1, far] < sv[0, far]


def test_frac_and_mpc():
    rng = np.random.default_rng(0)
    m = rng.normal(size=(3, 50)) + 1j * rng.normal(size=(3, 50))
    assert np.allclose(frf_correlation(m, 2.5j * m), 1.0)
    assert frf_correlation(m[:1], m[1:2])[0] < 0.2
    real = rng.normal(size=(10, 2))
    assert np.allclose(mpc(real * np.exp(0.7j)), 1.0)
    circ = np.exp(1j * np.linspace(0, 2 * np.pi, 8, endpoint=False))[:, None]
    assert mpc(circ)[0] == pytest.approx(0.0, abs=1e-12)


def test_lsfd_recovers_residues_and_residuals():
    f = np.arange(0.5, 100.0, 0.25)
    poles = poles_from_modal([25.0, 55.0], [0.01, 0.02])
    res = residues_from_shapes(
        poles, np.array([[1.0, 0.4], [0.2, -0.9]]), np.array([[1.0, 0.4], [1.0, 0.4]])
    )
    lower, upper = np.array([2e-3, -1e-3]), np.array([1e-7, 3e-7])
    h = synthesize_frf(f, poles, res, "accelerance", lower, upper)
    est, lo, up = lsfd_residues(f, h, poles, "accelerance")
    assert np.allclose(est, res, rtol=1e-8)
    assert np.allclose(lo, lower, rtol=1e-6) and np.allclose(up, upper, rtol=1e-6)


def test_automatic_bands_power_of_two_and_minima():
    f = np.arange(0, 150.0, 1 / 16)
    h = synthesize_from_modes(
        f, [12.0, 40.0, 70.0, 100.0, 130.0], [0.01] * 5, np.ones((1, 5)), np.ones((1, 5))
    )
    bands = automatic_bands(h, band_lines=512)
    assert len(bands) >= 3
    assert all(b.hi - b.lo == 512 for b in bands)  # 513 lines: IRF of 1024 samples
    assert bands[0].lo == 0 and bands[-1].hi == f.size - 1
    s = np.convolve(sum_frf(h), np.ones(3) / 3, mode="same")  # bands smooth over 3 lines
    for prev, nxt in zip(bands[:-1], bands[1:], strict=True):
        # each later band starts at a local minimum of the sum-FRF, inside the previous band
        k = nxt.own_lo
        assert prev.lo < k < prev.hi
        window = np.arange(prev.lo + 256, prev.lo + 449)
        local = window[(s[window] <= s[window - 1]) & (s[window] <= s[window + 1])]
        if local.size:  # the deepest local minimum of the window ...
            assert s[k] == pytest.approx(s[local].min())
        else:  # ... or, where the sum-FRF only rises or falls, the window's lowest line
            assert s[k] == pytest.approx(s[window].min())
        assert prev.own_hi == k - 1
    assert any(s[b.own_lo] <= s[b.own_lo - 1] and s[b.own_lo] <= s[b.own_lo + 1] for b in bands[1:])
