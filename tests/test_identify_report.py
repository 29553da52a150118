"""``bayesupdate identify --report DIR``: the report a user opens, on a virtual test and on the
real mAEWing1 ground vibration test."""

import re
from pathlib import Path

import numpy as np
import pytest
from gvt_runs import GVT, frf_argv

from bayesupdate.cli import main
from bayesupdate.ema.lsfd import realize
from bayesupdate.ema.modal_h5 import read_modal_h5
from bayesupdate.ema.uff_io import write_uff58
from bayesupdate.ema.virtual_test import virtual_impact_test

FN = np.array([18.0, 33.0, 52.0])
ZETA = np.array([0.01, 0.015, 0.02])
X = np.linspace(0, 1, 5)
SHAPES = np.stack([np.cos(np.pi * X), np.cos(2 * np.pi * X), np.cos(3 * np.pi * X)], 1)
LABELS = tuple(f"{k}V" for k in range(1, 6))


def _uff(folder: Path, layout, name: str) -> Path:
    frfs = virtual_impact_test(
        FN,
        ZETA,
        SHAPES / 2,
        LABELS,
        layout=layout,
        f_max_hz=64.0,
        sample_rate_hz=512.0,
        pulse_s=0.008,
        duration_s=8.0,
        noise=0.005,
        seed=1,
    )
    path = folder / name
    write_uff58(path, frfs)
    return path


@pytest.fixture(scope="module")
def roving_hammer(tmp_path_factory):
    """Roving hammer over 5 points, accelerometer at 1V (a driving point), and its report."""
    folder = tmp_path_factory.mktemp("report")
    uff = _uff(folder, [("1V", lab) for lab in LABELS], "test.uff")
    out, report = folder / "modes.h5", folder / "rep"
    assert main(["identify", str(uff), "--out", str(out), "--report", str(report)]) == 0
    return out, report


def md_table(md: str, caption: str) -> list[list[str]]:
    """Header and rows of the Markdown table under the bold caption starting with ``caption``."""
    lines = md.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(f"**{caption}"))
    rows = []
    for line in lines[start + 2 :]:
        if not line.startswith("|"):
            break
        rows.append([c.strip() for c in line.strip("|").split("|")])
    return [rows[0]] + rows[2:]  # drop the |---| line


def test_report_files_and_self_contained_html(roving_hammer):
    _, report = roving_hammer
    html = (report / "report.html").read_text()
    srcs = re.findall(r"src=[\"']([^\"']*)", html)
    assert len(srcs) == 4  # stabilization, AutoMAC, shapes, FRF synthesis
    assert all(s.startswith("data:image/png;base64,") and len(s) > 10_000 for s in srcs)
    assert not re.search(r"(href|src)=[\"']?(https?:|//|file:)", html)
    md = (report / "report.md").read_text()
    for name in ("stabilization", "shapes", "frf_fit", "automac"):
        assert f"(figures/{name}.png)" in md
        assert (report / "figures" / f"{name}.png").stat().st_size > 10_000


def test_modes_table_equals_hdf5(roving_hammer):
    out, report = roving_hammer
    modes = read_modal_h5(out)
    header, *rows = md_table((report / "report.md").read_text(), "Identified modes")
    assert header[:6] == [
        "mode",
        "frequency [Hz]",
        "damping ratio [%]",
        "MPC",
        "stable orders",
        "shape_sd_rel",
    ]
    assert len(rows) == modes.n_modes == 3
    for r, row in enumerate(rows):
        assert row[1] == f"{modes.frequencies_hz[r]:.6g}"
        assert row[2] == f"{100 * modes.damping_ratio[r]:.4g}"
        assert row[3] == f"{modes.mpc[r]:.3f}"
        assert int(row[4]) == int(modes.extra["stable_orders"][r])
        assert row[5] == f"{modes.shape_sd_rel[r]:.2g}"
        assert row[6] == "mass-normalized"  # the set has its driving point
    # and they are the true modes, not any numbers
    freqs = np.array([float(row[1]) for row in rows])
    assert np.max(np.abs(freqs / FN - 1)) < 0.002
    assert np.allclose([float(row[2]) for row in rows], 100 * ZETA, rtol=0.05)


def test_shapes_table_rows_columns_and_values(roving_hammer):
    out, report = roving_hammer
    modes = read_modal_h5(out)
    header, *rows = md_table((report / "report.md").read_text(), "Mode shapes")
    assert len(header) == 1 + modes.n_modes
    assert [row[0] for row in rows] == list(modes.dof_labels)
    assert sorted(modes.dof_labels) == sorted(LABELS)
    table = np.array([[float(v) for v in row[1:]] for row in rows])
    # realized from the HDF5 shapes, largest magnitude +1
    real = realize(modes.shapes)
    expect = real / real[np.argmax(np.abs(real), axis=0), range(real.shape[1])]
    assert np.allclose(table, expect, atol=5e-4)
    assert np.allclose(np.max(table, axis=0), 1.0)
    # against the true shapes, up to sign (cos(k pi x) has +-1 at both ends)
    order = [LABELS.index(lab) for lab in modes.dof_labels]
    truth = SHAPES[order]
    err = np.minimum(np.abs(table - truth).max(axis=0), np.abs(table + truth).max(axis=0))
    assert np.all(err < 0.03)


def test_single_cross_frf_report(tmp_path):
    """One cross FRF: one DOF (MPC not defined, said why), no driving point (unscaled)."""
    uff = _uff(tmp_path, [("3V", "1V")], "one.uff")
    out, report = tmp_path / "one.h5", tmp_path / "rep"
    assert main(["identify", str(uff), "--out", str(out), "--report", str(report)]) == 0
    md = (report / "report.md").read_text()
    _, *rows = md_table(md, "Identified modes")
    # 3V sits at x = 0.5, the node of the modes at 18 and 52 Hz: only 33 Hz shows
    assert [float(r[1]) for r in rows] == pytest.approx([FN[1]], rel=0.002)
    assert rows[0][3] == "n/a (one DOF)" and rows[0][6] == "unscaled"
    assert "unscaled (largest component 1)" in md
    header, *shape_rows = md_table(md, "Mode shapes")
    assert len(header) == 2 and shape_rows == [["1V", "+1.000"]]


def test_failure_still_writes_a_report(tmp_path, capsys):
    """A band with no mode: exit 2 with the one-line error, and a report saying so."""
    uff = _uff(tmp_path, [("1V", lab) for lab in LABELS], "test.uff")
    report = tmp_path / "rep"
    argv = ["identify", str(uff), "--band", "1:12", "--out", str(tmp_path / "m.h5")]
    assert main([*argv, "--report", str(report)]) == 2
    err = capsys.readouterr().err
    assert "no stable mode found" in err and "Traceback" not in err
    md = (report / "report.md").read_text()
    assert "**Warning:**" in md and "no stable mode found" in md
    assert "(figures/cmif.png)" in md
    assert not (tmp_path / "m.h5").exists()
    # the report is not overwritten without --force
    assert main([*argv, "--report", str(report)]) == 2
    assert "report.html already exists" in capsys.readouterr().err


@pytest.mark.skipif(not (GVT / "run_Run1.mat").is_file(), reason="GVT data not present")
def test_gvt_report_shapes_over_the_ten_accelerometers(tmp_path):
    """The user's path: ``frf`` per run, one ``identify`` of the 5 runs with --report."""
    paths = []
    for k in range(1, 6):
        out = tmp_path / f"run{k}.uff"
        argv = frf_argv(k, out)
        assert main([str(a) for a in argv]) == 0
        paths.append(str(out))
    h5, report = tmp_path / "gvt.h5", tmp_path / "gvt_report"
    argv = ["identify", *paths, "--band", "3:35", "--out", str(h5), "--report", str(report)]
    assert main(argv) == 0
    md = (report / "report.md").read_text()
    modes = read_modal_h5(h5)
    header, *rows = md_table(md, "Mode shapes")
    assert [row[0] for row in rows] == [f"{k}V" for k in range(1, 11)]
    assert len(header) == 1 + modes.n_modes
    _, *mode_rows = md_table(md, "Identified modes")
    assert [r[1] for r in mode_rows] == [f"{f:.6g}" for f in modes.frequencies_hz]
    assert all(r[6] == "unscaled" for r in mode_rows)  # the shaker point is not measured
    # the authors' clearest peak pick (explog.txt: 19.06 Hz) is among the modes
    assert np.min(np.abs(modes.frequencies_hz / 19.06 - 1)) < 0.01
    html = (report / "report.html").read_text()
    assert re.search(r'<img alt="Stabilization diagram[^"]*" src="data:image/png;base64,', html)


def test_report_folder_that_is_a_file(tmp_path, capsys):
    """Checked before any work: a one-line error, nothing written."""
    uff = _uff(tmp_path, [("1V", lab) for lab in LABELS], "test.uff")
    (tmp_path / "rep").write_text("")
    out = tmp_path / "m.h5"
    assert main(["identify", str(uff), "--out", str(out), "--report", str(tmp_path / "rep")]) == 2
    err = capsys.readouterr().err
    assert "--report" in err and "is a file" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_shape_cautions_name_complex_and_rough_modes():
    """The shapes section names modes whose realized shape drops much (low MPC) or whose
    shape error is large; a clean mode is not named."""
    from bayesupdate.modal_data import ModalData
    from bayesupdate.report.identify_report import _shape_cautions, shapes_table

    shapes = np.array([[1.0, 1.0 + 1.0j, 0.5], [-0.5, 1.0 - 1.0j, 1.0]])
    modes = ModalData(
        frequencies_hz=np.array([5.0, 7.0, 9.0]),
        shapes=shapes,
        dof_labels=("1V", "2V"),
        mpc=np.array([0.99, 0.0, 0.99]),
        shape_sd_rel=np.array([0.01, 0.02, 0.5]),
    )
    complex_note, rough_note = _shape_cautions(modes)
    assert complex_note.startswith("Mode(s) 2: MPC below")
    assert rough_note.startswith("Mode(s) 3: shape_sd_rel above")
    # mode 1 realized is itself; mode 3 scaled so its largest value (2V) is +1
    rows = shapes_table(modes).rows
    assert [r[1] for r in rows] == ["+1.000", "-0.500"]
    assert [r[3] for r in rows] == ["+0.500", "+1.000"]
