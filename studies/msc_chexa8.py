"""What MSC and NX Nastran's eight-node CHEXA is: its stiffness and lumped mass, found on their
own solutions.

Data nobody here made, from pyNastran's ``models`` folder (BSD-3-Clause, commit 1d25a92; read
with pyNastran's OP2 reader, which this script alone needs):

* ``bugs/msc_RBE_tests/rigid_rbe2.bdf`` and ``rigid_rbe2--v2021.1.op2`` (MSC Nastran 2021.1,
  SOL 101): 128 CHEXAs (0.05 m cubes, their GRIDs moved up to 1.5e-4 of an edge off the
  cube), aluminium (MAT1 E 6.9e10, NU 0.33, RHO 2700), PSOLID with IN and ISOP blank, two RBE2s
  and a CBAR, under gravity.  The op2 holds the displacements, the grid point forces of each
  element (GPFORCE: each CHEXA's forces on its GRIDs, -K_e u_e) and the load vector (OLOAD: the
  gravity load M g of the default lumped mass).
* ``unit/pload4/chexa.bdf`` and ``chexa.op2`` (NX Nastran, SOL 101): one 1 x 1 x 2 CHEXA (E 3e7,
  NU 0.3), its bottom face clamped, a unit pressure on each face in turn (PLOAD4).  On the
  four free GRIDs, K_e u must equal the face's load (a quarter of its area on each corner).

Candidates for K_e: the fully integrated trilinear brick (2 x 2 x 2 Gauss); Wilson's
incompatible modes with Taylor's correction (QM6: the bubbles 1 - xi^2, 1 - eta^2, 1 - zeta^2 on
each displacement, condensed); the package's ``fe.elements.hexa`` (assumed natural shear strains
on the lines through the centre, nine enhanced normal strains, condensed).  The float32 output
sets the floor: each element's error is also given against the error that rounding its
displacements and forces to float32 makes.

Measured (2026-11-30, this script):
- MSC's 128 elements, |K_e u_e + GPFORCE| / |GPFORCE| (median, 90th percentile): full 6.0e-2,
  1.3e-1; QM6 5.6e-4, 1.5e-3; ``fe.elements.hexa`` 1.4e-5, 2.3e-4, at 2.1 times the float32
  floor (median element).  What is left grows with an element's distortion (its GRIDs are up to
  1.5e-4 of an edge off the cube), about 5 % of it; the treatment of distorted bricks is the
  standard one (Simo & Rifai's centre Jacobian) but is not checked beyond that.
- NX's single brick, the five loaded faces: full 2.4, QM6 1.8e-1, ``fe.elements.hexa``
  1.6e-6 (largest relative |K u - F| over the faces).
- MSC's gravity load on the 250 GRIDs only CHEXAs join: rho g times the integral of each
  corner's N_a (``fe.elements.hexa.corner_volumes``) to 3.6e-8 (largest), where an eighth of
  each element's mass at each corner is 1.2e-4 off: Nastran lumps a brick's mass by its shape
  functions.

``--write`` stores what the tests need (``tests/data/msc_chexa8.json``: the corners, the
corners' displacements, the grid point forces, the gravity loads; the NX element's
displacements), so that the tests do not need pyNastran.

Run: PYTHONPATH=. python studies/msc_chexa8.py <pyNastran>/models
         [--write tests/data/msc_chexa8.json]
"""

import argparse
import json
from pathlib import Path

import numpy as np

from bayesupdate.fe.elements import hexa
from bayesupdate.fe.elements.solid import elasticity, strain_matrix

MSC = ("bugs/msc_RBE_tests/rigid_rbe2.bdf", "bugs/msc_RBE_tests/rigid_rbe2--v2021.1.op2")
NX = ("unit/pload4/chexa.bdf", "unit/pload4/chexa.op2")
#: the NX element's loaded faces (PLOAD4 load set -> its four GRIDs); the bottom face is held
NX_FACES = {5: (25, 26, 27, 28), 9: (21, 24, 28, 25), 13: (26, 27, 23, 22),
            17: (25, 26, 22, 21), 21: (23, 27, 28, 24)}  # fmt: skip


def full_brick(corners: np.ndarray, D: np.ndarray) -> np.ndarray:
    """(n, 24, 24) the fully integrated trilinear brick (2 x 2 x 2 Gauss)."""
    jac = hexa.jacobians(corners, hexa.GAUSS)
    dN = np.broadcast_to(hexa.shape_derivatives(hexa.GAUSS), jac.shape[:2] + (3, 8))
    grad = np.linalg.solve(jac, dN)
    B = strain_matrix(grad.reshape(-1, 3, 8)).reshape(len(corners), 8, 6, 24)
    return np.einsum("epji,ejk,epkl,ep->eil", B, D, B, np.linalg.det(jac))


def wilson_taylor(corners: np.ndarray, D: np.ndarray) -> np.ndarray:
    """(n, 24, 24) Wilson's incompatible modes with Taylor's centre-Jacobian correction (QM6),
    condensed."""
    n = len(corners)
    jac = hexa.jacobians(corners, hexa.GAUSS)
    det = np.linalg.det(jac)
    jac0 = hexa.jacobians(corners, np.zeros((1, 3)))[:, 0]
    det0 = np.linalg.det(jac0)
    K = np.zeros((n, 33, 33))
    for p, point in enumerate(hexa.GAUSS):
        dN = np.broadcast_to(hexa.shape_derivatives(point[None])[0], (n, 3, 8))
        grad = np.linalg.solve(jac[:, p], dN)
        bubble = np.linalg.solve(jac0, np.broadcast_to(np.diag(-2 * point), (n, 3, 3)))
        bubble = bubble * (det0 / det[:, p])[:, None, None]
        B = strain_matrix(np.concatenate([grad, bubble], axis=2))
        K += np.einsum("eji,ejk,ekl,e->eil", B, D, B, det[:, p])
    a, b = slice(0, 24), slice(24, None)
    return K[:, a, a] - K[:, a, b] @ np.linalg.solve(K[:, b, b], K[:, b, a])


CANDIDATES = {"full 2x2x2": full_brick, "Wilson-Taylor (QM6)": wilson_taylor,
              "fe.elements.hexa": hexa.stiffness}  # fmt: skip


def f32(values) -> list[float]:
    """float32 output as the shortest decimals that give its bits back (a smaller fixture)."""
    return [float(str(np.float32(v))) for v in values]


def read(models: Path, names) -> tuple:
    from pyNastran.bdf.bdf import read_bdf
    from pyNastran.op2.op2 import read_op2

    bdf = read_bdf(str(models / names[0]), debug=None, xref=False)
    op2 = read_op2(str(models / names[1]), debug=None, build_dataframe=False)
    return bdf, op2


def msc_data(models: Path) -> dict:
    bdf, op2 = read(models, MSC)
    (mat,) = bdf.materials.values()
    elements = sorted((eid, e.node_ids) for eid, e in bdf.elements.items() if e.type == "CHEXA")
    nodes = np.array([n for _, n in elements])
    xyz = {nid: node.xyz for nid, node in bdf.nodes.items()}  # basic = the GRIDs' own here
    disp = next(iter(op2.displacements.values()))
    u = dict(zip(disp.node_gridtype[:, 0], disp.data[0, :, :3], strict=True))
    gpf = next(iter(op2.grid_point_forces.values()))
    forces = {(int(e), int(n)): f for (n, e), name, f in
              zip(gpf.node_element[0], gpf.element_names[0], gpf.data[0, :, :3], strict=True)
              if "HEXA" in str(name)}  # fmt: skip
    load = next(iter(op2.load_vectors.values()))
    only_solids = sorted(set(nodes.ravel()))
    oload = dict(zip(load.node_gridtype[:, 0], load.data[0, :, 2], strict=True))
    (grav,) = bdf.loads[1]
    return {
        "E": mat.e,
        "nu": mat.nu,
        "rho": mat.rho,
        "gravity_z": -grav.scale * abs(grav.N[2]),
        "nodes": nodes.tolist(),
        "corners": [[list(map(float, xyz[n])) for n in row] for row in nodes],
        "u": [[f32(u[n]) for n in row] for row in nodes],
        "gpforce": [[f32(forces[(eid, n)]) for n in row] for eid, row in elements],
        "oload_grids": [int(n) for n in only_solids],
        "oload_z": f32([oload[n] for n in only_solids]),
    }


def nx_data(models: Path) -> dict:
    bdf, op2 = read(models, NX)
    (mat,) = bdf.materials.values()
    (e,) = bdf.elements.values()
    order = list(e.node_ids)
    out = {"E": mat.e, "nu": mat.nu, "grids": order,
           "corners": [list(map(float, bdf.nodes[n].xyz)) for n in order], "faces": {}}  # fmt: skip
    for case, face in NX_FACES.items():
        disp = op2.displacements[case]
        u = dict(zip(disp.node_gridtype[:, 0], disp.data[0, :, :3], strict=True))
        out["faces"][str(case)] = {"grids": list(face), "u": [f32(u[n]) for n in order]}
    return out


def msc_errors(data: dict, stiffness) -> tuple[np.ndarray, np.ndarray]:
    """(per element |K u + GPFORCE| / |GPFORCE|, the same of float32 rounding alone)."""
    corners = np.array(data["corners"])
    u, f = (np.array(data[k], dtype=np.float32).astype(float) for k in ("u", "gpforce"))
    n = len(corners)
    K = stiffness(corners, elasticity(np.full(n, data["E"]), np.full(n, data["nu"])))
    u, f = u.reshape(n, 24), f.reshape(n, 24)
    size = np.linalg.norm(f, axis=1)
    err = np.linalg.norm(np.einsum("eij,ej->ei", K, u) + f, axis=1) / size
    eps = 2.0**-24 / np.sqrt(3)  # float32's rounding, uniform on +-half an ulp
    floor = np.sqrt(np.einsum("eij,ej->e", K**2, (u * eps) ** 2) + (size * eps) ** 2) / size
    return err, floor


def nx_error(data: dict, stiffness) -> float:
    """Largest |K u - F| / |F| over the loaded faces on the four free GRIDs."""
    X = np.array(data["corners"])
    K = stiffness(X[None], elasticity(np.array([data["E"]]), np.array([data["nu"]])))[0]
    free = slice(12, 24)
    worst = 0.0
    for case in data["faces"].values():
        u = np.array(case["u"], dtype=np.float32).astype(float).ravel()
        P = X[[data["grids"].index(g) for g in case["grids"]]]
        normal = np.cross(P[2] - P[0], P[3] - P[1])
        F = np.zeros((8, 3))
        for g in case["grids"]:
            F[data["grids"].index(g)] = normal / 8  # |normal| / 2 is the area; a quarter each
        F = F.ravel()[free]
        Ku = K[free] @ u
        worst = max(worst, np.linalg.norm(Ku - np.sign(F @ Ku) * F) / np.linalg.norm(F))
    return worst


def gravity_errors(data: dict) -> dict[str, float]:
    """Largest relative difference of MSC's gravity load on the GRIDs only CHEXAs join from
    rho g x (the integral of N_a, an eighth of the volume) summed over their elements."""
    corners, nodes = np.array(data["corners"]), np.array(data["nodes"])
    rows = {g: i for i, g in enumerate(data["oload_grids"])}
    share = hexa.corner_volumes(corners)
    eighth = np.repeat(share.sum(axis=1, keepdims=True) / 8, 8, axis=1)
    rules = {"integral of N_a": share, "V / 8": eighth}
    out = {}
    for name, s in rules.items():
        load = np.zeros(len(rows))
        weight = data["rho"] * data["gravity_z"] * s
        np.add.at(load, [rows[g] for g in nodes.ravel()], weight.ravel())
        msc = np.array(data["oload_z"], dtype=np.float32).astype(float)
        out[name] = float(np.max(np.abs(load / msc - 1)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("models", type=Path, help="pyNastran's models folder")
    ap.add_argument("--write", type=Path, help="write the tests' fixture here")
    args = ap.parse_args()
    msc, nx = msc_data(args.models), nx_data(args.models)
    print(
        "MSC 2021.1, 128 CHEXA: |K u + GPFORCE| / |GPFORCE|: median, p90 (median / float32 floor)"
    )
    for name, stiffness in CANDIDATES.items():
        err, floor = msc_errors(msc, stiffness)
        spread = f"{np.median(err):.2e}  {np.percentile(err, 90):.2e}"
        print(f"  {name:22s} {spread}  ({np.median(err / floor):.1f})")
    print("NX, one 1 x 1 x 2 CHEXA, five loaded faces: largest |K u - F| / |F|")
    for name, stiffness in CANDIDATES.items():
        print(f"  {name:22s} {nx_error(nx, stiffness):.2e}")
    print("MSC's gravity load (lumped mass) on 250 GRIDs, largest relative difference:")
    for name, value in gravity_errors(msc).items():
        print(f"  {name:22s} {value:.2e}")
    if args.write:
        source = ("pyNastran (github.com/SteveDoyle2/pyNastran, BSD-3-Clause) commit "
                  f"1d25a92: models/{MSC[0]}, models/{MSC[1]}, models/{NX[0]}, models/{NX[1]}; "
                  "written by studies/msc_chexa8.py")  # fmt: skip
        args.write.write_text(json.dumps({"source": source, "msc": msc, "nx": nx}) + "\n")
        print(f"wrote {args.write}")


if __name__ == "__main__":
    main()
