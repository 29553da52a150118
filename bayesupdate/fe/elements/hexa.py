"""Eight-node hexahedra (Nastran CHEXA with eight GRIDs, PSOLID, isotropic MAT1): the trilinear
brick with assumed shear strains and enhanced normal strains, as MSC and NX Nastran form their
default CHEXA, vectorized over elements.

With the trilinear shape functions N_a (a = 1..8) of the corners in the natural coordinates
(xi, eta, zeta) in [-1, 1]^3 (Nastran's corner order: G1-G4 one face, G5-G8 the opposite one),
the compatible strain is eps = B u (B (6, 24): Voigt order xx, yy, zz, xy, yz, zx, engineering
shears).  Three changes make the element neither lock in bending nor in its hourglass modes:

1. *Assumed natural shear strains*: each covariant shear strain (the strain in the centre's
   natural axes, E = J0 eps J0^T, J0 the Jacobian at the centre) is taken on the line through
   the centre along the third axis: gamma_(xi eta) at (0, 0, zeta), gamma_(eta zeta) at
   (xi, 0, 0), gamma_(zeta xi) at (0, eta, 0) (the assumed strain of Dvorkin & Bathe, *Eng.
   Comput.* 1, 1984, carried to the brick; MacNeal, *Finite Elements: Their Design and
   Performance*, 1994, ch. 9): a bending mode keeps no parasitic shear.
2. *Enhanced normal strains* (Simo & Rifai, *IJNME* 29, 1990, eq. 3.9 with the centre's
   Jacobian): each natural normal strain E_(xi xi) gains the terms xi, xi eta, xi zeta (and so
   on by symmetry), nine parameters in all, each mapped as J0^-1 E J0^-T det J0 / det J,
   orthogonal to constant stress on a parallelepiped, and condensed out:
   K = K_cc - K_ca K_aa^-1 K_ac.  A bending mode's Poisson strains and an hourglass mode's
   normal strains are free, so an hourglass mode (u = xi eta zeta) carries E, not
   lambda + 2 mu.
3. All terms on the 2 x 2 x 2 Gauss rule.

The constant-strain states are exact (the patch test), and the stiffness is MSC's: on MSC's own
static solution of 128 near-cubes (``tests/data/msc_chexa8.json``: Nastran's grid point forces
of each element against K u), within 1.4e-5 (median; float32 output) where the fully integrated
brick is 6e-2 off and Wilson-Taylor's incompatible modes 5.6e-4; on NX's single 1 x 1 x 2 brick
under five face pressures within 1.6e-6.  The mass is lumped as Nastran lumps it, rho times the
integral of N_a on each corner (MSC's gravity load of the same model, 3.6e-8: on a distorted
element it is not rho V / 8), or consistent (PARAM COUPMASS 1: rho N_a N_b I_3 on the same
rule).  A solid has no rotations (``fe.elements.tetra``).  A parametric family: a factor on E
scales K and a factor on rho scales M, each exactly linearly.  SI units; K [N/m], M [kg], each
(n, 24, 24) on the corners' translations in global axes (``dofs``).
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.fe.elements.base import ElementSettings, register_parametric
from bayesupdate.fe.elements.solid import Solids, elasticity, factors, strain_matrix

#: the corners' natural coordinates (8, 3), Nastran's CHEXA order
CORNERS = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                    [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)  # fmt: skip
#: the 2 x 2 x 2 Gauss points (8, 3) (each weight 1)
GAUSS = CORNERS / np.sqrt(3.0)
#: elements whose stiffness is formed at once (``stiffness``: the memory of its temporaries)
CHUNK = 2048
#: (natural shear component of the Voigt order, the axis along which it is sampled)
_SHEAR_LINES = ((3, 2), (4, 0), (5, 1))
#: the enhanced terms of each natural normal strain: (its axis, the powers of (xi, eta, zeta))
_ENHANCED = ((0, (1, 0, 0)), (0, (1, 1, 0)), (0, (1, 0, 1)),
             (1, (0, 1, 0)), (1, (1, 1, 0)), (1, (0, 1, 1)),
             (2, (0, 0, 1)), (2, (1, 0, 1)), (2, (0, 1, 1)))  # fmt: skip


@register_parametric
@dataclass(frozen=True)
class Hexahedra(Solids):
    """n eight-node hexahedra: nodes (n, 8) corner node indices (Nastran's order); corners
    (n, 8, 3) their positions [m]; E [Pa], nu [-], rho [kg/m^3] (n,); lumped (n,) bool;
    part (n,) part indices.  An ``elements.base.ParametricFamily`` held in
    ``Structure.elements``: K is linear in the factor ``hexa_modulus_scale`` on E (the
    parameter ``hexa_modulus_factor``), M in ``hexa_density_scale`` (``hexa_density_factor``)."""

    #: registry name; the ``ElementProperties`` fields and the properties a parameter binds
    #: (``fe.model.Binding``) on a part's bricks
    family = "hexahedron"
    fields, properties = factors("hexa", "bricks")

    def matrices(self, props, settings: ElementSettings, elements=None):
        """(K, M) (n_e, 24, 24) of ``elements`` (default all) at the factors of ``props``
        (module docstring)."""
        e = slice(None) if elements is None else elements
        D = elasticity(self.E[e] * props.hexa_modulus_scale[e], self.nu[e])
        K = stiffness(self.corners[e], D)
        rho = self.rho[e] * props.hexa_density_scale[e]
        return K, mass_matrix(self.corners[e], rho, self.lumped[e])

    def masses(self, props, xyz: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(n,) element masses [kg] at ``props`` and (n, 3) their centroids [m] (the corners'
        positions weighted by the integrals of their shape functions)."""
        share = corner_volumes(self.corners)
        volume = share.sum(axis=1)
        centroid = np.einsum("ea,eai->ei", share, self.corners) / volume[:, None]
        return self.rho * props.hexa_density_scale * volume, centroid


def shape_functions(points: np.ndarray) -> np.ndarray:
    """(p, 8) N_a at natural points (p, 3)."""
    return np.prod(1 + points[:, None, :] * CORNERS[None], axis=2) / 8


def shape_derivatives(points: np.ndarray) -> np.ndarray:
    """(p, 3, 8) d N_a / d (xi, eta, zeta) at natural points (p, 3)."""
    f = 1 + points[:, None, :] * CORNERS[None]  # (p, 8, 3)
    out = np.empty((len(points), 3, 8))
    for j in range(3):
        others = [k for k in range(3) if k != j]
        out[:, j] = CORNERS[None, :, j] * f[:, :, others[0]] * f[:, :, others[1]] / 8
    return out


def jacobians(corners: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(n, p, 3, 3) J_ij = d x_j / d xi_i of hexahedra with corners (n, 8, 3) [m] at natural
    points (p, 3)."""
    return np.einsum("pia,eaj->epij", shape_derivatives(points), corners)


def corner_volumes(corners: np.ndarray) -> np.ndarray:
    """(n, 8) the integral of each corner's N_a over the element [m^3] (their sum: the volume;
    Gauss 2 x 2 x 2, exact for the trilinear map)."""
    det = np.linalg.det(jacobians(corners, GAUSS))  # (n, 8 points)
    return np.einsum("ep,pa->ea", det, shape_functions(GAUSS))


def volumes(corners: np.ndarray) -> np.ndarray:
    """(n,) volumes [m^3] of hexahedra with corners (n, 8, 3) [m] (signed: negative when the
    corners are numbered inside out)."""
    return corner_volumes(corners).sum(axis=1)


def _strain_at(corners: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(n, p, 6, 24) compatible B at natural points (p, 3)."""
    jac = jacobians(corners, points)
    n, p = jac.shape[:2]
    grad = np.linalg.solve(jac, np.broadcast_to(shape_derivatives(points), (n, p, 3, 8)))
    return strain_matrix(grad.reshape(n * p, 3, 8)).reshape(n, p, 6, 24)


def natural_transform(jac0: np.ndarray) -> np.ndarray:
    """(n, 6, 6) T with E_nat = T eps for the covariant strain E_nat = J0 eps J0^T (Voigt order,
    engineering shears on both sides), J0 (n, 3, 3) as ``jacobians``."""
    pairs = ((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2))
    T = np.empty((len(jac0), 6, 6))
    for r, (i, j) in enumerate(pairs):
        for c, (k, m) in enumerate(pairs):
            term = jac0[:, i, k] * jac0[:, j, m]
            if k != m:  # an engineering shear is twice the tensor component on either side
                term = (term + jac0[:, i, m] * jac0[:, j, k]) / 2
            T[:, r, c] = term if i == j else 2 * term
    return T


def stiffness(corners: np.ndarray, D: np.ndarray, enhanced: bool = True) -> np.ndarray:
    """(n, 24, 24) K [N/m] of hexahedra with corners (n, 8, 3) [m] and elasticity D (n, 6, 6)
    [Pa] (module docstring: assumed natural shear, nine enhanced normal strains condensed).
    ``enhanced=False``: the assumed shear alone, which is MYSTRAN 18's HEXA8 with PSOLID ISOP
    blank (its shear strains averaged over each face's Gauss points, ``Source/EMG/EMG5/
    HEXA.f90``; ``tests/test_nastran_hexa.py`` compares it with MYSTRAN).  Formed ``CHUNK``
    elements at a time: the strain matrices of all of them at once would take ten times K's
    memory."""
    K = np.empty((len(corners), 24, 24))
    for start in range(0, len(corners), CHUNK):
        part = slice(start, start + CHUNK)
        K[part] = _stiffness(corners[part], D[part], enhanced)
    return K


def _stiffness(corners: np.ndarray, D: np.ndarray, enhanced: bool) -> np.ndarray:
    """``stiffness`` of one chunk of elements."""
    n = len(corners)
    jac0 = jacobians(corners, np.zeros((1, 3)))[:, 0]
    det0 = np.linalg.det(jac0)
    T = natural_transform(jac0)
    Tinv = np.linalg.inv(T)
    det = np.linalg.det(jacobians(corners, GAUSS))  # (n, 8)
    B = T[:, None] @ _strain_at(corners, GAUSS)  # natural strains (n, 8, 6, 24)
    # each shear line's two points (+-1/sqrt(3) along its axis), then the Gauss points' side
    lines = np.zeros((6, 3))
    for i, (_, axis) in enumerate(_SHEAR_LINES):
        lines[2 * i : 2 * i + 2, axis] = (-GAUSS.max(), GAUSS.max())
    on_lines = _strain_at(corners, lines)
    for i, (row, axis) in enumerate(_SHEAR_LINES):
        side = 2 * i + (GAUSS[:, axis] > 0)
        B[:, :, row] = np.einsum("ej,epjk->epk", T[:, row], on_lines[:, side])
    B = Tinv[:, None] @ B
    weighted = (B * det[:, :, None, None]).reshape(n, 48, 24).transpose(0, 2, 1)
    Kcc = weighted @ (D[:, None] @ B).reshape(n, 48, 24)
    if not enhanced:
        return Kcc
    G = Tinv[:, :, :3]  # the physical strain of a unit natural normal strain along each axis
    terms = np.array([[np.prod(pt**powers) for axis, powers in _ENHANCED] for pt in GAUSS])
    axes = np.array([axis for axis, _ in _ENHANCED])
    Ma = G[:, None, :, axes] * (terms[None, :, None, :] * (det0[:, None] / det)[:, :, None, None])
    DM = (D[:, None] @ Ma).reshape(n, 48, 9)
    Kca = weighted @ DM
    Kaa = (Ma * det[:, :, None, None]).reshape(n, 48, 9).transpose(0, 2, 1) @ DM
    return Kcc - Kca @ np.linalg.solve(Kaa, np.swapaxes(Kca, 1, 2))


def mass_matrix(corners: np.ndarray, rho: np.ndarray, lumped: np.ndarray) -> np.ndarray:
    """(n, 24, 24) M [kg] of hexahedra with corners (n, 8, 3) [m] and densities rho (n,)
    [kg/m^3]: rho times the integral of N_a on corner a's translations where ``lumped``, else
    the consistent rho N_a N_b I_3 (Gauss 2 x 2 x 2)."""
    det = np.linalg.det(jacobians(corners, GAUSS))
    N = shape_functions(GAUSS)
    consistent = np.einsum("pa,pb,ep->eab", N, N, det) * rho[:, None, None]
    diagonal = consistent.sum(axis=2)
    lumped_nodal = np.einsum("ea,ab->eab", diagonal, np.eye(8))
    nodal = np.where(lumped[:, None, None], lumped_nodal, consistent)
    return np.einsum("eab,ij->eaibj", nodal, np.eye(3)).reshape(-1, 24, 24)
