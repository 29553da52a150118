"""PSHELL with MID1 or MID2 blank (MSC Nastran QRG PSHELL, remarks 2-3), and AUTOSPC per node.

A blank MID leaves its part of the shell out: MID2 blank, a membrane (no bending, no
transverse shear); MID1 blank, a bending panel (no membrane, so no drilling stiffness either),
whose mass is MID2's RHO.  The DOFs left with no stiffness are held as Nastran's AUTOSPC holds
them (``fe.autospc``).  Checked on a cantilever strip (1 m x 0.1 m, 10 mm steel, CQUAD4, its
x = 0 edge clamped, in the XY plane):

* the membrane's modes equal, to round-off, those of the full shell with w, rx and ry held
  by SPC at every GRID (a flat shell's membrane and bending do not couple), and MYSTRAN's on
  the same decks converge to one limit: on modes 1-8 the largest difference is 0.31 % at
  40 x 4 quads, 0.08 % at 80 x 8 and 0.02 % at 160 x 16 with the deck's default lumped mass
  (2.1, 0.52 and 0.13 % with consistent mass; second order; asserted: under 0.1 % at 80 x 8
  and shrinking by more than 3.5 from 40 x 4); its first axial mode is the rod's c / 4L within
  0.2 % (measured +0.13 % at 40 x 4: the strip's width and Poisson);
* the bending panel's modes equal those of the full shell with u, v and rz held by SPC, with
  E, NU and RHO taken from MID2; both equalities hold in CTRIA3 too;
* a PSHELL T binding on either gives the deck written with that T (a membrane's modes do not
  move with t, its mass does; a panel's modes rise by about the ratio of t);
* the same membrane turned off the axes (normal (0, -0.48, 0.88)) is refused, naming its
  GRIDs (its normal motion has mass and no stiffness off their axes); with each GRID's CD a
  CORD2R along the strip, its modes are the flat strip's; on rods along its normal (its
  translations stiff, its rotations free off the axes with no mass) it is held through chosen
  components, and its modes are the flat strip's on the same rods.

PSHELL T blank: the shells' corner thicknesses are theirs (a blank corner, TFLAG 1 and a T
binding refused); a MAT1 E binding reaches a bending panel through its MID2.

``singular_dofs`` is also checked on a pencil built with a null space off the axes: holding
the chosen components leaves the pencil's eigenvalues as they are when the null space itself
is removed.
"""

import json
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sl
import scipy.sparse as sp

from bayesupdate.cli import main
from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.autospc import singular_dofs
from bayesupdate.nastran import load_nastran_model

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
from pshell_blank_mids import RHO, STRIP_LENGTH, STRIP_T, E, Strip, strip_deck, turn  # noqa: E402
from pshell_ratios import mystran_hz  # noqa: E402

T = STRIP_T
#: the strip's rotation off the axes (its normal becomes (0, -0.48, 0.88))
TURN = turn(0.5)


def _strip(path, pshell, **options):
    """``strip_deck`` with the ``Strip`` options given by name."""
    return strip_deck(path, pshell, Strip(**options))


def _modes(path, capsys) -> np.ndarray:
    assert main(["modes", "--model", str(path), "--modes", "8", "--json"]) == 0
    return np.array(json.loads(capsys.readouterr().out)["frequencies_hz"])


def _as_the_full_shell_held(tmp_path, capsys, partial, full, held) -> np.ndarray:
    """The strip's modes with the PSHELL line ``partial``, checked equal (quads, then trias)
    to those with ``full`` and ``held`` components SPC'd at every GRID; the quads' modes."""
    modes = []
    for trias in (False, True):
        name = "t" if trias else "q"
        part = _modes(_strip(tmp_path / f"{name}p.bdf", partial, trias=trias), capsys)
        whole = _modes(_strip(tmp_path / f"{name}f.bdf", full, held=held, trias=trias), capsys)
        np.testing.assert_allclose(part, whole, rtol=1e-9)
        modes.append(part)
    return modes[0]


def test_membrane_is_the_full_shell_held_out_of_plane_and_mystrans(tmp_path, capsys):
    membrane = _as_the_full_shell_held(tmp_path, capsys, f"PSHELL,1,1,{T}",
                                       f"PSHELL,1,1,{T},1", "345")  # fmt: skip
    # MYSTRAN's QUAD4 on the same decks: the two elements converge to one limit (O(h^2))
    gaps = []
    for nx in (40, 80):
        deck = _strip(tmp_path / f"m{nx}.bdf", f"PSHELL,1,1,{T}", nx=nx, ny=nx // 10)
        gaps.append(np.max(np.abs(_modes(deck, capsys) / mystran_hz(deck) - 1)))
    assert gaps[1] < 1e-3 and gaps[0] / gaps[1] > 3.5, gaps
    rod = np.sqrt(E / RHO) / (4 * STRIP_LENGTH)  # the first axial mode of a clamped-free rod
    axial = membrane[np.argmin(np.abs(membrane - rod))]
    assert abs(axial / rod - 1) < 2e-3


def test_bending_panel_is_the_full_shell_held_in_plane_with_mid2s_material(tmp_path, capsys):
    panel = _as_the_full_shell_held(tmp_path, capsys, f"PSHELL,1,,{T},2,,2",
                                    f"PSHELL,1,2,{T},2,,2", "126")  # fmt: skip
    steel = _modes(_strip(tmp_path / "s.bdf", f"PSHELL,1,1,{T},1,,1", held="126"), capsys)
    assert np.all(np.abs(panel / steel - 1) > 0.05)  # MID1's material would be far off


@pytest.mark.parametrize("pshell", [f"PSHELL,1,1,{T}", f"PSHELL,1,,{T},2,,2"])
def test_bound_thickness_of_a_membrane_or_panel_is_the_deck_written_with_it(tmp_path, pshell):
    """A PSHELL T binding enters as exact powers of t: a membrane's K and M both go as t (its
    modes stay, its mass does not), a panel's K as t^3 (its modes rise by about t'/t)."""
    base = _strip(tmp_path / "base.bdf", pshell)
    moved = _strip(tmp_path / "moved.bdf", pshell.replace(f",{T}", ",0.013"))
    bound = load_nastran_model(str(base), {"t": {"binds": "PSHELL 1 T", "bounds": [5e-3, 0.02]}})
    at, deck = (
        bound.predict({"t": 0.013}, n_modes=8),
        load_nastran_model(str(moved)).predict(n_modes=8),
    )
    np.testing.assert_allclose(at.frequencies_hz, deck.frequencies_hz, rtol=1e-12)
    start = bound.predict(n_modes=8)
    assert at.mass_kg / start.mass_kg == pytest.approx(1.3, rel=1e-12)
    rise = at.frequencies_hz / start.frequencies_hz
    if ",," in pshell:  # the panel
        assert np.all((rise > 1.25) & (rise < 1.3 + 1e-9)), rise
    else:
        np.testing.assert_allclose(rise, 1.0, rtol=1e-9)


def test_membrane_off_the_axes_is_refused_or_held_in_its_cd_frame(tmp_path, capsys):
    flat = _modes(_strip(tmp_path / "m.bdf", f"PSHELL,1,1,{T}"), capsys)
    turned = _strip(tmp_path / "t.bdf", f"PSHELL,1,1,{T}", turn=TURN)
    assert main(["modes", "--model", str(turned), "--modes", "8", "--json"]) == 2
    err = capsys.readouterr().err
    assert "200 GRID(s) have a direction with mass but no stiffness" in err
    assert "GRID 6, GRID 7" in err and "CD frame" in err
    in_cd = _strip(tmp_path / "c.bdf", f"PSHELL,1,1,{T}", turn=TURN, cd=True)
    np.testing.assert_allclose(_modes(in_cd, capsys), flat, rtol=1e-6)


def test_membrane_off_the_axes_on_rods_holds_its_rotations_exactly(tmp_path, capsys):
    """Rods along the normal stiffen the turned membrane's translations; its rotations keep a
    null space off the axes with no mass (only the drilling is stiff), held through chosen
    components: the modes are the flat strip's on the same rods."""
    pshell = f"PSHELL,1,1,{T}"
    flat = _modes(_strip(tmp_path / "f.bdf", pshell, rods=True), capsys)
    deck = _strip(tmp_path / "t.bdf", pshell, turn=TURN, rods=True)
    assert main(["modes", "--model", str(deck), "--modes", "8", "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    notes = " ".join(result["notes"])
    assert "200 GRID(s) have rotations with no stiffness and no mass off their axes" in notes
    np.testing.assert_allclose(result["frequencies_hz"], flat, rtol=1e-6)


def test_blank_mid_cards_refused_together_with_their_lines(tmp_path, capsys):
    deck = _strip(tmp_path / "bad.bdf", f"PSHELL,1,1,{T},-1")
    text = deck.read_text()
    text = text.replace("CQUAD4,1,1,", "CQUAD4,1,2,").replace("CQUAD4,2,1,", "CQUAD4,2,3,")
    text = text.replace("CQUAD4,3,1,3,8,9,4", "CQUAD4,3,4,3,8,9,4,,0.001")
    extra = [f"PSHELL,2,,{T}", f"PSHELL,3,1,{T},,,1", f"PSHELL,4,1,{T}"]
    deck.write_text(text.replace("ENDDATA", "\n".join([*extra, "ENDDATA"])))
    assert main(["modes", "--model", str(deck), "--modes", "8", "--json"]) == 2
    err = capsys.readouterr().err
    lines = deck.read_text().splitlines()
    for card, why in ((f"PSHELL,1,1,{T},-1", "plane strain"),
                      (extra[0], "MID1 and MID2 are both blank"),
                      (extra[1], "MID3 must be blank when MID2 is blank"),
                      ("CQUAD4,3,4,3,8,9,4,,0.001", "ZOFFS needs both MID1 and MID2")):  # fmt: skip
        assert f"bad.bdf:{lines.index(card) + 1}" in err and why in err, (card, err)


def test_singular_dofs_off_the_axes_held_exactly_when_massless():
    rng = np.random.default_rng(147)
    n = 12
    null = np.zeros((n, 2))  # node 0's rotations (DOFs 3-5): a 2-D null space off the axes
    null[3:6] = np.linalg.qr(rng.normal(size=(3, 2)))[0]
    P = np.eye(n) - null @ null.T
    A, B = rng.normal(size=(n, n)), rng.normal(size=(n, n))
    K, M = P @ (A @ A.T) @ P, P @ (B @ B.T + n * np.eye(n)) @ P
    found = singular_dofs(sp.csr_matrix(K), sp.csr_matrix(M), np.arange(n))
    assert found.held.size == 2 and set(found.held) <= {3, 4, 5}
    assert found.off_axis.tolist() == [0] and found.loose.size == 0
    free = np.setdiff1d(np.arange(n), found.held)
    held = sl.eigh(K[np.ix_(free, free)], M[np.ix_(free, free)], eigvals_only=True)
    basis = sl.null_space(null.T)  # the null space itself removed
    exact = sl.eigh(basis.T @ K @ basis, basis.T @ M @ basis, eigvals_only=True)
    np.testing.assert_allclose(held, exact, rtol=1e-9)
    # with mass on that null space, components cannot hold it without changing the answer
    massive = M + null @ null.T
    found = singular_dofs(sp.csr_matrix(K), sp.csr_matrix(massive), np.arange(n))
    assert found.held.size == 0 and found.loose.tolist() == [0]


def test_pshell_t_blank_takes_the_corner_thicknesses(tmp_path, capsys):
    """PSHELL T blank: the shells give T1-T4 (QRG PSHELL); a blank corner, or TFLAG 1 (which
    scales T), is refused with its line, and a T binding is refused by name."""
    given = _modes(_strip(tmp_path / "t.bdf", f"PSHELL,1,1,{T},1"), capsys)
    every = {e: f",,,{T},{T},{T},{T}" for e in range(1, 161)}
    deck = _strip(tmp_path / "c.bdf", "PSHELL,1,1,,1", corners=every)
    np.testing.assert_array_equal(_modes(deck, capsys), given)
    with pytest.raises(BayesUpdateError, match=r"PSHELL 1 has T blank .* T cannot be bound"):
        load_nastran_model(str(deck), {"t": {"binds": "PSHELL 1 T", "bounds": [5e-3, 0.02]}})
    bad = _strip(tmp_path / "c.bdf", "PSHELL,1,1,,1",
                 corners=every | {7: f",,,{T}", 9: f",,1,{T},{T},{T},{T}"})  # fmt: skip
    assert main(["modes", "--model", str(bad), "--modes", "8", "--json"]) == 2
    err = capsys.readouterr().err
    lines = bad.read_text().splitlines()
    for e, why in ((7, "a corner thickness (T1-T4) is blank"), (9, "TFLAG 1 scales T")):
        line = next(i for i, text in enumerate(lines) if text.startswith(f"CQUAD4,{e},"))
        assert f"c.bdf:{line + 1} CQUAD4 {e}: {why}, and PSHELL 1 has no T" in err, err


def test_a_modulus_binding_reaches_a_bending_panel_through_mid2(tmp_path, capsys):
    """MAT1 E of a panel's MID2 (MID1 blank) scales its stiffness: E x 2, modes x sqrt 2."""
    deck = _strip(tmp_path / "b.bdf", f"PSHELL,1,,{T},2,,2")
    bound = load_nastran_model(str(deck), {"E": {"binds": "MAT1 2 E", "bounds": [1e11, 1e12]}})
    start, twice = (bound.predict({"E": e}, n_modes=8).frequencies_hz for e in (3e11, 6e11))
    np.testing.assert_allclose(twice / start, np.sqrt(2.0), rtol=1e-9)
