"""CROD (with PROD) and CONROD as ``fe.elements.rod`` elements (MSC Nastran QRG)."""

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
CARDS = ("CROD", "CONROD")


def rod_values(e, p) -> tuple[int, float, float, float]:
    """(MID, A, J, NSM) of a CROD's PROD or a CONROD."""
    return p.int("MID", positive=True), p.real("A"), p.real("J"), p.real("NSM")


def add(ctx: Context) -> None:
    """CROD (with PROD) and CONROD as rods (``fe.elements.rod``): axial EA / L and torsion GJ / L
    (G from
    MAT1), consistent mass (COUPMASS 1) or mass lumped at the ends."""
    ctx.each(("CROD", "CONROD"), _add_rod)


def _add_rod(ctx: Context, e) -> None:
    p = e if e.name == "CONROD" else ctx.prop(e, ("PROD",))
    mid, area, j, nsm = rod_values(e, p)
    mat = material(ctx, mid, e)
    rows = ctx.rows(e, ("G1", "G2"))
    x = ctx.grids.xyz[rows]
    length = np.linalg.norm(x[1] - x[0])
    a, b = ctx.node[rows]
    part = f"CONROD {e.id()}" if e.name == "CONROD" else f"PROD {p.id()}"
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
