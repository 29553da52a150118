"""UFF 58/55 and HDF5 round trips, pyuff pitfalls, bad input."""

import numpy as np
import pytest

from bayesupdate.ema.frf_set import FrfSet
from bayesupdate.ema.modal_h5 import read_modal_h5, write_modal_h5
from bayesupdate.ema.uff_io import read_uff55, read_uff58, write_uff55, write_uff58
from bayesupdate.errors import BayesUpdateError
from bayesupdate.modal_data import ModalData


def _frfs(n=3):
    f = np.arange(0, 50.5, 0.5)
    rng = np.random.default_rng(0)
    h = rng.normal(size=(n, f.size)) + 1j * rng.normal(size=(n, f.size))
    resp = ("1V", "1V", "1H")[:n]
    ref = ("1V", "12V", "3H")[:n]
    return FrfSet(f, h, resp, ref, kind="mobility")


def test_uff58_round_trip(tmp_path):
    frfs = _frfs()
    write_uff58(tmp_path / "a.uff", frfs)
    back = read_uff58(tmp_path / "a.uff")
    assert np.max(np.abs(back.frf - frfs.frf)) < 1e-10 * np.abs(frfs.frf).max()
    assert back.response_labels == frfs.response_labels
    assert back.reference_labels == frfs.reference_labels
    assert back.kind == "mobility"
    assert np.allclose(back.frequencies_hz, frfs.frequencies_hz)


def test_uff58_single_set_comes_back_as_frf_set(tmp_path):
    # pyuff returns a lone dataset as a dict, not a list
    frfs = _frfs(1)
    write_uff58(tmp_path / "one.uff", frfs)
    back = read_uff58(tmp_path / "one.uff")
    assert back.n_frf == 1
    assert back.frf[0, 7] == pytest.approx(frfs.frf[0, 7], rel=1e-10)


def test_uff58_refuses_nan_and_truncated(tmp_path):
    frfs = _frfs()
    write_uff58(tmp_path / "a.uff", frfs)
    text = (tmp_path / "a.uff").read_text()
    (tmp_path / "cut.uff").write_text(text[: len(text) // 2])  # mid-dataset
    with pytest.raises(BayesUpdateError, match="truncated"):
        read_uff58(tmp_path / "cut.uff")
    # FrfSet refuses NaN, so a NaN can only reach the writer by bypassing it
    object.__setattr__(frfs, "frf", np.where(np.arange(frfs.frf.shape[1]) == 3, np.nan, frfs.frf))
    with pytest.raises(BayesUpdateError, match="NaN"):
        write_uff58(tmp_path / "nan.uff", frfs)
    assert not (tmp_path / "nan.uff").exists()


def test_uff55_round_trip_with_numpy_int_nodes(tmp_path):
    rng = np.random.default_rng(2)
    labels = tuple(f"{np.int64(k)}V" for k in range(1, 6)) + ("3H", "5H")
    modes = ModalData(
        np.array([12.5, 30.25]), np.array([0.01, 0.02]), rng.normal(size=(7, 2)), labels
    )
    write_uff55(tmp_path / "m.uff", modes)
    back = read_uff55(tmp_path / "m.uff")
    assert back.dof_labels == labels
    assert np.allclose(back.frequencies_hz, modes.frequencies_hz)
    assert np.allclose(back.damping_ratio, modes.damping_ratio)
    # pyuff writes dataset 55 values with 6 significant digits
    assert np.max(np.abs(back.shapes - modes.shapes)) < 1e-5 * np.abs(modes.shapes).max()


def _complex_mode_55(mode: int, eig: complex, shape) -> str:
    """The text of one dataset 55 of a complex mode (analysis type 3, data type 5: complex,
    3 values a node) at nodes 101 and 102 along direction 2, laid out as a modal test
    program's export (pyuff's ``data/uff55 sample_test record10.uff``; pyuff's own writer
    produces a layout its reader refuses)."""
    lines = [
        "    -1",
        "    55",
        f"mode {mode}",
        "NONE",
        "NONE",
        "NONE",
        "NONE",
        "         1         3         2         8         5         3",
        f"         2         6         0{mode:10d}",
        f"{eig.real:13.6E}{eig.imag:13.6E}{1.0:13.6E}{0.0:13.6E}{0.0:13.6E}{0.0:13.6E}",
    ]
    for node, v in zip((101, 102), shape, strict=True):
        lines += [f"{node:10d}", f"{0.0:13.6E}{0.0:13.6E}{v.real:13.6E}{v.imag:13.6E}"
                  f"{0.0:13.6E}{0.0:13.6E}"]  # fmt: skip
    return "\n".join([*lines, "    -1"]) + "\n"


def test_uff55_complex_modes_as_test_software_exports_them(tmp_path):
    """Analysis type 3 (first-order complex modes, the form identified modes leave modal test
    software in): lambda = -zeta omega_n + i omega_n sqrt(1 - zeta^2) is read as the natural
    frequency |lambda| / 2 pi and the damping ratio -Re lambda / |lambda|, the shapes complex.
    (pyuff's sample file of such a mode raised KeyError 'freq' here before.)"""
    modes = [(12.5, 0.02, np.array([1.0 + 0.2j, -0.4 + 0.1j])),
             (7.25, 0.005, np.array([0.3 - 0.05j, 1.0 + 0.0j]))]  # fmt: skip
    text = ""
    for k, (f, zeta, shape) in enumerate(modes):
        w = 2 * np.pi * f
        text += _complex_mode_55(k + 1, complex(-zeta * w, w * np.sqrt(1 - zeta**2)), shape)
    (tmp_path / "complex.uff").write_text(text)
    back = read_uff55(tmp_path / "complex.uff")
    assert back.frequencies_hz == pytest.approx([7.25, 12.5], rel=1e-6)  # ascending
    assert back.damping_ratio == pytest.approx([0.005, 0.02], rel=1e-5)
    assert back.dof_labels == ("101H", "102H")
    assert np.iscomplexobj(back.shapes)
    assert back.shapes[:, 1] == pytest.approx(modes[0][2], rel=1e-6)


def _edited_58(tmp_path, name: str, **fields):
    """A one-FRF UFF 58 file written by ``write_uff58``, its dataset's ``fields`` changed
    and written again by pyuff (as another program would label the record)."""
    import pyuff

    write_uff58(tmp_path / "base.uff", _frfs(1))
    ds = pyuff.UFF(str(tmp_path / "base.uff")).read_sets()
    ds = (ds if isinstance(ds, dict) else ds[0]) | fields
    pyuff.UFF(str(tmp_path / name)).write_sets([ds], mode="add")
    return tmp_path / name


def test_uff58_records_that_are_not_frfs_are_named(tmp_path):
    """Time responses (function type 1) and PSDs (9) written as dataset 58 (pyuff's sample
    files; a time record with direction 0): the message says what the file holds and what
    to do, instead of failing on the record's direction."""
    for func, held, advice in ((1, "time responses", "bayesupdate frf"),
                               (9, "power spectral densities", "function type 4")):  # fmt: skip
        path = _edited_58(tmp_path, f"f{func}.uff", func_type=func, rsp_dir=0, ref_dir=0)
        with pytest.raises(BayesUpdateError, match=f"hold {held}, not FRFs.*{advice}"):
            read_uff58(path)


def test_uff58_frf_without_a_direction_names_node_and_direction(tmp_path):
    path = _edited_58(tmp_path, "s.uff", rsp_node=7, rsp_dir=0)
    with pytest.raises(BayesUpdateError, match=r"UFF node 7 direction 0 \(a scalar"):
        read_uff58(path)


def test_modal_h5_round_trip(tmp_path):
    shapes = np.array([[1.0 + 0.1j, 0.5], [0.2, -1.0 + 0.0j]])
    modes = ModalData(
        np.array([10.0, 20.0]),
        np.array([0.01, 0.02]),
        shapes,
        ("1V", "2H"),
        mpc=np.array([0.99, 1.0]),
        shape_sd_rel=np.array([0.03, 0.05]),
        source="x",
        extra={"stable_orders": np.array([7, 9])},
    )
    write_modal_h5(tmp_path / "m.h5", modes)
    back = read_modal_h5(tmp_path / "m.h5")
    assert np.array_equal(back.shapes, shapes)
    assert back.dof_labels == ("1V", "2H")
    assert np.array_equal(back.extra["stable_orders"], [7, 9])
    assert back.mpc[0] == pytest.approx(0.99)
    np.testing.assert_array_equal(back.shape_sd_rel, [0.03, 0.05])
    assert back.subset([1]).shape_sd_rel.tolist() == [0.05]


def test_shape_sd_needs_shapes_and_must_be_positive():
    with pytest.raises(BayesUpdateError, match="needs shapes"):
        ModalData(np.array([10.0]), shape_sd_rel=np.array([0.03]))
    with pytest.raises(BayesUpdateError, match="shape_sd_rel must be > 0"):
        ModalData(
            np.array([10.0]),
            shapes=np.ones((2, 1)),
            dof_labels=("a", "b"),
            shape_sd_rel=np.array([0.0]),
        )


@pytest.mark.parametrize(
    "freqs, match",
    [
        (np.array([0.0, 1.0, 2.0, 2.5, 4.0]), "not uniform"),
        (np.array([4.0, 3.0, 2.0, 1.0, 0.0]), "not strictly increasing"),
    ],
)
def test_bad_frequency_axis(freqs, match):
    with pytest.raises(BayesUpdateError, match=match):
        FrfSet(freqs, np.ones((1, 5)), ("1V",), ("1V",))


def test_nan_and_mismatched_shapes():
    f = np.arange(5.0)
    with pytest.raises(BayesUpdateError, match="NaN"):
        FrfSet(f, np.array([[1, 2, np.inf, 4, 5]]), ("1V",), ("1V",))
    with pytest.raises(BayesUpdateError, match="n_frf"):
        FrfSet(f, np.ones((2, 4)), ("1V", "2V"), ("1V", "1V"))
    with pytest.raises(BayesUpdateError, match="labels"):
        FrfSet(f, np.ones((2, 5)), ("1V",), ("1V", "1V"))


def test_mismatched_inputs_of_estimation_and_virtual_test():
    from bayesupdate.ema.frf_estimation import h1_h2_coherence
    from bayesupdate.ema.virtual_test import virtual_impact_test

    with pytest.raises(BayesUpdateError, match="equal length"):
        h1_h2_coherence(np.ones(100), np.ones(99), 100.0)
    with pytest.raises(BayesUpdateError, match="shapes"):
        virtual_impact_test([10.0, 20.0], [0.01, 0.01], np.ones((3, 3)), ("1V", "2V", "3V"))
    with pytest.raises(BayesUpdateError, match="no shape values"):
        virtual_impact_test([10.0], [0.01], np.ones((1, 1)), ("1V",), layout=[("1V", "2V")])
