"""Shape uncertainty from the data (``ModalData.shape_sd_rel``) checked against the truth of the
FE exhaust virtual test (seed layout, 1 % noise, seeds 1-4).

shape_sd_rel is meant to satisfy E[1 - MAC(identified, true)] ~ shape_sd_rel^2.  It holds the
residue noise and model error (residual inflated by its correlation across lines), each test
set's scale relative to the anchor set, and the part of a set too weak to be scaled (the V
reference barely moves in mode 3, the H reference in mode 4: 1 - MAC ~ 6e-3 to 8e-3 there).
Measured (issue 16): ratio realised / predicted over seeds 1-4 has median 1.46 and range
0.35-6.3 (seeds 5-8, kept for confirmation: median 1.09, range 0.07-11.8); before the scale
and correlation terms, median 16 and range 0.28-406.
"""

import numpy as np
import pytest

from bayesupdate.correlation import mac_matrix
from bayesupdate.ema.identify import identify
from bayesupdate.models import get_model
from bayesupdate.pipelines.simulate import VirtualTestSettings, simulate_test


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
