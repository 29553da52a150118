"""A content-addressed store of arrays on disk: what a command computed once for a model (its
certified reduced basis) is not computed again by the next command.

Each entry is one file ``<key>.npz`` under the cache folder: a first line with the SHA-256 of
the rest, then an ``np.savez`` archive.  The key is the SHA-256 of everything the entry depends
on (``content_key``), so a changed model, box, setting or package version is another entry and
nothing is ever invalidated by hand.

- Written atomically: a temporary file in the same folder, then ``os.replace``; a build killed
  in the middle leaves only a temporary file, which is never read (and is removed after an
  hour); two processes writing one key at once each replace it with a whole file.
- Read with its checksum verified: a truncated or foreign file is a miss, removed, with a note.
- Least recently used first out: a hit touches the file; ``save`` evicts the oldest entries
  while the folder holds more than ``max_bytes``.
- A folder that cannot be written gives one warning and the run goes on without the cache.

The folder is ``BAYESUPDATE_CACHE_DIR`` or the platform's user cache folder
(``$XDG_CACHE_HOME/bayesupdate``, ``~/.cache/bayesupdate``; ``~/Library/Caches/bayesupdate`` on
macOS; ``%LOCALAPPDATA%\\bayesupdate\\cache`` on Windows); ``BAYESUPDATE_NO_CACHE=1`` (the CLI's
``--no-cache``) turns it off; ``BAYESUPDATE_CACHE_MAX_MB`` sets the cap (default 2048).
"""

import dataclasses
import hashlib
import io
import os
import sys
import tempfile
import time
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from bayesupdate.errors import BayesUpdateError

__all__ = ["ArrayStore", "CacheInfo", "content_key", "default_directory"]

#: suffix of an entry; temporary files end in ``.tmp``
SUFFIX = ".npz"
#: a temporary file older than this [s] belongs to a killed writer
STALE_TMP_S = 3600.0
DEFAULT_MAX_MB = 2048


def default_directory() -> Path:
    """The platform's user cache folder for bayesupdate (module docstring)."""
    if sys.platform == "win32":
        base = os.environ.get("LOCALAPPDATA") or str(Path.home() / "AppData" / "Local")
        return Path(base) / "bayesupdate" / "cache"
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Caches" / "bayesupdate"
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "bayesupdate"


@dataclass(frozen=True)
class CacheInfo:
    """What ``ArrayStore.info`` found: folder, entries, their total size [bytes], the cap."""

    directory: str
    entries: int
    bytes: int
    max_bytes: int

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def _max_mb() -> float:
    """``BAYESUPDATE_CACHE_MAX_MB`` [MB], a number >= 0 (unset or blank: ``DEFAULT_MAX_MB``)."""
    text = os.environ.get("BAYESUPDATE_CACHE_MAX_MB", "").strip()
    if not text:
        return float(DEFAULT_MAX_MB)
    try:
        mb = float(text)
    except ValueError:
        mb = float("nan")
    if not (np.isfinite(mb) and mb >= 0):
        raise BayesUpdateError(
            f"BAYESUPDATE_CACHE_MAX_MB={text!r}: give the cache's cap in MB, a number >= 0 "
            f"(default {DEFAULT_MAX_MB})"
        )
    return mb


@dataclass(frozen=True)
class ArrayStore:
    """The store at ``directory`` (None: disabled, every load a miss, every save a no-op),
    holding at most ``max_bytes`` [bytes] of entries."""

    directory: Path | None
    max_bytes: int = DEFAULT_MAX_MB * 2**20

    @classmethod
    def from_environment(cls, honour_off: bool = True) -> "ArrayStore":
        """The store the environment asks for (module docstring); ``honour_off=False`` gives
        the folder even under ``BAYESUPDATE_NO_CACHE`` (to show or clear it)."""
        if honour_off and os.environ.get("BAYESUPDATE_NO_CACHE", "").strip() not in ("", "0"):
            return cls(None)
        folder = os.environ.get("BAYESUPDATE_CACHE_DIR") or default_directory()
        return cls(Path(folder), int(_max_mb() * 2**20))

    @property
    def enabled(self) -> bool:
        return self.directory is not None

    def path(self, key: str) -> Path:
        return Path(self.directory) / f"{key}{SUFFIX}"

    # -- read --------------------------------------------------------------------------------
    def load(self, key: str) -> dict[str, np.ndarray] | None:
        """The arrays stored under ``key``, or None (disabled, missing, or corrupt: then the
        file is removed, with a note)."""
        if not self.enabled:
            return None
        path = self.path(key)
        try:
            data = path.read_bytes()
        except OSError:
            return None
        arrays = _decode(data)
        if arrays is None:
            warnings.warn(
                f"cache entry {path.name} is damaged (checksum); it is rebuilt",
                RuntimeWarning,
                stacklevel=2,
            )
            _remove(path)
            return None
        try:
            os.utime(path)  # least recently used = oldest modification time
        except OSError:
            pass
        return arrays

    # -- write -------------------------------------------------------------------------------
    def save(self, key: str, arrays: Mapping[str, np.ndarray]) -> bool:
        """Store ``arrays`` under ``key`` atomically; False (with one warning) when the folder
        cannot be written."""
        if not self.enabled:
            return False
        folder = Path(self.directory)
        try:
            folder.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=folder, prefix=f".{key[:16]}-", suffix=".tmp")
            with os.fdopen(fd, "wb") as handle:
                handle.write(_encode(arrays))
                handle.flush()
                os.fsync(handle.fileno())
            os.replace(tmp, self.path(key))
        except OSError as exc:
            warnings.warn(
                f"cache folder {folder} cannot be written ({exc.strerror or exc}); "
                "going on without the cache (set BAYESUPDATE_CACHE_DIR or --no-cache)",
                RuntimeWarning,
                stacklevel=2,
            )
            return False
        self._evict(keep=key)
        return True

    def _entries(self) -> list[Path]:
        folder = Path(self.directory)
        if not folder.is_dir():
            return []
        return [p for p in folder.iterdir() if p.suffix == SUFFIX and p.is_file()]

    def _evict(self, keep: str) -> None:
        now = time.time()
        for tmp in Path(self.directory).glob("*.tmp"):
            try:
                if now - tmp.stat().st_mtime > STALE_TMP_S:
                    _remove(tmp)
            except OSError:
                pass
        entries = []
        for p in self._entries():
            try:
                st = p.stat()
            except OSError:
                continue
            entries.append((st.st_mtime, st.st_size, p))
        total = sum(size for _, size, _ in entries)
        for _, size, p in sorted(entries, key=lambda e: e[0]):
            if total <= self.max_bytes:
                break
            if p.stem != keep:
                _remove(p)
                total -= size

    # -- housekeeping ------------------------------------------------------------------------
    def info(self) -> CacheInfo:
        """Entries and their size."""
        if not self.enabled:
            return CacheInfo("(disabled)", 0, 0, self.max_bytes)
        sizes = []
        for p in self._entries():
            try:
                sizes.append(p.stat().st_size)
            except OSError:
                continue
        return CacheInfo(str(self.directory), len(sizes), int(sum(sizes)), self.max_bytes)

    def clear(self) -> int:
        """Remove every entry (and temporary file); the number of entries removed."""
        if not self.enabled:
            return 0
        entries = self._entries()
        for p in entries + list(Path(self.directory).glob("*.tmp")):
            _remove(p)
        return len(entries)


def _remove(path: Path) -> None:
    try:
        path.unlink()
    except OSError:
        pass


def _encode(arrays: Mapping[str, np.ndarray]) -> bytes:
    buffer = io.BytesIO()
    np.savez(buffer, **{k: np.asarray(v) for k, v in arrays.items()})
    payload = buffer.getvalue()
    return hashlib.sha256(payload).hexdigest().encode() + b"\n" + payload


def _decode(data: bytes) -> dict[str, np.ndarray] | None:
    head, sep, payload = data.partition(b"\n")
    if not sep or hashlib.sha256(payload).hexdigest().encode() != head:
        return None
    try:
        with np.load(io.BytesIO(payload), allow_pickle=False) as archive:
            return {k: archive[k] for k in archive.files}
    except (ValueError, OSError, EOFError):
        return None


def content_key(*parts) -> str:
    """SHA-256 (hex) of ``parts``: arrays by dtype, shape and bytes, sparse matrices by their
    CSR arrays, dataclasses by their fields, mappings by sorted items, sequences in order, other
    values by ``repr``.  Equal content gives equal keys across processes."""
    h = hashlib.sha256()
    _feed(h, parts)
    return h.hexdigest()


def _feed(h, obj) -> None:
    if isinstance(obj, np.ndarray):
        a = np.ascontiguousarray(obj)
        h.update(f"nd{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    elif sp.issparse(obj):
        m = sp.csr_matrix(obj)
        m.sort_indices()
        h.update(f"sp{m.shape}".encode())
        for a in (m.indptr, m.indices, m.data):
            _feed(h, a)
    elif dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        h.update(f"dc{type(obj).__qualname__}".encode())
        for f in dataclasses.fields(obj):
            h.update(f.name.encode())
            _feed(h, getattr(obj, f.name))
    elif isinstance(obj, Mapping):
        h.update(b"map")
        for k in sorted(obj, key=repr):
            _feed(h, k)
            _feed(h, obj[k])
    elif isinstance(obj, list | tuple):
        h.update(f"seq{len(obj)}".encode())
        for item in obj:
            _feed(h, item)
    elif isinstance(obj, float | np.floating):
        h.update(f"f{float(obj).hex()}".encode())
    else:
        h.update(f"r{obj!r}".encode())
