"""Automatic identification on virtual impact tests (seed layout, 1 % noise)."""

import numpy as np
import pytest
from synthetic_models import exhaust_like_model, free_beam_shapes

from bayesupdate.correlation import mac_matrix
from bayesupdate.ema.bands import sum_frf
from bayesupdate.ema.identify import identify
from bayesupdate.ema.virtual_test import virtual_impact_test


@pytest.fixture(scope="module")
def exhaust_case():
    fn, zeta, shapes, labels = exhaust_like_model()
    frfs = virtual_impact_test(fn, zeta, shapes, labels, noise=0.01, seed=3)
    return fn, zeta, shapes, labels, frfs, identify(frfs)


def test_twelve_modes_found_none_spurious(exhaust_case):
    fn, _, _, _, _, result = exhaust_case
    assert result.modes.n_modes == 12
    assert np.max(np.abs(result.modes.frequencies_hz - fn) / fn) <= 0.002


def test_twelve_modes_damping_and_shapes(exhaust_case):
    _, zeta, shapes, labels, _, result = exhaust_case
    modes = result.modes
    assert np.max(np.abs(modes.damping_ratio - zeta) / zeta) <= 0.10
    true = shapes[[labels.index(lab) for lab in modes.dof_labels]]
    mac = np.diag(mac_matrix(true, modes.shapes))
    assert mac.min() >= 0.98
    assert np.all(result.mass_normalized)
    # driving points give mass-normalized shapes: scale error of the real part below 2 %
    from bayesupdate.ema.lsfd import realize

    est = realize(modes.shapes)
    scale = np.sum(est * true, axis=0) / np.sum(true * true, axis=0)
    assert np.max(np.abs(np.abs(scale) - 1)) < 0.02
    assert modes.mpc.min() > 0.95
    assert np.all(modes.extra["stable_orders"] >= 5)


def test_synthesized_frfs_match_measured(exhaust_case):
    assert exhaust_case[5].frf_correlation.min() > 0.99


def test_close_pair_and_weak_mode_found():
    x = (np.arange(20) + 0.5) / 20
    phi = free_beam_shapes(x, 4)
    fn = np.array([30.0, 40.0, 40.6, 70.0, 95.0])  # 40 / 40.6: 1.5 % apart
    zeta = np.array([0.01, 0.008, 0.008, 0.01, 0.015])
    shapes_v = np.stack([phi[:, 0], phi[:, 1], 0.2 * phi[:, 2], 0.1 * phi[:, 3], phi[:, 2]], 1)
    shapes_h = np.stack([0 * x, 0.3 * phi[:, 1], phi[:, 0], 0 * x, 0.5 * phi[:, 3]], 1)
    shapes = np.vstack([shapes_v, shapes_h]) / np.sqrt(10.0)
    labels = tuple(f"{k}V" for k in range(1, 21)) + tuple(f"{k}H" for k in range(1, 21))
    frfs = virtual_impact_test(fn, zeta, shapes, labels, f_max_hz=120.0, noise=0.01, seed=5)
    # the 70 Hz mode is weak: its sum-FRF peak is under 5 % of the largest peak
    total = sum_frf(frfs.frf)
    assert total[np.argmin(np.abs(frfs.frequencies_hz - 70.0))] < 0.05 * total.max()
    modes = identify(frfs).modes
    assert modes.n_modes == 5
    assert np.max(np.abs(modes.frequencies_hz - fn) / fn) < 0.002
    true = shapes[[labels.index(lab) for lab in modes.dof_labels]]
    assert np.diag(mac_matrix(true, modes.shapes)).min() > 0.95


def test_mode_just_above_the_data_does_not_bias_the_shapes():
    """A mode 3 % above the last line appears as a stable pole at the top edge of the data: it is
    not reported, but modelled in the LSFD basis (a constant upper residual cannot follow its
    flank), so the shape of the mode below it stays exact on noise-free data."""
    x = (np.arange(20) + 0.5) / 20
    phi = free_beam_shapes(x, 4)
    fn = np.array([30.0, 55.0, 85.0, 103.0])  # data end at 100 Hz
    zeta = np.array([0.01, 0.01, 0.012, 0.012])
    shapes_v = np.stack([phi[:, 0], phi[:, 1], phi[:, 2], phi[:, 3]], 1)
    shapes_h = np.stack([0.3 * phi[:, 1], phi[:, 0], 0.1 * phi[:, 3], phi[:, 2]], 1)
    shapes = np.vstack([shapes_v, shapes_h]) / np.sqrt(10.0)
    labels = tuple(f"{k}V" for k in range(1, 21)) + tuple(f"{k}H" for k in range(1, 21))
    frfs = virtual_impact_test(fn, zeta, shapes, labels, f_max_hz=100.0, noise=0.0, seed=0)
    result = identify(frfs)
    modes = result.modes
    np.testing.assert_allclose(modes.frequencies_hz, fn[:3], rtol=1e-3)
    assert result.poles.size == 3
    true = shapes[[labels.index(lab) for lab in modes.dof_labels]][:, :3]
    mac = np.diag(mac_matrix(true, modes.shapes))
    # the 85 Hz mode's weak H part (10 % of its V amplitude) is the one the 103 Hz flank biased
    assert mac.min() >= 0.999
