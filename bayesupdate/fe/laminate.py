"""Classical lamination theory: a stack of orthotropic plies -> the shell section's stiffness.

A ply k (thickness t_k [m], fibre angle theta_k [rad] from the section's x-axis, counter-
clockwise about its normal) of an orthotropic material (E1, E2 [Pa], nu12, G12 [Pa], transverse
shear moduli G1Z, G2Z [Pa]) has the reduced plane-stress stiffness in its own axes (Jones,
*Mechanics of Composite Materials*, 2nd ed., 1999, eq. 2.61)

    Q11 = E1 / (1 - nu12 nu21), Q22 = E2 / (1 - nu12 nu21), Q12 = nu12 E2 / (1 - nu12 nu21),
    Q66 = G12, with nu21 = nu12 E2 / E1,

and, in the section's axes, Qbar = T^T Q T with T the engineering-strain rotation
eps_ply = T eps (Jones eq. 2.80-2.85; the strains are [eps_x, eps_y, gamma_xy]).  Integrated over
the thickness about the stack's mid-plane z in [-h/2, h/2] (Jones eqs. 4.22-4.24):

    A = sum_k Qbar_k (z_k - z_{k-1}),  B = 1/2 sum_k Qbar_k (z_k^2 - z_{k-1}^2),
    D = 1/3 sum_k Qbar_k (z_k^3 - z_{k-1}^3),

the membrane, coupling and bending stiffness [N/m, N, N m].  The transverse shear stiffness H is
found by energy equivalence with the shear stresses that cylindrical bending puts through the
stack (``transverse_shear``: Whitney 1973; Reddy, *Mechanics of Laminated Composite Plates and
Shells*, 2nd ed., 2004, sec. 6.4): 5/6 h G for a homogeneous stack (the shell's own factor);
a ply with no transverse shear flexibility (G1Z, G2Z infinite) adds no compliance, and a soft
core carries a sandwich's shear, as Nastran's PCOMP derives its shear from the stack's bending
stress (MSC Nastran Reference Manual, composite elements; its own numbers not checked).

The shell element takes these as a section per unit thickness (``SectionMatrices``), the form
Nastran gives PCOMP's equivalent PSHELL: membrane A / h (its MID1), bending 12 D / h^3 (its MID2,
12I/T**3 = 1), transverse shear H / h (its MID3 with TS/T = 1).
"""

from dataclasses import dataclass

import numpy as np

__all__ = [
    "Ply",
    "SectionMatrices",
    "laminate",
    "ply_stiffness",
    "rotary_ratio",
    "section_per_unit_thickness",
    "shear_rotation",
    "strain_rotation",
]

#: first-order transverse shear correction factor (Reissner)
SHEAR_FACTOR = 5.0 / 6.0


@dataclass(frozen=True)
class Ply:
    """One orthotropic ply: E1, E2, G12, G1Z, G2Z [Pa] (G1Z and G2Z inf: no transverse shear
    flexibility), nu12, rho [kg/m^3], thickness [m], angle [rad] of its fibre from the
    section's x-axis."""

    E1: float
    E2: float
    nu12: float
    G12: float
    G1Z: float
    G2Z: float
    rho: float
    thickness: float
    angle: float


@dataclass(frozen=True)
class SectionMatrices:
    """A shell section per unit thickness, in some in-plane axes: membrane (n, 3, 3) = A / h,
    bending (n, 3, 3) = 12 D / h^3, shear (n, 2, 2) = H / h (kappa included), coupling
    (n, 3, 3) = B / h^2 or None (no membrane-bending coupling), all [Pa], for strains
    [eps_x, eps_y, gamma_xy], curvatures [kappa_x, kappa_y, kappa_xy] and transverse shears
    [gamma_xz, gamma_yz], about the section's mid-plane; rotary (n,) or None (1): the rotary
    inertia per area over that of the mean density, sum rho_k (z_k^3 - z_k-1^3) / 3 over
    rho_mean h^3 / 12 (a sandwich's heavy faces: above 1)."""

    membrane: np.ndarray
    bending: np.ndarray
    shear: np.ndarray
    coupling: np.ndarray | None = None
    rotary: np.ndarray | None = None

    def rows(self, idx) -> "SectionMatrices":
        """The sections of the elements ``idx``."""
        coupling = None if self.coupling is None else self.coupling[idx]
        rotary = None if self.rotary is None else self.rotary[idx]
        return SectionMatrices(self.membrane[idx], self.bending[idx], self.shear[idx], coupling,
                               rotary)  # fmt: skip

    def rotated(self, angle) -> "SectionMatrices":
        """The same sections seen in axes turned by -angle (n,) [rad]: the section's x-axis
        lies at +angle from the new x-axis (a material axis at ``angle`` from an element's)."""
        T = strain_rotation(angle)
        R = shear_rotation(angle)
        coupling = None if self.coupling is None else _congruent(T, self.coupling)
        return SectionMatrices(_congruent(T, self.membrane), _congruent(T, self.bending),
                               _congruent(R, self.shear), coupling, self.rotary)  # fmt: skip


def _congruent(T, S):
    """T^T S T for stacks T (n, k, k), S (n, k, k)."""
    return np.einsum("nai,nab,nbj->nij", T, S, T)


def strain_rotation(angle) -> np.ndarray:
    """(n, 3, 3) T with eps' = T eps for axes x' at +angle (n,) [rad] from x (engineering shear
    strain; Jones eq. 2.80 with Reuter's matrix folded in)."""
    c, s = np.cos(angle), np.sin(angle)
    T = np.empty(np.shape(angle) + (3, 3))
    T[..., 0, :] = np.stack([c * c, s * s, c * s], -1)
    T[..., 1, :] = np.stack([s * s, c * c, -c * s], -1)
    T[..., 2, :] = np.stack([-2 * c * s, 2 * c * s, c * c - s * s], -1)
    return T


def shear_rotation(angle) -> np.ndarray:
    """(n, 2, 2) R with [gamma_x'z, gamma_y'z] = R [gamma_xz, gamma_yz] for x' at +angle."""
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([np.stack([c, s], -1), np.stack([-s, c], -1)], -2)


def ply_stiffness(E1, E2, nu12, G12) -> np.ndarray:
    """(k, 3, 3) reduced plane-stress stiffness Q [Pa] of plies in their own axes (Jones eq.
    2.61); E1, E2, nu12, G12 (k,)."""
    E1, E2, nu12, G12 = (np.asarray(v, dtype=float) for v in (E1, E2, nu12, G12))
    nu21 = nu12 * E2 / E1
    d = 1.0 - nu12 * nu21
    Q = np.zeros(E1.shape + (3, 3))
    Q[..., 0, 0] = E1 / d
    Q[..., 1, 1] = E2 / d
    Q[..., 0, 1] = Q[..., 1, 0] = nu12 * E2 / d
    Q[..., 2, 2] = G12
    return Q


def laminate(plies: list[Ply]) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(A, B, D (3, 3), H (2, 2)) of a stack, plies bottom (z = -h/2) to top, about its
    mid-plane (module docstring; H from ``transverse_shear``: inf where no ply has transverse
    shear flexibility, NaN where the stack is rigid in one plane only)."""
    t = np.array([p.thickness for p in plies])
    angle = np.array([p.angle for p in plies])
    Q = ply_stiffness(*(np.array([getattr(p, a) for p in plies]) for a in ("E1", "E2", "nu12",
                                                                            "G12")))  # fmt: skip
    T = strain_rotation(angle)
    Qbar = _congruent(T, Q)
    z = np.concatenate([[0.0], np.cumsum(t)]) - t.sum() / 2
    A, B, D = (np.einsum("k,kij->ij", (z[1:] ** p - z[:-1] ** p) / p, Qbar) for p in (1, 2, 3))
    G = np.array([[p.G1Z, p.G2Z] for p in plies])
    if np.all(np.isinf(G)):
        return A, B, D, np.full((2, 2), np.inf)
    R = shear_rotation(angle)
    compliance = np.einsum("kai,ka,kaj->kij", R, 1.0 / G, R)  # 1 / inf: a rigid plane, 0
    return A, B, D, transverse_shear(Qbar, z, A, B, D, compliance)


#: 3-point Gauss-Legendre rule on [0, 1]: exact for the quartic f(z)^2 within a ply
_GAUSS3 = (0.5 + np.array([-1.0, 0.0, 1.0]) * np.sqrt(0.15), np.array([5.0, 8.0, 5.0]) / 18.0)


def transverse_shear(Qbar, z, A, B, D, compliance) -> np.ndarray:
    """(2, 2) transverse shear stiffness H [N/m] of a stack by energy equivalence in cylindrical
    bending (Whitney, J. Compos. Mater. 7 (1973) 403; Vlachoutsis, IJNME 35 (1992) 1537).

    Bending about each in-plane axis i (x: i = 0, y: i = 1) with the other strains zero
    stresses the plies sigma_i = Qbar_ii (z - z_n) kappa, about the axis's neutral plane
    z_n = B_ii / A_ii; equilibrium gives the shear stress tau_i(z) = f_i(z) Q_i / D*_ii with
    f_i(z) = int_-h/2^z Qbar_ii (zeta - z_n) dzeta and D*_ii = D_ii - B_ii^2 / A_ii.  The
    complementary energy of the resultant Q per unit area is 1/2 Q^T C Q with
    C = int F(z) S(z) F(z) dz, F = diag(f_0 / D*_00, f_1 / D*_11) and S the ply's shear
    compliance in the stack's axes (0 for a ply with no shear flexibility), and H = C^-1.  A
    homogeneous stack gives 5/6 h G (Reissner's factor); a sandwich's soft core carries it.

    Qbar (k, 3, 3) [Pa], z (k + 1,) [m] ply interfaces, A, B, D (3, 3), compliance (k, 2, 2)
    [1/Pa].  NaN where C is singular (rigid in one plane only)."""
    zn = np.diag(B)[:2] / np.diag(A)[:2]
    Dstar = np.diag(D)[:2] - np.diag(B)[:2] ** 2 / np.diag(A)[:2]
    q = Qbar[:, [0, 1], [0, 1]]  # (k, 2): Qbar_00, Qbar_11 of each ply
    lo, hi = z[:-1], z[1:]
    step = q * ((hi**2 - lo**2)[:, None] / 2 - zn * (hi - lo)[:, None])
    f0 = np.concatenate([np.zeros((1, 2)), np.cumsum(step, axis=0)[:-1]])  # f at each ply's base
    x, w = _GAUSS3
    zg = lo[:, None] + np.outer(hi - lo, x)  # (k, 3)
    f = f0[:, None] + q[:, None] * ((zg**2 - lo[:, None] ** 2)[..., None] / 2
                                    - zn * (zg - lo[:, None])[..., None])  # fmt: skip
    F = f / Dstar  # (k, 3, 2): the diagonal of F at each Gauss point
    C = np.einsum("kg,g,kgi,kij,kgj->ij", (hi - lo)[:, None] * np.ones(3), w, F, compliance, F)
    if np.linalg.cond(C) > 1e12:
        return np.full((2, 2), np.nan)
    return np.linalg.inv(C)


def section_per_unit_thickness(A, B, D, H, h, rotary: float = 1.0) -> SectionMatrices:
    """The (1,)-stack ``SectionMatrices`` of a stack of thickness h [m]: A / h, 12 D / h^3,
    H / h (zeros where H is inf: the shell is then shear rigid, its quads Kirchhoff's), B / h^2
    (None where the stack is symmetric: B below 1e-12 of A h), the ``rotary_ratio``."""
    shear = np.zeros((2, 2)) if not np.all(np.isfinite(H)) else H / h
    symmetric = np.abs(B).max() <= 1e-12 * np.abs(A).max() * h
    coupling = None if symmetric else (B / h**2)[None]
    return SectionMatrices((A / h)[None], (12.0 * D / h**3)[None], shear[None], coupling,
                           np.array([rotary]))  # fmt: skip


def rotary_ratio(plies: list[Ply]) -> float:
    """sum rho_k (z_k^3 - z_k-1^3) / 3 about the stack's mid-plane over rho_mean h^3 / 12: the
    rotary inertia of a stack of plies of unequal densities over that of their mean (1 where
    every ply has one density, or the stack none)."""
    t = np.array([p.thickness for p in plies])
    rho = np.array([p.rho for p in plies])
    z = np.concatenate([[0.0], np.cumsum(t)]) - t.sum() / 2
    mean = rho @ t / t.sum() * t.sum() ** 3 / 12
    return float(rho @ (z[1:] ** 3 - z[:-1] ** 3) / 3 / mean) if mean > 0 else 1.0
