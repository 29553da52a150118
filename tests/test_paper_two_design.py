"""The beam exhaust fitted to both of the paper's FE designs (seed Table 1 at the initial design,
Table 4 at the Table 3 design), and its calibration against seed Table 2 checked against the
paper's optimum (Tables 3 and 4, eq. 19, the 12.12 kg mass).

The fitted geometry is package data written by ``studies/reproduce_paper_fe.py --fit two_design``
(``bayesupdate/data/exhaust_geometry_two_design.json``); the numbers below were measured on it
with the commands named in each test and are asserted to the tolerance the arithmetic or the
physics gives.  Where the paper's optimum is not reached, the test asserts what is measured and
its docstring says by how much the target is missed and why.
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from bayesupdate.cli import main  # noqa: E402
from bayesupdate.errors import BayesUpdateError  # noqa: E402
from bayesupdate.fe.reduced import reduced_model_for  # noqa: E402
from bayesupdate.inference import (  # noqa: E402
    CalibrationSettings,
    ObjectiveSpec,
    build_problem,
    calibrate,
    load_modal_data,
    objective_expr,
)
from bayesupdate.models import get_model  # noqa: E402
from bayesupdate.models.exhaust import (  # noqa: E402
    DEFAULT_GEOMETRY,
    GEOMETRY_FILES,
    JOINT_WALL_PART,
    fitted_geometry,
    load_geometries,
)
from bayesupdate.models.exhaust_fit import FIT_SETUPS, evaluate  # noqa: E402
from bayesupdate.models.exhaust_paper import (  # noqa: E402
    DESIGN_VARIABLES,
    MEASURED_MASS_KG,
    OPTIMUM_MASS_KG,
    TABLE1_FEA_HZ,
    TABLE2_EMA_HZ,
    TABLE3_INITIAL_SI,
    TABLE3_OPTIMUM_SI,
    TABLE4_FINAL_HZ,
)


@pytest.fixture(scope="module")
def two_design():
    """The stored two-design geometry at both of the paper's designs (``exhaust_fit.evaluate``:
    Table 1 design and Table 3 design)."""
    return evaluate(fitted_geometry("two_design"))


def rms(x):
    return float(np.sqrt(np.mean(np.square(x))))


# ---- geometry names ------------------------------------------------------------------------


def test_geometry_sets_by_name():
    """ "best" is the default set's best fit; each set is reachable by name and by "NAME:k"."""
    assert set(GEOMETRY_FILES) == {"table1", "two_design"}
    assert fitted_geometry("best") == fitted_geometry(DEFAULT_GEOMETRY)
    assert fitted_geometry(1) == fitted_geometry(f"{DEFAULT_GEOMETRY}:1")
    assert fitted_geometry("table1") == load_geometries("table1")["best"]["values"]
    assert "joint_wall_log10_k" in fitted_geometry("two_design")
    assert "joint_wall_log10_k" not in fitted_geometry("table1")


@pytest.mark.parametrize("bad", ["nope", "two_design:x", "table1:99", "shell"])
def test_unknown_geometry_names_the_known_ones(bad):
    with pytest.raises(BayesUpdateError) as err:
        get_model("exhaust", geometry=bad)
    message = str(err.value)
    assert "\n" not in message and bad.partition(":")[0] in message
    if bad != "table1:99":  # an index out of range names the set's range instead
        assert "'table1'" in message and "'two_design'" in message


def test_cli_unknown_geometry_exits_2_with_one_line(capsys):
    code = main(["modes", "--model", "exhaust", "--geometry", "nope"])
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2 and len(lines) == 1, err
    assert "table1" in lines[0] and "two_design" in lines[0]


def test_study_file_unknown_geometry_exits_2_with_one_line(tmp_path, capsys):
    """The same refusal where a user names the geometry in a study file's [model] options
    (the way the guide's two_design.toml does), before any calibration work starts."""
    study = tmp_path / "bad.toml"
    study.write_text('[model]\nsource = "exhaust"\noptions = { geometry = "two_desing" }\n')
    code = main(["calibrate", str(study), "--data", "paper:ema", "--json"])
    captured = capsys.readouterr()
    lines = [line for line in captured.err.splitlines() if line.strip()]
    assert code == 2 and len(lines) == 1, captured.err
    assert "'two_desing'" in lines[0] and "'table1'" in lines[0] and "'two_design'" in lines[0]
    assert captured.out == ""


# ---- the two-design fit (studies/reproduce_paper_fe.py --check --fit two_design) -----------------


def test_two_design_fit_reproduces_both_tables_to_the_measured_floor(two_design):
    """Both of the paper's FE designs at once: Table 1 RMS 5.07 % (max 7.89 %), Table 4 RMS
    5.23 % (max 8.24 %); the Table-1 fit had 2.33 % / 8.15 %.  Two independent ends (one from
    the 60-evaluation fit of random start 4, one from the Table-1 geometry) stop at the same cost
    (0.0637 / 0.0638), so this is the model's floor, not the optimizer's: 0.07 pp above the
    5 % Table 1 floor of the Table-1 fit (stored with "acceptable": false).  Tolerance 0.01 pp:
    the stored geometry fixes the model; only the rounding of the quoted numbers is left."""
    e1 = two_design["f_initial"] / TABLE1_FEA_HZ - 1.0
    e4 = two_design["f_optimum"] / TABLE4_FINAL_HZ - 1.0
    assert rms(e1) == pytest.approx(0.0507, abs=1e-4)
    assert np.max(np.abs(e1)) == pytest.approx(0.0789, abs=1e-4)
    assert rms(e4) == pytest.approx(0.0523, abs=1e-4)
    assert np.max(np.abs(e4)) == pytest.approx(0.0824, abs=1e-4)
    assert [c["plane"] for c in two_design["characters"][:3]] == ["H", "V", "H"]


def test_two_design_masses_fitted_and_held_out(two_design):
    """12.29 kg at the initial design (the budget is closed by construction, to rounding); at
    the Table 3 design the model predicts 12.525 kg where the paper's model weighs 12.12 kg
    (+3.3 %, held out, not fitted).  Why: the thicker pipes (+0.64, +0.68 kg) and the denser
    intermediate muffler (+1.11 kg) outweigh the thinner main muffler (-1.99 kg: 4.7 kg of sheet
    at 1 mm); the paper's -0.17 kg needs 5.65 kg of sheet (sheet factor 2.84, inside its range
    [1, 3]) - the frequencies alone chose 2.36."""
    assert two_design["mass_kg"] == pytest.approx(MEASURED_MASS_KG, abs=0.005)
    assert two_design["mass_optimum_kg"] == pytest.approx(12.525, abs=0.005)
    assert two_design["mass_optimum_kg"] / OPTIMUM_MASS_KG - 1.0 == pytest.approx(0.033, abs=1e-3)


def test_two_design_fitted_values_in_range_and_the_ones_at_a_bound():
    """Every fitted value inside its plausible range (the ranges were not widened); five sit on
    a bound, the fit's evidence of what the beam model lacks: a short hot pipe, a long first cold
    pipe, the shortest tail pipe and main muffler, and a rigid vertical joint spring (all the
    joints' vertical compliance then lies in the wall-following stubs)."""
    values = fitted_geometry("two_design")
    bounds = FIT_SETUPS["two_design"].bounds
    at_bound = set()
    for name, (lo, hi) in bounds.items():
        assert lo <= values[name] <= hi, name
        if min(values[name] - lo, hi - values[name]) <= 1e-3 * (hi - lo):
            at_bound.add(name)
    assert at_bound == {
        "hot_length",
        "cold1_length",
        "tail_length",
        "mm_length",
        "joint_log10_k_v",
    }


def test_wall_following_joints_belong_to_their_wall():
    """The section rule: each joint's stub is a beam of the part whose wall it follows
    (``JOINT_WALL_PART``), so that part's thickness binding reaches it; the two joints of the
    intermediate muffler (thinner 0.8 mm wrapper, not a design variable) have none.  The stub's
    bending stiffness EI/L at the 1.0 mm wall is 10**joint_wall_log10_k (closed form)."""
    from bayesupdate.fe import STEEL
    from bayesupdate.fe.sections import circular_tube

    values = fitted_geometry("two_design")
    s = get_model("exhaust", geometry="two_design").structure
    # the stubs: massless beams softer than steel (the main muffler's massless links are steel)
    stubs = np.flatnonzero((s.beam_rho < 1.0) & (s.beam_E < 0.5 * STEEL.youngs_modulus))
    owners = sorted(s.parts[s.beam_part[e]] for e in stubs)
    assert owners == sorted(p for p in JOINT_WALL_PART.values() if p is not None)
    length = np.linalg.norm(np.diff(s.nodes[s.beam_nodes[stubs]], axis=1), axis=2).ravel()
    np.testing.assert_allclose(length, 0.02, rtol=1e-12)
    inertia = circular_tube(values["pipe_od"], 1.0e-3).properties()["Iy"]
    np.testing.assert_allclose(
        s.beam_E[stubs] * inertia / length, 10.0 ** values["joint_wall_log10_k"], rtol=1e-9
    )
    assert get_model("exhaust", geometry="table1").structure.n_dof < s.n_dof


# ---- calibrated against seed Table 2, checked against the paper's optimum -----------------------


@pytest.fixture(scope="module")
def optimum():
    """``studies/paper_optimum.py --geometry two_design --starts 4``: eq. 19 against Table 2 with
    the weighed 12.29 kg kept (weight 10), tracked pairing, 4 Sobol starts + the initial design
    searched on the certified reduced basis, every end near the best polished on the full model.
    Returns (full problem, result)."""
    fe = get_model("exhaust", geometry="two_design")
    data = load_modal_data("paper:ema")
    objective = ObjectiveSpec(mass_target_kg=MEASURED_MASS_KG, mass_weight=10.0)
    problem = build_problem(fe, data, None, pairing="tracked", objective=objective)
    rom = reduced_model_for(fe, tol=1e-4, seed=0, n_modes=14)
    search = build_problem(rom, data, None, pairing="tracked", objective=objective)
    result = calibrate(search, CalibrationSettings(starts=4, seed=0), refine=problem)
    return problem, result


def test_calibrated_expr_reaches_the_papers_optimum(optimum):
    """The target: Expr <= 0.0406 (the paper's 0.04, from its Table 4 against its Table 4 EMA
    column) with the mass within 1.5 % of the weighed 12.29 kg.  Measured: Expr 0.0402 (the
    Table-1 geometry: 0.0669), mass 12.311 kg (+0.17 %), every start in the best's basin, no
    mode swapped."""
    _, opt = optimum
    assert opt.expr <= 0.0406
    assert objective_expr(opt.frequencies_hz, TABLE2_EMA_HZ) == pytest.approx(opt.expr)
    assert abs(opt.mass_kg / MEASURED_MASS_KG - 1.0) <= 0.015
    assert not opt.table.swapped
    np.testing.assert_array_equal(opt.table.model_mode, np.arange(1, 13))


def test_calibrated_variables_move_the_way_table3_does(optimum):
    """Each of the five design variables moves from the initial design the way seed Table 3
    does (the Table-1 geometry also gets the directions, at Expr 0.0669)."""
    _, opt = optimum
    for name in DESIGN_VARIABLES:
        paper = np.sign(TABLE3_OPTIMUM_SI[name] - TABLE3_INITIAL_SI[name])
        ours = np.sign(opt.parameters[name] - TABLE3_INITIAL_SI[name])
        assert ours == paper, name


def test_calibrated_variables_within_the_model_error_of_table3(optimum):
    """Magnitudes against Table 3, with the tolerance the model gives: the two-design model
    reproduces the paper's FE model to 5.2 % RMS in frequency (Table 4 at the Table 3 design),
    so a variable is pinned only to the change that moves the 12 frequencies by that much:
    tol_j = 0.052 / s_j with s_j = RMS over modes of d ln f / d ln x_j at the optimum (central
    differences, +-2 %).  Measured ln(ours / paper) against tol: t_hot_pipe -0.22 / 1.27,
    t_cold_pipe +0.08 / 0.22, t_main_muffler +0.14 / 1.14, rho_catalyst -0.40 / 1.00,
    rho_intermediate_muffler -0.03 / 0.55: the frequencies pin t_cold_pipe (s = 0.24) and
    rho_intermediate_muffler (0.09) and barely the other three (s = 0.04-0.05), which is why
    only the directions of those three are a sharp check."""
    problem, opt = optimum
    fe = problem.model
    x = dict(opt.parameters)
    for name in DESIGN_VARIABLES:
        up, down = dict(x), dict(x)
        up[name] *= 1.02
        down[name] /= 1.02
        f_up = fe.solve(up, n_modes=12).frequencies_hz
        f_down = fe.solve(down, n_modes=12).frequencies_hz
        s = rms(np.log(f_up / f_down) / (2 * np.log(1.02)))
        tol = 0.052 / s
        assert abs(np.log(x[name] / TABLE3_OPTIMUM_SI[name])) <= tol, (name, tol)


def test_calibrated_frequencies_against_table4(optimum):
    """Our optimum's frequencies against the paper's FE model at its optimum (Table 4): no
    closer can be asked than the model reproduces the paper's model at the same design (RMS
    5.23 %, max 8.24 %, the fit above).  Measured: RMS 3.9 %, max 7.8 % (mode 12)."""
    _, opt = optimum
    err = opt.frequencies_hz / TABLE4_FINAL_HZ - 1.0
    assert rms(err) <= 0.0523
    assert np.max(np.abs(err)) <= 0.0824


def test_calibrated_mass_against_the_papers_optimum_mass(optimum):
    """The paper let its mass fall to 12.12 kg (-1.4 %); our objective keeps the weighed
    12.29 kg (weight 10), and the optimum weighs 12.311 kg: 1.58 % above the paper's 12.12 kg,
    just outside a 1.5 % band around it (missed by 0.08 pp), within it around 12.29 kg.
    Tolerance 0.005 kg: the optimum's spread over the starts (all five within 1 % in Expr)."""
    _, opt = optimum
    assert opt.mass_kg == pytest.approx(12.311, abs=0.005)
    assert opt.mass_kg / OPTIMUM_MASS_KG - 1.0 == pytest.approx(0.0158, abs=0.0005)
