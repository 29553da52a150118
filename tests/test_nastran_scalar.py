"""Scalar points and scalar elements (MSC Nastran QRG: SPOINT, CELAS1-4, CMASS1-4) against closed
forms: spring-mass chains on scalar points, a grounded oscillator, an absorber on a free rigid
body (its rigid modes and mass properties), springs whose ends name one axis in two frames; bad
input in one message with file:line."""

import numpy as np
import pytest
import scipy.linalg

from bayesupdate.cli import main
from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran import load_nastran_model


def _deck(bulk: str, n_modes: int = 2) -> str:
    return f"SOL 103\nCEND\nMETHOD = 1\nBEGIN BULK\nEIGRL,1,,,{n_modes}\n{bulk}ENDDATA\n"


def _write(tmp_path, text: str, name: str = "deck.bdf"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _hz(omega2) -> np.ndarray:
    return np.sqrt(np.asarray(omega2, float)) / (2 * np.pi)


def _value(model, shapes, sid: int) -> np.ndarray:
    """A scalar point's row of mode shapes (n_dof, m) (``metadata["nastran"]["spoint_dofs"]``)."""
    node, direction = model.structure.metadata["nastran"]["spoint_dofs"][sid]
    return direction @ shapes[6 * node : 6 * node + 6]


def test_two_dof_chain_on_scalar_points(tmp_path):
    """SPOINT 1 grounded by CELAS4 k1 = 1000, joined to SPOINT 2 by CELAS3 -> PELAS k2 = 500;
    CMASS4 m1 = 2 and CMASS3 -> PMASS m2 = 1 (x WTMASS 0.5): the modes of K = [[k1 + k2, -k2],
    [-k2, k2]], M = 0.5 diag(m1, m2), shapes included; scalar points carry no rigid-body mass."""
    bulk = ("PARAM,WTMASS,0.5\nSPOINT,1,2\nCELAS4,1,1000.,1\nCELAS3,2,5,1,2\nPELAS,5,500.\n"
            "CMASS4,3,2.,1\nCMASS3,4,6,2\nPMASS,6,1.\n")  # fmt: skip
    model = load_nastran_model(_write(tmp_path, _deck(bulk)))
    r = model.solve(n_modes=2)
    K, M = np.array([[1500.0, -500.0], [-500.0, 500.0]]), 0.5 * np.diag([2.0, 1.0])
    lam, phi = scipy.linalg.eigh(K, M)
    assert r.frequencies_hz == pytest.approx(_hz(lam), rel=1e-12)
    assert r.modes.n_rigid == 0
    ratio = _value(model, r.modes.shapes, 2) / _value(model, r.modes.shapes, 1)
    assert ratio == pytest.approx(phi[1] / phi[0], rel=1e-10)
    assert r.mass_kg == 0.0 and model.mass_properties().mass == 0.0


def test_free_chain_has_one_zero_mode(tmp_path):
    """Two scalar points joined by one spring and no ground: one rigid (zero) mode, all points
    equal, and omega^2 = k (m1 + m2) / (m1 m2)."""
    bulk = "SPOINT,7,THRU,8\nCELAS4,1,300.,7,8\nCMASS4,3,2.,7\nCMASS4,4,3.,8\n"
    r = load_nastran_model(_write(tmp_path, _deck(bulk, 1))).solve(n_modes=1)
    assert r.modes.n_rigid == 1
    assert r.frequencies_hz[0] == pytest.approx(_hz(300.0 * 5.0 / 6.0), rel=1e-12)


def test_grounded_celas4_cmass4_oscillator(tmp_path):
    """One scalar point on a grounded CELAS4 with a grounded CMASS4: f = sqrt(k / m) / 2 pi."""
    bulk = "SPOINT,3\nCELAS4,1,250.,3\nCMASS4,2,4.,0,3\n"
    r = load_nastran_model(_write(tmp_path, _deck(bulk, 1))).solve(n_modes=1)
    assert r.frequencies_hz[0] == pytest.approx(_hz(250.0 / 4.0), rel=1e-12)


def _absorber(celas: str, cmass: str = "CMASS4,3,2.,5\n") -> str:
    """A stiff bar (two CONM2s, lumped bar mass) with GRID 1 in a rotated CD frame, free in
    space; a scalar point 5 with mass 2 on a spring k = 1000 from GRID 1's component 3."""
    return _deck(
        "CORD2R,7,,0.,0.,0.,0.3,0.4,0.866\n,1.,0.2,0.\nGRID,1,,0.5,0.2,0.1,7\n"
        "GRID,2,,1.5,0.2,0.1\nMAT1,1,2.e11,,0.3,7800.\nPBAR,5,1,1.e-2,1.,1.,1.\n"
        "CBAR,6,5,1,2,0.,0.,1.\nCONM2,9,1,,3.\n,1.,,1.,,,1.\nCONM2,10,2,,3.\n,1.,,1.,,,1.\n"
        f"SPOINT,5\n{celas}{cmass}",
        n_modes=1,
    )


def test_absorber_on_a_free_body_keeps_six_rigid_modes(tmp_path):
    """The scalar point follows GRID 1's CD z in every rigid motion, so the body keeps its six
    rigid modes and the absorber's mode is the two-mass closed form with the body's effective
    mass at GRID 1 along that axis, 1 / m_e = 1 / m + (r x e) . J^-1 (r x e) (r from the centre
    of gravity, J about it); mass properties: the body's alone (84 = 2 x 3 + 7800 x 0.01)."""
    model = load_nastran_model(_write(tmp_path, _absorber("CELAS2,1,1000.,1,3,5\n")))
    r = model.solve(n_modes=1)
    mp = model.mass_properties()
    assert r.modes.n_rigid == 6
    assert r.mass_kg == pytest.approx(84.0, rel=1e-12) and mp.mass == pytest.approx(84.0)
    assert mp.cg == pytest.approx([1.0, 0.2, 0.1], abs=1e-12)
    e = np.array([0.3, 0.4, 0.866]) / np.linalg.norm([0.3, 0.4, 0.866])
    c = np.cross(np.array([0.5, 0.2, 0.1]) - mp.cg, e)
    m_e = 1.0 / (1.0 / mp.mass + c @ np.linalg.solve(mp.inertia, c))
    expected = _hz(1000.0 * (m_e + 2.0) / (m_e * 2.0))
    assert r.frequencies_hz[0] == pytest.approx(expected, rel=1e-7)


def test_spring_ends_on_one_axis_in_two_frames(tmp_path):
    """CELAS2 between component 1 of GRID 1 (basic) and component 2 of GRID 2, whose CD frame
    has its y axis along basic x: one axis, so C1 != C2 is the same spring as C1 = C2 = 1 in
    basic; GRID 2 held, CMASS2 m = 4 on GRID 1's x: f = sqrt(k / m) / 2 pi."""
    bulk = ("CORD2R,8,,0.,0.,0.,0.,0.,1.\n,0.,-1.,0.\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.,8\n"
            "CELAS2,1,400.,1,1,2,2\nCMASS2,2,4.,1,1\nSPC1,1,123456,2\n"
            "SPC1,1,23456,1\n")  # fmt: skip
    deck = _deck(bulk, 1).replace("CEND\n", "CEND\nSPC = 1\n")
    r = load_nastran_model(_write(tmp_path, deck)).solve(n_modes=1)
    assert r.frequencies_hz[0] == pytest.approx(_hz(100.0), rel=1e-12)


def test_scalar_points_can_be_on_cmass1_celas1_ends(tmp_path):
    """CELAS1 (PELAS) and CMASS1 (PMASS) with a scalar point at G2 (C2 blank) and at G1 (C1 0):
    the two-mass chain GRID 1 (x, held otherwise; CONM2 1) - SPOINT 9 (mass 1, grounded
    CELAS2 200): K = [[100, -100], [-100, 300]], M = diag(1, 1)."""
    bulk = ("GRID,1,,0.,0.,0.\nCONM2,5,1,,1.\nSPOINT,9\nCELAS1,1,7,1,1,9\nPELAS,7,100.\n"
            "CELAS2,2,200.,9,0\nCMASS1,3,8,9,0\nPMASS,8,1.\nSPC1,1,23456,1\n")  # fmt: skip
    deck = _deck(bulk, 2).replace("CEND\n", "CEND\nSPC = 1\n")
    r = load_nastran_model(_write(tmp_path, deck)).solve(n_modes=2)
    lam = scipy.linalg.eigh([[100.0, -100.0], [-100.0, 300.0]], eigvals_only=True)
    assert r.frequencies_hz == pytest.approx(_hz(lam), rel=1e-12)


# -- bad input: one message, exit 2, every card's file:line ---------------------------------------
def rejected(capsys, path) -> str:
    code = main(["modes", "--model", str(path)])
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert code == 2 and len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def test_unknown_scalar_points_in_one_message(capsys, tmp_path):
    """CELAS3 on an SPOINT id that no SPOINT declares, a CELAS2 on an id that is neither GRID
    nor SPOINT and an SPOINT with a GRID's id: one message with each card's file:line (the
    CELAS2 between unlike DOFs, x of GRID 1 and z of GRID 2, is a scalar spring: accepted)."""
    bulk = ("GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nCONM2,9,1,,1.\nCONM2,10,2,,1.\nSPOINT,101\n"
            "CELAS3,2,5,101,102\nPELAS,5,10.\nCELAS2,4,5.,77,0\nSPOINT,2\n"
            "CELAS2,6,5.,1,1,2,3\nCMASS4,7,1.,101\n")  # fmt: skip
    line = rejected(capsys, _write(tmp_path, _deck(bulk), "scalar.bdf"))
    for where in ("scalar.bdf:11 CELAS3 2: S2: SPOINT 102 does not exist",
                  "scalar.bdf:13 CELAS2 4: G1: GRID or SPOINT 77 does not exist",
                  "scalar.bdf:14 SPOINT 2: SPOINT 2 is also a GRID id"):  # fmt: skip
        assert where in line, line
    assert "3 card(s) refused" in line and "CELAS2 6" not in line, line


def _x_to_ry(k=300.0, k0=500.0, kr=200.0, m=2.0, j=0.5, extra=""):
    """GRID 1 (x free) and GRID 2 (ry free, 3 in away): CELAS2 k between component 1 of GRID 1
    and component 5 of GRID 2, grounded CELAS2 k0 (1x) and kr (2ry), CMASS2 m (1x), j (2ry)."""
    bulk = (f"GRID,1,,0.,0.,0.\nGRID,2,,3.,0.,0.\nCELAS2,1,{k},1,1,2,5\nCELAS2,2,{k0},1,1\n"
            f"CELAS2,3,{kr},2,5\nCMASS2,4,{m},1,1\nCMASS2,5,{j},2,5\nSPC1,1,23456,1\n"
            f"SPC1,1,12346,2\n{extra}")  # fmt: skip
    return _deck(bulk, 2).replace("CEND\n", "CEND\nSPC = 1\n")


def test_celas2_between_unlike_dofs_is_a_scalar_spring(tmp_path):
    """CELAS2 k = 300 between x of GRID 1 and ry of GRID 2 (C1 != C2: k [[1, -1], [-1, 1]] on the
    two DOFs, QRG CELAS2; ``fe.elements.scalar_spring``): the modes of the 2-DOF closed form
    K = [[k0 + k, -k], [-k, k + kr]], M = diag(m, j), shapes included."""
    model = load_nastran_model(_write(tmp_path, _x_to_ry()))
    r = model.solve(n_modes=2)
    lam, phi = scipy.linalg.eigh([[800.0, -300.0], [-300.0, 500.0]], np.diag([2.0, 0.5]))
    assert r.frequencies_hz == pytest.approx(_hz(lam), rel=1e-12)
    shapes = r.modes.shapes
    ratio = shapes[6 * 1 + 4] / shapes[0]  # GRID 2 ry over GRID 1 x
    assert ratio == pytest.approx(phi[1] / phi[0], rel=1e-10)
    assert "scalar_spring" in [f.family for f in model.structure.elements]


def test_celas1_between_a_scalar_point_and_a_rotation(tmp_path):
    """CELAS1 (PELAS 300) between SPOINT 9 (mass 2, sprung by 500 to the held GRID 1's x, which
    places it along x) and ry of GRID 2: the closed form of
    ``test_celas2_between_unlike_dofs_is_a_scalar_spring`` (a scalar point is a DOF like any
    other)."""
    bulk = ("GRID,1,,0.,0.,0.\nGRID,2,,3.,0.,0.\nSPOINT,9\nCELAS2,1,500.,9,0,1,1\n"
            "CELAS1,6,7,9,0,2,5\nPELAS,7,300.\nCELAS2,3,200.,2,5\nCMASS4,4,2.,9\n"
            "CMASS2,5,0.5,2,5\nCONM2,8,1,,1.\nSPC1,1,123456,1\nSPC1,1,12346,2\n")  # fmt: skip
    deck = _deck(bulk, 2).replace("CEND\n", "CEND\nSPC = 1\n")
    model = load_nastran_model(_write(tmp_path, deck))
    r = model.solve(n_modes=2)
    lam = scipy.linalg.eigh([[800.0, -300.0], [-300.0, 500.0]], np.diag([2.0, 0.5]),
                            eigvals_only=True)  # fmt: skip
    assert r.frequencies_hz == pytest.approx(_hz(lam), rel=1e-12)
    assert "scalar_spring" in [f.family for f in model.structure.elements]


def test_celas2_between_two_dofs_of_one_grid(tmp_path):
    """CELAS2 k = 300 between x and ry of the same GRID (two distinct connection points, QRG
    CELAS2 remark): the closed form of ``test_celas2_between_unlike_dofs_is_a_scalar_spring``
    with both DOFs on one node."""
    bulk = ("GRID,1,,0.,0.,0.\nCELAS2,1,300.,1,1,1,5\nCELAS2,2,500.,1,1\nCELAS2,3,200.,1,5\n"
            "CMASS2,4,2.,1,1\nCMASS2,5,0.5,1,5\nSPC1,1,2346,1\n")  # fmt: skip
    deck = _deck(bulk, 2).replace("CEND\n", "CEND\nSPC = 1\n")
    r = load_nastran_model(_write(tmp_path, deck)).solve(n_modes=2)
    lam = scipy.linalg.eigh([[800.0, -300.0], [-300.0, 500.0]], np.diag([2.0, 0.5]),
                            eigvals_only=True)  # fmt: skip
    assert r.frequencies_hz == pytest.approx(_hz(lam), rel=1e-12)


def test_a_binding_on_a_scalar_spring_is_refused(tmp_path):
    """``binds = "CELAS2 1 K"`` on the spring between unlike DOFs: one message naming it."""
    path = _write(tmp_path, _x_to_ry())
    with pytest.raises(BayesUpdateError, match=r"CELAS2 1 join\(s\) unlike DOFs"):
        load_nastran_model(path, parameters={"k": {"binds": "CELAS2 1 K"}})


def test_a_scalar_point_apart_from_the_structure_is_named(capsys, tmp_path):
    """A scalar-point oscillator beside a grid structure: the disconnected-structure message
    names it as SPOINT, not as a node index."""
    bulk = ("GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nMAT1,1,2.e11,,0.3,7800.\n"
            "PBAR,5,1,1.e-2,1.e-5,1.e-5,1.e-5\nCBAR,6,5,1,2,0.,0.,1.\nSPOINT,40\n"
            "CELAS4,1,250.,40\nCMASS4,2,4.,40\n")  # fmt: skip
    line = rejected(capsys, _write(tmp_path, _deck(bulk), "apart.bdf"))
    assert "SPOINT 40" in line and "disconnected" in line, line


def test_bindings_on_scalar_springs(tmp_path):
    """``binds = "CELAS4 1 K"`` and ``"PELAS 5 K"`` (the CELAS3 of that property) on the chain
    of ``test_two_dof_chain_on_scalar_points``: the modes at k1 = 1800, k2 = 300 are those of
    the closed form at those values."""
    bulk = ("SPOINT,1,2\nCELAS4,1,1000.,1\nCELAS3,2,5,1,2\nPELAS,5,500.\nCMASS4,3,2.,1\n"
            "CMASS3,4,6,2\nPMASS,6,1.\n")  # fmt: skip
    params = {"k1": {"binds": "CELAS4 1 K"}, "k2": {"binds": "PELAS 5 K"}}
    model = load_nastran_model(_write(tmp_path, _deck(bulk)), parameters=params)
    f = model.solve({"k1": 1800.0, "k2": 300.0}, n_modes=2).frequencies_hz
    lam = scipy.linalg.eigh([[2100.0, -300.0], [-300.0, 300.0]], np.diag([2.0, 1.0]),
                            eigvals_only=True)  # fmt: skip
    assert f == pytest.approx(_hz(lam), rel=1e-12)


def test_spc_on_a_scalar_point(tmp_path):
    """SPC1 (component 0) holds SPOINT 1 of the chain of ``test_two_dof_chain_on_scalar_points``:
    SPOINT 2 alone on k2 = 500, m2 = 1."""
    bulk = ("SPOINT,1,2\nCELAS4,1,1000.,1\nCELAS3,2,5,1,2\nPELAS,5,500.\nCMASS4,3,2.,1\n"
            "CMASS3,4,6,2\nPMASS,6,1.\nSPC1,1,0,1\n")  # fmt: skip
    deck = _deck(bulk, 1).replace("CEND\n", "CEND\nSPC = 1\n")
    r = load_nastran_model(_write(tmp_path, deck)).solve(n_modes=1)
    assert r.frequencies_hz[0] == pytest.approx(_hz(500.0), rel=1e-12)


def test_cmass2_between_unlike_dofs(tmp_path):
    """CMASS2 m = 1 between x of GRID 1 and y of GRID 2 (C1 != C2: [[m, -m], [-m, m]] on the two
    DOFs, QRG CMASS2), grounded CMASS2 2 and 3 on them, grounded springs 400 and 900, the other
    DOFs held: the modes of K = diag(400, 900), M = [[3, -1], [-1, 4]]."""
    bulk = ("GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nCMASS2,1,1.,1,1,2,2\nCMASS2,2,2.,1,1\n"
            "CMASS2,3,3.,2,2\nCELAS2,4,400.,1,1\nCELAS2,5,900.,2,2\nSPC1,1,23456,1\n"
            "SPC1,1,13456,2\n")  # fmt: skip
    deck = _deck(bulk, 2).replace("CEND\n", "CEND\nSPC = 1\n")
    r = load_nastran_model(_write(tmp_path, deck)).solve(n_modes=2)
    lam = scipy.linalg.eigh(np.diag([400.0, 900.0]), [[3.0, -1.0], [-1.0, 4.0]],
                            eigvals_only=True)  # fmt: skip
    assert r.frequencies_hz == pytest.approx(_hz(lam), rel=1e-12)
