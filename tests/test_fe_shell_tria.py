"""The 3-node shell triangle (DKT bending, ``bayesupdate.fe.elements.shell_tria``) against closed
forms.

Tolerances and why:
- simply supported square plate, 32 x 32 cells each cut in two triangles along the same diagonal
  (the CTRIA3 deck of a mesher), modes 1-8 against Kirchhoff (Leissa 1969, eq. 4.3): 1 % on each
  mode, the quads' own level (MITC4 on 32 x 32 quads: 0.79 % on modes 7-8, measured).  Measured
  worst: 0.93 % (a/t = 100), 0.98 % (a/t = 1000), 0.31 % with lumped mass; the MITC3 triangle
  it replaces was 2.1 % (a/t = 100) and 32 % (a/t = 1000, shear locking) off on the same mesh.
- a/t = 10: the element is Kirchhoff with rotary inertia, so it converges to the Rayleigh plate
  (measured within 0.5 % at 32 x 32 x 2; asserted 1 %), which lies above Mindlin's plate.
- patch tests and rigid motions: exact to round-off (1e-9 relative).
"""

import sys
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.fe import shell_mesh as sm
from bayesupdate.fe.elements import shell, shell_tria
from bayesupdate.fe.shell_model import ShellAssembly, shell_mesh
from bayesupdate.fe.sparse_modal import ModalSettings, solve_sparse_modes

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
from pshell_ratios import Plate, plate_deck  # noqa: E402
from shell_powers import assert_thickness_polynomials  # noqa: E402

E, NU, RHO, A = 200e9, 0.3, 8000.0, 10.0
#: the first eight (m, n) of the square plate in order of m^2 + n^2, each pair counted twice
MODES_1_TO_8 = [(1, 1), (1, 2), (2, 1), (2, 2), (1, 3), (3, 1), (2, 3), (3, 2)]


def _dofs(nodes_idx, comps):
    return (6 * np.asarray(nodes_idx)[:, None] + np.asarray(comps)).ravel()


def _ss_fixed(nodes):
    """Hard simple support on the edges of [0, A]^2 (w and the tangential rotation held) and no
    in-plane motion (u, v, rz held everywhere: the flat plate's bending modes only)."""
    x, y = nodes[:, 0], nodes[:, 1]
    ex = np.flatnonzero((x < 1e-9) | (x > A - 1e-9))
    ey = np.flatnonzero((y < 1e-9) | (y > A - 1e-9))
    return np.concatenate(
        [_dofs(ex, [2, 3]), _dofs(ey, [2, 4]), _dofs(np.arange(len(x)), [0, 1, 5])]
    )


def _frequencies(mesh, lumped=False, n=8):
    K, M = ShellAssembly(mesh, lumped=lumped).assemble()
    r = solve_sparse_modes(K, M, mesh.nodes, ModalSettings(n_modes=n), _ss_fixed(mesh.nodes))
    return r.frequencies_hz


def _kirchhoff(t, m, n, rotary=False):
    """Simply supported square Kirchhoff plate (Leissa, *Vibration of Plates*, 1969, eq. 4.3),
    f = (pi / 2) (m^2 + n^2) / a^2 sqrt(D / (rho t)); ``rotary``: with the rotary inertia
    rho t^3 / 12 of the Rayleigh plate, rho t w^2 (1 + t^2 k^2 / 12) = D k^4."""
    D = E * t**3 / (12 * (1 - NU**2))
    k2 = (np.pi / A) ** 2 * (m * m + n * n)
    return np.sqrt(D * k2**2 / (RHO * t * (1 + (t * t * k2 / 12 if rotary else 0.0)))) / (2 * np.pi)


def _tria_plate(n, t, diagonals="same"):
    """n x n cells on [0, A]^2, each cut into two triangles along the same diagonal (``same``)
    or in a checkerboard."""
    nodes, quads, _ = sm.plate(A, A, n, n)
    flip = np.zeros(len(quads), bool)
    if diagonals == "checker":
        flip = (np.repeat(np.arange(n), n) + np.tile(np.arange(n), n)) % 2 == 1
    return shell_mesh(nodes, None, sm.split_quads(quads, flip), thickness=t, E=E, nu=NU, rho=RHO)


@pytest.mark.parametrize(
    "slenderness, lumped",
    [(100, False), (100, True), (1000, False)],
    ids=["a/t=100", "a/t=100-lumped", "a/t=1000"],
)
def test_ctria3_simply_supported_plate_modes_1_to_8_within_1_percent(slenderness, lumped):
    t = A / slenderness
    ref = np.array([_kirchhoff(t, m, n) for m, n in MODES_1_TO_8])
    f = _frequencies(_tria_plate(32, t), lumped)
    np.testing.assert_allclose(f, ref, rtol=0.01)
    # consistent mass bounds the frequencies from above (as the quads' does), lumped from below
    assert np.all(f > ref) if not lumped else np.all(f < ref)


def test_triangles_converge_at_rate_two_without_locking():
    """Checkerboard triangles, a/t = 1000: the error falls by 4 per mesh halving (rate 2), as a
    Kirchhoff element's does; a locking element's error would not fall at that rate."""
    t = A / 1000
    ref = np.array([_kirchhoff(t, m, n) for m, n in MODES_1_TO_8[:6]])
    coarse = _frequencies(_tria_plate(12, t, "checker"), n=6)
    fine = _frequencies(_tria_plate(24, t, "checker"), n=6)
    rate = np.log2((coarse - ref) / (fine - ref))
    assert np.all((rate > 1.8) & (rate < 2.3)), rate


def test_thick_plate_converges_to_the_rayleigh_plate_not_mindlin():
    """a/t = 10: the DKT triangle has no transverse shear flexibility, so it matches the
    Kirchhoff plate with rotary inertia (within 0.5 %, measured) and is stiffer than the Mindlin
    plate by the shear share of the mode: 2.8 % on mode 1 to 15.4 % on mode 8 here (the closed
    forms differ by 2.7-14.3 %; at a/t = 20 by 0.7-4.3 %, at a/t = 50 by 0.1-0.7 %)."""
    t = A / 10
    rayleigh = np.array([_kirchhoff(t, m, n, rotary=True) for m, n in MODES_1_TO_8])
    mindlin = np.array([Plate(A, E, NU, RHO).mindlin_hz(t, m, n) for m, n in MODES_1_TO_8])
    f = _frequencies(_tria_plate(32, t))
    np.testing.assert_allclose(f, rayleigh, rtol=0.01)
    np.testing.assert_allclose(f / mindlin, rayleigh / mindlin, rtol=0.01)
    assert np.all(f / mindlin - 1 > 0.02)


def test_mixed_quad_and_triangle_plate():
    """Left half MITC4 quads, right half triangles on the same grid (shared nodes on x = A/2):
    modes 1-8 within 1 % of Kirchhoff at a/t = 100, like either mesh alone."""
    t = A / 100
    nodes, quads, _ = sm.plate(A, A, 32, 32)
    right = nodes[quads].mean(axis=1)[:, 0] > A / 2
    trias = sm.split_quads(quads[right], np.zeros(right.sum(), bool))
    mesh = shell_mesh(nodes, quads[~right], trias, thickness=t, E=E, nu=NU, rho=RHO)
    ref = np.array([_kirchhoff(t, m, n) for m, n in MODES_1_TO_8])
    np.testing.assert_allclose(_frequencies(mesh), ref, rtol=0.01)


def _irregular_triangles():
    """The MacNeal-Harder irregular 5-quad patch (0.24 x 0.12 m) cut into 10 triangles."""
    xy = np.array([[0, 0], [0.24, 0], [0.24, 0.12], [0, 0.12], [0.04, 0.02], [0.18, 0.03],
                   [0.16, 0.08], [0.08, 0.08]])  # fmt: skip
    quads = np.array([[0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7], [4, 5, 6, 7]])
    return xy, sm.split_quads(quads)


def test_dkt_bending_energy_of_a_constant_curvature_is_exact():
    """Element form of the bending patch test on distorted triangles: for w = -(a x^2 + b y^2 +
    c x y) / 2 and beta = -grad w at the corners, d^T Kb d = kappa^T D kappa x area, with the
    constant curvature kappa = (a, b, c) and D the plane-stress matrix times E / 12 (per t^3)."""
    xy, trias = _irregular_triangles()
    x = xy[trias]
    ops = shell.tria_operators(x - x.mean(axis=1, keepdims=True))
    nu = np.full(len(trias), NU)
    Kb = shell.local_pieces(ops, np.full(len(trias), E), nu).bending
    a, b, c = 1e-2, -2e-2, 3e-2
    d = np.zeros((len(trias), 3, 6))
    px, py = x[..., 0], x[..., 1]
    d[..., 2] = -0.5 * (a * px**2 + b * py**2 + c * px * py)
    d[..., 4] = a * px + 0.5 * c * py  # ry = beta_x = -w,x
    d[..., 3] = -(b * py + 0.5 * c * px)  # rx = -beta_y = w,y
    d = d.reshape(len(trias), 18)
    kappa = np.array([a, b, c])
    e1, e2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    D = E / 12 / (1 - NU**2) * np.array([[1, NU, 0], [NU, 1, 0], [0, 0, (1 - NU) / 2]])
    np.testing.assert_allclose(np.einsum("ni,nij,nj->n", d, Kb, d), kappa @ D @ kappa * area,
                               rtol=1e-10)  # fmt: skip
    # the curvature itself is the constant one at every integration point
    curv = np.einsum("nqkj,nj->nqk", ops.Bb, d)
    np.testing.assert_allclose(curv, np.broadcast_to(kappa, curv.shape), rtol=1e-10, atol=1e-14)


def test_free_curved_triangle_patch_has_exactly_six_rigid_modes():
    """Irregular triangles on a cylinder of radius 0.2 m (no two elements coplanar): the
    stiffness has exactly six zero eigenvalues (the rigid motions), at two thicknesses, and
    the DKT rotations reproduce a rigid tilt (no curvature)."""
    xy, trias = _irregular_triangles()
    phi = xy[:, 0] / 0.2
    nodes = np.column_stack([0.2 * np.sin(phi), xy[:, 1], 0.2 * (1 - np.cos(phi))])
    for t in (1e-3, 2e-2):
        mesh = shell_mesh(nodes, None, trias, thickness=t, E=E, nu=NU, rho=RHO)
        lam = np.linalg.eigvalsh(ShellAssembly(mesh).assemble()[0].toarray())
        assert np.sum(np.abs(lam) < 1e-9 * lam.max()) == 6, np.sort(np.abs(lam))[:8]
    # a rigid tilt w = 0.3 x - 0.2 y + 1 (beta = -grad w) gives zero curvature in every triangle
    x = xy[trias]
    d = np.zeros((len(trias), 3, 6))
    d[..., 2] = 0.3 * x[..., 0] - 0.2 * x[..., 1] + 1
    d[..., 4], d[..., 3] = -0.3, -0.2
    A_rot = shell_tria.rotation_nodes(x)
    beta = np.einsum("nmcj,nj->nmc", A_rot, d.reshape(len(trias), 18))
    np.testing.assert_allclose(beta, np.broadcast_to([-0.3, 0.2], beta.shape), atol=1e-14)


def test_triangle_matrices_are_exact_thickness_polynomials():
    """K(t) = t K1 + t^3 K3 and, with an offset ratio, the t^2 terms: the power form equals the
    directly built matrices at three thicknesses (the affine split the reduced basis uses)."""
    xy, trias = _irregular_triangles()
    x = np.concatenate([xy, 0 * xy[:, :1]], axis=1)[trias]
    f = shell.tria_frames(x)
    n = len(trias)
    source = shell.PieceSource(f.xy, None, np.full(n, E), np.full(n, NU))
    p = source.pieces(np.arange(n))
    K = assert_thickness_polynomials(p, n, RHO)
    assert sorted(K) == [1, 2, 3] and not np.any(p.shear)


def _ctria3_deck(path, n, t):
    """A SOL 103 deck (SI) of the simply supported plate in n x n x 2 CTRIA3 (one diagonal),
    written by ``studies/pshell_ratios.plate_deck``."""
    pshell, mat1 = f"PSHELL,1,1,{t:.4f},1,,1", f"MAT1,1,{E:.3E},,{NU:.2f},{RHO:.1f}"
    return plate_deck(path, n, t, pshell, triangles=True, a=A, mat1=mat1)


def test_ctria3_deck_of_the_plate_through_modes(tmp_path, capsys):
    """The same plate as a Nastran deck (CTRIA3, PSHELL, MAT1, SPC1) through ``bayesupdate modes
    --model`` (the reader keeps consistent shell mass): modes 1-8 within 1 % of Kirchhoff at
    a/t = 100 (measured +0.11 ... +0.93 %, as the mesh built directly)."""
    import json

    from bayesupdate.cli import main

    t = A / 100
    deck = _ctria3_deck(tmp_path / "ctria3_plate.bdf", 32, t)
    assert main(["modes", "--model", str(deck), "--modes", "8", "--json"]) == 0
    f = np.array(json.loads(capsys.readouterr().out)["frequencies_hz"])
    ref = np.array([_kirchhoff(t, m, n) for m, n in MODES_1_TO_8])
    np.testing.assert_allclose(f, ref, rtol=0.01)
