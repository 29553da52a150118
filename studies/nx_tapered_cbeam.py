"""What NX Nastran's tapered CBEAM is: its stiffness and its lumped mass, found on its own static
solution; and how far the mean section (how this package read a tapered PBEAM before it read it
as NX does: ``fe.elements.general_beam.tapered_stiffness``) is from it.

Data nobody here made, from pyNastran's ``models`` folder (BSD-3-Clause, commit 1d25a92; read
with pyNastran's OP2 reader, which this script alone needs): ``sol200/model_200.bdf`` and its
``model_200.op2`` (NX Nastran 8.5, SOL 200): a cantilever of four CBEAMs along a curved line
(GRIDs 1-5, GRID 1 held), each PBEAM tapered from end A to end B in A, I2, J and NSM, its I1 at
either end set by a DVPREL2 (I1 = 1.6906 - 0.3822 y at the GRIDs' DTABLE y: 1.69 down to 0.07,
strongly tapered), MAT1 E = G = 1 with no density, a CONM2 with an offset at the tip, under
gravity (9.81, -z).  The op2's first displacement set is the analysis at the initial design
(the DESVARs' initial values).  Its grid point weight generator gives the lumped mass's first
moments.

The candidates: each end-B translation and rotation of a cantilever from its flexibility, the
integral of the section forces' complementary energy along the element (axial, two shears with
the PBEAM's default K1 = K2 = 1, torsion, two bending moments: I1 about the element's z, I2
about its y) with the section's A, I1, I2, J linear between the ends, integrated exactly (20
Gauss points) or by 2 or 3 Gauss points, Simpson's rule or the trapezoid rule; or the mean
section (what ``nastran.cards.beams`` read before).  The NSM lumped at each end as half the
element's mean (the mean section's) or by its first moments, L (a/3 + b/6) at end A and
L (a/6 + b/3) at end B.

Measured (2026-11-30, this script): the lumped mass's first moments are NX's to its printed
digits only with the first-moment lumping (m x 2.8092654 against 2.809265, m y 6.8175854
against 6.817585, m z 0.4159474; half the mean: 2.8156832, 6.8354836, 0.4168854); the
displacements (largest relative difference per component, over the GRIDs) are NX's to 7e-8
(its float32 output) only with the properties linear along the element, the flexibility
integrated by 3 Gauss points and the first-moment lumping; exact integration is 2.4e-4 off,
2 Gauss points 1.1e-3, Simpson 2.8e-3, the half-mean lumping 3.4e-3 to 4.0e-3 whatever the
rule, and the mean section (the reading before) 5.2e-3 on the translations and 2.2e-2 on the
bending rotations.  The package's own path on the deck ``--write`` stores: 1.2e-8 to 7.0e-8
(``tests/test_nastran_cards.py``).  NX's
tapered CBEAM is therefore: linear properties, 3-point Gauss flexibility, NSM lumped by its
first moments.  MSC's (common code with NX before 2003) is not checked here.

``--write DIR`` stores what the tests need (``tests/data/nx_tapered_cbeam.bdf``: the deck at the
initial design, its I1 typed in from the DVPREL2s, without the design cards; and
``nx_tapered_cbeam.json``: NX's displacements and mass), so that they do not need pyNastran.

Run: PYTHONPATH=. python studies/nx_tapered_cbeam.py <pyNastran>/models [--write tests/data]
"""

import argparse
import json
from pathlib import Path

import numpy as np

#: GRIDs 1-5 (basic, the deck's)
XYZ = np.array([[0.093728, 0, 0], [0.5351075, 1.2275, 0.0643305], [0.8927557, 2.2275, 0.1167383],
                [1.253594, 3.2275, 0.1691461], [1.61353, 4.24, 0.222209]])  # fmt: skip
#: the DTABLE y of GRIDs 1-5 and I1 = QUAD(a, b, c, y) at the DESVARs' initial values
I1 = 1.6906 - 0.3822 * np.array([0, 1.2275, 2.2275, 3.2275, 4.24])
#: each PBEAM's (A, I2, J, NSM) at end A and end B (I1 from ``I1``)
SECTIONS = (
    ((71156.29, 684.183, 11.5833, 0.7993671), (80727.37, 562.1705, 9.517492, 0.7486528)),
    ((80727.37, 562.1705, 9.517492, 0.7486528), (92898.52, 458.2828, 7.757458, 0.7073376)),
    ((92898.52, 458.2828, 7.757458, 0.7073376), (99817.51, 408.7442, 6.918595, 0.6660225)),
    ((99817.51, 408.7442, 6.918595, 0.6660225), (126457.0, 288.6337, 4.884768, 0.6241909)),
)
TIP_MASS, TIP_OFFSET, GRAVITY = 0.0666, np.array([0.8763962, 0.1567351, 0.8888889]), 9.81


def gauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    """(points in [0, 1], weights summing to 1) of the n-point Gauss rule."""
    x, w = np.polynomial.legendre.leggauss(n)
    return (x + 1) / 2, w / 2


RULES = {"exact (20 Gauss points)": gauss(20), "3 Gauss points": gauss(3),
         "2 Gauss points": gauss(2), "Simpson": (np.array([0, 0.5, 1]), np.array([1, 4, 1]) / 6),
         "trapezoid": (np.array([0.0, 1.0]), np.array([0.5, 0.5]))}  # fmt: skip


def element(e: int, rule, mean: bool) -> np.ndarray:
    """(12, 12) global K of CBEAM e (orientation vector (0, 0, 1), E = G = 1) from its
    cantilever flexibility along the rule (points, weights); ``mean``: the mean section."""
    xa, xb = XYZ[e], XYZ[e + 1]
    L = np.linalg.norm(xb - xa)
    ex = (xb - xa) / L
    ez = np.cross(ex, [0.0, 0.0, 1.0])
    ez /= np.linalg.norm(ez)
    frame = np.array([ex, np.cross(ez, ex), ez])
    (A0, I20, J0, _), (A1, I21, J1, _) = SECTIONS[e]
    F = np.zeros((6, 6))
    for t, w in zip(*rule, strict=True):
        s = 0.5 if mean else t
        A, i2, J = A0 + (A1 - A0) * s, I20 + (I21 - I20) * s, J0 + (J1 - J0) * s
        i1 = I1[e] + (I1[e + 1] - I1[e]) * s
        r = L * (1 - t)  # arm from the section to end B
        phi = np.eye(6)  # section forces (N, Vy, Vz, T, My, Mz) from end-B loads
        phi[4, 2], phi[5, 1] = -r, r
        F += phi.T @ np.diag(1 / np.array([A, A, A, J, i2, i1])) @ phi * w * L
    link = np.eye(6, 12, 6)  # end B's motion relative to end A's rigid motion
    link[:3, :3] = link[3:, 3:6] = -np.eye(3)
    link[:3, 3:6] = -L * np.array([[0, 0, 0], [0, 0, 1], [0, -1, 0]])
    T = np.kron(np.eye(4), frame)
    return T.T @ link.T @ np.linalg.inv(F) @ link @ T


def lumped_nsm(first_moments: bool) -> np.ndarray:
    """(5,) NSM lumped at the GRIDs: by first moments, or half the element's mean at each end."""
    m = np.zeros(5)
    for e, ((*_, a), (*_, b)) in enumerate(SECTIONS):
        L = np.linalg.norm(XYZ[e + 1] - XYZ[e])
        ends = (
            (L * (a / 3 + b / 6), L * (a / 6 + b / 3)) if first_moments else (L * (a + b) / 4,) * 2
        )
        m[e] += ends[0]
        m[e + 1] += ends[1]
    return m


def displacements(rule, mean: bool, first_moments: bool) -> np.ndarray:
    """(5, 6) the GRIDs' displacements under gravity."""
    K, F = np.zeros((30, 30)), np.zeros(30)
    for e in range(4):
        K[6 * e : 6 * e + 12, 6 * e : 6 * e + 12] += element(e, rule, mean)
    F[2::6] -= lumped_nsm(first_moments) * GRAVITY
    tip = np.array([0.0, 0.0, -TIP_MASS * GRAVITY])
    F[24:27] += tip
    F[27:30] += np.cross(TIP_OFFSET, tip)
    u = np.zeros(30)
    u[6:] = np.linalg.solve(K[6:, 6:], F[6:])
    return u.reshape(5, 6)


def initial_deck() -> str:
    """The cantilever at the initial design as a deck (free field, every value as read above):
    GRIDs, CBEAMs, PBEAMs with I1 typed in, the CONM2, MAT1 E = G = 1, GRID 1 held, SOL 103."""
    lines = ["$ pyNastran models/sol200/model_200.bdf (BSD-3-Clause, commit 1d25a92) at its",
             "$ initial design: I1 from its DVPREL2s; written by studies/nx_tapered_cbeam.py",
             "SOL 103", "CEND", "METHOD = 1", "SPC = 1", "BEGIN BULK", "EIGRL,1,,,8",
             "MAT1,1,1.,1.", "SPC1,1,123456,1"]  # fmt: skip
    lines += [f"GRID,{k + 1},,{x!r},{y!r},{z!r}" for k, (x, y, z) in enumerate(XYZ.tolist())]
    for e, ((a0, i20, j0, n0), (a1, i21, j1, n1)) in enumerate(SECTIONS):
        lines += [f"CBEAM,{e + 1},{e + 1},{e + 1},{e + 2},0.,0.,1.",
                  f"PBEAM,{e + 1},1,{a0!r},{I1[e]!r},{i20!r},,{j0!r},{n0!r}",
                  f",NO,1.,{a1!r},{I1[e + 1]!r},{i21!r},,{j1!r},{n1!r}"]  # fmt: skip
    lines += [f"CONM2,10,5,,{TIP_MASS!r},{','.join(map(repr, TIP_OFFSET.tolist()))}", "ENDDATA"]
    return "\n".join(lines) + "\n"


def main() -> None:
    from pyNastran.op2.op2 import read_op2

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("models", type=Path, help="pyNastran's models folder")
    ap.add_argument("--write", type=Path, help="write the tests' deck and data in this folder")
    args = ap.parse_args()
    op2 = read_op2(str(args.models / "sol200/model_200.op2"), debug=None, build_dataframe=False)
    nx = next(iter(op2.displacements.values())).data[0]
    if args.write:
        (args.write / "nx_tapered_cbeam.bdf").write_text(initial_deck())
        weight = next(iter(op2.grid_point_weight.values()))
        moments = (weight.MO[1, 5], -weight.MO[0, 5], weight.MO[0, 4])  # m x, m y, m z
        data = {"displacements": [[float(str(v)) for v in row] for row in nx],
                "mass": float(str(weight.mass[0])), "gravity": GRAVITY,
                "first_moments": [float(str(v)) for v in moments]}  # fmt: skip
        (args.write / "nx_tapered_cbeam.json").write_text(json.dumps(data) + "\n")
    print("lumped mass first moments (m x, m y, m z) against NX's grid point weight generator")
    for first in (True, False):
        m = np.append(lumped_nsm(first), TIP_MASS)
        where = np.vstack([XYZ, XYZ[4] + TIP_OFFSET])
        moments = ", ".join(f"{v:.7f}" for v in m @ where)
        print(f"  {'first moments' if first else 'half the mean'}: mass {m.sum():.7f}, {moments}")
    print("  NX: mass 3.276537, 2.809265, 6.817585, 0.4159474")
    print("largest relative difference from NX per component (x, y, z, rx, ry, rz)")
    for name, rule in RULES.items():
        for first in (True, False):
            u = displacements(rule, False, first)
            err = np.abs(u - nx)[1:].max(axis=0) / np.abs(nx).max(axis=0)
            print(
                f"  linear properties, {name:24s} lumping {'first' if first else 'half'}: "
                + " ".join(f"{v:.1e}" for v in err)
            )
    u = displacements(gauss(1), True, False)
    err = np.abs(u - nx)[1:].max(axis=0) / np.abs(nx).max(axis=0)
    errors = " ".join(f"{v:.1e}" for v in err)
    print(f"  mean section (the reading before), half the mean: {errors}")


if __name__ == "__main__":
    main()
