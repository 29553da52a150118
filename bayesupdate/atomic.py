"""Atomic file output: write to a temporary file beside the target, then rename.

A crash or Ctrl-C while writing leaves either the previous file or nothing, never half a file.
"""

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from bayesupdate.errors import BayesUpdateError


def check_output_path(path: str | os.PathLike, force: bool = False) -> Path:
    """Validate an output path before any work starts.

    Raises BayesUpdateError if the file exists (and ``force`` is false) or its folder does not
    exist or is not writable, so that a long run never fails at the very end.
    """
    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
    if target.exists() and target.is_dir():
        raise BayesUpdateError(f"{target}: is a folder; give a file name for the output")
    if target.exists() and not force:
        raise BayesUpdateError(f"{target}: already exists; use --force to overwrite it")
    if not folder.is_dir():
        raise BayesUpdateError(f"{target}: folder {folder} does not exist; create it first")
    # os.access says yes to root even where nothing can be created (read-only mounts, /sys):
    # try it for real
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError:
        raise BayesUpdateError(
            f"{target}: folder {folder} is not writable; choose another --out"
        ) from None
    return target


def make_writable_folder(folder: Path) -> None:
    """Create ``folder`` (and parents) and write-probe it for real (os.access says yes to root
    even on read-only mounts); raises OSError if nothing can be written there."""
    folder.mkdir(parents=True, exist_ok=True)
    probe = folder / ".write_test"
    probe.write_text("")
    probe.unlink()


def _current_umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path in the target's folder; rename it onto ``path`` on success.

    On any exception (including KeyboardInterrupt) the temporary file is removed and the previous
    content of ``path``, if any, is left untouched.
    """
    target = Path(path)
    folder = target.parent if str(target.parent) else Path(".")
    fd, tmp_name = tempfile.mkstemp(
        prefix=f".{target.name}.", suffix=suffix or target.suffix or ".tmp", dir=folder
    )
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        # mkstemp creates 0600; a result file gets the mode a plain open() would give it
        with contextlib.suppress(FileNotFoundError):
            tmp.chmod(0o666 & ~_current_umask())
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        raise
