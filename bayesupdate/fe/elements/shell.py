"""Flat shell elements (4-node quadrilateral, 3-node triangle), vectorized over elements.

Local DOFs per node (6): [u v w rx ry rz] in the element frame (x, y in the element plane, z its
normal); displacements in m, rotations in rad.  Mindlin-Reissner kinematics with the rotations
about the local axes: a point at height z above the reference plane moves by
u + z ry, v - z rx, so the section rotations are beta_x = ry, beta_y = -rx.

Quadrilateral (24 DOFs):

* transverse shear: MITC4, covariant shear strains tied at the edge mid-points
  (Dvorkin & Bathe, Eng. Comput. 1 (1984) 77, eqs 9-11; Bathe, *Finite Element Procedures*,
  2014, sec. 5.4.2), so the element does not lock in shear;
* bending: bilinear rotations, 2x2 Gauss;
* membrane: bilinear displacements plus the four incompatible modes (1 - xi^2), (1 - eta^2) of
  Taylor, Beresford & Wilson (IJNME 10 (1976) 1211) with their Jacobian at the centre (so the
  constant-strain patch test holds), statically condensed per element; this removes the
  parasitic shear of the bilinear membrane in in-plane bending;
* drilling: a penalty alpha G t on (rz - omega), omega = (v,x - u,y)/2 the in-plane rotation of
  the membrane field (Hughes & Brezzi, CMAME 72 (1989) 105), 2x2 Gauss, alpha = DRILL_ALPHA.
  It vanishes for rigid motions, so a free element keeps exactly six zero modes.

Triangle (18 DOFs): bending of the Discrete Kirchhoff Triangle (Batoz, Bathe & Ho, IJNME 15
(1980) 1771; ``shell_tria``), which is shear rigid (Kirchhoff) and so free of shear locking with
its stiffness a t^3 term; CST membrane and the same drilling penalty (linear fields, mid-edge
rule).  The MITC3 triangle it replaces locked on uniform meshes of thin plates (``shell_tria``).

Mass per unit area: (rho t + nsm) on translations and rho t^3 / 12 on the two bending rotations
(rotary inertia), none on the drilling rotation; consistent (shape functions, exact quadrature) or
lumped (row sums).

Offset: the nodes lie on a reference plane at distance e = offset + offset_ratio * t *below* the
mid-surface (e > 0 puts the mid-surface on the +z side); the mid-surface motion is
T(e) d with u_mid = u + e ry, v_mid = v - e rx, so membrane stiffness and translational mass
become T^T X T (Nastran's ZOFFS with the sign of the element normal).  The non-structural mass
sits on the reference plane.

Thickness powers: every matrix is an exact polynomial in the element's thickness t,
K(t) = t K1 + t^2 K2 + t^3 K3 and M(t) = M0 + t M1 + t^2 M2 + t^3 M3 (t^2 only with an
offset_ratio), see ``power_matrices``.  Units: m, Pa, kg/m^3, kg/m^2.
"""

from dataclasses import dataclass, replace

import numpy as np

from bayesupdate.fe.elements import shell_dkq, shell_tria
from bayesupdate.fe.laminate import SectionMatrices

#: drilling penalty as a fraction of the in-plane shear modulus (Hughes & Brezzi 1989 allow
#: any gamma > 0).  Measured on the free cylinder (48 x 60 quads): alpha 1e-5 -> 1e-3 moves the
#: first two mode pairs by < 0.01 % and the 4th-6th by 0.1-0.2 %; 1 stiffens them by ~0.3 %.
#: Flat plates are unaffected (drilling decouples from bending).
DRILL_ALPHA = 1e-3
#: transverse shear correction factor (Reissner)
SHEAR_FACTOR = 5.0 / 6.0

_G = 1.0 / np.sqrt(3.0)
_QUAD_XI = np.array([-1.0, 1.0, 1.0, -1.0])
_QUAD_ETA = np.array([-1.0, -1.0, 1.0, 1.0])
_GAUSS_2x2 = np.array([[-_G, -_G], [_G, -_G], [_G, _G], [-_G, _G]])
# triangle: mid-edge rule (exact for quadratics), weights sum to the reference area 1/2
_TRI_PTS = np.array([[0.5, 0.0], [0.5, 0.5], [0.0, 0.5]])
_TRI_W = np.full(3, 1.0 / 6.0)

U, V, W, RX, RY, RZ = range(6)


@dataclass(frozen=True)
class ElementFrames:
    """Local element frames.  R : (n, 3, 3) rows = local x, y, z (normal) in global axes;
    xy : (n, k, 2) node coordinates in the element plane [m]; warp : (n,) largest node distance
    from the mean plane divided by the mean diagonal (quads; 0 for triangles); area : (n,) [m^2];
    height : (n, k) node distances from the element plane along its normal [m] (0 for
    triangles), used by ``warp_link``.
    """

    R: np.ndarray
    xy: np.ndarray
    warp: np.ndarray
    area: np.ndarray
    height: np.ndarray | None = None


def _unit(v):
    with np.errstate(invalid="ignore", divide="ignore"):  # degenerate elements: checked later
        return v / np.linalg.norm(v, axis=-1, keepdims=True)


def quad_frames(x: np.ndarray) -> ElementFrames:
    """Frames of quads with node coordinates x (n, 4, 3) [m]: normal along the cross product of
    the diagonals, local x along the mean xi-direction projected on the mean plane."""
    c = x.mean(axis=1)
    d1, d2 = x[:, 2] - x[:, 0], x[:, 3] - x[:, 1]
    cross = np.cross(d1, d2)
    area = 0.5 * np.linalg.norm(cross, axis=1)
    ez = _unit(cross)
    g1 = 0.5 * (x[:, 1] + x[:, 2] - x[:, 0] - x[:, 3])
    ex = _unit(g1 - np.einsum("ni,ni->n", g1, ez)[:, None] * ez)
    ey = np.cross(ez, ex)
    R = np.stack([ex, ey, ez], axis=1)
    rel = np.einsum("nkj,nij->nki", x - c[:, None], R)
    diag = 0.5 * (np.linalg.norm(d1, axis=1) + np.linalg.norm(d2, axis=1))
    warp = np.max(np.abs(rel[:, :, 2]), axis=1) / diag
    return ElementFrames(R, rel[:, :, :2], warp, area, rel[:, :, 2])


def tria_frames(x: np.ndarray) -> ElementFrames:
    """Frames of triangles x (n, 3, 3) [m]: local x along edge 1-2, z along the normal."""
    c = x.mean(axis=1)
    cross = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    area = 0.5 * np.linalg.norm(cross, axis=1)
    ez = _unit(cross)
    ex = _unit(x[:, 1] - x[:, 0])
    ey = np.cross(ez, ex)
    R = np.stack([ex, ey, ez], axis=1)
    rel = np.einsum("nkj,nij->nki", x - c[:, None], R)
    return ElementFrames(R, rel[:, :, :2], np.zeros(len(x)), area, np.zeros(x.shape[:2]))


def plane_stress(nu):
    """(n, 3, 3) plane-stress elasticity per unit E: [[1, nu, 0], [nu, 1, 0], [0, 0, (1-nu)/2]]
    / (1 - nu^2)."""
    D = np.zeros(nu.shape + (3, 3))
    D[:, 0, 0] = D[:, 1, 1] = 1.0
    D[:, 0, 1] = D[:, 1, 0] = nu
    D[:, 2, 2] = 0.5 * (1.0 - nu)
    return D / (1.0 - nu**2)[:, None, None]


def _quad_shape(xi, eta):
    """Bilinear N (4,), dN/dxi (4,), dN/deta (4,) at one point."""
    N = 0.25 * (1 + _QUAD_XI * xi) * (1 + _QUAD_ETA * eta)
    return N, 0.25 * _QUAD_XI * (1 + _QUAD_ETA * eta), 0.25 * _QUAD_ETA * (1 + _QUAD_XI * xi)


@dataclass(frozen=True)
class _Operators:
    """Strain-displacement operators at the q integration points of n elements with k nodes.
    Bm, Bb : (n, q, 3, 6k) membrane strain, curvature; Bs : (n, q, 2, 6k) transverse shear;
    Bd : (n, q, 6k) drilling (rz - omega); N : (q, k) shape functions; wdet : (n, q) weights x
    det J [m^2]; Ginc : (n, q, 3, 4) incompatible-mode strains (quads) or None."""

    Bm: np.ndarray
    Bb: np.ndarray
    Bs: np.ndarray
    Bd: np.ndarray
    N: np.ndarray
    wdet: np.ndarray
    Ginc: np.ndarray | None


def _fill_common(n, q, k, N, dNx, dNy):
    """Membrane, bending and drilling operators from N (q, k), dN/dx, dN/dy (n, q, k)."""
    nd = 6 * k
    Bm = np.zeros((n, q, 3, nd))
    Bb = np.zeros((n, q, 3, nd))
    Bd = np.zeros((n, q, nd))
    Bm[:, :, 0, U::6] = dNx
    Bm[:, :, 1, V::6] = dNy
    Bm[:, :, 2, U::6] = dNy
    Bm[:, :, 2, V::6] = dNx
    Bb[:, :, 0, RY::6] = dNx  # kappa_x = d(beta_x)/dx, beta_x = ry
    Bb[:, :, 1, RX::6] = -dNy  # kappa_y = d(beta_y)/dy, beta_y = -rx
    Bb[:, :, 2, RY::6] = dNy
    Bb[:, :, 2, RX::6] = -dNx
    Bd[:, :, RZ::6] = N
    Bd[:, :, V::6] = -0.5 * dNx
    Bd[:, :, U::6] = 0.5 * dNy
    return Bm, Bb, Bd


def _covariant_shear(xy, N, dNr, k):
    """Covariant transverse shear e_r = w,r + beta . x,r at one point, (n, 6k) row, for the
    natural direction whose shape-function derivatives are dNr (k,)."""
    x_r = np.einsum("k,nkd->nd", dNr, xy)
    row = np.zeros((xy.shape[0], 6 * k))
    row[:, W::6] = dNr
    row[:, RY::6] = N[None, :] * x_r[:, 0:1]
    row[:, RX::6] = -N[None, :] * x_r[:, 1:2]
    return row


def quad_operators(xy: np.ndarray, kirchhoff: bool = False) -> _Operators:
    """MITC4 / bilinear / incompatible-mode operators at 2x2 Gauss points, xy (n, 4, 2) [m].
    ``kirchhoff``: the shear-rigid quadrilateral instead (a PSHELL with MID3 blank): the
    curvatures of the discrete Kirchhoff quadrilateral (``shell_dkq.dkq_curvature``) and no
    transverse shear rows; the membrane and drilling are the same."""
    n = xy.shape[0]
    shapes = [_quad_shape(*p) for p in _GAUSS_2x2]
    N = np.array([s[0] for s in shapes])
    dnat = np.array([[s[1], s[2]] for s in shapes])  # (q, 2, 4)
    J = np.einsum("qak,nkd->nqad", dnat, xy)  # rows: d/dxi, d/deta of (x, y)
    det = J[..., 0, 0] * J[..., 1, 1] - J[..., 0, 1] * J[..., 1, 0]
    Jinv = np.linalg.inv(J)
    dN = np.einsum("nqab,qbk->nqak", Jinv, dnat)  # (n, q, 2, 4): d/dx, d/dy
    Bm, Bb, Bd = _fill_common(n, 4, 4, N, dN[:, :, 0], dN[:, :, 1])
    if kirchhoff:
        Bb = shell_dkq.dkq_curvature(xy, Jinv, _GAUSS_2x2)
        Bs = np.zeros((n, len(_GAUSS_2x2), 0, 24))
    else:
        Bs = _mitc4_shear(xy, Jinv)
    return _Operators(Bm, Bb, Bs, Bd, N, det, _incompatible_modes(xy, det))


def _mitc4_shear(xy: np.ndarray, Jinv: np.ndarray) -> np.ndarray:
    """(n, q, 2, 24) MITC4 transverse shear at the 2x2 Gauss points, with the inverse
    Jacobians Jinv (n, q, 2, 2) there: the covariant strains tied at the edge mid-points."""
    # MITC4 tying: e_xi at A (0, 1), C (0, -1); e_eta at B (1, 0), D (-1, 0)
    tie = {}
    for name, (xi, eta, direction) in {
        "A": (0.0, 1.0, 1),
        "C": (0.0, -1.0, 1),
        "B": (1.0, 0.0, 2),
        "D": (-1.0, 0.0, 2),
    }.items():
        s = _quad_shape(xi, eta)
        tie[name] = _covariant_shear(xy, s[0], s[direction], 4)
    g = _GAUSS_2x2
    e_xi = (
        0.5 * (1 + g[:, 1])[None, :, None] * tie["A"][:, None]
        + 0.5 * (1 - g[:, 1])[None, :, None] * tie["C"][:, None]
    )
    e_eta = (
        0.5 * (1 + g[:, 0])[None, :, None] * tie["B"][:, None]
        + 0.5 * (1 - g[:, 0])[None, :, None] * tie["D"][:, None]
    )
    return np.einsum("nqab,nqbj->nqaj", Jinv, np.stack([e_xi, e_eta], axis=2))


def _incompatible_modes(xy, det):
    """(n, q, 3, 4) strains of the modes a1 u(1-xi^2), a2 u(1-eta^2), a3 v(1-xi^2),
    a4 v(1-eta^2) with the centre Jacobian J0 and the factor det J0 / det J (Taylor et al. 1976),
    so that their integral over the element vanishes (patch test)."""
    _, dxi0, deta0 = _quad_shape(0.0, 0.0)
    J0 = np.einsum("ak,nkd->nad", np.array([dxi0, deta0]), xy)
    J0inv = np.linalg.inv(J0)
    det0 = np.linalg.det(J0)
    g = _GAUSS_2x2
    # natural derivatives of P1 = 1 - xi^2 and P2 = 1 - eta^2: (q, 2 [d/dxi, d/deta], 2 [P1, P2])
    dP = np.zeros((4, 2, 2))
    dP[:, 0, 0] = -2 * g[:, 0]
    dP[:, 1, 1] = -2 * g[:, 1]
    dPx = np.einsum("nab,qbp->nqap", J0inv, dP) * (det0[:, None] / det)[:, :, None, None]
    G = np.zeros(xy.shape[:1] + (4, 3, 4))
    G[:, :, 0, 0:2] = dPx[:, :, 0]
    G[:, :, 1, 2:4] = dPx[:, :, 1]
    G[:, :, 2, 0:2] = dPx[:, :, 1]
    G[:, :, 2, 2:4] = dPx[:, :, 0]
    return G


def tria_operators(xy: np.ndarray) -> _Operators:
    """DKT / CST operators at the three mid-edge points, xy (n, 3, 2) [m]: the curvatures of the
    discrete Kirchhoff triangle (``shell_tria.dkt_curvature``), no transverse shear rows (the
    element is shear rigid), linear membrane and drilling fields."""
    n = xy.shape[0]
    r, s = _TRI_PTS[:, 0], _TRI_PTS[:, 1]
    N = np.stack([1 - r - s, r, s], axis=1)  # (q, 3)
    dnat = np.array([[-1.0, 1.0, 0.0], [-1.0, 0.0, 1.0]])
    J = np.einsum("ak,nkd->nad", dnat, xy)
    det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
    Jinv = np.linalg.inv(J)
    dN = np.einsum("nab,bk->nak", Jinv, dnat)
    dNx = np.broadcast_to(dN[:, None, 0], (n, 3, 3))
    dNy = np.broadcast_to(dN[:, None, 1], (n, 3, 3))
    Bm, _, Bd = _fill_common(n, 3, 3, N, dNx, dNy)
    Bb = shell_tria.dkt_curvature(xy, Jinv, _TRI_PTS)
    wdet = det[:, None] * _TRI_W[None, :]
    return _Operators(Bm, Bb, np.zeros((n, 3, 0, 18)), Bd, N, wdet, None)


def _quadrature_form(B, D, wdet, C=None):
    """sum_q wdet B^T D C for B (n, q, r, d), C (n, q, r, e) (default B), D (n, r, r) or None
    (identity) -> (n, d, e), as one batched matrix product over the stacked (q, r) rows."""
    C = B if C is None else C
    n, q, r, _ = B.shape
    DC = C if D is None else np.matmul(D[:, None], C)
    Bw = (B * wdet[:, :, None, None]).reshape(n, q * r, B.shape[3])
    return np.matmul(Bw.transpose(0, 2, 1), DC.reshape(n, q * r, C.shape[3]))


@dataclass(frozen=True)
class LocalPieces:
    """Thickness-free element matrices in local axes, (n, d, d) each (d = 6 x nodes).

    membrane : E x int B^T D B (incompatible modes condensed) [N/m per unit t];
    shear : kappa G x int Bs^T Bs; drilling : alpha G x int Bd^T Bd;
    bending : (bending ratio) E/12 x int Bb^T D Bb
    (per unit t^3); mass_t : translational mass per unit mass-per-area [m^2];
    mass_r : rotary mass of rx, ry per unit (mass-per-area x m^2) [m^2]; offset : (d, d) S with
    T(e) = I + e S; coupling : membrane-bending coupling int (Bm^T b Bb + Bb^T b Bm) (per unit
    t^2; an unsymmetric laminate, ``fe.laminate``) or None.
    """

    membrane: np.ndarray
    shear: np.ndarray
    drilling: np.ndarray
    bending: np.ndarray
    mass_t: np.ndarray
    mass_r: np.ndarray
    offset: np.ndarray
    coupling: np.ndarray | None = None


def local_pieces(
    ops: _Operators, E, nu, lumped: bool = False, bending_ratio=None, shear_ratio=None,
    bending_nu=None, membrane_ratio=None, section=None,
) -> LocalPieces:  # fmt: skip
    """Element pieces from operators and (n,) E [Pa], nu.  ``lumped``: row-sum mass.

    bending_ratio (n,) or None (1): the bending inertia over that of the solid section,
    I / (t^3 / 12) (Nastran PSHELL 12I/T**3: a sandwich's faces carry its bending), so the
    bending piece is bending_ratio E / 12 x int Bb^T D Bb; shear_ratio (n,) or None
    (``SHEAR_FACTOR``): the transverse shear thickness over t (PSHELL TS/T), the shear piece's
    kappa; bending_nu (n,) or None (nu): the Poisson ratio of the bending material, in the
    bending piece's D (PSHELL MID2, another MAT1 than MID1: D = E2 t^3 / 12 (1 - nu2^2) x
    [[1, nu2, 0], [nu2, 1, 0], [0, 0, (1 - nu2) / 2]], with bending_ratio carrying E2 / E);
    membrane_ratio (n,) or None (1): 1, or 0 for a shell with no membrane stiffness (PSHELL
    MID1 blank: a bending panel), which then has no drilling stiffness either (the drilling
    penalty is the membrane's).  A shell with no bending (PSHELL MID2 blank: a membrane) has
    bending_ratio 0 and shear_ratio 0, and no rotary inertia (it has no bending rotations to
    carry it); otherwise the rotary inertia rho t^3 / 12 stays, and the thickness powers stay
    as they are (MSC Nastran QRG, PSHELL remarks 2-3).

    section : ``fe.laminate.SectionMatrices`` (n rows) in the elements' local axes, or None:
    an anisotropic section per unit thickness (a laminate, Nastran's PCOMP), which then
    replaces E, nu and the ratios in the stiffness: membrane int Bm^T Am Bm (incompatible modes
    condensed with Am), bending int Bb^T Db Bb / 12, shear int Bs^T Hs Bs, drilling alpha Am_66
    int Bd^T Bd, and where the section has a coupling b = B / h^2 the coupling piece (the
    incompatible modes then condensed with the coupling too: ``_coupled``); its ``rotary``
    ratio scales the rotary inertia; a section with no bending has no rotary inertia.
    """
    coupling = None
    if section is None:
        Km, Ks, Kd, Kb = _isotropic_stiffness(ops, E, nu, bending_ratio, shear_ratio,
                                              bending_nu, membrane_ratio)  # fmt: skip
        bending = bending_ratio
    else:
        Km, Ks, Kd, Kb, coupling = _section_stiffness(ops, section)
        bending = np.abs(section.bending).sum(axis=(1, 2))
    Mt, Mr, S = _mass_pieces(ops, Km.shape, lumped)
    if section is not None and section.rotary is not None:
        Mr *= section.rotary[:, None, None]
    if bending is not None and not np.all(bending > 0):
        Mr *= (bending > 0)[:, None, None]
    return LocalPieces(
        membrane=Km, shear=Ks, drilling=Kd, bending=Kb, mass_t=Mt, mass_r=Mr, offset=S,
        coupling=coupling,
    )  # fmt: skip


def _incompatible(ops: _Operators, D):
    """(H, C) = (int G^T D G, int G^T D Bm) of the incompatible modes (quads) with membrane
    D (n, 3, 3), or None for elements without them (triangles)."""
    if ops.Ginc is None:
        return None
    return (_quadrature_form(ops.Ginc, D, ops.wdet),
            _quadrature_form(ops.Ginc, D, ops.wdet, ops.Bm))  # fmt: skip


def _membrane(ops: _Operators, D, modes):
    """int Bm^T D Bm with the incompatible modes ``modes`` (``_incompatible``) condensed,
    symmetrized; D (n, 3, 3)."""
    Km = _quadrature_form(ops.Bm, D, ops.wdet)
    if modes is not None:
        H, C = modes
        Km = Km - np.einsum("nai,naj->nij", C, np.linalg.solve(H, C))
    return 0.5 * (Km + Km.transpose(0, 2, 1))


def _isotropic_stiffness(ops, E, nu, bending_ratio, shear_ratio, bending_nu, membrane_ratio):
    """(membrane, shear, drilling, bending) pieces of isotropic sections (``local_pieces``)."""
    D = plane_stress(nu)
    G = E / (2.0 * (1.0 + nu))
    Km = _membrane(ops, D, _incompatible(ops, D))
    Ks = _quadrature_form(ops.Bs, None, ops.wdet)
    Kd = _quadrature_form(ops.Bd[:, :, None], None, ops.wdet)
    Kb = _quadrature_form(ops.Bb, D if bending_nu is None else plane_stress(bending_nu),
                          ops.wdet)  # fmt: skip
    # scaled in place: the same products as X * factor without a second (n, d, d) copy
    Km *= E[:, None, None]
    kappa = SHEAR_FACTOR if shear_ratio is None else shear_ratio
    if ops.Bs.shape[2]:  # shear-rigid elements (DKT, DKQ) have no shear rows: no kappa (inf)
        Ks *= (kappa * G)[:, None, None]
    Kd *= (DRILL_ALPHA * G)[:, None, None]
    if membrane_ratio is not None:
        Km *= membrane_ratio[:, None, None]
        Kd *= membrane_ratio[:, None, None]
    Kb *= (E / 12.0 if bending_ratio is None else bending_ratio * E / 12.0)[:, None, None]
    return Km, Ks, Kd, Kb


def _section_stiffness(ops, section):
    """(membrane, shear, drilling, bending, coupling or None) pieces of anisotropic sections
    (``local_pieces``).  A section with no membrane (Nastran's LAM BEND) gets none: its
    incompatible modes would be singular, so they are condensed with a stand-in and the piece
    is zeroed (such a section has no coupling)."""
    none = ~np.any(section.membrane, axis=(1, 2))
    a = np.where(none[:, None, None], np.eye(3), section.membrane)
    modes = _incompatible(ops, a)
    Km = _membrane(ops, a, modes)
    Km[none] = 0.0
    Hs = section.shear if ops.Bs.shape[2] else None  # shear-rigid elements: no shear rows
    Ks = _quadrature_form(ops.Bs, Hs, ops.wdet)
    Kd = _quadrature_form(ops.Bd[:, :, None], None, ops.wdet)
    Kd *= (DRILL_ALPHA * section.membrane[:, 2, 2])[:, None, None]
    Kb = _quadrature_form(ops.Bb, section.bending, ops.wdet)
    Kb /= 12.0
    Kc = None
    if section.coupling is not None:
        Kc, Kx = _coupled(ops, section.coupling, modes)
        Kb += Kx
    return Km, Ks, Kd, Kb, Kc


def _coupled(ops: _Operators, b, modes):
    """(coupling piece (n, d, d) per unit t^2, the bending's share per unit t^3) of sections
    with coupling b (n, 3, 3) [Pa]: int (Bm^T b Bb + Bb^T b Bm), and where the element has
    incompatible modes (quads; ``modes`` = (H, Cm) of the membrane a, ``_incompatible``),
    their condensation with the coupling: with H = int G^T a G, Cm = int G^T a Bm,
    Cb = int G^T b Bb the condensed energy of
    [eps; kappa] [[A, B], [B, D]] [eps; kappa] takes -(Cm^T H^-1 Cb + Cb^T H^-1 Cm) t^2 off the
    coupling and -Cb^T H^-1 Cb t^3 off the bending (the membrane's -Cm^T H^-1 Cm t is
    ``_membrane``'s), so that the thickness powers stay exact."""
    Kc = _quadrature_form(ops.Bm, b, ops.wdet, ops.Bb)
    Kx = np.zeros(Kc.shape)
    if modes is not None:
        H, Cm = modes
        Cb = _quadrature_form(ops.Ginc, b, ops.wdet, ops.Bb)
        HinvCb = np.linalg.solve(H, Cb)
        Kc = Kc - np.einsum("nai,naj->nij", Cm, HinvCb)
        Kx = -np.einsum("nai,naj->nij", Cb, HinvCb)
        Kx = 0.5 * (Kx + Kx.transpose(0, 2, 1))
    return Kc + Kc.transpose(0, 2, 1), Kx


def _mass_pieces(ops: _Operators, shape, lumped: bool):
    """(translational, rotary (rx, ry) mass pieces (n, d, d), offset operator S (d, d))."""
    k = ops.N.shape[1]
    mass = np.einsum("nq,qi,qj->nij", ops.wdet, ops.N, ops.N)  # (n, k, k)
    if lumped:
        mass = np.einsum("nij,ij->nij", mass.sum(axis=2)[:, :, None], np.eye(k))
    Mt = np.zeros(shape)
    Mr = np.zeros(shape)
    for c in (U, V, W):
        Mt[:, c::6, c::6] = mass
    for c in (RX, RY):
        Mr[:, c::6, c::6] = mass
    S = np.zeros((6 * k, 6 * k))
    S[np.arange(U, 6 * k, 6), np.arange(RY, 6 * k, 6)] = 1.0
    S[np.arange(V, 6 * k, 6), np.arange(RX, 6 * k, 6)] = -1.0
    return Mt, Mr, S


def optional_rows(rows, *arrays) -> tuple:
    """Each of ``arrays`` (the optional per-element section arrays: bending and shear ratios,
    bending nu, membrane ratio) at the elements ``rows``, None where it is None."""
    return tuple(None if a is None else a[rows] for a in arrays)


#: elements per chunk of ``PieceSource.chunks`` (``direct_matrices``, ``ShellAssembly.power_data``):
#: the temporaries are then ~15 (CHUNK, 24, 24) float64 stacks (~70 MB) whatever the mesh size
CHUNK = 2048
PIECE_NAMES = ("membrane", "shear", "drilling", "bending", "mass_t", "mass_r")


@dataclass(frozen=True)
class PieceSource:
    """What the thickness-free pieces (``LocalPieces``) of a family of elements are computed from,
    kept in their place: the six (n, d, d) stacks take 27.6 kB per quad (4.3 GiB for the 166,000
    quads of a 1e6-DOF plate), the source 0.1 kB.  Pieces are computed when asked for, ``CHUNK``
    elements at a time (each chunk vectorized), with the same values every time.

    xy (n, k, 2) in-plane node coordinates [m] (k = 4: MITC4 quads, 3: DKT triangles);
    height (n, k) node heights above the element plane [m] (``warp_link``) or None; E [Pa], nu
    (n,); lumped : row-sum mass; rotary_inertia : False zeroes mass_r (for peers without it);
    bending_ratio, shear_ratio, bending_nu, membrane_ratio (n,) or None: ``local_pieces``'s;
    kirchhoff : quadrilaterals without transverse shear flexibility
    (``quad_operators(kirchhoff=True)``) instead of MITC4; section : ``fe.laminate
    .SectionMatrices`` (n rows, local axes) or None: anisotropic sections (``local_pieces``).
    """

    xy: np.ndarray
    height: np.ndarray | None
    E: np.ndarray
    nu: np.ndarray
    lumped: bool = False
    rotary_inertia: bool = True
    bending_ratio: np.ndarray | None = None
    shear_ratio: np.ndarray | None = None
    kirchhoff: bool = False
    bending_nu: np.ndarray | None = None
    membrane_ratio: np.ndarray | None = None
    section: SectionMatrices | None = None

    def __len__(self) -> int:
        return len(self.xy)

    def pieces(self, rows) -> LocalPieces:
        """``LocalPieces`` of the elements ``rows`` (index array or slice), as one batch."""
        xy = self.xy[rows]
        ops = quad_operators(xy, self.kirchhoff) if xy.shape[1] == 4 else tria_operators(xy)
        b, s, n, m = optional_rows(rows, self.bending_ratio, self.shear_ratio, self.bending_nu,
                                   self.membrane_ratio)  # fmt: skip
        section = None if self.section is None else self.section.rows(rows)
        p = local_pieces(ops, self.E[rows], self.nu[rows], self.lumped, b, s, n, m, section)
        if self.height is not None:
            p = warp_link(p, self.height[rows])
        if not self.rotary_inertia:
            p = replace(p, mass_r=np.zeros_like(p.mass_r))
        return p

    def chunks(self, rows=None):
        """(rows of the chunk, its ``LocalPieces``) for the elements ``rows`` (int array, default
        all) in chunks of ``CHUNK``."""
        rows = np.arange(len(self)) if rows is None else np.asarray(rows)
        for lo in range(0, rows.size, CHUNK):
            k = rows[lo : lo + CHUNK]
            yield k, self.pieces(k)


def warp_link(p: LocalPieces, height: np.ndarray) -> LocalPieces:
    """Pieces of a warped quad seen from its real nodes: each node at height h above the flat
    element's plane is tied rigidly to its projection, u_p = u - h ry, v_p = v + h rx
    (the rigid-link warping correction of flat quads; MacNeal, *Finite Elements: Their Design
    and Performance*, 1994, on warped elements), X -> W^T X W.  Without it a rigid rotation of
    the real nodes strains the flat element (the FEMAP exhaust deck: three rigid 'modes' at
    5-25 Hz).  W commutes with the offset transform T(e), so ``power_matrices`` stays exact.
    height (n, k) [m]."""
    if not np.any(height):
        return p
    # W = I + E with E's only entries -h at (U, RY) and h at (V, RX) of each node: X W adds
    # columns, W^T (X W) rows, in O(d k) per element instead of two (d, d) products
    pairs = [
        (6 * k + src, 6 * k + dst, sign * height[:, k, None])
        for k in range(p.membrane.shape[1] // 6)
        for src, dst, sign in ((U, RY, -1.0), (V, RX, 1.0))
    ]

    def link(X):
        Y = X.copy()
        for src, dst, h in pairs:
            Y[:, :, dst] += h * Y[:, :, src]
        for src, dst, h in pairs:
            Y[:, dst, :] += h * Y[:, src, :]
        return Y

    coupling = None if p.coupling is None else link(p.coupling)
    return LocalPieces(*(link(getattr(p, a)) for a in PIECE_NAMES), p.offset, coupling)


def _sandwich(S, X):
    """(S^T X + X S, S^T X S) for a constant (d, d) S and stacks X (n, d, d)."""
    XS = X @ S
    return XS.transpose(0, 2, 1) + XS, S.T @ XS


def power_matrices(p: LocalPieces, rho, nsm, offset, offset_ratio):
    """Per-power local matrices: K = sum_p t^p K[p], M = sum_p t^p M[p], exactly.

    rho [kg/m^3], nsm [kg/m^2], offset [m], offset_ratio [-] : (n,).  With
    e = offset + offset_ratio t, t T(e)^T X T(e) expands into powers 1..3 of t.
    Returns (K, M) dicts {power: (n, d, d)}; K has powers 1, 2, 3 and M has 0, 1, 2, 3, where
    the t^2 powers (present only with an offset or a coupling) are left out when every offset
    is zero and there is no coupling.  A coupling piece (an unsymmetric laminate, whose offset
    is its own, not a ratio of t) enters power 2 as t^2 T(e0)^T Kc T(e0).
    """
    r = rho[:, None, None]
    if not (np.any(offset) or np.any(offset_ratio)):
        return _power_matrices_centred(p, r, nsm)
    e0, c = offset[:, None, None], offset_ratio[:, None, None]
    m1, m2 = _sandwich(p.offset, p.membrane)
    t1, t2 = _sandwich(p.offset, p.mass_t)
    K = {
        1: p.membrane + e0 * m1 + e0**2 * m2 + p.shear + p.drilling,
        2: c * m1 + 2 * e0 * c * m2,
        3: c**2 * m2 + p.bending,
    }
    if p.coupling is not None:
        if np.any(c * np.any(p.coupling, axis=(1, 2))[:, None, None]):
            raise ValueError("a coupled section's offset must not scale with t")
        k1, k2 = _sandwich(p.offset, p.coupling)
        K[2] = K[2] + p.coupling + e0 * k1 + e0**2 * k2
    M = {
        0: nsm[:, None, None] * p.mass_t,
        1: r * (p.mass_t + e0 * t1 + e0**2 * t2),
        2: r * (c * t1 + 2 * e0 * c * t2),
        3: r * (c**2 * t2 + p.mass_r / 12.0),
    }
    return K, M


def _power_matrices_centred(p: LocalPieces, r, nsm):
    """``power_matrices`` without offsets (e = 0): the same sums with the zero offset terms
    left out (adding +0.0 is exact, so the values are identical) and no t^2 power but the
    coupling's; r (n, 1, 1) density [kg/m^3]."""
    K = {1: p.membrane + p.shear + p.drilling, 3: p.bending}
    if p.coupling is not None:
        K[2] = p.coupling
    M = {0: nsm[:, None, None] * p.mass_t, 1: r * p.mass_t, 3: r * (p.mass_r / 12.0)}
    return K, M


def direct_matrices(p, t, rho, nsm, offset, offset_ratio):
    """K, M (n, d, d) at thickness t (n,) [m] built directly (offset transform applied as the
    matrix product T^T X T); an independent path to check ``power_matrices``.  p : the
    ``LocalPieces`` or their ``PieceSource`` (then computed ``CHUNK`` elements at a time)."""
    if isinstance(p, LocalPieces):
        return _direct(p, t, rho, nsm, offset, offset_ratio)
    n, d = len(p), 6 * p.xy.shape[1]
    K, M = np.empty((n, d, d)), np.empty((n, d, d))
    for k, pk in p.chunks():
        K[k], M[k] = _direct(pk, t[k], rho[k], nsm[k], offset[k], offset_ratio[k])
    return K, M


def _direct(p: LocalPieces, t, rho, nsm, offset, offset_ratio):
    """``direct_matrices`` of ``LocalPieces``."""
    e = offset + offset_ratio * t
    T = np.eye(p.offset.shape[0])[None] + e[:, None, None] * p.offset[None]
    tt = t[:, None, None]
    Tt = T.transpose(0, 2, 1)
    K = tt * (Tt @ p.membrane @ T + p.shear + p.drilling) + tt**3 * p.bending
    if p.coupling is not None:
        K = K + tt**2 * (Tt @ p.coupling @ T)
    m_area = (rho * t)[:, None, None]
    M = m_area * (Tt @ p.mass_t @ T) + nsm[:, None, None] * p.mass_t
    M = M + (rho * t**3 / 12.0)[:, None, None] * p.mass_r
    return K, M


def to_global(X: np.ndarray, R: np.ndarray) -> np.ndarray:
    """Rotate (n, d, d) local matrices to global axes with frames R (n, 3, 3) (rows = local
    axes): X_g = T^T X T with T = blockdiag(R, ..., R)."""
    n, d, _ = X.shape
    b = d // 3
    # X T: every 3-column block times R; then T^T (X T): every 3-row block times R^T
    XT = np.matmul(X.reshape(n, d * b, 3), R).reshape(n, b, 3, d).transpose(0, 1, 3, 2)
    out = np.matmul(XT.reshape(n, b * d, 3), R).reshape(n, b, d, 3).transpose(0, 1, 3, 2)
    return out.reshape(n, d, d)
