"""The on-disk cache of reduced bases (``compute.cache``): atomic, checksummed, LRU, and a
reduced model built once and loaded after, re-certified at fresh points."""

import json
import os
import signal
import subprocess
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.cli import main
from bayesupdate.compute.cache import ArrayStore, content_key
from bayesupdate.fe.reduced import basis as basis_module
from bayesupdate.fe.reduced import certification, reduced_model_for
from bayesupdate.models import get_model

ROOT = Path(__file__).resolve().parents[1]


def test_content_key_is_stable_and_sees_every_part():
    a = np.arange(6.0).reshape(2, 3)
    key = content_key("x", a, {"b": 1.0, "a": (2, 3)})
    assert key == content_key("x", a.copy(), {"a": (2, 3), "b": 1.0})  # order of a mapping
    assert key != content_key("x", a.T.copy(), {"b": 1.0, "a": (2, 3)})  # shape
    assert key != content_key("x", a + 1e-16 * a.max(), {"b": 1.0, "a": (2, 3)})  # one bit
    assert key != content_key("x", a.astype(np.float32), {"b": 1.0, "a": (2, 3)})  # dtype


def test_round_trip_and_a_damaged_entry_is_a_miss_with_a_note(tmp_path):
    store = ArrayStore(tmp_path)
    arrays = {"V": np.random.default_rng(0).normal(size=(50, 7)), "n": np.array(6)}
    assert store.save("k1", arrays)
    back = store.load("k1")
    np.testing.assert_array_equal(back["V"], arrays["V"])
    assert int(back["n"]) == 6
    path = store.path("k1")
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])  # truncated
    with pytest.warns(RuntimeWarning, match="damaged"):
        assert store.load("k1") is None
    assert not path.exists()  # removed, so the next build writes a whole one
    path.write_bytes(b"not a cache file at all\n" + data[100:])  # foreign
    with pytest.warns(RuntimeWarning, match="damaged"):
        assert store.load("k1") is None


def test_least_recently_used_entries_go_first(tmp_path):
    one = {"a": np.zeros(20_000)}  # 160 kB each
    store = ArrayStore(tmp_path, max_bytes=int(2.5 * 160_000))
    for k in ("old", "mid"):
        store.save(k, one)
        time.sleep(0.02)
    os.utime(store.path("old"), (time.time() - 100, time.time() - 100))
    os.utime(store.path("mid"), (time.time() - 50, time.time() - 50))
    assert store.load("old") is not None  # a hit makes "old" the most recent
    store.save("new", one)
    assert sorted(p.stem for p in tmp_path.glob("*.npz")) == ["new", "old"]
    assert store.info().entries == 2
    assert store.clear() == 2 and store.info().entries == 0


def test_a_folder_that_cannot_be_written_warns_once_and_the_run_goes_on(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("a file where the cache folder would go")
    store = ArrayStore(blocker / "cache")
    with pytest.warns(RuntimeWarning, match="cannot be written") as caught:
        assert store.save("k", {"a": np.ones(3)}) is False
    assert len(caught) == 1
    assert store.load("k") is None


_WRITER = """
import os, sys, time
import numpy as np
from pathlib import Path
from bayesupdate.compute import cache
store = cache.ArrayStore(Path(sys.argv[1]))
if sys.argv[2] == "hang":  # killed between writing the temporary file and publishing it
    def hang(*a):
        print("written", flush=True)
        time.sleep(600)
    cache.os.replace = hang
value = float(sys.argv[3])
print("start", flush=True)
store.save("key", {"V": np.full((1000, 500), value)})
print("saved", flush=True)
"""


def _writer(folder, mode, value):
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    return subprocess.Popen(
        [sys.executable, "-c", _WRITER, str(folder), mode, str(value)],
        stdout=subprocess.PIPE,
        text=True,
        env=env,
    )


def test_a_build_killed_in_the_middle_leaves_no_entry_that_is_used(tmp_path):
    proc = _writer(tmp_path, "hang", 1.0)
    assert proc.stdout.readline().strip() == "start"
    assert proc.stdout.readline().strip() == "written"
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert list(tmp_path.glob("*.tmp"))  # the killed writer's temporary file is there ...
    assert ArrayStore(tmp_path).load("key") is None  # ... and never read as an entry
    assert ArrayStore(tmp_path).info().entries == 0


def test_two_concurrent_writers_leave_one_valid_entry(tmp_path):
    procs = [_writer(tmp_path, "plain", v) for v in (1.0, 2.0)]
    for p in procs:
        p.communicate(timeout=60)
        assert p.returncode == 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no damaged entry
        V = ArrayStore(tmp_path).load("key")["V"]
    assert V.shape == (1000, 500)
    assert np.unique(V).size == 1 and V[0, 0] in (1.0, 2.0)  # one writer's whole array
    assert ArrayStore(tmp_path).info().entries == 1


def _counting_solves(monkeypatch):
    points = []
    real = basis_module.full_solves

    def counted(fe, names, theta, n_modes, executor=None, what="full solves"):
        points.append(theta.shape[0])
        return real(fe, names, theta, n_modes, executor, what)

    monkeypatch.setattr(certification, "full_solves", counted)
    return points


SMALL = dict(n_modes=6, n_snapshots=8, n_validation=8)


def test_a_reduced_model_is_built_once_then_loaded_and_rechecked(tmp_path, monkeypatch):
    monkeypatch.setenv("BAYESUPDATE_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("BAYESUPDATE_NO_CACHE", raising=False)
    points = _counting_solves(monkeypatch)
    model = get_model("exhaust")
    first = reduced_model_for(model, None, **SMALL)
    built = sum(points)
    assert first.certified and built >= 16
    assert ArrayStore(tmp_path).info().entries == 1
    points.clear()
    second = reduced_model_for(model, None, **SMALL)
    assert sum(points) == certification.RECHECK_POINTS  # only the fresh check points
    np.testing.assert_array_equal(second.certification.basis.V, first.certification.basis.V)
    theta = {"t_hot_pipe": 1.7e-3, "rho_catalyst": 1.2e-8}
    f1 = first.predict(theta, 6).frequencies_hz
    np.testing.assert_array_equal(second.predict(theta, 6).frequencies_hz, f1)
    assert second.certificate.n_points == first.certificate.n_points + 1
    assert second.max_rel_error <= 1e-4
    # another box is another entry
    points.clear()
    reduced_model_for(model, {"t_hot_pipe": (1e-3, 2e-3)}, **SMALL)
    assert sum(points) >= 16 and ArrayStore(tmp_path).info().entries == 2


def test_a_cached_basis_that_misses_at_fresh_points_is_rebuilt_with_a_note(tmp_path, monkeypatch):
    monkeypatch.setenv("BAYESUPDATE_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("BAYESUPDATE_NO_CACHE", raising=False)
    model = get_model("exhaust")
    good = reduced_model_for(model, None, **SMALL)
    store = ArrayStore(tmp_path)
    (path,) = tmp_path.glob("*.npz")
    c = good.certification
    elastic = c.basis.size - c.basis.n_rigid
    small = c.basis.restricted(np.eye(elastic)[:, :6])  # a valid entry, its basis far too small
    store.save(path.stem, certification._arrays(replace(c, basis=small)))
    with pytest.warns(RuntimeWarning, match="misses its tolerance"):
        again = reduced_model_for(model, None, **SMALL)
    assert again.certified and again.size == good.size
    arrays = store.load(path.stem)
    arrays["V"] = arrays["V"][:, :-1]  # stored terms that no longer fit the basis
    store.save(path.stem, arrays)
    with pytest.warns(RuntimeWarning, match="unreadable"):
        again = reduced_model_for(model, None, **SMALL)
    assert again.certified and again.size == good.size


def test_cli_cache_info_and_clear(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("BAYESUPDATE_CACHE_DIR", str(tmp_path))
    ArrayStore(tmp_path).save("k", {"a": np.ones(1000)})
    assert main(["cache", "info", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["entries"] == 1 and info["directory"] == str(tmp_path)
    assert info["bytes"] == ArrayStore(tmp_path).path("k").stat().st_size
    assert main(["cache", "clear", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["removed"] == 1
    assert not list(tmp_path.glob("*.npz"))


def test_no_cache_flag_neither_reads_nor_writes_and_restores_the_environment(
    tmp_path, monkeypatch, capsys
):
    monkeypatch.setenv("BAYESUPDATE_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("BAYESUPDATE_NO_CACHE", raising=False)
    seen = []
    monkeypatch.setattr(
        "bayesupdate.commands.modes.run",
        lambda args: seen.append(ArrayStore.from_environment().enabled) or 0,
    )
    assert main(["modes", "--no-cache"]) == 0
    assert main(["modes"]) == 0
    assert seen == [False, True]
    assert "BAYESUPDATE_NO_CACHE" not in os.environ
