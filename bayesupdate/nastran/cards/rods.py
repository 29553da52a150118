"""CROD (with PROD), CONROD and CTUBE (with PTUBE) as ``fe.elements.rod`` elements (MSC Nastran
QRG).  A CTUBE is the CROD of its tube (QRG PTUBE: outer diameter OD, wall T, T = 0 a solid
circular rod): A = pi (OD^2 - D_i^2) / 4 and J = pi (OD^4 - D_i^4) / 32 with D_i = OD - 2T.  A
tapered PTUBE (OD2 other than OD) and a wall T outside [0, OD/2] are refused."""

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran.cards.common import (
    Context,
    _builder_message,
    _lumped_mass,
    mat1,
    material,
)

#: the cards this file converts (``cards.FAMILIES``)
CARDS = ("CROD", "CONROD", "CTUBE", "PTUBE")


def rod_values(e, p) -> tuple[int, float, float, float]:
    """(MID, A, J, NSM) of a CROD's PROD, a CONROD or a CTUBE's PTUBE (``tube_section``)."""
    if p.name == "PTUBE":
        return p.int("MID", positive=True), *tube_section(p), p.real("NSM")
    return p.int("MID", positive=True), p.real("A"), p.real("J"), p.real("NSM")


def tube_section(p) -> tuple[float, float]:
    """(A, J) of a PTUBE (module docstring)."""
    od = p.real("OD")
    t = 0.0 if p.is_blank("T") else p.real("T")
    if not od > 0 or not 0 <= t <= od / 2:
        p.fail(f"needs OD > 0 and 0 <= T <= OD/2 (T = 0: a solid rod), got OD {od:g}, T {t:g}")
    if not p.is_blank("OD2") and p.real("OD2") != od:
        p.fail("a tapered tube (OD2 other than OD) is not supported")
    inner = od - 2 * t if t > 0 else 0.0
    return np.pi * (od**2 - inner**2) / 4, np.pi * (od**4 - inner**4) / 32


def add(ctx: Context) -> None:
    """CROD (with PROD), CONROD and CTUBE (with PTUBE) as rods (``fe.elements.rod``): axial
    EA / L and torsion GJ / L (G from MAT1), consistent mass (COUPMASS 1) or mass lumped at the
    ends."""
    ctx.each(("CROD", "CONROD", "CTUBE"), _add_rod)


def _add_rod(ctx: Context, e) -> None:
    p = e if e.name == "CONROD" else ctx.prop(e, ("PTUBE",) if e.name == "CTUBE" else ("PROD",))
    mid, area, j, nsm = rod_values(e, p)
    mat = material(ctx, mid, e)
    rows = ctx.rows(e, ("G1", "G2"))
    x = ctx.grids.xyz[rows]
    length = np.linalg.norm(x[1] - x[0])
    a, b = ctx.node[rows]
    part = f"CONROD {e.id()}" if e.name == "CONROD" else f"{p.name} {p.id()}"
    nsm = nsm * ctx.wtmass
    try:
        ctx.builder.add_rods(
            [[a, b]], area, mat, part, torsion=j, nsm=nsm,
            mass="none" if ctx.lumped else "consistent", shear_modulus=mat1(ctx, mid, e).G,
        )  # fmt: skip
    except BayesUpdateError as exc:
        e.fail(_builder_message(exc))
    if ctx.lumped:
        _lumped_mass(ctx, (a, b), mat.density * area + nsm, length, part)
