"""The block Krylov eigen-solver (``fe.eigensolve``) on a free body held by a point spring to
ground: the test suspension a discovery's ``boundary_spring`` candidate adds at a sensor point.

The spring (3 translations, k = 2e4 N/m) turns three rigid motions into suspension modes
(8.7-12.7 Hz here, below the first bending mode): they lie mostly in the span of the rigid
motions but not in it.  With the rigid motions' shift-invert images in the start block the
solve converges at its first Rayleigh-Ritz check (before, a block orthogonal to the rigid
motions reached them so slowly that every block up to ``max_blocks`` was built: nine checks
and 126 of the 156 DOFs spanned); a free body's start block is the random one, unchanged.
The numbers that could be wrong: the checks counted, and the frequencies against LAPACK's
dense solution of the same matrices."""

import numpy as np
import pytest
from test_discovery_workflow import frame_model

import bayesupdate.fe.eigensolve as eigensolve
from bayesupdate.fe import Binding, FEModel
from bayesupdate.fe.modify import with_spring

K_GROUND = 2e4  # N/m, each translation
#: the block Krylov's frequencies against dense LAPACK's: (tol = 1e-4)^2 / 2
FREQUENCY_RTOL = 5e-9


@pytest.fixture(scope="module")
def models():
    frame = frame_model()
    node = int(frame.structure.sensor_node[frame.structure.sensor_labels.index("4V")])
    held = with_spring(frame.structure, node, None, [1.0, 1.0, 1.0, 0.0, 0.0, 0.0], "cord")
    grounded = FEModel(
        held,
        {**frame.bindings, "k": Binding("cord", "stiffness_factor")},
        {"t_a": 1.8e-3, "k": K_GROUND},
        {"t_a": (0.5e-3, 3e-3), "k": (0.0, 1e5)},
    )
    return frame, grounded


def _counted_solve(monkeypatch, model, method="krylov"):
    """(frequencies [Hz] (8,), Rayleigh-Ritz checks made) of one solve of ``model``."""
    checks = []
    real = eigensolve._rayleigh_ritz

    def counting(*args):
        checks.append(args[0].shape[0])
        return real(*args)

    monkeypatch.setattr(eigensolve, "_rayleigh_ritz", counting)
    f = model.solve(None, 8, method=method).frequencies_hz
    return f, checks


def test_a_point_spring_to_ground_converges_at_the_first_check(models, monkeypatch):
    _, grounded = models
    f, checks = _counted_solve(monkeypatch, grounded)
    dense, _ = _counted_solve(monkeypatch, grounded, "dense")
    assert len(checks) == 1
    # the residual test (tol 1e-4) bounds an eigenvalue's error by ~tol^2 (Kato-Temple), a
    # frequency's by half that: 5e-9 (measured 8.8e-10)
    np.testing.assert_allclose(f, dense, rtol=FREQUENCY_RTOL)
    assert 5.0 < f[0] < f[2] < 15.0 < f[3]  # three suspension modes under the first bending one


def test_a_free_body_keeps_its_random_start_block(models, monkeypatch):
    frame, _ = models
    seen = []
    real = eigensolve._start_block

    def spy(random, V, KV, K):
        block = real(random, V, KV, K)
        seen.append(block is random)
        return block

    monkeypatch.setattr(eigensolve, "_start_block", spy)
    f, _ = _counted_solve(monkeypatch, frame)
    dense, _ = _counted_solve(monkeypatch, frame, "dense")
    assert seen == [True]
    np.testing.assert_allclose(f, dense, rtol=FREQUENCY_RTOL)  # measured 3.9e-10
