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
from bayesupdate.paper import (  # noqa: E402
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
    """"best" is the default set's best fit; each set is reachable by name and by "NAME:k"."""
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
