"""The optional GPU path of the batched reduced eigen-solve (``fe.batched_eigen``): the
array-module code (``solve_on``) run with numpy gives today's CPU results, and it is chosen only
when a CuPy module is available, the batch is large enough and ``BAYESUPDATE_GPU`` allows it (CuPy
is replaced by a stand-in: no GPU is needed)."""

import numpy as np
import pytest

from bayesupdate.fe import batched_eigen as be

N_RIGID, N_ELASTIC, N_MODES = 6, 20, 8


def pencils(batch: int, seed: int = 3):
    """Reduced free-free pencils: K_ww (B, r_e, r_e) positive definite, M (B, r, r) positive
    definite coupling the rigid and elastic coordinates."""
    rng = np.random.default_rng(seed)
    r = N_RIGID + N_ELASTIC
    A = rng.standard_normal((batch, N_ELASTIC, N_ELASTIC))
    K_ww = A @ A.transpose(0, 2, 1) * 1e4 + 1e3 * np.eye(N_ELASTIC)
    Bm = rng.standard_normal((batch, r, r))
    return K_ww, Bm @ Bm.transpose(0, 2, 1) / r + np.eye(r)


class Recorder:
    """A stand-in for CuPy: numpy's functions, counting the arrays moved to the 'device'."""

    def __init__(self):
        self.calls = 0

    def __getattr__(self, name):
        return getattr(np, name)

    def asarray(self, x):
        self.calls += 1
        return np.asarray(x)


def test_numpy_through_the_array_module_code_matches_the_cpu_path():
    K_ww, M = pencils(12)
    lam_cpu = be.batched_elastic_eigenvalues(K_ww, M, N_RIGID, N_MODES, threads=1)
    lam_xp = be.solve_on(np, K_ww, M, N_RIGID, N_MODES)
    np.testing.assert_allclose(lam_xp, lam_cpu, rtol=1e-12, atol=0)
    lam1, y1 = be.batched_elastic_eigenvalues(K_ww, M, N_RIGID, N_MODES, vectors=True, threads=1)
    lam2, y2 = be.solve_on(np, K_ww, M, N_RIGID, N_MODES, vectors=True)
    np.testing.assert_allclose(lam2, lam1, rtol=1e-12, atol=0)
    # eigenvectors up to sign, mass-normalized: y^T M y = I
    sign = np.sign(np.sum(y1 * y2, axis=1, keepdims=True))
    np.testing.assert_allclose(y2 * sign, y1, rtol=0, atol=1e-12 * np.abs(y1).max())
    gram = np.einsum("bri,brs,bsj->bij", y2, M, y2)
    np.testing.assert_allclose(gram, np.broadcast_to(np.eye(N_MODES), gram.shape), atol=1e-12)


def test_array_module_code_raises_on_an_indefinite_mass():
    K_ww, M = pencils(4)
    M[2] = -M[2]
    with pytest.raises(np.linalg.LinAlgError):
        be.solve_on(np, K_ww, M, N_RIGID, N_MODES)


def test_gpu_path_only_when_cupy_is_available_and_the_batch_is_large(monkeypatch):
    monkeypatch.delenv(be.GPU_VARIABLE, raising=False)
    fake = Recorder()
    K_big, M_big = pencils(be.GPU_MIN_BATCH)
    K_small, M_small = pencils(be.GPU_MIN_BATCH - 1)
    expected = be.solve_on(np, K_big, M_big, N_RIGID, N_MODES)

    monkeypatch.setattr(be, "_cupy_module", lambda: None)  # no CuPy, or no device
    assert be.gpu_module(10_000) is None
    monkeypatch.setattr(be, "_cupy_module", lambda: fake)
    assert be.gpu_module(be.GPU_MIN_BATCH - 1) is None
    assert be.gpu_module(be.GPU_MIN_BATCH) is fake

    be.batched_elastic_eigenvalues(K_small, M_small, N_RIGID, N_MODES, threads=1)
    assert fake.calls == 0  # below the threshold: the CPU path
    lam = be.batched_elastic_eigenvalues(K_big, M_big, N_RIGID, N_MODES, threads=1)
    assert fake.calls == 2  # K and M sent to the device once each
    np.testing.assert_allclose(lam, expected, rtol=1e-12, atol=0)

    monkeypatch.setenv(be.GPU_VARIABLE, "0")
    assert be.gpu_module(10_000) is None
    be.batched_elastic_eigenvalues(K_big, M_big, N_RIGID, N_MODES, threads=1)
    assert fake.calls == 2


def test_cupy_detection_without_cupy_installed(monkeypatch):
    """Where CuPy cannot be imported the module reports none (the default install)."""
    import builtins

    real_import = builtins.__import__

    def no_cupy(name, *args, **kwargs):
        if name == "cupy":
            raise ImportError("no cupy")
        return real_import(name, *args, **kwargs)

    be._cupy_module.cache_clear()
    monkeypatch.setattr(builtins, "__import__", no_cupy)
    try:
        assert be._cupy_module() is None
    finally:
        be._cupy_module.cache_clear()
