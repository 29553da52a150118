"""Atomic output files get the permissions a plain ``open()`` would give them (not mkstemp's 0600),
so a report or result written for a team can be read by the team."""

import os

from bayesupdate.atomic import atomic_path


def test_atomic_file_mode_follows_umask(tmp_path):
    old = os.umask(0o022)
    try:
        with atomic_path(tmp_path / "result.h5") as tmp:
            tmp.write_text("x")
    finally:
        os.umask(old)
    assert (tmp_path / "result.h5").stat().st_mode & 0o777 == 0o644
    assert [p.name for p in tmp_path.iterdir()] == ["result.h5"]
