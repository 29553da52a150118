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
from synthetic_models import exhaust_like_model

from bayesupdate.cli import main
from bayesupdate.ema.frf_set import FrfSet
from bayesupdate.ema.uff_io import write_uff58
from bayesupdate.ema.virtual_test import virtual_impact_test


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


@pytest.mark.parametrize(
    "flags, needle",
    [
        (["--plots", "{file}"], "--plots {file}: is a file; give a folder"),
        (["--plots", "/proc/x"], "--plots /proc/x: cannot write there"),
        (["--out", "{uff}", "--force"], "is an input FRF file; give another name"),
    ],
)  # fmt: skip
def test_identify_outputs_checked_before_the_work(tmp_path, capsys, good_uff, flags, needle):
    """A ``--plots`` folder that is a file or unwritable, and an ``--out`` that is the input:
    one line before any work (the plots failed after the modes file was written, with an
    internal FileExistsError / FileNotFoundError; the input was overwritten)."""
    path, _ = good_uff
    uff = tmp_path / "frf.uff"
    uff.write_text(path.read_text())
    names = {"file": str(write_text(tmp_path / "plain.txt", "x")), "uff": str(uff)}
    argv = ["identify", uff, "--out", tmp_path / "m.h5", *[f.format(**names) for f in flags]]
    code, _, err = run_cli(argv, capsys)
    assert_clean_rejection(code, err, None, needle.format(**names))
    assert not (tmp_path / "m.h5").exists() and uff.read_text() == path.read_text()


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
        (["--set", "t_hot_pipe=0"], "t_hot_pipe"),
        (["--set", "rho_catalyst=-1e4"], "rho_catalyst"),
    ],
)
def test_simulate_bad_arguments(tmp_path, capsys, extra, needle):
    out = tmp_path / "t.uff"
    code, _, err = run_cli(["simulate", "--model", "exhaust", "--out", out, *extra], capsys)
    assert_clean_rejection(code, err, out, needle)


# -- calibrate and sample: study files, data, models -------------------------------------------
# A small valid study (two-storey shear building, exact data at theta = (1, 1)); each case below
# breaks one thing.  Every case is run through both commands where it applies.
BASE = """
[model]
source = "shear_building"
[data]
frequencies_hz = [4.30, 10.80]
[parameters.theta_1]
bounds = [0.2, 3.0]
[parameters.theta_2]
bounds = [0.2, 3.0]
[optimizer]
starts = 2
[sampler]
walkers = 8
steps = 20
check_every = 10
predictive_draws = 5
"""

# name -> (text replacing, text replaced by | a whole study, needle in the message)
STUDY_CASES = {
    "empty_study": ("", None, "empty"),
    "not_toml": ("[model\nsource = ", None, "not valid toml"),
    "unknown_table": (BASE + "[sampler_settings]\nwalkers = 8\n", None, "sampler_settings"),
    "misspelt_key": (BASE.replace("walkers = 8", "walkerz = 8"), None, "sampler.walkerz"),
    "misspelt_parameter_key": (
        BASE.replace(
            "bounds = [0.2, 3.0]\n[parameters.theta_2]", "bound = [0.2, 3.0]\n[parameters.theta_2]"
        ),
        None,
        "theta_1.bound",
    ),
    "misspelt_model_key": (BASE.replace('source = "shear', 'sauce = "shear'), None, "sauce"),
    "wrong_type_walkers": (BASE.replace("walkers = 8", 'walkers = "many"'), None, "walkers"),
    "wrong_type_starts": (BASE.replace("starts = 2", "starts = 2.5"), None, "starts"),
    "wrong_type_bool": (BASE + "[objective]\nmass_weight = true\n", None, "mass_weight"),
    "wrong_type_bounds": (
        BASE.replace("bounds = [0.2, 3.0]", 'bounds = "wide"', 1),
        None,
        "bounds",
    ),
    "wrong_type_start": (
        BASE.replace("[parameters.theta_2]", 'start = "one"\n[parameters.theta_2]'),
        None,
        "start",
    ),
    "wrong_type_data": (BASE.replace("[4.30, 10.80]", '["4.3 Hz", 10.8]'), None, "frequencies_hz"),
    "wrong_type_parameter": (
        BASE.replace("[parameters.theta_1]\n", "parameters.theta_1 = 3\n[parameters.unused]\n"),
        None,
        "parameters",
    ),
    "inverted_bounds": (BASE.replace("[0.2, 3.0]", "[3.0, 0.2]", 1), None, "bounds"),
    "equal_bounds": (BASE.replace("[0.2, 3.0]", "[1.0, 1.0]", 1), None, "bounds"),
    "start_outside_bounds": (
        BASE.replace("[parameters.theta_2]", "start = 5.0\n[parameters.theta_2]"),
        None,
        "outside bounds",
    ),
    "prior_without_support": (
        BASE.replace(
            "[parameters.theta_2]",
            'prior = {kind = "normal", mean = 50.0, sd = 0.1}\n[parameters.theta_2]',
        ),
        None,
        "no support",
    ),
    "prior_unknown_kind": (
        BASE.replace("[parameters.theta_2]", 'prior = {kind = "gaussian"}\n[parameters.theta_2]'),
        None,
        "gaussian",
    ),
    "prior_negative_sd": (
        BASE.replace(
            "[parameters.theta_2]",
            'prior = {kind = "normal", mean = 1.0, sd = -1.0}\n[parameters.theta_2]',
        ),
        None,
        "sd",
    ),
    "prior_missing_key": (
        BASE.replace(
            "[parameters.theta_2]", 'prior = {kind = "normal", mean = 1.0}\n[parameters.theta_2]'
        ),
        None,
        "sd",
    ),
    "unknown_parameter": (BASE.replace("theta_2]", "theta_3]"), None, "theta_3"),
    "unknown_builtin_model": (
        BASE.replace("shear_building", "shear_bulding"),
        None,
        "shear_bulding",
    ),
    "bad_model_option": (BASE.replace("[data]", "options = {floors = 3}\n[data]"), None, "options"),
    "weights_wrong_length": (
        BASE.replace("[data]\n", "[data]\nweights = [1.0]\n"),
        None,
        "weights",
    ),
    "negative_weight": (
        BASE.replace("[data]\n", "[data]\nweights = [1.0, -1.0]\n"),
        None,
        "weight",
    ),
    "zero_weights": (BASE.replace("[data]\n", "[data]\nweights = [0.0, 0.0]\n"), None, "weights"),
    "sd_wrong_length": (BASE.replace("[data]\n", "[data]\nsd_hz = [0.1, 0.1, 0.1]\n"), None, "sd"),
    "nan_frequency": (BASE.replace("[4.30, 10.80]", "[4.30, nan]"), None, "frequenc"),
    "negative_frequency": (BASE.replace("[4.30, 10.80]", "[-4.30, 10.80]"), None, "frequenc"),
    "more_test_modes_than_model": (
        BASE.replace("[4.30, 10.80]", "[4.30, 10.80, 20.0]"),
        None,
        "modes",
    ),
    "data_source_and_inline": (
        BASE.replace("[data]\n", '[data]\nsource = "paper:ema"\n'),
        None,
        "not both",
    ),
    "unknown_paper_data": (
        BASE.replace("frequencies_hz = [4.30, 10.80]", 'source = "paper:fea"'),
        None,
        "paper:fea",
    ),
    "unknown_pairing": (BASE + '[pairing]\nmethod = "magic"\n', None, "pairing"),
    "negative_extra_modes": (BASE + "[pairing]\nextra_modes = -3\n", None, "extra_modes"),
    "mass_term_without_mass": (BASE + "[objective]\nmass_weight = 1.0\n", None, "mass_kg"),
    # NaN dropped the mass term and inf froze the optimizer at its start, silently
    "nan_mass_weight": (BASE + "[objective]\nmass_weight = nan\nmass_kg = 1.0\n", None,
                        "mass_weight and mac_weight must be finite numbers >= 0"),
    "infinite_mass_target": (BASE + "[objective]\nmass_weight = 1.0\nmass_kg = inf\n", None,
                             "give the measured mass (finite, > 0)"),
    "unknown_optimizer_method": (
        BASE.replace("starts = 2", 'starts = 2\nmethod = "newton"'),
        None,
        "method",
    ),
    "zero_starts": (BASE.replace("starts = 2", "starts = 0"), None, "starts"),
    "negative_optimizer_seed": (
        BASE.replace("starts = 2", "starts = 2\nseed = -1"),
        None,
        "optimizer.seed: must be an integer >= 0",
    ),
    "negative_sigma": (BASE + "[likelihood]\nsigma = -0.05\n", None, "sigma"),
    "sampler_hdi": (BASE.replace("walkers = 8", "walkers = 8\nhdi_prob = 1.5"), None, "hdi_prob"),
    "too_few_walkers": (BASE.replace("walkers = 8", "walkers = 2"), None, "walkers"),
    "zero_steps": (BASE.replace("steps = 20", "steps = 0"), None, "steps"),
    # the built-in model's options, checked (each was an internal error: a 0 x 0 or
    # indefinite mass matrix, an IndexError, NaN in eigh)
    "shear_building_one_mass": (
        BASE.replace('"shear_building"', '"shear_building"\noptions = { masses_kg = [1.0] }'),
        None, "shear_building: masses_kg must be 2 finite number(s)",
    ),
    "shear_building_zero_mass": (
        BASE.replace('"shear_building"', '"shear_building"\noptions = { masses_kg = [0.0, 1.0] }'),
        None, "needs masses_kg > 0",
    ),
    "shear_building_nan_stiffness": (
        BASE.replace('"shear_building"', '"shear_building"\noptions = { k_nominal = nan }'),
        None, "k_nominal must be 1 finite number(s)",
    ),
    "shear_building_no_bounds": (
        BASE.replace('"shear_building"', '"shear_building"\noptions = { bounds = [] }'),
        None, "bounds must be 2 finite number(s)",
    ),
}  # fmt: skip


@pytest.fixture
def write_study(tmp_path):
    def write(text: str, name: str = "study.toml") -> Path:
        return write_text(tmp_path / name, text)

    return write


def test_base_study_is_valid(write_study, tmp_path, capsys):
    # the cases below differ from a study that works
    out = tmp_path / "ok.h5"
    code, _, err = run_cli(["calibrate", write_study(BASE), "--out", out], capsys)
    assert code == 0, err
    assert out.exists()


@pytest.mark.parametrize("command", ["calibrate", "sample"])
@pytest.mark.parametrize("case", sorted(STUDY_CASES))
def test_bad_study(case, command, write_study, tmp_path, capsys):
    text, _, needle = STUDY_CASES[case]
    study = write_study(text)
    out = tmp_path / "result.h5"
    code, _, err = run_cli([command, study, "--out", out], capsys)
    assert_clean_rejection(code, err, out, needle)


def test_missing_study_file(tmp_path, capsys):
    out = tmp_path / "r.h5"
    code, _, err = run_cli(["calibrate", tmp_path / "nope.toml", "--out", out], capsys)
    assert_clean_rejection(code, err, out, "nope.toml")


@pytest.mark.parametrize(
    "csv, needle",
    [
        ("", "empty"),
        ("# only a comment\n", "empty"),
        ("freq,weight\n4.3,1\n", "frequency_hz"),
        ("frequency_hz,weight\n", "no data rows"),
        ("frequency_hz,weight\n4.3,1\nten,1\n", "row"),
        ("frequency_hz\n4.3\nnan\n", "frequenc"),
        ("frequency_hz\n4.3\ninf\n", "frequenc"),
        ("frequency_hz,weight\n4.3,1\n10.8,-2\n", "weight"),
        ("frequency_hz,sd_hz\n4.3,0.1\n10.8,-0.1\n", "sd_hz"),
    ],
)
def test_bad_frequency_csv(tmp_path, capsys, csv, needle):
    data = write_text(tmp_path / "freqs.csv", csv)
    out = tmp_path / "r.h5"
    argv = ["calibrate", "--model", "shear_building", "--data", data, "--out", out]
    code, _, err = run_cli(argv, capsys)
    assert_clean_rejection(code, err, out, needle)


@pytest.mark.parametrize(
    "argv, needle",
    [
        (["calibrate"], "study"),
        (["calibrate", "--model", "shear_building", "--data", "missing.csv"], "missing.csv"),
        (["calibrate", "--model", "shear_building", "--data", "freqs.xlsx"], "freqs.xlsx"),
        (["calibrate", "--model", "shear_building", "--data", "paper:fea"], "paper:fea"),
        (["calibrate", "--model", "exhaust", "--starts", "-1"], "starts"),
        (["calibrate", "--model", "exhaust", "--seed", "x"], "--seed"),
        (["calibrate", "--model", "exhaust", "--seed", "-1"], "--seed: '-1': give an integer >= 0"),
        # sizes no machine holds: one line (were an internal MemoryError / OverflowError)
        (
            ["calibrate", "--model", "exhaust", "--data", "paper:ema", "--starts", "1000000000000"],
            "not enough memory for this run",
        ),
        (
            [
                "calibrate",
                "--model",
                "exhaust",
                "--data",
                "paper:ema",
                "--workers",
                "1000000000000",
            ],
            "compute.workers: must be in 1..1024",
        ),
        (
            ["simulate", "--model", "exhaust", "--seed", "-1", "--out", "t.uff"],
            "--seed: '-1': give an integer >= 0",
        ),
        (
            ["simulate", "--model", "shear_building", "--out", "t.uff"],
            "model 'shear_building' is not an FE model; 'simulate' needs one",
        ),
        (
            [
                "correlate",
                "--model",
                "exhaust",
                "--data",
                "m.h5",
                "--out",
                "a.h5",
                "--report",
                "a.h5",
            ],
            "name the same path; give each its own",
        ),
        (
            ["sample", "--model", "shear_building", "--data", "f.csv", "--out", ""],
            "--out: give a path, not an empty text",
        ),
        (
            [
                "simulate",
                "--model",
                str(Path(__file__).parent / "data" / "msc_fmondsp.dat"),
                "--test-points",
                "bin.dat",
                "--out",
                "t.uff",
            ],
            "--test-points bin.dat: not a text file",
        ),
        (["sample", "--model", "shear_building", "--data", "f.csv", "--walkers", "1"], "walkers"),
        (["sample", "--model", "shear_building", "--data", "f.csv", "--steps", "0"], "steps"),
        (["sample", "--model", "shear_building", "--data", "f.csv", "--resume"], "--out"),
    ],
)
def test_calibrate_sample_bad_flags(tmp_path, capsys, argv, needle, monkeypatch):
    monkeypatch.chdir(tmp_path)
    write_text(tmp_path / "freqs.xlsx", "not a table")
    write_text(tmp_path / "f.csv", "frequency_hz\n4.3\n10.8\n")
    (tmp_path / "bin.dat").write_bytes(b"\x8e\x8f\x00bin")
    before = sorted(p.name for p in tmp_path.iterdir())
    code, _, err = run_cli(argv, capsys)
    assert_clean_rejection(code, err, None, needle)
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_resume_without_partial_file(write_study, tmp_path, capsys):
    out = tmp_path / "r.h5"
    code, _, err = run_cli(["sample", write_study(BASE), "--out", out, "--resume"], capsys)
    assert_clean_rejection(code, err, out, "resume")


@pytest.mark.parametrize("command", ["calibrate", "sample"])
def test_output_checks_for_calibrate_and_sample(command, write_study, tmp_path, capsys):
    study = write_study(BASE)
    code, _, err = run_cli([command, study, "--out", "/sys/r.h5"], capsys)
    assert_clean_rejection(code, err, None, "not writable")
    code, _, err = run_cli([command, study, "--out", tmp_path / "no" / "r.h5"], capsys)
    assert_clean_rejection(code, err, None, "does not exist")
    out = write_text(tmp_path / "r.h5", "previous result")
    code, _, err = run_cli([command, study, "--out", out], capsys)
    assert_clean_rejection(code, err, None, "--force")
    assert out.read_text() == "previous result"
    code, _, err = run_cli([command, study, "--out", tmp_path], capsys)
    assert_clean_rejection(code, err, None, "folder")


# -- modal-data files given as --data (UFF 55 and HDF5 from identify) ----------------------------
@pytest.fixture(scope="module")
def uff55_text(tmp_path_factory):
    from bayesupdate.ema.uff_io import write_uff55
    from bayesupdate.modal_data import ModalData

    rng = np.random.default_rng(0)
    modes = ModalData(
        frequencies_hz=np.array([9.0, 11.0]),
        shapes=rng.normal(size=(3, 2)),
        dof_labels=("1V", "2V", "3H"),
    )
    path = tmp_path_factory.mktemp("uff55") / "modes.uff"
    write_uff55(path, modes)
    return path.read_text()


def _bad_modal_files(text: str) -> dict[str, bytes]:
    lines = text.splitlines()
    value = lines[13].split()[2]  # a shape value of mode 1
    return {
        "truncated.uff": text[: len(text) * 3 // 4].encode(),
        "empty.uff": b"",
        "nan.uff": text.replace(value, "nan".rjust(len(value)), 1).encode(),
        "inf.uff": text.replace(value, "inf".rjust(len(value)), 1).encode(),
        "corrupt.uff": text.replace(value, "garbage!".rjust(len(value)), 1).encode(),
        "empty.h5": b"",
        "junk.h5": b"\x89HDF\r\n\x1a\n" + b"\x00" * 50,
        "binary.csv": bytes(range(256)),
    }


@pytest.mark.parametrize(
    "name",
    [
        "truncated.uff",
        "empty.uff",
        "nan.uff",
        "inf.uff",
        "corrupt.uff",
        "empty.h5",
        "junk.h5",
        "binary.csv",
    ],
)
def test_bad_modal_data_file(name, uff55_text, tmp_path, capsys):
    data = tmp_path / name
    data.write_bytes(_bad_modal_files(uff55_text)[name])
    out = tmp_path / "r.h5"
    argv = ["calibrate", "--model", "exhaust", "--starts", "1", "--data", data, "--out", out]
    code, _, err = run_cli(argv, capsys)
    assert_clean_rejection(code, err, out, name)


def test_hdf5_that_is_not_a_modal_result(tmp_path, capsys):
    import h5py

    data = tmp_path / "other.h5"
    with h5py.File(data, "w") as h5:
        h5["x"] = 1
    out = tmp_path / "r.h5"
    argv = ["calibrate", "--model", "exhaust", "--data", data, "--out", out]
    code, _, err = run_cli(argv, capsys)
    assert_clean_rejection(code, err, out, "other.h5")


# -- sensor labels and physical values of the exhaust -------------------------------------------
def test_identify_result_with_foreign_sensor_labels(tmp_path, capsys):
    # an EMA result whose DOF names are not the exhaust's sensors (e.g. another test's layout)
    from bayesupdate.ema.modal_h5 import write_modal_h5
    from bayesupdate.modal_data import ModalData

    rng = np.random.default_rng(0)
    labels = ("101X", "102X", "103Y")
    modes = ModalData(
        frequencies_hz=np.array([10.0, 20.0]), shapes=rng.normal(size=(3, 2)), dof_labels=labels
    )
    data = tmp_path / "modes.h5"
    write_modal_h5(data, modes)
    out = tmp_path / "r.h5"
    argv = ["calibrate", "--model", "exhaust", "--data", data, "--out", out, "--starts", "1"]
    code, _, err = run_cli(argv, capsys)
    assert_clean_rejection(code, err, out, "101X")


@pytest.mark.parametrize(
    "name, bounds",
    [
        ("t_hot_pipe", "[0.0, 3e-3]"),
        ("t_main_muffler", "[-1e-3, 3e-3]"),
        ("rho_catalyst", "[-1e3, 3e4]"),
        ("rho_intermediate_muffler", "[0.0, 3e4]"),
    ],
)
def test_study_bounds_with_non_physical_values(name, bounds, write_study, tmp_path, capsys):
    study = write_study(
        f'[model]\nsource = "exhaust"\n[data]\nsource = "paper:ema"\n'
        f"[parameters.{name}]\nbounds = {bounds}\n[optimizer]\nstarts = 1\n"
    )
    out = tmp_path / "r.h5"
    code, _, err = run_cli(["calibrate", study, "--out", out], capsys)
    assert_clean_rejection(code, err, out, f"parameters.{name}")


@pytest.mark.parametrize(
    "assignment",
    [
        "t_cold_pipe=0",
        "t_main_muffler=-0.5mm",
        "rho_catalyst=-5kg/m3",
        "rho_intermediate_muffler=0",
        "t_hot_pipe=nan",
        "t_hot_pipe=inf",
    ],
)
def test_modes_non_physical_values(assignment, capsys):
    code, _, err = run_cli(["modes", "--set", assignment], capsys)
    assert_clean_rejection(code, err, None, assignment.split("=")[0])


# -- custom models ------------------------------------------------------------------------------
USER_MODELS = {
    "ok": "def f(p):\n    return [4.30 * p['a'] ** 0.5, 10.8 * p['a'] ** 0.5]\n",
    "raises_at_import": "raise RuntimeError('licence server down')\ndef f(p):\n    return [1.0]\n",
    "syntax_error": "def f(p)\n    return [1.0]\n",
    "too_few": "def f(p):\n    return [4.30]\n",
    "always_raises": "def f(p):\n    raise ValueError('solver diverged')\n",
    "always_nan": "def f(p):\n    return [float('nan'), float('nan')]\n",
    "wrong_mapping": "def f(p):\n    return {'freqs': [4.3, 10.8]}\n",
    "text": "def f(p):\n    return 'abc'\n",
    "table": "def f(p):\n    return [[4.3, 10.8], [4.3, 10.8]]\n",
    "not_callable": "f = 3\n",
}


@pytest.fixture
def user_models(tmp_path, monkeypatch, request):
    """A package on sys.path with one module per USER_MODELS entry (unique name per test)."""
    package = f"usermods_{abs(hash(request.node.name)) % 10**8}"
    folder = tmp_path / "lib" / package
    folder.mkdir(parents=True)
    (folder / "__init__.py").write_text("")
    for name, text in USER_MODELS.items():
        (folder / f"{name}.py").write_text(text)
    monkeypatch.syspath_prepend(str(tmp_path / "lib"))
    return package


def _user_study(source: str, bounds: str = "[0.5, 2.0]") -> str:
    return (
        f'[model]\nsource = "{source}"\n[data]\nfrequencies_hz = [4.30, 10.80]\n'
        f"[parameters.a]\nbounds = {bounds}\n[optimizer]\nstarts = 2\n"
        "[sampler]\nwalkers = 4\nsteps = 20\ncheck_every = 10\npredictive_draws = 5\n"
    )


@pytest.mark.parametrize(
    "source, needle",
    [
        ("no_such_package_xyz.model:f", "does not import"),
        ("{pkg}.raises_at_import:f", "does not import"),
        ("{pkg}.syntax_error:f", "does not import"),
        ("{pkg}.ok:g", "no function"),
        ("{pkg}.not_callable:f", "no function"),
        ("{pkg}.ok:f:extra", "module:function"),
        ("{pkg}.too_few:f", "frequencies"),
        ("{pkg}.always_raises:f", "solver diverged"),
        ("{pkg}.always_nan:f", "failed"),
        ("{pkg}.wrong_mapping:f", "frequencies_hz"),
        ("{pkg}.text:f", "returned frequencies that are not numbers: 'abc'"),
        ("{pkg}.table:f", "returned frequencies of shape (2, 2)"),
    ],
)
@pytest.mark.parametrize("command", ["calibrate", "sample"])
def test_bad_custom_model(command, source, needle, user_models, write_study, tmp_path, capsys):
    study = write_study(_user_study(source.format(pkg=user_models)))
    out = tmp_path / "r.h5"
    code, _, err = run_cli([command, study, "--out", out], capsys)
    assert_clean_rejection(code, err, out, needle)


def test_custom_model_needs_bounds(user_models, write_study, tmp_path, capsys):
    text = _user_study(f"{user_models}.ok:f").replace("bounds = [0.5, 2.0]", "start = 1.0")
    out = tmp_path / "r.h5"
    code, _, err = run_cli(["calibrate", write_study(text), "--out", out], capsys)
    assert_clean_rejection(code, err, out, "bounds")


def test_custom_model_that_works(user_models, write_study, tmp_path, capsys):
    # the same set-up with a working function calibrates: a = 1 fits both frequencies exactly
    out = tmp_path / "r.h5"
    study = write_study(_user_study(f"{user_models}.ok:f"))
    code, stdout, err = run_cli(["calibrate", study, "--out", out, "--json"], capsys)
    assert code == 0, err
    import json

    assert json.loads(stdout)["parameters"]["a"] == pytest.approx(1.0, rel=1e-6)


# -- identify: more cases -----------------------------------------------------------------------
@pytest.mark.parametrize(
    "extra, needle",
    [
        (["--band", "10:12", "--max-order", "60"], "order"),
        (["--max-order", "0"], "--max-order"),
        (["--band", "-5:50"], "band"),
        (["--band", "nan:50"], "band"),
    ],
)
def test_identify_order_and_band(tmp_path, capsys, good_uff, extra, needle):
    path, _ = good_uff
    out = tmp_path / "m.h5"
    code, _, err = run_cli(["identify", path, "--out", out, *extra], capsys)
    assert_clean_rejection(code, err, out, needle)


def test_identify_uff_without_frfs(tmp_path, capsys):
    # a UFF 55 (modal result) given where FRFs (UFF 58) are expected
    from bayesupdate.ema.uff_io import write_uff55
    from bayesupdate.modal_data import ModalData

    modes = ModalData(
        frequencies_hz=np.array([10.0, 20.0]), shapes=np.eye(2), dof_labels=("1V", "2V")
    )
    path = tmp_path / "modes.uff"
    write_uff55(path, modes)
    out = tmp_path / "m.h5"
    code, _, err = run_cli(["identify", path, "--out", out], capsys)
    assert_clean_rejection(code, err, out, "modes.uff")


def test_simulate_output_checks(tmp_path, capsys):
    code, _, err = run_cli(["simulate", "--model", "exhaust", "--out", "/sys/t.uff"], capsys)
    assert_clean_rejection(code, err, None, "not writable")
    out = write_text(tmp_path / "t.uff", "old test")
    code, _, err = run_cli(["simulate", "--model", "exhaust", "--out", out], capsys)
    assert_clean_rejection(code, err, None, "--force")
    assert out.read_text() == "old test"


# -- discover ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "extra, needle",
    [
        (["--model", "exhaust", "--data", "missing.h5"], "missing.h5"),
        (["--model", "shear_building", "--data", "f.csv"], "fe model"),
        (["--model", "exhaust", "--data", "paper:ema", "--effect", "gremlin@3"], "gremlin"),
        (["--model", "exhaust", "--data", "paper:ema", "--effect", "added_mass@99:m=0.1"], "99"),
        (["--model", "exhaust", "--data", "paper:ema", "--kinds", "nope"], "nope"),
        (["--model", "exhaust", "--data", "paper:ema", "--sigma", "-1"], "sigma"),
        (["--model", "exhaust", "--data", "paper:ema", "--threshold", "nan"], "threshold"),
        (["--model", "exhaust", "--data", "paper:ema", "--threshold", "-1"], "threshold"),
        (["--model", "exhaust", "--data", "paper:ema", "--effect-prior", "0"], "effect_prior"),
        (["--model", "exhaust", "--data", "paper:ema", "--effect-prior", "1"], "effect_prior"),
        (["--model", "exhaust", "--data", "paper:ema", "--effect-prior", "nan"], "effect_prior"),
        (["--model", "exhaust", "--data", "paper:ema", "--max-refits", "-2"], "max_refits"),
        (["--model", "exhaust", "--data", "paper:ema", "--starts", "0"], "starts"),
        (["--model", "exhaust", "--data", "paper:ema", "--posterior-steps", "-5"], "steps"),
        (["study.toml"], "t_hot_pipe"),
        (["empty.toml"], "empty"),
    ],
)
def test_discover_bad_input(tmp_path, capsys, monkeypatch, extra, needle):
    if not (Path(__file__).parents[1] / "bayesupdate" / "commands" / "discover.py").exists():
        pytest.skip("discover command not installed")
    monkeypatch.chdir(tmp_path)
    write_text(tmp_path / "f.csv", "frequency_hz\n4.3\n10.8\n")
    write_text(tmp_path / "empty.toml", "")
    write_text(
        tmp_path / "study.toml",
        '[model]\nsource = "exhaust"\n[data]\nsource = "paper:ema"\n'
        "[parameters.t_hot_pipe]\nbounds = [-1e-3, 3e-3]\n",
    )
    out = tmp_path / "d.h5"
    code, _, err = run_cli(["discover", *extra, "--out", out], capsys)
    assert_clean_rejection(code, err, out, needle)
    code, _, err = run_cli(["discover", "--model", "exhaust", "--out", "/sys/d.h5"], capsys)
    assert_clean_rejection(code, err, None, "not writable")


def test_console_script_bad_study_one_line(tmp_path):
    study = write_text(tmp_path / "s.toml", BASE.replace("walkers = 8", "walkers = -8"))
    out = tmp_path / "o.h5"
    proc = subprocess.run(
        [
            str(Path(sys.executable).with_name("bayesupdate")),
            "sample",
            str(study),
            "--out",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1 and "sampler.walkers" in proc.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml"]


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


@pytest.mark.parametrize("value", ["abc", "nan", "-5"])
def test_a_cache_cap_that_is_no_size_is_one_error_line(value, monkeypatch, capsys):
    """``BAYESUPDATE_CACHE_MAX_MB`` that is no number >= 0: one line naming the variable (it was
    an internal ValueError in ``cache info`` and in every command that caches)."""
    monkeypatch.setenv("BAYESUPDATE_CACHE_MAX_MB", value)
    code, _, err = run_cli(["cache", "info"], capsys)
    assert_clean_rejection(code, err, None, f"BAYESUPDATE_CACHE_MAX_MB='{value}': give the")


def test_a_cache_folder_that_cannot_be_written_is_one_warning_line(tmp_path, monkeypatch, capsys):
    """The run goes on without the cache, and the warning is one ``warning:`` line (the CLI
    shows warnings so, ``cli.plain_warnings``; Python's own format adds the package's file,
    line and source), and the caller's warning display is restored after the command."""
    import warnings

    blocker = tmp_path / "file"
    blocker.write_text("a file where the cache folder would go")
    monkeypatch.setenv("BAYESUPDATE_CACHE_DIR", str(blocker / "cache"))
    monkeypatch.delenv("BAYESUPDATE_NO_CACHE")  # the suite's own (conftest): the user's default
    before = warnings.showwarning
    code, out, err = run_cli(["calibrate", "--model", "exhaust", "--data", "paper:ema",
                              "--starts", "1", "--no-polish"], capsys)  # fmt: skip
    assert code == 0 and "objective" in out
    warned = [line for line in err.splitlines() if "cannot be written" in line]
    assert len(warned) == 1 and warned[0].startswith("warning: cache folder "), err
    assert ".py:" not in err and "RuntimeWarning" not in err
    assert warnings.showwarning is before
