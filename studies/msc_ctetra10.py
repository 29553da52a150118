"""What MSC Nastran's ten-node CTETRA is: its stiffness rule found, its default mass not.

Data nobody here made: pyNastran's ``models/complex/tet10`` (BSD-3-Clause, read only): two ten-node
CTETRAs (one edge curved: GRID 2534 is 0.008 in off its edge's midpoint), MAT1 E 1.705e7, NU
0.31, RHO 4.14413e-4, four GRIDs held, SOL 111 by MSC.NASTRAN 2005 with the f06 it printed:
the ten real eigenvalues before residual-vector augmentation and the response at 0 Hz to a
unit x force at GRID 2154.  With residual vectors, a modal response at 0 Hz is the static
solution K^-1 F, whatever the mass: it tests the stiffness alone.

The element here is the isoparametric ten-node tetrahedron (Zienkiewicz, Taylor & Zhu, 7th ed.,
sec. 6.5: corner N = L (2L - 1), edge N = 4 L_i L_j, Nastran's G5-G10 on edges 1-2, 2-3, 3-1,
1-4, 2-4, 3-4) integrated by one of three rules: Keast's 4-point (degree 2), Hammer's 5-point
(degree 3, a negative centroid weight) and Keast's 11-point (degree 4); its masses: the
consistent one (11 points), HRZ diagonal scaling of it, its row sums, nodal quadrature over the
element's eight sub-tetrahedra (corners 1/32, edges 7/48 of the mass), the corners only, the
edges only.

Measured (2026-11-30): the static response with the 5-point rule is MSC's to 9.3e-8 of the
largest displacement (the f06 prints seven digits), with the 4-point rule 1.4e-2, with the
11-point rule 9.0e-3: MSC's CTETRA10 stiffness is Hammer's 5-point rule.  No mass tried gives
MSC's eigenvalues (5-point stiffness; eigenvalues 1-10 against MSC's): consistent +20 to +97 %,
HRZ -14 to -42 %, row sums -12 to +44 %, sub-tetrahedra -15 to -42 %, corners only -59 to
-86 %, edges only -22 to +4 %; nor (scanned by hand, not in this script) any mixture of the
consistent and HRZ masses or any corner/edge split of a diagonal one.  So the package refuses a
ten-node CTETRA (``nastran.cards.solids``) rather than guess its mass.

Run: PYTHONPATH=. python studies/msc_ctetra10.py <pyNastran>/models/complex/tet10
"""

import argparse
import itertools
import re
from pathlib import Path

import numpy as np
import scipy.linalg as sl

from bayesupdate.nastran.deck import Refusals, read_deck
from bayesupdate.nastran.frames import read_grids

#: Nastran's CTETRA G5-G10: the edges between corners (0-based)
EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))


def rule(name: str) -> tuple[np.ndarray, np.ndarray]:
    """(barycentric points (q, 4), weights (q,) summing to 1) of a tetrahedron rule."""
    if name == "4-point":
        a, b = 0.5854101966249685, 0.1381966011250105
        return b + (a - b) * np.eye(4), np.full(4, 0.25)
    if name == "5-point":
        points = np.vstack([np.full(4, 0.25), 1 / 6 + (0.5 - 1 / 6) * np.eye(4)])
        return points, np.array([-0.8, 0.45, 0.45, 0.45, 0.45])
    # Keast's 11-point rule (degree 4), weights x 6 for a unit-volume sum
    points, weights = [np.full(4, 0.25)], [-0.0789333333333333]
    for i in range(4):
        p = np.full(4, 0.0714285714285714)
        p[i] = 0.785714285714286
        points.append(p)
        weights.append(0.0457333333333333)
    for i, j in itertools.combinations(range(4), 2):
        p = np.full(4, 0.100596423833201)
        p[[i, j]] = 0.399403576166799
        points.append(p)
        weights.append(0.149333333333333)
    return np.array(points), np.array(weights)


def shape(L: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """N (10,) and dN / dL (10, 4) at barycentric L (4,)."""
    N, dN = np.zeros(10), np.zeros((10, 4))
    for i in range(4):
        N[i], dN[i, i] = L[i] * (2 * L[i] - 1), 4 * L[i] - 1
    for k, (i, j) in enumerate(EDGES):
        N[4 + k], dN[4 + k, i], dN[4 + k, j] = 4 * L[i] * L[j], 4 * L[j], 4 * L[i]
    return N, dN


def element(xyz, E, nu, rho, stiffness_rule, mass_rule="11-point"):
    """(K, M) (30, 30) of a ten-node tetrahedron on GRIDs xyz (10, 3)."""
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[range(3), range(3)] += 2 * mu
    D[range(3, 6), range(3, 6)] = mu
    K, M = np.zeros((30, 30)), np.zeros((30, 30))
    for which, name in (("K", stiffness_rule), ("M", mass_rule)):
        for L, w in zip(*rule(name), strict=True):
            N, dN = shape(L)
            dxi = dN[:, 1:] - dN[:, [0]]  # d / d(L2, L3, L4) with L1 = 1 - L2 - L3 - L4
            J = dxi.T @ xyz
            dv = abs(np.linalg.det(J)) / 6 * w
            if which == "M":
                M += dv * rho * np.kron(np.outer(N, N), np.eye(3))
                continue
            g = np.linalg.solve(J, dxi.T)
            B = np.zeros((6, 30))
            for a in range(10):
                gx, gy, gz = g[:, a]
                c = 3 * a
                B[[0, 3, 5], c] = gx, gy, gz
                B[[1, 3, 4], c + 1] = gy, gx, gz
                B[[2, 4, 5], c + 2] = gz, gy, gx
            K += dv * B.T @ D @ B
    return K, M


def lumped(M: np.ndarray, kind: str) -> np.ndarray:
    """A diagonal mass (30, 30) from the consistent one by ``kind``."""
    total = M.sum() / 3
    d = np.diag(M)
    weights = {"corners only": (0.25, 0.0), "edges only": (0.0, 1 / 6),
               "sub-tetrahedra": (1 / 32, 7 / 48)}  # fmt: skip
    if kind == "HRZ":
        return np.diag(d * 3 * total / d.sum())
    if kind == "row sums":
        return np.diag(M.sum(axis=1))
    corner, edge = weights[kind]
    return np.diag(np.repeat(np.r_[np.full(4, corner), np.full(6, edge)] * total, 3))


def read_case(folder: Path):
    """(grid ids, xyz, elements as grid ids (2, 10), E, nu, rho, held ids, f06 text)."""
    deck_path = next(folder.glob("*.bdf"))
    deck = read_deck(deck_path, Refusals(str(deck_path)))
    grids = read_grids(deck, Refusals(str(deck_path)))
    tets = [[c[f"G{i}"] for i in range(1, 11)] for c in deck.of("CTETRA")]
    mat = deck.of("MAT1")[0]
    held = [g for c in deck.of("SPC1") for g in c.values(2) if isinstance(g, int)]
    f06 = next(folder.glob("*.f06")).read_text(errors="replace")
    return grids.ids, grids.xyz, tets, mat.real("E"), mat.real("NU"), mat.real("RHO"), held, f06


def f06_tables(f06: str, ids) -> tuple[np.ndarray, np.ndarray]:
    """(the real eigenvalues before augmentation, the 0-Hz displacement (n, 3) in ``ids`` order)."""
    table = f06.split("BEFORE AUGMENTATION")[1].split("PAGE")[0]
    lam = [float(m) for m in re.findall(r"^\s+\d+\s+\d+\s+(\S+)\s", table, re.M)]
    block = f06.split("C O M P L E X   D I S P L A C E M E N T")[1].split("PAGE")[0]
    rows = {int(g): [float(v) for v in vals.split()[:3]]
            for g, vals in re.findall(r"^0\s+(\d+)\s+G\s+(.*)$", block, re.M)}  # fmt: skip
    return np.array(lam), np.array([rows[int(g)] for g in ids])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("folder", type=Path, help="pyNastran's models/complex/tet10")
    ids, xyz, tets, E, nu, rho, held, f06 = read_case(ap.parse_args().folder)
    msc_lam, msc_u = f06_tables(f06, ids)
    index = {int(g): i for i, g in enumerate(ids)}
    free = np.array([3 * index[int(g)] + c for g in ids if g not in held for c in range(3)])
    f = np.zeros(3 * len(ids))
    f[3 * index[2154]] = 1.0  # FORCE 30: a unit x force at GRID 2154

    def assemble(stiffness_rule, mass_kind="consistent"):
        K, M = np.zeros((f.size, f.size)), np.zeros((f.size, f.size))
        for tet in tets:
            dofs = np.array([3 * index[g] + c for g in tet for c in range(3)])
            Ke, Me = element(xyz[[index[g] for g in tet]], E, nu, rho, stiffness_rule)
            K[np.ix_(dofs, dofs)] += Ke
            M[np.ix_(dofs, dofs)] += Me if mass_kind == "consistent" else lumped(Me, mass_kind)
        return K[np.ix_(free, free)], M[np.ix_(free, free)]

    print("static response to FORCE 30 at 0 Hz against MSC's f06 (largest difference / largest "
          "displacement):")  # fmt: skip
    for name in ("4-point", "5-point", "11-point"):
        K, _ = assemble(name)
        u = np.zeros(f.size)
        u[free] = np.linalg.solve(K, f[free])
        err = np.abs(u.reshape(-1, 3) - msc_u).max() / np.abs(msc_u).max()
        print(f"  stiffness by the {name:8s} rule: {err:.1e}")
    print("eigenvalues 1-10 with the 5-point stiffness, relative to MSC's [%]:")
    kinds = ("consistent", "HRZ", "row sums", "sub-tetrahedra", "corners only", "edges only")
    for kind in kinds:
        K, M = assemble("5-point", kind)
        mu = sl.eigh(M, K, eigvals_only=True)  # M may be singular or indefinite
        lam = np.sort(1 / mu[mu > 0])[: msc_lam.size]
        print(f"  {kind:15s}", " ".join(f"{v:+6.1f}" for v in 100 * (lam / msc_lam - 1)))


if __name__ == "__main__":
    main()
