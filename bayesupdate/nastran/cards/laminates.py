"""PCOMP / PCOMPG (a laminate of plies) with MAT8 (orthotropic) or MAT1 plies -> a shell section.

MSC Nastran QRG, PCOMP: plies from the bottom surface up, each MIDi Ti THETAi SOUTi (PCOMPG: one
ply a line, GPLYIDi MIDi Ti THETAi SOUTi); a blank MIDi or Ti repeats the ply below's; THETAi
[deg] is the ply's fibre angle from the element's material axis (CQUAD4/CTRIA3 THETA or MCID,
``reader``).  Z0 is the bottom surface's distance from the element's reference plane (default
-T/2: the plies centred on it); NSM the non-structural mass per area; SB, FT, TREF, GE (failure,
thermal and damping data) do not enter the real normal modes.  LAM: blank, all plies; SYM, the
plies given are the lower half of a symmetric stack; MEM, membrane stiffness only; BEND, bending
(and transverse shear) only.  MAT8 (QRG): E1, E2, NU12, G12; G1Z, G2Z the transverse shear moduli
(blank: infinite, no shear flexibility); RHO.  A MAT1 ply is isotropic: E1 = E2 = E,
G12 = G1Z = G2Z = G.

The stack's stiffness is classical lamination theory's (``fe.laminate``): A, B, D and the
first-order transverse shear H about the stack's mid-plane (B, the membrane-bending coupling
of an unsymmetric stack, Nastran's equivalent MID4, enters the shell as its coupling piece),
which sits Z0 + T/2 above the reference plane: a shell offset (``fe.elements.shell``'s ZOFFS
mechanism, added to the element's own ZOFFS), which couples membrane and bending as the
reference plane's A, B, D do.  Refused, each naming the card: LAM SMEAR / SMCORE, a Z0 off the
centre of a LAM MEM or BEND
stack (an offset needs both parts, as ZOFFS does on a PSHELL), a ply material that is neither
MAT1 nor MAT8.  A ply whose MAT8 leaves G1Z or G2Z blank (infinite, QRG MAT8) adds no transverse
shear compliance (``fe.laminate.transverse_shear``); when no ply has any, the shells are shear
rigid (Kirchhoff), as a PSHELL without MID3.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.fe.laminate import SHEAR_FACTOR, Ply, SectionMatrices, laminate, rotary_ratio
from bayesupdate.fe.laminate import section_per_unit_thickness as per_unit
from bayesupdate.nastran.cards.common import mat1

#: the laminate property cards (their plies' materials: MAT8 or MAT1)
CARDS = ("PCOMP", "PCOMPG")
#: LAM options read (blank: every ply given; the rest are refused)
LAM_OPTIONS = (None, "SYM", "MEM", "BEND")


@dataclass(frozen=True)
class LaminateSection:
    """A laminate property read: thickness T [m, deck units], mass per area of its plies
    rho_t [kg/m^2, WTMASS applied] and its NSM (as given), offset of its mid-plane above the
    reference plane Z0 + T/2 [m], its section per unit thickness in its material axes (one
    row), and which parts it has: membrane, bending (with transverse shear unless
    ``shear_rigid``)."""

    thickness: float
    rho_t: float
    nsm: float
    offset: float
    section: SectionMatrices
    membrane: bool
    bending: bool
    shear_rigid: bool

    @property
    def ratios(self) -> tuple[float, float, float]:
        """(bending ratio, shear ratio, membrane ratio) as ``ShellMesh`` reads them: the
        families and checks of a shell with these parts (the stiffness is the section's)."""
        shear = (np.inf if self.shear_rigid else SHEAR_FACTOR) if self.bending else 0.0
        return float(self.bending), shear, float(self.membrane)


def _ply_fields(p) -> list[tuple]:
    """(MID, T, THETA) of each ply as given, blanks as None (PCOMP: groups of four from field 10;
    PCOMPG: one ply a line, GPLYID first)."""
    start, size, first = (8, 4, 0) if p.name == "PCOMP" else (8, 8, 1)
    out = []
    for i in range(start, len(p.raw), size):
        mid, t, theta = (p.value(i + first + j) for j in range(3))
        if mid is None and t is None and theta is None:
            continue
        out.append((mid, t, theta))
    return out


def ply_materials(p) -> list[int]:
    """The MIDs a PCOMP/PCOMPG card's plies name (given ones; blanks repeat them)."""
    return [int(mid) for mid, _, _ in _ply_fields(p) if isinstance(mid, int)]


def _plies(ctx, p) -> list[Ply]:
    """The plies of PCOMP/PCOMPG ``p``, blanks repeating the ply below's MID and T."""
    plies, mid, t = [], None, None
    for k, (m, tk, theta) in enumerate(_ply_fields(p), start=1):
        mid, t = (mid if m is None else m), (t if tk is None else tk)
        if not isinstance(mid, int) or mid <= 0 or not isinstance(t, int | float) or not t > 0:
            p.fail(f"ply {k}: give its MID (or the ply below's) and its thickness T > 0")
        angle = np.radians(0.0 if theta is None else float(theta))
        plies.append(_ply(ctx, p, int(mid), float(t), angle))
    if not plies:
        p.fail("has no plies")
    return plies


def _ply(ctx, p, mid: int, t: float, angle: float) -> Ply:
    """A ply of material ``mid`` (MAT8 or MAT1), density x WTMASS."""
    card = ctx.mats.get(mid)
    if card is not None and card.name == "MAT8":
        E1, E2, G12 = (card.real(k) for k in ("E1", "E2", "G12"))
        if not (E1 > 0 and E2 > 0 and G12 > 0):
            card.fail("a ply's MAT8 needs E1, E2 and G12 > 0")
        nu12 = card.real("NU12")
        if not nu12**2 * E2 / E1 < 1:
            card.fail(f"NU12 = {nu12:g}: the ply's stiffness is not positive (NU12^2 E2/E1 >= 1)")
        Gz = [np.inf if card.is_blank(k) else card.real(k) for k in ("G1Z", "G2Z")]
        if not all(g > 0 for g in Gz):
            card.fail("G1Z and G2Z must be > 0 (blank: no transverse shear flexibility)")
        return Ply(E1, E2, nu12, G12, *Gz, card.real("RHO") * ctx.wtmass, t, angle)
    m = mat1(ctx, mid, p)  # refuses a material that is neither
    if not (-1 < m.NU < 0.5 and m.G > 0):
        p.fail(f"ply material MAT1 {mid}: NU = {m.NU:.4g}, G = {m.G:g}: a ply needs G > 0 and "
               "NU in (-1, 0.5)")  # fmt: skip
    return Ply(m.E, m.E, m.NU, m.G, m.G, m.G, m.RHO * ctx.wtmass, t, angle)


def laminate_section(ctx, p) -> LaminateSection:
    """The ``LaminateSection`` of PCOMP/PCOMPG card ``p`` (module docstring); refusals raise
    ``CardError`` naming the card."""
    lam = p.value(7)
    lam = str(lam).upper() if lam is not None else None
    if lam not in LAM_OPTIONS:
        p.fail(f"LAM {lam} is not supported (blank, SYM, MEM and BEND are)")
    plies = _plies(ctx, p)
    if lam == "SYM":
        plies = plies + plies[::-1]
    A, B, D, H = laminate(plies)
    h = sum(q.thickness for q in plies)
    if np.isnan(H).any():
        p.fail(
            "its plies are rigid in transverse shear in one plane only (MAT8 G1Z or G2Z "
            "blank on every ply that gives the other): give both or neither"
        )
    section = per_unit(A, B, D, H, h, rotary_ratio(plies))
    membrane, bending = lam != "BEND", lam != "MEM"
    coupling = section.coupling if membrane and bending else None  # MEM, BEND: one part alone
    section = SectionMatrices(section.membrane * membrane, section.bending * bending,
                              section.shear * bending, coupling, section.rotary)  # fmt: skip
    z0 = -h / 2 if p.is_blank("Z0") else p.real("Z0")
    if lam in ("MEM", "BEND") and abs(z0 + h / 2) > 1e-9 * h:
        p.fail(f"Z0 = {z0:g} offsets a LAM {lam} stack: an offset needs both membrane and bending")
    return LaminateSection(
        thickness=h, rho_t=sum(q.rho * q.thickness for q in plies),
        nsm=p.real("NSM"), offset=z0 + h / 2, section=section,
        membrane=membrane, bending=bending, shear_rigid=not np.all(np.isfinite(H)),
    )  # fmt: skip
