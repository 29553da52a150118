"""``bayesupdate sensitivity`` and its maths (``pipelines.sensitivity``) against closed forms.

A cantilever deck written here (CBAR, MAT1 with G blank so G follows E, no shear flexibility):
K is E times a fixed matrix and M is RHO times one plus the tip CONM2's mass, so for every mode
d ln f / d ln E = 1/2 and d ln f / d ln RHO + d ln f / d ln M = -1/2 (lambda is homogeneous of
degree 1 in K and -1 in M), and scaling E, RHO and M together moves nothing: one singular value
0 with the direction (1, 1, 1) / sqrt(3).  Without the CONM2, E and RHO move the frequencies
only through E / RHO: one group, one direction.  The eigenvalue derivative agrees with central
differences of full solves on the MSC beam deck (line elements re-built from their cards).
"""

import json
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.cli import main
from bayesupdate.pipelines.sensitivity import confounded_groups, identifiability

SHARED = next(
    (p / "shared" for p in Path(__file__).resolve().parents if (p / "shared" / "data").is_dir()),
    Path(__file__).resolve().parents[2] / "shared",
)
BEAM = SHARED / "data" / "nastran" / "beam_modes" / "beam_modes.dat"


def _card(*fields) -> str:
    """A small-field bulk data card (8 columns a field)."""
    return "".join(f"{f!s:<8}"[:8] if i == 0 else f"{f!s:>8}"[:8] for i, f in enumerate(fields))


def _cantilever(folder: Path, tip_mass: bool) -> Path:
    """A 1 m steel cantilever of 10 CBARs (SI units), optionally with a 0.2 kg tip CONM2."""
    lines = ["SOL 103", "CEND", "METHOD = 1", "SPC = 1", "BEGIN BULK", _card("EIGRL", 1, "", "", 8)]
    lines += [_card("GRID", i + 1, "", f"{0.1 * i:.2f}", "0.", "0.") for i in range(11)]
    lines += [_card("CBAR", i + 1, 1, i + 1, i + 2, "0.", "1.", "0.") for i in range(10)]
    lines += [
        _card("PBAR", 1, 1, "1.-4", "2.-9", "1.-9", "3.-9"),
        _card("MAT1", 1, "2.1+11", "", ".3", "7850."),
    ]
    lines += [_card("SPC1", 1, 123456, 1)]
    if tip_mass:
        lines.append(_card("CONM2", 99, 11, "", ".2"))
    path = folder / ("tip.bdf" if tip_mass else "bare.bdf")
    path.write_text("\n".join([*lines, "ENDDATA", ""]))
    return path


def _run(capsys, argv) -> dict:
    code = main([*argv, "--json"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    return json.loads(captured.out.strip().splitlines()[-1])


def _frequencies_csv(folder: Path, deck: Path, n: int) -> Path:
    """The deck's own first n frequencies as a test (frequencies only: paired in order)."""
    from bayesupdate.nastran import load_nastran_model

    f = load_nastran_model(str(deck), None).solve(None, n).frequencies_hz
    path = folder / "test.csv"
    path.write_text("frequency_hz\n" + "\n".join(f"{v:.9g}" for v in f) + "\n")
    return path


def test_cantilever_sensitivities_are_the_closed_forms(tmp_path, capsys):
    deck = _cantilever(tmp_path, tip_mass=True)
    data = _frequencies_csv(tmp_path, deck, 6)
    out = _run(capsys, ["sensitivity", "--model", str(deck), "--data", str(data),
                        "--candidates", "MAT1 * E", "MAT1 * RHO", "CONM2 * M"])  # fmt: skip
    assert [c["name"] for c in out["candidates"]] == ["MAT1 1 E", "MAT1 1 RHO", "CONM2 99 M"]
    s = np.asarray(out["sensitivity"])
    assert s.shape == (6, 3) and out["method"] == "analytic"
    np.testing.assert_allclose(s[:, 0], 0.5, atol=1e-6)
    np.testing.assert_allclose(s[:, 1] + s[:, 2], -0.5, atol=1e-6)
    assert np.all(s[:, 2] < 0) and np.all(s[:, 1] < 0)
    # E, RHO and M scaled together leave every frequency where it is: a direction not seen
    assert out["rank"] == 2 and out["singular_values"][2] < 1e-5
    unseen = out["unseen"][0]
    np.testing.assert_allclose(sorted(unseen.values()), [3**-0.5] * 3, atol=1e-4)
    assert out["groups"] == []  # three columns confounded together, no two parallel


def test_e_and_rho_of_the_only_material_are_one_direction(tmp_path, capsys):
    deck = _cantilever(tmp_path, tip_mass=False)
    data = _frequencies_csv(tmp_path, deck, 6)
    out = _run(capsys, ["sensitivity", "--model", str(deck), "--data", str(data),
                        "--candidates", "MAT1 1 E", "MAT1 1 RHO"])  # fmt: skip
    s = np.asarray(out["sensitivity"])
    np.testing.assert_allclose(s, np.tile([0.5, -0.5], (6, 1)), atol=1e-6)
    assert out["groups"] == [["MAT1 1 E", "MAT1 1 RHO"]]
    assert out["rank"] == 1 and len(out["suggested"]) == 1
    assert out["singular_values"][1] < 1e-5 * out["singular_values"][0]
    # the seen direction is E / RHO: equal and opposite weights
    seen = out["directions"][0]["terms"]
    assert seen["MAT1 1 E"] == pytest.approx(-seen["MAT1 1 RHO"], abs=1e-6)


def test_eigenvalue_derivative_agrees_with_central_differences_on_the_msc_beam(tmp_path, capsys):
    if not BEAM.exists():
        pytest.skip(f"shared data not found: {BEAM}")
    data = _frequencies_csv(tmp_path, BEAM, 8)
    args = ["sensitivity", "--model", str(BEAM), "--data", str(data), "--candidates",
            "PBARL * DIM1", "PBEAML * DIM1", "CONM2 * M", "MAT1 * E"]  # fmt: skip
    analytic = np.asarray(_run(capsys, args)["sensitivity"])
    fd = np.asarray(_run(capsys, [*args, "--method", "fd", "--step", "1e-3"])["sensitivity"])
    assert np.abs(analytic).max() > 0.1
    np.testing.assert_allclose(analytic, fd, atol=2e-5)


def test_identifiability_of_hand_matrices():
    # two parallel columns (one scaled by -2) and one independent: one group, rank 2
    s = np.array([[1.0, -2.0, 0.0], [2.0, -4.0, 1.0], [0.5, -1.0, 3.0]])
    ident = identifiability(s, rank_tol=0.02, group_cos=0.99)
    assert ident.rank == 2 and ident.groups == ((0, 1),)
    assert ident.singular_values[2] < 1e-12
    # the pivoted QR takes the largest column first, then the one independent of it
    assert ident.suggested == (1, 2)
    assert confounded_groups(np.eye(3), 0.99) == ()
    # transitive: 0~1 and 1~2 above the threshold, 0 and 2 below it
    a = np.array([[1.0, 1.0, 1.0], [0.0, 0.1, 0.2]])
    assert confounded_groups(a, 0.99) == ((0, 1, 2),)


@pytest.mark.parametrize(
    ("extra", "needle"),
    [
        (["--candidates", "PSHELL * T"], "only for a Nastran deck"),
        (["--rank-tol", "2"], "--rank-tol"),
        (["--step", "0"], "--step"),
    ],
)
def test_bad_input_is_one_line_exit_2_and_no_file(tmp_path, capsys, extra, needle):
    out, report = tmp_path / "s.h5", tmp_path / "report"
    argv = ["sensitivity", "--model", "exhaust", "--data", "paper:ema", "--out", str(out),
            "--report", str(report), *extra]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err
    assert not out.exists() and not report.exists()


def test_a_card_the_deck_lacks_is_named(tmp_path, capsys):
    deck = _cantilever(tmp_path, tip_mass=False)
    data = _frequencies_csv(tmp_path, deck, 3)
    argv = ["sensitivity", "--model", str(deck), "--data", str(data), "--candidates", "PSHELL * T"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no PSHELL card" in err


def test_a_study_files_bound_parameters_are_the_candidates(tmp_path, capsys):
    deck = _cantilever(tmp_path, tip_mass=True)
    data = _frequencies_csv(tmp_path, deck, 4)
    study = tmp_path / "study.toml"
    study.write_text(
        f'[model]\nsource = "{deck}"\n[data]\nsource = "{data}"\n'
        '[parameters.e]\nbinds = "MAT1 1 E"\n[parameters.m_tip]\nbinds = "CONM2 99 M"\n'
    )
    out = _run(capsys, ["sensitivity", str(study), "--out", str(tmp_path / "s.h5")])
    assert [c["name"] for c in out["candidates"]] == ["e", "m_tip"]
    assert out["candidates"][0]["value"] == pytest.approx(2.1e11)
    s = np.asarray(out["sensitivity"])
    np.testing.assert_allclose(s[:, 0], 0.5, atol=1e-6)
    assert np.all((s[:, 1] < 0) & (s[:, 1] > -0.5))
    import h5py

    with h5py.File(tmp_path / "s.h5", "r") as fh:
        np.testing.assert_allclose(fh["sensitivity/matrix"][()], s, atol=1e-6)
