"""MSC's own modes of a glider of tapered PBEAML tubes and PBEAML boxes (pyNastran's
``aero/fmondsp``, MSC.Nastran 2005; the deck as published in ``tests/data/msc_fmondsp.dat``,
BSD-3-Clause; its f06's eigenvalues, weight and PBEAM replacements in ``msc_fmondsp.json``).

Read as a user reads it (``bayesupdate modes --model``): its DMIG, selected only by K2PP (an
extra point's dynamic stiffness), is ignored with a note; each PBEAML is the PBEAM of its
stations' sections, as MSC replaces it (a tapered one linear between its ends, its lumped mass
split by the first moments of the linear mass), with MSC's shear factors (TUBE 0.5, BOX the
walls' area along each direction over A).  Before: the deck was refused (DMIG); with the mean
of the exact section and Cowper's shear factors its modes were up to 3.7 % low and its
weight's CG 5e-4 m off.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.cli import main
from bayesupdate.nastran import load_nastran_model

DATA = Path(__file__).parent / "data"
DECK = DATA / "msc_fmondsp.dat"
MSC = json.loads((DATA / "msc_fmondsp.json").read_text())


@pytest.fixture(scope="module")
def modes():
    """``bayesupdate modes --model msc_fmondsp.dat --modes 12 --json``'s object."""
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        code = main(["modes", "--model", str(DECK), "--modes", "12", "--json"])
    assert code == 0
    return json.loads(out.getvalue())


def test_the_twelve_elastic_modes_are_mscs(modes):
    """All 12 elastic modes below 60 Hz within 1e-5 of MSC's (measured 6.0e-6, mode 12), after
    6 rigid ones (SUPORT)."""
    assert modes["rigid_modes"] == MSC["rigid_modes"]
    ours, msc = np.array(modes["frequencies_hz"]), np.array(MSC["elastic_hz"])
    assert np.max(np.abs(ours / msc - 1)) < 1e-5, ours / msc - 1
    assert any("DMIG STIFF ignored: no K2GG or M2GG selects it" in n for n in modes["notes"])


def test_the_weight_is_mscs(modes):
    """Mass, CG and inertia about the CG as MSC's grid point weight generator prints them
    (7 digits: within 1e-6 of their size)."""
    assert modes["mass"] == pytest.approx(MSC["mass"], rel=1e-6)
    assert modes["cg"] == pytest.approx(MSC["cg"], abs=1e-6)
    i = modes["inertia"]
    ours = [[i["ixx"], i["ixy"], i["ixz"]], [i["ixy"], i["iyy"], i["iyz"]],
            [i["ixz"], i["iyz"], i["izz"]]]  # fmt: skip
    assert np.allclose(ours, MSC["inertia_s"], rtol=0, atol=1e-6 * 3534.565)


@pytest.mark.parametrize("pid", ["1", "5"])
def test_a_pbeaml_is_the_pbeam_msc_prints_for_it(pid):
    """The section of PBEAML 1 (a TUBE, tapered: its end A) and PBEAML 5 (a BOX) against the
    PBEAM that MSC's f06 prints in its place: A, I1, I2, J and the shear factors K1, K2 to the
    printed five digits."""
    structure = load_nastran_model(DECK).structure
    g = structure.general_beams
    k = int(np.flatnonzero(np.array(structure.parts)[g.part] == f"PBEAML {pid}")[0])
    end_a = g.taper[k, 0] * np.array([g.area[k], g.iy[k], g.iz[k], g.torsion[k]])
    ours = {"A": end_a[0], "I1": end_a[2], "I2": end_a[1], "J": end_a[3],
            "K1": g.shear_y[k], "K2": g.shear_z[k]}  # fmt: skip
    printed = {key: value for key, value in MSC["pbeam_from_pbeaml"][pid].items() if key != "type"}
    for key, value in printed.items():
        assert ours[key] == pytest.approx(value, rel=5e-5), key
