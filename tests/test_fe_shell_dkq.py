"""The shear-rigid shell quadrilateral (discrete Kirchhoff quadrilateral, ``fe.elements.shell_dkq``;
``ShellMesh`` ``shear_ratio`` inf; a PSHELL with MID3 blank) against closed forms.

Tolerances and why:
- patch tests and rigid motions: exact to round-off (1e-10 relative);
- simply supported square plate, a/t = 100, against Kirchhoff (Leissa 1969, eq. 4.3): 32 x 32
  quads measured +0.08 to +0.63 % on modes 1-8, convergence rate 2.08-2.11; asserted 1 % (the
  MITC4 quads' level) and rate in (1.8, 2.3);
- a/t = 10: the element has no transverse shear flexibility, so it converges to the Rayleigh
  plate (Kirchhoff's with the rotary inertia rho t^3 / 12 the element carries), measured +0.09
  to +0.67 % at 32 x 32, rate 2.00-2.01, and not to Mindlin's, 2.7-14.3 % below it;
- a mesh mixing both kinds of quad and triangles: K and M are the all-DKQ mesh's on the
  shear-rigid elements plus the all-MITC4 mesh's on the others to 1e-12;
- a deck with MID3 blank through ``bayesupdate modes --model``: the mesh built directly with
  ``shear_ratio`` inf to 1e-8 (``--json`` prints about nine digits), and above the same deck
  with MID3 = MID1 by more than 2 % on every mode at a/t = 10.
"""

import json
import sys
from pathlib import Path

import numpy as np

from bayesupdate.cli import main
from bayesupdate.fe import shell_mesh as sm
from bayesupdate.fe.elements import shell
from bayesupdate.fe.shell_model import ShellAssembly, shell_mesh
from bayesupdate.fe.sparse_modal import ModalSettings, solve_sparse_modes

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "studies"))
from pshell_ratios import MODES_1_TO_8, STEEL, plate_deck  # noqa: E402
from shell_powers import assert_thickness_polynomials  # noqa: E402

A, E, NU, RHO = STEEL.a, STEEL.E, STEEL.nu, STEEL.rho
#: a distorted quadrilateral [m] (no two sides parallel)
DISTORTED = np.array([[0.0, 0.0], [2.0, 0.2], [2.3, 1.8], [-0.2, 1.5]])


def _ss_fixed(nodes):
    """Hard simple support on the edges of [0, A]^2 (w and the tangential rotation held) and
    u, v, rz held everywhere (the flat plate's bending modes only)."""
    x, y = nodes[:, 0], nodes[:, 1]
    dofs = lambda idx, comps: (6 * idx[:, None] + np.asarray(comps)).ravel()  # noqa: E731
    ex = np.flatnonzero((x < 1e-9) | (x > A - 1e-9))
    ey = np.flatnonzero((y < 1e-9) | (y > A - 1e-9))
    return np.concatenate([dofs(ex, [2, 3]), dofs(ey, [2, 4]), dofs(np.arange(len(x)), [0, 1, 5])])


def _plate_hz(n, t):
    nodes, quads, _ = sm.plate(A, A, n, n)
    mesh = shell_mesh(nodes, quads, thickness=t, E=E, nu=NU, rho=RHO, shear_ratio=np.inf)
    K, M = ShellAssembly(mesh).assemble()
    r = solve_sparse_modes(K, M, mesh.nodes, ModalSettings(n_modes=8), _ss_fixed(mesh.nodes))
    return r.frequencies_hz


def test_a_constant_curvature_is_reproduced_exactly_on_a_distorted_quad():
    """w = a x^2 + b x y + c y^2 with beta = -grad w at the corners: the curvature is the
    constant (-2a, -2c, -2b) at every Gauss point (the bending patch test of the element)."""
    a, b, c = 0.3, -0.2, 0.5
    d = np.zeros(24)
    for k, (x, y) in enumerate(DISTORTED):
        d[6 * k + 2] = a * x * x + b * x * y + c * y * y
        d[6 * k + 3] = b * x + 2 * c * y  # rx = -beta_y = w,y
        d[6 * k + 4] = -(2 * a * x + b * y)  # ry = beta_x = -w,x
    kappa = np.einsum("qrj,j->qr", shell.quad_operators(DISTORTED[None], kirchhoff=True).Bb[0], d)
    np.testing.assert_allclose(kappa, np.broadcast_to([-2 * a, -2 * c, -2 * b], kappa.shape),
                               rtol=1e-12, atol=1e-12)  # fmt: skip


def test_a_free_quad_has_exactly_six_rigid_modes_and_no_shear_stiffness():
    ops = shell.quad_operators(DISTORTED[None], kirchhoff=True)
    p = shell.local_pieces(ops, np.array([E]), np.array([NU]))
    assert not np.any(p.shear)
    t = 0.01
    lam = np.linalg.eigvalsh(t * (p.membrane + p.drilling)[0] + t**3 * p.bending[0])
    assert np.sum(np.abs(lam) < 1e-10 * lam.max()) == 6, np.sort(np.abs(lam))[:8]


def test_the_thin_plate_converges_to_kirchhoff():
    t = A / 100
    ref = np.array([STEEL.kirchhoff_hz(t, m, n) for m, n in MODES_1_TO_8])
    coarse, fine = _plate_hz(16, t), _plate_hz(32, t)
    np.testing.assert_allclose(fine, ref, rtol=0.01)
    rate = np.log2((coarse - ref) / (fine - ref))
    assert np.all((rate > 1.8) & (rate < 2.3)), rate


def test_the_thick_plate_converges_to_the_rayleigh_plate_not_mindlin():
    t = A / 10
    rayleigh = np.array([STEEL.kirchhoff_hz(t, m, n, rotary=True) for m, n in MODES_1_TO_8])
    mindlin = np.array([STEEL.mindlin_hz(t, m, n) for m, n in MODES_1_TO_8])
    coarse, fine = _plate_hz(16, t), _plate_hz(32, t)
    np.testing.assert_allclose(fine, rayleigh, rtol=0.01)
    rate = np.log2((coarse - rayleigh) / (fine - rayleigh))
    assert np.all((rate > 1.8) & (rate < 2.3)), rate
    assert np.all(fine / mindlin - 1 > 0.02)  # not Mindlin's plate: no shear flexibility


def _modes(deck, capsys) -> np.ndarray:
    assert main(["modes", "--model", str(deck), "--modes", "8", "--json"]) == 0
    return np.array(json.loads(capsys.readouterr().out)["frequencies_hz"])


def test_a_pshell_with_mid3_blank_is_shear_rigid(tmp_path, capsys):
    """MSC QRG PSHELL: no transverse shear flexibility without MID3.  Through ``modes
    --model`` the deck is the mesh built directly with ``shear_ratio`` inf, and stiffer than
    the same deck with MID3 = MID1 by the shear share of each mode."""
    t = A / 10
    rigid = _modes(plate_deck(tmp_path / "rigid.bdf", 16, t, f"PSHELL,1,1,{t},1"), capsys)
    mindlin = _modes(plate_deck(tmp_path / "mindlin.bdf", 16, t, f"PSHELL,1,1,{t},1,,1"), capsys)
    np.testing.assert_allclose(rigid, _plate_hz(16, t), rtol=1e-8)  # --json's printed digits
    assert np.all(rigid / mindlin - 1 > 0.02)


def test_its_matrices_are_exact_thickness_polynomials():
    """K(t) = t K1 + t^3 K3 (and the offset's t^2 terms): the power form equals the directly
    built matrices at three thicknesses (the affine split a PSHELL T binding and the reduced
    basis use)."""
    x = np.concatenate([DISTORTED, np.zeros((4, 1))], axis=1)[None].repeat(3, axis=0)
    x[1, :, :2] *= 0.5
    x[2, :, :2] = x[2, :, :2] @ np.array([[0.8, 0.6], [-0.6, 0.8]])
    f = shell.quad_frames(x)
    n = len(x)
    p = shell.PieceSource(f.xy, None, np.full(n, E), np.full(n, NU), kirchhoff=True)
    pieces = p.pieces(np.arange(n))
    K = assert_thickness_polynomials(pieces, n, RHO)
    assert sorted(K) == [1, 2, 3] and not np.any(pieces.shear)


def test_shear_rigid_and_mitc4_quads_mix_in_one_mesh():
    """Quads of two kinds in one mesh (some PSHELLs with MID3, some without) with triangles
    beside them: each element keeps its own kind, the assembled K and M are the all-DKQ mesh's
    on the shear-rigid elements plus the all-MITC4 mesh's on the others (1e-12), and the plate
    converges to Kirchhoff at a/t = 100 (within 1 % at 32 x 32)."""
    t = A / 100
    nodes, quads, _ = sm.plate(A, A, 32, 32)
    right = nodes[quads].mean(axis=1)[:, 0] > 0.75 * A
    trias = sm.split_quads(quads[right], np.zeros(right.sum(), bool))
    quads = quads[~right]
    rigid = np.random.default_rng(0).uniform(size=len(quads)) < 0.5
    n_el = len(quads) + len(trias)
    shear = np.full(n_el, 5 / 6)
    shear[: len(quads)][rigid] = np.inf

    def mesh(ratio):
        return shell_mesh(nodes, quads, trias, thickness=t, E=E, nu=NU, rho=RHO,
                          shear_ratio=ratio)  # fmt: skip

    mixed = ShellAssembly(mesh(shear)).assemble()
    chosen = np.r_[rigid, np.zeros(len(trias), bool)]
    dkq = ShellAssembly(mesh(np.full(n_el, np.inf))).assemble(include=chosen)
    mitc = ShellAssembly(mesh(np.full(n_el, 5 / 6))).assemble(include=~chosen)
    for X, Y, Z in zip(mixed, dkq, mitc, strict=True):
        np.testing.assert_allclose((X - Y - Z).toarray(), 0.0, atol=1e-12 * abs(X).max())
    K, M = mixed
    m = mesh(shear)
    f = solve_sparse_modes(K, M, m.nodes, ModalSettings(n_modes=8), _ss_fixed(m.nodes))
    ref = np.array([STEEL.kirchhoff_hz(t, i, j) for i, j in MODES_1_TO_8])
    np.testing.assert_allclose(f.frequencies_hz, ref, rtol=0.01)
