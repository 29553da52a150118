"""Shell mass as Nastran forms it: lumped at the GRIDs, translational only, by default (PARAM
COUPMASS -1); consistent, with the rotary inertia rho t^3 / 12, with PARAM COUPMASS 1.

A typical section: a rigid plate (1 m chord x 10 m span, 3 x 28 CQUAD4, 10 mm aluminium) tied
by an RBE2 to a reference GRID a quarter chord aft of its leading edge, free in plunge and
pitch on two springs (as pyNastran's ``models/aero/2_mode_flutter`` deck, whose MSC Nastran
f06 gives 2.66709 and 10.6282 Hz, which this package reproduces to 4e-6 with the lumped mass and
misses by +10.4 % on pitch with the consistent one).  Its two modes are closed forms of the
plate's mass, static moment and pitch inertia about the reference: with lumped mass the
GRIDs' trapezoid-rule masses (1/6, 1/3, 1/3, 1/6 of the chord's), with consistent mass the
exact integrals plus the rotary inertia.  On this chord of 3 elements the lumped pitch inertia
about the reference is 12.7 % above the exact one, so the two are told apart.

And a simply supported plate (a/t = 10, ``studies/pshell_ratios.py``'s) with the default mass
converges at second order to Mindlin's plate without rotary inertia: 32 x 32 quads within
0.36 % on modes 1-8 (16 x 16: 1.4 %), the Richardson extrapolation within 0.01 % (measured);
asserted 0.5 % and 0.03 %, and away from the plate with rotary inertia by more than 0.5 % on
modes 4-8.
"""

import json
import sys
from pathlib import Path

import numpy as np
import scipy.linalg as sl

from bayesupdate.cli import main

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
from pshell_ratios import MODES_1_TO_8, STEEL, plate_deck  # noqa: E402

CHORD, SPAN, NX, NY, T, RHO = 1.0, 10.0, 3, 28, 0.01, 2700.0
X0, K3, K5 = 0.25, 1.0e5, 1.0e5


def _section(path, coupled: bool):
    """The typical section's deck (SI)."""
    x, y = np.linspace(0, CHORD, NX + 1), np.linspace(0, SPAN, NY + 1)
    grid = np.array([(xi, yj) for yj in y for xi in x])
    lines = ["SOL 103", "CEND", "SPC = 1", "METHOD = 1", "BEGIN BULK", "EIGRL,1,,,2"]
    lines += ["PARAM,COUPMASS,1"] if coupled else []
    lines += [f"GRID,{i + 1},,{float(p[0])!r},{float(p[1])!r},0." for i, p in enumerate(grid)]
    ref = len(grid) + 1
    lines += [f"GRID,{ref},,{X0!r},{SPAN / 2!r},0."]
    for j in range(NY):
        for i in range(NX):
            a = j * (NX + 1) + i + 1
            lines.append(f"CQUAD4,{j * NX + i + 1},1,{a},{a + 1},{a + NX + 2},{a + NX + 1}")
    lines += [f"PSHELL,1,1,{T!r},1", f"MAT1,1,7.0E+10,,0.33,{RHO!r}"]
    legs = [str(i + 1) for i in range(len(grid))]
    rows = [legs[:5]] + [legs[k : k + 8] for k in range(5, len(legs), 8)]  # 8 fields a line
    lines += [f"RBE2,9001,{ref},123456," + ",".join(rows[0])] + [
        ",".join(["", *r]) for r in rows[1:]
    ]
    lines += [f"SPC1,1,1246,{ref}", f"CELAS2,9002,{K3!r},{ref},3", f"CELAS2,9003,{K5!r},{ref},5"]
    path.write_text("\n".join([*lines, "ENDDATA", ""]))
    return path


def _section_hz(m, s, inertia) -> np.ndarray:
    """The plunge-pitch modes [Hz] with mass m, static moment s and pitch inertia about the
    reference: K = diag(K3, K5), M = [[m, -s], [-s, I]] (a pitch ry lifts a point at x by
    -(x - x0) ry)."""
    lam = sl.eigh(np.diag([K3, K5]), np.array([[m, -s], [-s, inertia]]), eigvals_only=True)
    return np.sqrt(lam) / (2 * np.pi)


def _modes(path, capsys, n: int = 2) -> np.ndarray:
    assert main(["modes", "--model", str(path), "--modes", str(n), "--json"]) == 0
    return np.array(json.loads(capsys.readouterr().out)["frequencies_hz"])


def test_lumped_by_default_and_consistent_with_coupmass_1(tmp_path, capsys):
    mass = RHO * T * CHORD * SPAN
    h = CHORD / NX
    x = np.linspace(0, CHORD, NX + 1)
    w = np.full(NX + 1, h)
    w[[0, -1]] = h / 2  # the trapezoid rule of the lumped GRID masses along the chord
    lumped = mass / CHORD * np.array([w @ (x - X0), w @ (x - X0) ** 2])
    exact = mass / CHORD * np.array([(CHORD / 2 - X0) * CHORD,
                                     ((CHORD - X0) ** 3 + X0**3) / 3])  # fmt: skip
    rotary = RHO * T**3 / 12 * CHORD * SPAN  # each GRID's ry turns with the pitch
    f_lumped = _modes(_section(tmp_path / "lumped.bdf", coupled=False), capsys)
    # to the last of the six decimals --json prints
    np.testing.assert_allclose(f_lumped, _section_hz(mass, *lumped), rtol=0, atol=5e-7)
    f_coupled = _modes(_section(tmp_path / "coupled.bdf", coupled=True), capsys)
    coupled_hz = _section_hz(mass, exact[0], exact[1] + rotary)
    np.testing.assert_allclose(f_coupled, coupled_hz, rtol=0, atol=5e-7)
    assert lumped[1] / exact[1] > 1.12  # 3 elements on the chord: 12.7 % more pitch inertia
    assert f_coupled[1] / f_lumped[1] > 1.05


def test_lumped_plate_converges_to_mindlin_without_rotary_inertia(tmp_path, capsys):
    t = 0.1
    pshell = f"PSHELL,1,1,{t},1,,1"
    coarse, fine = (_modes(plate_deck(tmp_path / f"p{n}.bdf", n, t, pshell, coupled=False),
                           capsys, 8) for n in (16, 32))  # fmt: skip
    ref = np.array([STEEL.mindlin_hz(t, m, n, rotary=False) for m, n in MODES_1_TO_8])
    np.testing.assert_allclose(fine, ref, rtol=5e-3)
    extrapolated = fine + (fine - coarse) / 3
    np.testing.assert_allclose(extrapolated, ref, rtol=3e-4)
    with_rotary = np.array([STEEL.mindlin_hz(t, m, n) for m, n in MODES_1_TO_8])
    assert np.all(np.abs(extrapolated[3:] / with_rotary[3:] - 1) > 5e-3)
