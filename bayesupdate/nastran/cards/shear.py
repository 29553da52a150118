"""CSHEAR + PSHEAR (MSC Nastran QRG) as ``fe.elements.shear_panel`` elements.

A PSHEAR gives the panel's MAT1 (its G and NU, completed from any two of E, G, NU), thickness T
and NSM.  Refused, each naming its card: PSHEAR F1-F4 other than 0 (the extensional stiffness
of effective rods along the sides, not modelled), a MAT1 with no shear modulus, a panel with an
interior angle of 180 degrees or more (the QRG's rule) or a repeated GRID.  The mass is lumped at
the corners (translational), whatever PARAM COUPMASS says (``fe.elements.shear_panel``).
"""

import numpy as np

from bayesupdate.fe.elements.shear_panel import ShearPanels, convex
from bayesupdate.nastran.cards.common import Context, mat1

#: the cards this file converts (``cards.FAMILIES``)
CARDS = ("CSHEAR", "PSHEAR")


def add(ctx: Context) -> None:
    """The CSHEAR cards, each with its PSHEAR's (G, NU, T, RHO x WTMASS, NSM x WTMASS, part
    "PSHEAR pid"); their ``ShearPanels`` join the built structure (``Context.finishers``)."""
    found, props = [], {}
    ctx.each(("CSHEAR",), lambda ctx, e: found.append(_panel(ctx, e, props)))
    found = [f for f in found if f is not None]
    if found:
        ctx.finishers.append(lambda parts: shear_panels(found, parts))


def _panel(ctx: Context, e, props: dict):
    """(node indices (4,), property record) of one CSHEAR, or None where its PSHEAR was
    refused; its own faults raise ``CardError``."""
    p = ctx.prop(e, ("PSHEAR",))
    if p.id() not in props:
        props[p.id()] = ctx.refusals.guard(_pshear, ctx, p)
    ids = [e.int(f"G{i}", positive=True) for i in range(1, 5)]
    if len(set(ids)) < 4:
        e.fail(f"GRIDs {ids}: a corner is repeated")
    rows = ctx.grids.index(ids, e)
    if not convex(ctx.grids.xyz[rows][None])[0]:
        e.fail("an interior angle is 180 degrees or more (QRG CSHEAR), or the corners are not "
               "in order around the panel")  # fmt: skip
    return None if props[p.id()] is None else (ctx.node[rows], props[p.id()])


def _pshear(ctx: Context, p) -> tuple:
    """(G, NU, T, RHO x WTMASS, NSM x WTMASS, part name) of a PSHEAR."""
    given = [f"F{i}" for i in range(1, 5) if p.value(3 + i) not in (None, 0, 0.0)]
    if given:
        p.fail(f"{', '.join(given)} (the sides' extensional stiffness) are not supported; "
               "give 0 or blank")  # fmt: skip
    t = p.real("T")
    if not t > 0:
        p.fail(f"T = {t:g}: it must be > 0")
    m = mat1(ctx, p.int("MID", positive=True), p)
    if not m.G > 0:
        p.fail(f"MAT1 {p['MID']}: a shear panel needs G > 0 (or E and NU)")
    return m.G, m.NU, t, m.RHO * ctx.wtmass, p.real("NSM") * ctx.wtmass, f"PSHEAR {p.id()}"


def shear_panels(found: list, parts: tuple):
    """(``ShearPanels`` of the records [(nodes (4,), property record)], the parts extended with
    the PSHEARs' names)."""
    names = list(parts)
    for _, prop in found:
        if prop[5] not in names:
            names.append(prop[5])
    values = np.array([prop[:5] for _, prop in found], dtype=float)
    panels = ShearPanels(
        nodes=np.array([nodes for nodes, _ in found], dtype=np.int64),
        part=np.array([names.index(prop[5]) for _, prop in found], dtype=np.int64),
        G=values[:, 0], nu=values[:, 1], thickness=values[:, 2], rho=values[:, 3],
        nsm=values[:, 4],
    )  # fmt: skip
    return panels, tuple(names)
