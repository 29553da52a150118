"""MSC's modal solution of pyNastran's ``solid_shell_bar`` model: a fresh check of the CHEXA,
and where MSC's CPENTA is not yet found.

Data nobody here made, from pyNastran's ``models`` folder (BSD-3-Clause, commit 1d25a92; text,
no pyNastran needed): ``sol_101_elements/mode_solid_shell_bar.bdf`` (with ``geom.inc``) and
its ``.f06`` (MSC Nastran 2005, SOL 103, 3 modes): a tower of shells, one CHEXA (a unit cube),
two CPENTA (the next cube split along a diagonal), two CTETRA and bars, MAT1 E 2.9e7, NU 0.32.
The f06 prints each mode's eigenvector and, per element, its grid point forces (GPFORCE: the
element's K_e phi_e at its GRIDs), seven digits each.

Checked: K_e phi_e of the package's brick (``fe.elements.hexa``, found in an earlier session on
other MSC and NX solutions; this model was not used then) against the CHEXA's grid point forces
in the three modes; and candidates for the six-node CPENTA: the fully integrated wedge (3 x 2
and 1 x 2 Gauss points) and the brick collapsed onto a wedge (each of the three ways, with and
without its enhanced strains).

Measured (2026-11-30, this script): the CHEXA's forces are MSC's to 5.1e-6, 4.8e-6 and 5.0e-6
(|K phi - f| / |f|, modes 1-3: the f06's seven digits); no CPENTA candidate comes within 14 %
(the wedges with 3 x 2 or 1 x 2 Gauss points 30-45 %, the collapsed bricks 14-32 %): MSC's
wedge is none of these, and CPENTA stays refused.

The model's PSHELL shells (T 0.25 on unit squares, a / t = 4, two quads and four triangles),
the same way: their in-plane forces are MSC's to 1e-4 (the f06's digits), so the membrane is
MSC's; their normal forces and bending moments miss by 0.6 to 4.6 of their size: at this
thickness MSC's QUAD4 and CTRIA3 bend and shear otherwise than this package's MITC4 and DKT
(measured, not explained).

``--write DIR`` stores the CHEXA's corners, eigenvectors and forces
(``tests/data/msc_solid_shell_bar_hexa.json``) for ``tests/test_nastran_hexa.py``.

Run: PYTHONPATH=. python studies/msc_solid_shell_bar.py <pyNastran>/models [--write tests/data]
"""

import argparse
import json
import re
from pathlib import Path

import numpy as np

from bayesupdate.fe.elements.hexa import stiffness
from bayesupdate.fe.elements.solid import elasticity

FOLDER = "sol_101_elements"
E, NU = 2.9e7, 0.32
#: the CHEXA's and the CPENTAs' GRIDs, in their cards' order (``geom.inc``)
HEXA = {1: [2, 3, 4, 1, 8, 5, 6, 7]}
PENTA = {2: [6, 8, 5, 10, 11, 9], 3: [6, 7, 8, 10, 12, 11]}


def grids(folder: Path) -> dict[int, np.ndarray]:
    """{GRID id: basic coordinates} of the model's small-field GRIDs (CP 0 in this model)."""
    out = {}
    for name in ("mode_solid_shell_bar.bdf", "geom.inc"):
        for line in (folder / name).read_text().splitlines():
            if line.startswith("GRID"):
                f = [line[i : i + 8] for i in range(0, 48, 8)]
                out[int(f[1])] = np.array([float(v) for v in f[3:6]])
    return out


def modes_and_forces(f06: str, kinds: str, dofs: int = 3) -> tuple[dict, dict]:
    """({mode: {GRID: displacement (dofs,)}}, {mode: {(element, GRID): force (dofs,)}}) of the
    f06's eigenvectors and its grid point force tables' rows of the element types ``kinds`` (a
    regular expression: HEXA, PENTA, QUAD4|TRIA3); dofs 3 (translations) or 6."""
    values = r"\s+(\S+)" * dofs
    vecs = {}
    pattern = r"R E A L   E I G E N V E C T O R   N O \.\s+(\d+)(.*?)(?=1    MSC)"
    for m in re.finditer(pattern, f06, re.S):
        rows = re.findall(r"^\s+(\d+)\s+G" + values, m.group(2), re.M)
        vecs[int(m.group(1))] = {int(g): np.array([float(v) for v in r]) for g, *r in rows}
    forces, mode = {}, 0
    for page in f06.split("G R I D   P O I N T   F O R C E   B A L A N C E")[1:]:
        rows = re.findall(rf"^[0 ]?\s+(\d+)\s+(\d+)\s+(?:{kinds})" + values, page, re.M)
        if re.search(r"^[0 ]?\s+1\s+1\s+HEXA", page, re.M):  # each mode's table starts here
            mode += 1
        for g, e, *f in rows:
            forces.setdefault(mode, {})[(int(e), int(g))] = np.array([float(v) for v in f])
    return vecs, forces


def misses(K_of, elements, xyz, vecs, forces) -> list[float]:
    """|K phi - f| / |f| per mode and element for stiffness ``K_of(corners)`` (18 or 24 DOFs)."""
    out = []
    for mode in sorted(vecs):
        for e, nodes in elements.items():
            u = np.concatenate([vecs[mode][n] for n in nodes])
            f = np.concatenate([forces[mode][(e, n)] for n in nodes])
            r = K_of(np.array([xyz[n] for n in nodes])) @ u
            out.append(float(min(np.linalg.norm(r - f), np.linalg.norm(r + f)) / np.linalg.norm(f)))
    return out


def wedge(points, zs):
    """K (18, 18) of the fully integrated six-node wedge at triangle points (r, s, w) and
    through-thickness points (z, w)."""
    D = elasticity(np.array([E]), np.array([NU]))[0]

    def K_of(X):
        K = np.zeros((18, 18))
        for r, s, wt in points:
            for z, wz in zs:
                L = np.array([1 - r - s, r, s])
                dL = np.array([[-1.0, 1.0, 0.0], [-1.0, 0.0, 1.0]])
                dN = np.vstack([np.concatenate([d * (1 - z) / 2, d * (1 + z) / 2]) for d in dL]
                               + [np.concatenate([-L / 2, L / 2])])  # fmt: skip
                J = dN @ X
                dx = np.linalg.solve(J, dN)
                B = np.zeros((6, 18))
                for a in range(6):
                    x, y, w = dx[:, a]
                    B[:, 3 * a : 3 * a + 3] = [[x, 0, 0], [0, y, 0], [0, 0, w], [y, x, 0],
                                               [0, w, y], [w, 0, x]]  # fmt: skip
                K += B.T @ D @ B * np.linalg.det(J) * wt * wz
        return K

    return K_of


def collapsed(mapping, enhanced):
    """K (18, 18) of the brick on the wedge's corners repeated by ``mapping`` (8,)."""
    P = np.zeros((24, 18))
    for a, b in enumerate(mapping):
        P[3 * a : 3 * a + 3, 3 * b : 3 * b + 3] = np.eye(3)
    D = elasticity(np.array([E]), np.array([NU]))
    return lambda X: P.T @ stiffness(X[mapping][None], D, enhanced=enhanced)[0] @ P


#: the PSHELL 4 shells (T 0.25 on unit squares: a / t = 4) and their GRIDs
SHELLS = {6: [4, 1, 14, 15], 7: [3, 2, 17, 16], 8: [4, 3, 16], 9: [16, 15, 4], 10: [1, 2, 17],
          11: [17, 14, 1]}  # fmt: skip


def shell_misses(f06: str, xyz: dict) -> dict:
    """Per PSHELL shell, the largest over the modes of |K phi - (-f)| / |f| on its in-plane
    forces, its normal forces and its bending moments (the package's shell, 6 DOFs a GRID)."""
    from bayesupdate.fe.shell_model import ShellAssembly, shell_mesh

    vecs, forces = modes_and_forces(f06, "QUAD4|TRIA3", dofs=6)
    out = {}
    for eid, nodes in SHELLS.items():
        X = np.array([xyz[n] for n in nodes])
        cells = {"quads" if len(nodes) == 4 else "trias": [list(range(len(nodes)))]}
        mesh = shell_mesh(X, thickness=0.25, E=E, nu=NU, rho=0.283, **cells)
        K = ShellAssembly(mesh).element_matrices()[0][0][0]
        c = int(np.argmax(np.abs(np.cross(X[1] - X[0], X[2] - X[0]))))  # the normal's axis
        corners = range(len(nodes))
        parts = ([6 * a + k for a in corners for k in range(3) if k != c],
                 [6 * a + c for a in corners],
                 [6 * a + 3 + k for a in corners for k in range(3) if k != c])  # fmt: skip
        miss = np.zeros(3)
        for mode in sorted(vecs):
            r = K @ np.concatenate([vecs[mode][n] for n in nodes])
            f = np.concatenate([forces[mode][(eid, n)] for n in nodes])
            miss = np.maximum(miss, [np.linalg.norm((r + f)[ix]) / np.linalg.norm(f[ix])
                                     for ix in parts])  # fmt: skip
        out[eid] = miss
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("models", type=Path, help="pyNastran's models folder")
    ap.add_argument("--write", type=Path, help="write the tests' data in this folder")
    args = ap.parse_args()
    folder = args.models / FOLDER
    f06 = (folder / "mode_solid_shell_bar.f06").read_text(errors="replace")
    xyz = grids(folder)
    vecs, hexa_forces = modes_and_forces(f06, "HEXA")
    D = elasticity(np.array([E]), np.array([NU]))
    hexa = misses(lambda X: stiffness(X[None], D)[0], HEXA, xyz, vecs, hexa_forces)
    print("CHEXA, K phi against MSC's grid point forces, modes 1-3:", np.round(hexa, 8))
    _, penta_forces = modes_and_forces(f06, "PENTA")
    g = 1 / np.sqrt(3)
    candidates = {
        "wedge 3 x 2": wedge(
            [(1 / 6, 1 / 6, 1 / 6), (2 / 3, 1 / 6, 1 / 6), (1 / 6, 2 / 3, 1 / 6)],
            [(-g, 1.0), (g, 1.0)],
        ),  # fmt: skip
        "wedge 1 x 2": wedge([(1 / 3, 1 / 3, 0.5)], [(-g, 1.0), (g, 1.0)]),
    }
    for label, mp in {"1233": [0, 1, 2, 2, 3, 4, 5, 5], "1123": [0, 0, 1, 2, 3, 3, 4, 5],
                      "1223": [0, 1, 1, 2, 3, 4, 4, 5]}.items():  # fmt: skip
        for enhanced in (True, False):
            candidates[f"brick {label} {'enhanced' if enhanced else 'plain'}"] = collapsed(
                mp, enhanced)  # fmt: skip
    for name, K_of in candidates.items():
        m = misses(K_of, PENTA, xyz, vecs, penta_forces)
        print(f"CPENTA {name:26s} misses {min(m):.3f} to {max(m):.3f}")
    for eid, m in shell_misses(f06, xyz).items():
        print(f"PSHELL shell {eid}: in-plane forces {m[0]:.1e}, normal forces {m[1]:.2f}, "
              f"bending moments {m[2]:.2f} (largest over the modes)")  # fmt: skip
    if args.write:
        nodes = HEXA[1]
        data = {"corners": [xyz[n].tolist() for n in nodes], "E": E, "nu": NU,
                "modes": [[vecs[m][n].tolist() for n in nodes] for m in sorted(vecs)],
                "forces": [[hexa_forces[m][(1, n)].tolist() for n in nodes]
                           for m in sorted(vecs)]}  # fmt: skip
        (args.write / "msc_solid_shell_bar_hexa.json").write_text(json.dumps(data) + "\n")


if __name__ == "__main__":
    main()
