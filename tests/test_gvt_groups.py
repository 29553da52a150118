"""A roving test measured run by run: FRF files on one line grid merge within UFF 58's 6-digit
rounding, and poles that shift between run groups are estimated per group.

Truths: the line offsets are built (41 lines, and 41.3 lines which no rounding explains); the
synthetic test is a 2-mode model whose first mode sits 1.6 half-power half-widths higher in
the second group of runs (10.00 Hz in runs 1-2, 10.08 Hz in runs 3-4, 0.5 % damping), the
second mode at 17 Hz in all runs, on lines 2 half-widths apart: as the GVT's mode 1 (1.6
half-widths between runs 1-5 and 6-10, 1/60 Hz lines against its 0.013 Hz half-width), one
global pole then stands for both groups.
"""

import json

import numpy as np
import pytest

from bayesupdate.cli import main
from bayesupdate.ema.frf_set import FrfSet, line_offset_tolerance
from bayesupdate.ema.synthesis import synthesize_from_modes
from bayesupdate.ema.uff_io import read_uff58, write_uff58

#: the GVT's line spacing: 2000 Hz over 120001 samples
DF_HZ = 2000 / 120001


def _flat_frfs(first_line: float, labels=("1V", "2V"), n=200) -> FrfSet:
    f = (first_line + np.arange(n)) * DF_HZ
    h = np.vstack([(1 + 0.01 * k) * (1 + 1j * f) for k in range(len(labels))])
    return FrfSet(f, h, labels, ("25V",) * len(labels), "accelerance", source="x")


def _identify_json(argv, capsys) -> tuple[int, dict | str]:
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, (json.loads(out.out) if code == 0 else out.err)


def test_uff_rounding_of_a_41_line_offset_merges(tmp_path, capsys):
    """Starts 145 and 104 lines up (GVT runs 1-6 and 7): UFF keeps 6 digits, so they read
    41.0002 lines apart; identify merges the files on their common lines."""
    a, b = tmp_path / "run1.uff", tmp_path / "run7.uff"
    write_uff58(a, _flat_frfs(145))
    write_uff58(b, _flat_frfs(104, ("13V", "14V")))
    fa, fb = read_uff58(a), read_uff58(b)
    offset = (fa.frequencies_hz[0] - fb.frequencies_hz[0]) / fa.df_hz
    assert abs(offset - 41) > 1e-6  # the rounding the old check refused
    assert abs(offset - 41) < line_offset_tolerance(
        fa.frequencies_hz[0], fb.frequencies_hz[0], fa.df_hz, 41
    )
    from bayesupdate.ema.frf_set import merge_frf_sets

    merged, notes = merge_frf_sets([fa, fb])
    assert merged.frequencies_hz.size == 200 - 41
    assert merged.frequencies_hz[0] == pytest.approx(145 * DF_HZ, rel=1e-5)
    # file b's row is cut at its line 41, the same frequency as file a's line 0
    np.testing.assert_allclose(merged.frf[2], fb.frf[0, 41:], rtol=0)
    np.testing.assert_allclose(merged.frf[0], fa.frf[0, :159], rtol=0)
    assert any("common lines" in n for n in notes)


def test_lines_off_the_grid_refuse_naming_both_files(tmp_path, capsys):
    a, b = tmp_path / "runA.uff", tmp_path / "runB.uff"
    write_uff58(a, _flat_frfs(145))
    write_uff58(b, _flat_frfs(103.7, ("13V", "14V")))
    code, err = _identify_json(["identify", a, b, "--out", tmp_path / "m.h5"], capsys)
    assert code == 2
    lines = [x for x in err.splitlines() if x.strip()]
    assert len(lines) == 1 and "runA.uff" in lines[0] and "runB.uff" in lines[0]
    assert "41.3002 lines apart, not a whole number" in lines[0]


TRUE_HZ = {"group 1": (10.0, 17.0), "group 2": (10.08, 17.0)}
ZETA = 0.005
NOISE = 0.002
LINES_HZ = np.arange(60, 260) * 0.1  # 6-26 Hz


def _shapes(labels_rows: np.ndarray) -> np.ndarray:
    """Real shapes (n, 2) of the synthetic structure at nodes 1..8 (a bending and a twist)."""
    x = labels_rows.astype(float)
    return np.stack([np.sin(np.pi * x / 9), np.cos(np.pi * x / 4.5)], axis=1) * 0.3


@pytest.fixture(scope="module")
def two_group_files(tmp_path_factory):
    """Four runs of two accelerometers each; the 1st mode shifts between runs 1-2 and 3-4;
    reference 25V (its shape value 0.2, 0.15); 0.2 % complex noise, seed 3."""
    folder = tmp_path_factory.mktemp("groups")
    rng = np.random.default_rng(3)
    f = LINES_HZ
    ref = np.array([[0.2, 0.15]])
    paths = []
    for run in range(4):
        nodes = np.array([2 * run + 1, 2 * run + 2])
        fn = TRUE_HZ["group 1" if run < 2 else "group 2"]
        h = synthesize_from_modes(f, np.array(fn), np.full(2, ZETA), _shapes(nodes),
                                  np.repeat(ref, 2, axis=0))  # fmt: skip
        noise = rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape)
        h = h + NOISE * np.abs(h).mean() * noise
        labels = tuple(f"{n}V" for n in nodes)
        path = folder / f"run{run + 1}.uff"
        write_uff58(path, FrfSet(f, h, labels, ("25V", "25V"), "accelerance", source=path.name))
        paths.append(path)
    return folder, paths


def test_shift_found_and_estimated_per_group(two_group_files, capsys):
    folder, paths = two_group_files
    code, summary = _identify_json(
        ["identify", *paths, "--out", folder / "m.h5", "--json", "--force"], capsys
    )
    assert code == 0, summary
    assert summary["groups"] == [
        {"files": [1, 2], "automatic": True},
        {"files": [3, 4], "automatic": True},
    ]
    first, second = summary["modes"]
    g1, g2 = first["per_group"]
    # each group's pole at its own truth, within 4 of its sds
    assert abs(g1["frequency_hz"] - 10.0) < 4 * g1["sd_hz"] + 1e-4
    assert abs(g2["frequency_hz"] - 10.08) < 4 * g2["sd_hz"] + 1e-4
    assert first["pole_shift"] and not second["pole_shift"]
    assert first["frequency_spread_hz"] == pytest.approx(0.08, abs=0.002)
    # the reported frequency lies between the groups and its sd holds the spread
    assert 10.0 < first["frequency_hz"] < 10.08 and first["identification_sd_hz"] > 0.03
    # one pole over all runs turns the residues of the group away from it; per group not
    assert first["mpc_one_pole"] < 0.9 < 0.999 < first["mpc"]
    assert second["mpc"] > 0.999 and abs(second["frequency_hz"] - 17.0) < 2e-3
    assert any("poles shift" in n and "mode 1" in n for n in summary["notes"])


def test_given_groups_and_the_modes_file(two_group_files, capsys):
    from bayesupdate.ema.modal_h5 import read_modal_h5

    folder, paths = two_group_files
    out = folder / "given.h5"
    code, summary = _identify_json(
        ["identify", *paths, "--out", out, "--json", "--force", "--groups", "1 2,3-4"], capsys
    )
    assert code == 0, summary
    assert [g["automatic"] for g in summary["groups"]] == [False, False]
    modes = read_modal_h5(out)
    np.testing.assert_array_equal(modes.extra["group_of_file"], [0, 0, 1, 1])
    assert modes.extra["group_frequencies_hz"].shape == (2, 2)
    np.testing.assert_allclose(modes.extra["group_frequencies_hz"][0], [10.0, 10.08], atol=2e-3)
    assert modes.mpc[0] > 0.999 and modes.extra["mpc_one_pole"][0] < 0.9


def test_bad_groups_refused(two_group_files, capsys):
    folder, paths = two_group_files
    code, err = _identify_json(
        ["identify", *paths, "--out", folder / "bad.h5", "--groups", "1-2,2-4"], capsys
    )
    assert code == 2 and "exactly one group" in err
