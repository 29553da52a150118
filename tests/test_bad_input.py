"""Bad input across the CLI: every case exits 2 with one line on stderr that names the file or
field, prints no traceback, and leaves no output file behind.

Cases run in-process through ``bayesupdate.cli.main`` (fast); one case also runs the installed
console script in a subprocess to show the real entry point behaves the same.
"""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.cli import main
from bayesupdate.ema.frf_set import FrfSet
from bayesupdate.ema.uff_io import write_uff58
from bayesupdate.ema.virtual_test import exhaust_like_model, virtual_impact_test


@pytest.fixture(scope="module")
def good_uff(tmp_path_factory):
    folder = tmp_path_factory.mktemp("uff")
    f, z, shapes, labels = exhaust_like_model()
    frfs = virtual_impact_test(f, z, shapes, labels, noise=0.0, seed=0)
    path = folder / "good.uff"
    write_uff58(path, frfs)
    return path, frfs


def run_cli(argv, capsys):
    code = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def assert_clean_rejection(code, err, out_file: Path | None, *needles):
    assert code == 2, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    for needle in needles:
        assert needle.lower() in lines[0].lower(), lines[0]
    if out_file is not None:
        assert not out_file.exists()
        leftovers = [p for p in out_file.parent.glob(f".{out_file.name}.*")]
        assert not leftovers, leftovers


def write_text(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


# -- identify ---------------------------------------------------------------------------------
def _uff_with(tmp_path, frfs: FrfSet, name: str, **changes) -> Path:
    """Write a UFF file through pyuff directly (bypassing our NaN guard) with changed FRFs."""
    import pyuff

    from bayesupdate.ema.uff_io import parse_label

    freqs = changes.get("frequencies_hz", frfs.frequencies_hz)
    data = changes.get("frf", frfs.frf)
    labels = changes.get(
        "labels", list(zip(frfs.response_labels, frfs.reference_labels, strict=True))
    )
    sets = []
    for k, (resp, ref) in enumerate(labels):
        rn, rd = parse_label(resp)
        fn, fd = parse_label(ref)
        sets.append(
            pyuff.prepare_58(
                func_type=4,
                rsp_node=int(rn),
                rsp_dir=int(rd),
                ref_node=int(fn),
                ref_dir=int(fd),
                ordinate_spec_data_type=12,
                orddenom_spec_data_type=13,
                abscissa_spec_data_type=18,
                data=np.asarray(data[k], dtype=complex),
                x=np.asarray(freqs, dtype=float),
                abscissa_spacing=0 if changes.get("uneven") else 1,
                abscissa_min=float(freqs[0]),
                abscissa_inc=float(freqs[1] - freqs[0]),
            )
        )
    path = tmp_path / name
    pyuff.UFF(str(path)).write_sets(sets, mode="add")
    return path


def test_identify_missing_file(tmp_path, capsys):
    out = tmp_path / "m.h5"
    code, _, err = run_cli(["identify", tmp_path / "nope.uff", "--out", out], capsys)
    assert_clean_rejection(code, err, out, "nope.uff")


def test_identify_empty_file(tmp_path, capsys):
    out = tmp_path / "m.h5"
    code, _, err = run_cli(["identify", write_text(tmp_path / "e.uff", ""), "--out", out], capsys)
    assert_clean_rejection(code, err, out, "e.uff")


def test_identify_truncated_uff(tmp_path, capsys, good_uff):
    path, _ = good_uff
    text = path.read_text()
    bad = write_text(tmp_path / "trunc.uff", text[: len(text) // 3])
    out = tmp_path / "m.h5"
    code, _, err = run_cli(["identify", bad, "--out", out], capsys)
    assert_clean_rejection(code, err, out, "trunc.uff")


def test_identify_corrupt_uff(tmp_path, capsys, good_uff):
    path, _ = good_uff
    lines = path.read_text().splitlines()
    lines[30] = "this is not a number at all"
    bad = write_text(tmp_path / "corrupt.uff", "\n".join(lines) + "\n")
    out = tmp_path / "m.h5"
    code, _, err = run_cli(["identify", bad, "--out", out], capsys)
    assert_clean_rejection(code, err, out, "corrupt.uff")


@pytest.mark.parametrize("token", ["NaN", "inf", "-Infinity"])
def test_identify_nan_or_inf_in_frf(tmp_path, capsys, good_uff, token):
    # another tool's export with a non-finite value in a data line (pyuff itself would have
    # written 0 there, silently)
    path, _ = good_uff
    lines = path.read_text().splitlines()
    row = 40
    fields = lines[row].split()
    fields[1] = token
    lines[row] = "".join(f"{f:>20}" for f in fields)
    bad = write_text(tmp_path / "nan.uff", "\n".join(lines) + "\n")
    out = tmp_path / "m.h5"
    code, _, err = run_cli(["identify", bad, "--out", out], capsys)
    assert_clean_rejection(code, err, out, "nan")


def test_identify_non_uniform_axis(tmp_path, capsys, good_uff):
    _, frfs = good_uff
    f = frfs.frequencies_hz.copy()
    f[10:] += 0.01
    bad = _uff_with(tmp_path, frfs, "uneven.uff", frequencies_hz=f, uneven=True)
    out = tmp_path / "m.h5"
    code, _, err = run_cli(["identify", bad, "--out", out], capsys)
    assert_clean_rejection(code, err, out, "uneven.uff")


def test_identify_duplicated_dofs(tmp_path, capsys, good_uff):
    _, frfs = good_uff
    labels = list(zip(frfs.response_labels, frfs.reference_labels, strict=True))
    labels[2] = labels[1]
    bad = _uff_with(tmp_path, frfs, "dup.uff", labels=labels)
    out = tmp_path / "m.h5"
    code, _, err = run_cli(["identify", bad, "--out", out], capsys)
    assert_clean_rejection(code, err, out, "dup")


@pytest.mark.parametrize(
    "band, needle", [("200:300", "band"), ("80:70", "band"), ("abc", "band"), ("10:10.5", "lines")]
)
def test_identify_bad_band(tmp_path, capsys, good_uff, band, needle):
    path, _ = good_uff
    out = tmp_path / "m.h5"
    code, _, err = run_cli(["identify", path, "--band", band, "--out", out], capsys)
    assert_clean_rejection(code, err, out, needle)


def test_identify_existing_output_needs_force(tmp_path, capsys, good_uff):
    path, _ = good_uff
    out = write_text(tmp_path / "m.h5", "keep me")
    code, _, err = run_cli(["identify", path, "--out", out], capsys)
    assert code == 2 and "--force" in err and "Traceback" not in err
    assert out.read_text() == "keep me"


def test_output_folder_missing(tmp_path, capsys, good_uff):
    path, _ = good_uff
    out = tmp_path / "no" / "such" / "m.h5"
    code, _, err = run_cli(["identify", path, "--out", out], capsys)
    assert_clean_rejection(code, err, None, "does not exist")


def test_output_folder_not_writable(capsys, good_uff):
    # /sys refuses new files even to root (os.access alone would say it is writable)
    path, _ = good_uff
    code, _, err = run_cli(["identify", path, "--out", "/sys/modes.h5"], capsys)
    assert_clean_rejection(code, err, None, "not writable")


# -- modes and simulate ------------------------------------------------------------------------
@pytest.mark.parametrize(
    "argv, needle",
    [
        (["modes", "--model", "nosuch"], "unknown model"),
        (["modes", "--set", "t_hot_pipe"], "NAME=VALUE"),
        (["modes", "--set", "t_hot_pipe=-1mm"], "t_hot_pipe"),
        (["modes", "--set", "rho_catalyst=0"], "rho_catalyst"),
        (["modes", "--set", "t_hot_pipe=2furlongs"], "unit"),
        (["modes", "--set", "t_hotpipe=2mm"], "t_hotpipe"),
        (["modes", "--modes", "0"], "--modes"),
        (["modes", "--modes", "twelve"], "invalid int"),
        (["modes", "--colour", "red"], "unrecognized"),
    ],
)
def test_modes_bad_arguments(argv, needle, capsys):
    code, _, err = run_cli(argv, capsys)
    assert_clean_rejection(code, err, None, needle)


@pytest.mark.parametrize(
    "extra, needle",
    [
        (["--effect", "added_mass@99:m=0.1"], "location"),
        (["--effect", "hidden_gremlin@3"], "unknown kind"),
        (["--effect", "added_mass@14:m=9"], "bounds"),
        (["--noise", "-0.1"], "--noise"),
    ],
)
def test_simulate_bad_arguments(tmp_path, capsys, extra, needle):
    out = tmp_path / "t.uff"
    code, _, err = run_cli(["simulate", "--model", "exhaust", "--out", out, *extra], capsys)
    assert_clean_rejection(code, err, out, needle)


def test_console_script_subprocess_one_line(tmp_path):
    exe = Path(sys.executable).with_name("bayesupdate")
    proc = subprocess.run(
        [str(exe), "identify", str(tmp_path / "missing.uff"), "--out", str(tmp_path / "o.h5")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2
    assert len(proc.stderr.strip().splitlines()) == 1 and "missing.uff" in proc.stderr
