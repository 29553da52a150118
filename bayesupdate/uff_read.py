"""Reading a universal file (UFF) with pyuff, its prints kept off the user's stdout.

pyuff 2.5's reader of dataset 2467 (groups, which modal test programs write beside their
geometry) prints each group it reads to stdout: a geometry file with groups would put that
text before the JSON of ``bayesupdate correlate --json``.  The datasets are read with stdout
redirected for the call alone; anything pyuff printed is dropped.
"""

import contextlib
import io
import os

__all__ = ["quiet_read"]


def quiet_read(path: str | os.PathLike):
    """pyuff's ``UFF(path).read_sets()`` (a list of dataset dicts, or a bare dict for a file
    of one dataset) with whatever pyuff prints dropped; pyuff's own exceptions pass through."""
    import pyuff

    with contextlib.redirect_stdout(io.StringIO()):
        return pyuff.UFF(str(path)).read_sets()
