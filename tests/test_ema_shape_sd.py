"""Shape uncertainty from the data (``ModalData.shape_sd_rel``) checked against the truth of the
FE exhaust virtual test (seed layout, 1 % noise, seeds 1-4).

shape_sd_rel is meant to satisfy E[1 - MAC(identified, true)] ~ shape_sd_rel^2.  It holds the
residue noise and model error (residual inflated by its correlation across lines), each test
set's scale relative to the anchor set, and the part of a set too weak to be scaled (the V
reference barely moves in mode 3, the H reference in mode 4: 1 - MAC ~ 6e-3 to 8e-3 there).
Measured (real data): ratio realized / predicted over seeds 1-4 has median 1.46 and range
0.35-6.3 (seeds 5-8, kept for confirmation: median 1.09, range 0.07-11.8); before the scale
and correlation terms, median 16 and range 0.28-406.

A mode near the top of the band (exhaust with the joint flexibility k_rot = 3e3 at cold_pipe/
main_muffler: mode 13 at 144.37 Hz, damping fixed at 2.5 %, so its half-power band reaches 3.6
Hz of the 150 Hz end) is repeated over noise seeds with the truth held fixed: its realized
1 - MAC (2.1e-5 to 2.5e-5, nearly all bias, the same in every repeat) is 1.55x the predicted
sd^2 on average over 8 repeats (seeds 100-107; the test runs 100-102), so its shape sd is
calibrated.  Its frequency was biased low by 0.02-0.04 % in every repeat (noise sd about
0.006 %; the modes inside the band: mostly within 0.01 %), as LSCE's band fit misses the flank
of the 176 Hz mode above the data; that bias, not the shape sd, failed discovery's adequacy
test at mode 13 on the CLI path (seed 7085: -0.040 %, z = 4.15 at the 0.01 % frequency floor).
The poles at the range's ends are now refined by variable projection with an extra pole
beyond the end (:mod:`bayesupdate.ema.pole_refinement`): within 0.01 %, as inside the band.
"""

import numpy as np
import pytest

from bayesupdate.correlation import mac_matrix
from bayesupdate.discovery.effects import extend_model, parse_effect_spec
from bayesupdate.ema.identify import identify
from bayesupdate.ema.virtual_test import best_reference_points, seed_layout, virtual_impact_test
from bayesupdate.models import get_model
from bayesupdate.pipelines.simulate import BAND_HZ, VirtualTestSettings, simulate_test


def _case(seed):
    truth = simulate_test(get_model("exhaust"), VirtualTestSettings(noise=0.01, seed=seed))
    modes = identify(truth.frfs).modes
    labels = list(truth.dof_labels)
    true = truth.shapes[[labels.index(lab) for lab in modes.dof_labels]]
    idx = [int(np.argmin(np.abs(truth.frequencies_hz - f))) for f in modes.frequencies_hz]
    one_minus_mac = 1 - np.diag(mac_matrix(modes.shapes, true[:, idx]))
    return modes, one_minus_mac


@pytest.fixture(scope="module")
def cases():
    return [_case(seed) for seed in (1, 2, 3, 4)]


def test_shape_sd_finite_positive_and_stored(cases):
    for modes, _ in cases:
        sd = modes.shape_sd_rel
        assert sd.shape == (modes.n_modes,)
        assert np.all(np.isfinite(sd)) and np.all(sd > 0)
        assert not np.any(modes.extra["shape_sd_fallback"])


def test_shape_sd_calibrated_against_truth(cases):
    ratio = np.concatenate([omm / modes.shape_sd_rel**2 for modes, omm in cases])
    assert 0.3 <= np.median(ratio) <= 3.0
    # no mode's error underestimated by more than 10x, nor overestimated by more than 10x
    assert np.max(ratio) < 10.0
    assert np.min(ratio) > 0.1


def test_weak_set_modes_get_their_large_sd(cases):
    # the modes whose V or H part no set can scale are ~100x worse than the rest; so is their sd
    for modes, omm in cases:
        bad = omm > 3e-3
        assert bad.sum() >= 2
        assert np.all(modes.extra["shape_weak_part"][bad])
        assert np.min(modes.shape_sd_rel[bad]) ** 2 > 1e-3


EDGE_MODE = 12  # 0-based: mode 13, 144.37 Hz, below the 150 Hz end of the virtual test


@pytest.fixture(scope="module")
def edge_repeats():
    """(n_rep, 3): 1 - MAC to the truth, predicted sd^2 and relative frequency error of the
    band-edge mode, over noise seeds 100-102 with modes, damping and layout fixed."""
    effect = parse_effect_spec("joint_flexibility@cold_pipe/main_muffler:k_rot=3e3")
    res = extend_model(get_model("exhaust"), effect).solve(None, n_modes=20)
    f, shapes, labels = res.frequencies_hz, res.sensor_shapes, list(res.sensor_labels)
    damping = np.random.default_rng(1).uniform(0.005, 0.03, f.size)
    damping[EDGE_MODE] = 0.025
    layout = seed_layout(20, *best_reference_points(shapes[:, f <= BAND_HZ], res.sensor_labels))
    rows = []
    for seed in (100, 101, 102):
        frfs = virtual_impact_test(f, damping, shapes, labels, layout=layout, noise=0.01, seed=seed)
        modes = identify(frfs).modes
        k = int(np.argmin(np.abs(modes.frequencies_hz - f[EDGE_MODE])))
        true = shapes[[labels.index(lab) for lab in modes.dof_labels], EDGE_MODE]
        omm = 1 - mac_matrix(modes.shapes[:, [k]], true[:, None])[0, 0]
        err = modes.frequencies_hz[k] / f[EDGE_MODE] - 1
        rows.append((omm, modes.shape_sd_rel[k] ** 2, err))
    return np.array(rows)


def test_band_edge_mode_shape_sd_against_repeats(edge_repeats):
    assert np.all(np.abs(edge_repeats[:, 2]) < 0.01)  # the edge mode is found in every repeat
    ratio = np.mean(edge_repeats[:, 0]) / np.mean(edge_repeats[:, 1])
    assert 1 / 3 <= ratio <= 3.0, ratio


def test_band_edge_mode_frequency_unbiased(edge_repeats):
    # within 0.01 %, as the modes inside the band are
    assert np.max(np.abs(edge_repeats[:, 2])) < 1e-4, edge_repeats[:, 2]
