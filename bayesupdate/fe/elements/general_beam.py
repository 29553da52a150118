"""General 3-D beams: arbitrary section properties, rigid end offsets and pin flags, vectorized
over elements (the ``CBAR``/``CBEAM`` of Nastran).

Each element is the Timoshenko beam of ``fe.elements.beam`` (Przemieniecki 1968, eqs 5.116 and
11.41-11.42, the same bending blocks), built in four exact steps:

1. *Principal axes.*  With a product of inertia iyz != 0 the element is formed in the section's
   principal axes, turned by alpha about x with tan(2 alpha) = 2 iyz / (iz - iy) (|alpha| <= pi/4),
   and turned back, K = T_a^T K' T_a.  The shear compliances 1 / (k A) are carried to the
   principal axes by the same rotation, keeping its diagonal (exact when both shear factors are
   equal or both are rigid; Nastran ignores K1, K2 whenever I12 != 0, i.e. rigid in shear).
2. *Pin flags* (released end DOFs, element axes): static condensation, K_c = T^T K T and
   M_c = T^T M T with T = [I; -K_pp^-1 K_pr] (the released DOFs follow the element's own
   equilibrium; Cook et al., *Concepts and Applications of FEA*, 4th ed., sec. 2.9).  The released
   DOFs then carry nothing and the node's DOF is free of this element.
3. *Global axes*: ``beam.to_global``.
4. *Rigid end offsets* w_a, w_b (global, from the node to the element's end): the element spans
   the offset ends, and its end DOFs are u_end = u_node + theta_node x w (exact small-rotation
   link), K_node = G^T K G, G = diag(rigid_link(w_a), rigid_link(w_b)).

A tapered element (``taper``: its section's A, iy, iz and J at end A and end B differ, iyz = 0)
takes its stiffness from its flexibility as a cantilever, clamped at end A: the complementary
energy of the section forces that end-B loads cause (axial, two shears, torsion, two bending
moments), with A, iy, iz, J linear along the element, integrated by 3 Gauss points, inverted
and spread to both ends by equilibrium, K = D^T F^-1 D (Przemieniecki 1968, sec. 5.6).  That is
NX Nastran's tapered CBEAM: its static solution of a strongly tapered cantilever to 7e-8
(``studies/nx_tapered_cbeam.py``); for a constant section it is the Timoshenko beam above.  Its
mass is that of the mean section (the element's own fields).

Mass per unit length m = rho A + nsm [kg/m]; rotary inertia rho iy, rho iz [kg m] (if the
structure keeps rotary inertia); torsional inertia per unit length ``torsion_inertia`` [kg m]
(rho (iy + iz) unless given).  Lumped mass: m L / 2 on each end's translations and
torsion_inertia L / 2 on each end's twist; "translational" mass: the consistent mass of the
translations alone (no rotary or torsional inertia), as MSC's coupled CBAR mass.  All inputs
SI; arrays (n,), results (n, 12, 12).
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.fe.constraints import rigid_link
from bayesupdate.fe.elements.base import ElementSettings, LineElements, register
from bayesupdate.fe.elements.beam import (
    _XY,
    _XZ,
    _XZ_SIGN,
    _bending_mass,
    _bending_stiffness,
    element_frames,
    to_global,
)

#: mass formulations of a line element
#: "translational": the consistent mass of the translations alone, no rotary inertia of bending
#: and no torsional inertia (MSC's CBAR with PARAM COUPMASS 1)
MASS_KINDS = ("consistent", "lumped", "none", "translational")


@register
@dataclass(frozen=True)
class GeneralBeams(LineElements):
    """General beam elements as arrays (n elements).

    nodes (n, 2), part (n,); E, G [Pa], rho [kg/m^3]; area [m^2], iy, iz, iyz, torsion [m^4],
    shear_y, shear_z (shear-area factors, 0 = rigid in shear); nsm [kg/m]; torsion_inertia
    [kg m]; up (n, 3) local z reference (local y = up x axis normalized); offset (n, 2, 3) [m]
    from each node to the element's end (global axes); pins (n, 2, 6) bool released element-axis
    DOFs at end a and b; mass (n,) index into ``MASS_KINDS``; taper (n, 2, 4) the section's A,
    iy, iz, J at end a and end b as ratios to the fields above (all 1: a constant section;
    else those fields are the element's mean section, which its mass uses, and a binding that
    sets them keeps the taper's shape).  An ``elements.base.ElementFamily``
    (``Structure.general_beams``).
    """

    #: registry name (a plain class attribute: not a dataclass field)
    family = "general_beam"

    nodes: np.ndarray
    part: np.ndarray
    E: np.ndarray
    G: np.ndarray
    rho: np.ndarray
    area: np.ndarray
    iy: np.ndarray
    iz: np.ndarray
    iyz: np.ndarray
    torsion: np.ndarray
    shear_y: np.ndarray
    shear_z: np.ndarray
    nsm: np.ndarray
    torsion_inertia: np.ndarray
    up: np.ndarray
    offset: np.ndarray
    pins: np.ndarray
    mass: np.ndarray
    taper: np.ndarray

    def mass_per_length(self) -> np.ndarray:
        """(n,) rho A + nsm [kg/m], 0 where the mass kind is "none"."""
        carries = np.asarray(MASS_KINDS)[self.mass] != "none"
        return np.where(carries, self.rho * self.area + self.nsm, 0.0)

    def matrices(self, xyz: np.ndarray, settings: ElementSettings):
        """Global (K, M) (n, 12, 12) on nodes xyz (N, 3) [m] (``general_beam_matrices``)."""
        return general_beam_matrices(xyz, self, settings.shear, settings.rotary_inertia)

    @classmethod
    def of(cls, structure) -> "GeneralBeams | None":
        return structure.general_beams


def end_frames(xyz: np.ndarray, b: GeneralBeams):
    """Element frames R (n, 3, 3) (rows local x, y, z) and lengths L (n,) between the offset
    ends."""
    xa = xyz[b.nodes[:, 0]] + b.offset[:, 0]
    xb = xyz[b.nodes[:, 1]] + b.offset[:, 1]
    return element_frames(xa, xb, b.up)


def principal_angle(iy, iz, iyz) -> np.ndarray:
    """(n,) alpha in [-pi/4, pi/4] turning local (y, z) to principal axes (0 where iyz = 0)."""
    a = 0.5 * np.arctan2(2.0 * iyz, iz - iy)
    a = np.where(a > np.pi / 4, a - np.pi / 2, a)
    return np.where(a < -np.pi / 4, a + np.pi / 2, a)


def _principal_properties(b: GeneralBeams, alpha):
    """Second moments and shear areas in the principal axes (shear area inf = rigid)."""
    c, s = np.cos(alpha), np.sin(alpha)
    iz = c**2 * b.iz + 2 * c * s * b.iyz + s**2 * b.iy
    iy = s**2 * b.iz - 2 * c * s * b.iyz + c**2 * b.iy
    asy = np.where(b.shear_y > 0, b.shear_y * b.area, np.inf)
    asz = np.where(b.shear_z > 0, b.shear_z * b.area, np.inf)
    turned = alpha != 0
    with np.errstate(divide="ignore"):
        fy = c**2 / asy + s**2 / asz
        fz = s**2 / asy + c**2 / asz
        asy = np.where(turned, 1.0 / fy, asy)
        asz = np.where(turned, 1.0 / fz, asz)
    iy = np.where(turned, iy, b.iy)
    iz = np.where(turned, iz, b.iz)
    return iy, iz, asy, asz


def local_matrices(L, E, G, A, iy, iz, J, asy, asz, m_line, rot_y, rot_z, ip):
    """(K, M) (n, 12, 12) of Timoshenko beams in their (principal) local axes.

    asy, asz : shear areas [m^2] (inf: rigid in shear); m_line [kg/m]; rot_y, rot_z rotary
    inertia per length of bending about y and z [kg m]; ip torsional inertia per length [kg m].
    The arithmetic is that of ``beam.local_beam_matrices`` (same results for the same data).
    """
    n = L.shape[0]
    EIy = E * iy
    EIz = E * iz
    phi_y = 12 * EIz / (G * asy * L**2)
    phi_z = 12 * EIy / (G * asz * L**2)
    K = np.zeros((n, 12, 12))
    M = np.zeros((n, 12, 12))
    ax, tor = np.array([0, 6]), np.array([3, 9])
    unit2 = np.array([[1.0, -1.0], [-1.0, 1.0]])
    cons2 = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6.0
    K[:, ax[:, None], ax] = (E * A / L)[:, None, None] * unit2
    K[:, tor[:, None], tor] = (G * J / L)[:, None, None] * unit2
    M[:, ax[:, None], ax] = (m_line * L)[:, None, None] * cons2
    M[:, tor[:, None], tor] = (ip * L)[:, None, None] * cons2
    K[:, _XY[:, None], _XY] = _bending_stiffness(L, EIz, phi_y)
    M[:, _XY[:, None], _XY] = _bending_mass(L, m_line, rot_z, phi_y)
    s = np.outer(_XZ_SIGN, _XZ_SIGN)
    K[:, _XZ[:, None], _XZ] = _bending_stiffness(L, EIy, phi_z) * s
    M[:, _XZ[:, None], _XZ] = _bending_mass(L, m_line, rot_y, phi_z) * s
    return K, M


#: the 3-point Gauss rule on [0, 1] of a tapered element's flexibility: (points, weights)
_GAUSS_3 = np.polynomial.legendre.leggauss(3)  # (points, weights) on [-1, 1]
_TAPER_RULE = ((_GAUSS_3[0] + 1) / 2, _GAUSS_3[1] / 2)


def tapered_stiffness(L, E, G, ends, shear_y, shear_z, shear: bool) -> np.ndarray:
    """(n, 12, 12) element-axis K of tapered beams (module docstring): L (n,) [m], E, G (n,)
    [Pa], ends (n, 2, 4) A [m^2], iy, iz, J [m^4] at end a and b (linear between), shear_y,
    shear_z (n,) shear-area factors (0: rigid in shear; ``shear`` False: all rigid)."""
    n = L.shape[0]
    points, weights = _TAPER_RULE
    F = np.zeros((n, 6, 6))
    for t, w in zip(points, weights, strict=True):
        A, iy, iz, J = (ends[:, 0] + (ends[:, 1] - ends[:, 0]) * t).T
        r = L * (1 - t)  # the arm from the section to end b
        phi = np.broadcast_to(np.eye(6), (n, 6, 6)).copy()  # section forces of end-b loads
        phi[:, 4, 2], phi[:, 5, 1] = -r, r  # My = My_b - r Fz, Mz = Mz_b + r Fy
        with np.errstate(divide="ignore"):
            c_y = np.where(shear & (shear_y > 0), 1 / (G * shear_y * A), 0.0)
            c_z = np.where(shear & (shear_z > 0), 1 / (G * shear_z * A), 0.0)
        c = np.stack([1 / (E * A), c_y, c_z, 1 / (G * J), 1 / (E * iy), 1 / (E * iz)], axis=1)
        F += np.einsum("eki,ek,ekj->eij", phi, c, phi) * (w * L)[:, None, None]
    D = np.zeros((n, 6, 12))  # end b's motion relative to the rigid motion of end a
    D[:, :, 6:] = np.eye(6)
    D[:, :3, :3] = D[:, 3:, 3:6] = -np.eye(3)
    D[:, 1, 5], D[:, 2, 4] = -L, L  # theta_a x (L e_x) = L (0, theta_z, -theta_y)
    return np.swapaxes(D, 1, 2) @ np.linalg.solve(F, D)


def is_tapered(b: GeneralBeams) -> np.ndarray:
    """(n,) True where an element's section differs between its ends (``taper``)."""
    return np.any(b.taper[:, 0] != b.taper[:, 1], axis=1)


def section_ends(b: GeneralBeams) -> np.ndarray:
    """(n, 2, 4) A [m^2], iy, iz, J [m^4] at each end (``taper`` x the fields)."""
    return b.taper * np.stack([b.area, b.iy, b.iz, b.torsion], axis=1)[:, None, :]


def lumped_mass(L, m_line, ip) -> np.ndarray:
    """(n, 12, 12) lumped mass: m L / 2 per end translation, ip L / 2 per end twist."""
    M = np.zeros((L.shape[0], 12, 12))
    idx = np.array([0, 1, 2, 6, 7, 8])
    M[:, idx, idx] = (0.5 * m_line * L)[:, None]
    M[:, [3, 9], [3, 9]] = (0.5 * ip * L)[:, None]
    return M


def _block_diag4(R):
    T = np.zeros((R.shape[0], 12, 12))
    for k in range(4):
        T[:, 3 * k : 3 * k + 3, 3 * k : 3 * k + 3] = R
    return T


def condensation(K, released) -> np.ndarray:
    """(n, 12, 12) T with u = T u for the released DOFs (n, 12) bool eliminated by static
    condensation: released rows -K_pp^-1 K_pr, other rows the identity, released columns 0."""
    P = released.astype(float)
    keep = 1.0 - P
    A = K * P[:, :, None] * P[:, None, :] + np.eye(12) * keep[:, :, None]
    B = K * P[:, :, None] * keep[:, None, :]
    return np.eye(12) * keep[:, None, :] - np.linalg.solve(A, B)


def pin_mechanisms(K, released) -> np.ndarray:
    """(n,) True where the released DOFs (n, 12) let the element move without strain (K_pp
    singular: e.g. the axial or twist DOF released at both ends)."""
    P = released.astype(float)
    scale = np.abs(np.diagonal(K, axis1=1, axis2=2)).max(axis=1)
    A = (
        K * P[:, :, None] * P[:, None, :]
        + (scale[:, None, None] * np.eye(12)) * (1.0 - P)[:, :, None]
    )
    w = np.linalg.eigvalsh(A)
    return w[:, 0] < 1e-10 * scale


def element_local(L, b: GeneralBeams, idx, shear: bool, rotary: bool):
    """Element-axis (K, M) (k, 12, 12) of beams ``idx`` (before pins, offsets and rotation to
    global axes)."""
    alpha = principal_angle(b.iy[idx], b.iz[idx], b.iyz[idx])
    sub = _subset(b, idx)
    iy, iz, asy, asz = _principal_properties(sub, alpha)
    if not shear:
        asy = asz = np.full(len(idx), np.inf)
    m_line = sub.rho * sub.area + sub.nsm
    kind = np.asarray(MASS_KINDS)[sub.mass]
    translational = kind == "translational"
    rot = np.where(translational, 0.0, 1.0 if rotary else 0.0)
    twist = np.where(translational, 0.0, sub.torsion_inertia)
    K, M = local_matrices(
        L,
        sub.E,
        sub.G,
        sub.area,
        iy,
        iz,
        sub.torsion,
        asy,
        asz,
        m_line,
        rot * sub.rho * iy,
        rot * sub.rho * iz,
        twist,
    )
    M[kind == "lumped"] = lumped_mass(L, m_line, sub.torsion_inertia)[kind == "lumped"]
    M[kind == "none"] = 0.0
    tapered = is_tapered(sub)
    if np.any(tapered):  # iyz = 0 there (the builder's check): principal axes are local ones
        t = tapered
        K[t] = tapered_stiffness(L[t], sub.E[t], sub.G[t], section_ends(sub)[t], sub.shear_y[t],
                                 sub.shear_z[t], shear)  # fmt: skip
    turned = alpha != 0
    if np.any(turned):
        c, s = np.cos(alpha[turned]), np.sin(alpha[turned])
        Q = np.zeros((c.size, 3, 3))
        Q[:, 0, 0] = 1.0
        Q[:, 1, 1], Q[:, 1, 2], Q[:, 2, 1], Q[:, 2, 2] = c, s, -s, c
        T = _block_diag4(Q)
        Tt = T.transpose(0, 2, 1)
        K[turned] = Tt @ K[turned] @ T
        M[turned] = Tt @ M[turned] @ T
    return K, M


def _subset(b: GeneralBeams, idx) -> GeneralBeams:
    return GeneralBeams(**{k: getattr(b, k)[idx] for k in b.__dataclass_fields__})


def general_beam_matrices(xyz, b: GeneralBeams, shear=True, rotary_inertia=True):
    """Global (K, M) (n, 12, 12) at the nodes' DOFs of general beams ``b`` on nodes xyz (N, 3).

    shear=False drops shear deformation, rotary_inertia=False the rotary inertia of bending
    (the structure's settings)."""
    R, L = end_frames(xyz, b)
    idx = np.arange(b.n_elements)
    K, M = element_local(L, b, idx, shear, rotary_inertia)
    released = b.pins.reshape(-1, 12)
    pinned = np.flatnonzero(released.any(axis=1))
    if pinned.size:
        T = condensation(K[pinned], released[pinned])
        Tt = T.transpose(0, 2, 1)
        K[pinned] = Tt @ K[pinned] @ T
        M[pinned] = Tt @ M[pinned] @ T
    K, M = to_global(K, R), to_global(M, R)
    off = np.flatnonzero(np.any(b.offset != 0, axis=(1, 2)))
    if off.size:
        G = np.zeros((off.size, 12, 12))
        G[:, :6, :6] = rigid_link(b.offset[off, 0])
        G[:, 6:, 6:] = rigid_link(b.offset[off, 1])
        Gt = G.transpose(0, 2, 1)
        K[off] = Gt @ K[off] @ G
        M[off] = Gt @ M[off] @ G
    return K, M
