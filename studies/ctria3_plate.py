"""The shell triangle on the simply supported square plate: errors per mode and cost per element.

Plate: steel (E 200 GPa, nu 0.3, rho 8000 kg/m^3), a = 10 m, hard simple support (w and the
tangential rotation held on the edges, u, v, rz held everywhere), 32 x 32 cells, each cut into
two triangles along the same diagonal (as a mesher writes a CTRIA3 deck), beside 32 x 32 quads
(MITC4).  Modes 1-8 against the closed forms: Kirchhoff (Leissa, *Vibration of Plates*, 1969,
eq. 4.3) for a/t = 100 and 1000, the Mindlin plate with rotary inertia (Mindlin 1951) for
a/t = 10, 20, 50; consistent mass, and lumped (row-sum, Nastran's COUPMASS default) at a/t = 100.
Cost: the median wall time of the thickness-free element pieces (``shell.PieceSource.pieces``,
what an assembly computes per element) over 20,000 elements of each kind, per element.

Run: PYTHONPATH=. .venv/bin/python studies/ctria3_plate.py
     (the same script on an older checkout prints that version's numbers: the "before" of
     docs/validation/fe.md, section Triangles)
"""

import time

import numpy as np

from bayesupdate.fe import shell_mesh as sm
from bayesupdate.fe.elements import shell
from bayesupdate.fe.shell_model import ShellAssembly, shell_mesh
from bayesupdate.fe.sparse_modal import ModalSettings, solve_sparse_modes

E, NU, RHO, A, CELLS = 200e9, 0.3, 8000.0, 10.0, 32
MODES = [(1, 1), (1, 2), (2, 1), (2, 2), (1, 3), (3, 1), (2, 3), (3, 2)]


def kirchhoff_hz(t, m, n):
    """Leissa (1969) eq. 4.3: f = (pi / 2) (m^2 + n^2) / a^2 sqrt(D / (rho t))."""
    D = E * t**3 / (12 * (1 - NU**2))
    return np.pi / 2 * (m * m + n * n) / A**2 * np.sqrt(D / (RHO * t))


def mindlin_hz(t, m, n, kappa=5.0 / 6.0):
    """Flexural root of (s k^2 - rho t w^2)(D k^2 + s - I w^2) = s^2 k^2 (Mindlin 1951),
    s = kappa G t, I = rho t^3 / 12."""
    G, D = E / (2 * (1 + NU)), E * t**3 / (12 * (1 - NU**2))
    k2 = (np.pi / A) ** 2 * (m * m + n * n)
    s, inertia = kappa * G * t, RHO * t**3 / 12
    a2, b = RHO * t * inertia, -(RHO * t * (D * k2 + s) + inertia * s * k2)
    c = s * k2 * (D * k2 + s) - s**2 * k2
    return np.sqrt((-b - np.sqrt(b * b - 4 * a2 * c)) / (2 * a2)) / (2 * np.pi)


def plate_hz(t, kind, lumped=False):
    """First 8 frequencies [Hz] of the supported plate meshed in ``kind`` ("tria" or "quad")."""
    nodes, quads, _ = sm.plate(A, A, CELLS, CELLS)
    if kind == "tria":
        trias = sm.split_quads(quads, np.zeros(len(quads), bool))
        mesh = shell_mesh(nodes, None, trias, thickness=t, E=E, nu=NU, rho=RHO)
    else:
        mesh = shell_mesh(nodes, quads, None, thickness=t, E=E, nu=NU, rho=RHO)
    x, y = nodes[:, 0], nodes[:, 1]
    ex = np.flatnonzero((x < 1e-9) | (x > A - 1e-9))
    ey = np.flatnonzero((y < 1e-9) | (y > A - 1e-9))
    fixed = [6 * ex[:, None] + [2, 3], 6 * ey[:, None] + [2, 4]]
    fixed.append(6 * np.arange(len(nodes))[:, None] + [0, 1, 5])
    fixed = np.concatenate([f.ravel() for f in fixed])
    K, M = ShellAssembly(mesh, lumped=lumped).assemble()
    return solve_sparse_modes(K, M, nodes, ModalSettings(n_modes=8), fixed).frequencies_hz


def error_rows():
    """(label, errors [%] per mode) of every case."""
    rows = []
    for slender, lumped in ((100, False), (100, True), (1000, False)):
        t = A / slender
        ref = np.array([kirchhoff_hz(t, m, n) for m, n in MODES])
        for kind in ("tria", "quad"):
            f = plate_hz(t, kind, lumped)
            mass = "lumped" if lumped else "consistent"
            rows.append((f"{kind} a/t={slender} {mass} vs Kirchhoff", 100 * (f / ref - 1)))
    for slender in (10, 20, 50):
        t = A / slender
        ref = np.array([mindlin_hz(t, m, n) for m, n in MODES])
        for kind in ("tria", "quad"):
            f = plate_hz(t, kind)
            rows.append((f"{kind} a/t={slender} consistent vs Mindlin", 100 * (f / ref - 1)))
    return rows


def cost_per_element_us(kind, n=20_000, repeats=5):
    """Median wall time [us] per element of ``PieceSource.pieces`` on n random elements."""
    rng = np.random.default_rng(0)
    k = 3 if kind == "tria" else 4
    base = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)[:k] if k == 4 else None
    base = np.array([[0, 0], [1, 0], [0.3, 0.9]]) if k == 3 else base
    xy = 0.01 * (base[None] + 0.1 * rng.standard_normal((n, k, 2)))
    xy -= xy.mean(axis=1, keepdims=True)
    source = shell.PieceSource(xy, None, np.full(n, E), np.full(n, NU))
    rows = np.arange(n)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for lo in range(0, n, shell.CHUNK):
            source.pieces(rows[lo : lo + shell.CHUNK])
        times.append(time.perf_counter() - t0)
    return 1e6 * float(np.median(times)) / n


def main():
    print(f"simply supported square plate, {CELLS} x {CELLS} cells (tria: 2 per cell, one "
          "diagonal); error [%] of modes 1-8")  # fmt: skip
    for label, err in error_rows():
        print(
            f"{label:42s}", " ".join(f"{e:+6.2f}" for e in err), f"| worst {np.abs(err).max():.2f}"
        )
    for kind in ("tria", "quad"):
        print(f"cost per element ({kind}, element pieces): {cost_per_element_us(kind):.1f} us")


if __name__ == "__main__":
    main()
