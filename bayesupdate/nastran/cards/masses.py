"""CONM2, CONM1 and CMASS1/CMASS2 as point masses (MSC Nastran QRG).

CONM2 inertia is [[I11, -I21, -I31], [-I21, I22, -I32], [-I31, -I32, I33]] in its CID frame; a
CMASS on one grid's rotation is an inertia about that CD axis.  Masses are x WTMASS.
"""

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran.cards import scalar
from bayesupdate.nastran.cards.common import Context, _builder_message
from bayesupdate.nastran.frames import coordinate

#: the cards this file converts (``cards.FAMILIES``)
CARDS = ("CONM2", "CONM1", "CMASS1", "CMASS2", "CMASS3", "CMASS4")


def add(ctx: Context) -> None:
    """CONM2 (offset and inertia; CID -1, 0 or rectangular), CONM1 (any symmetric PSD 6x6) and
    CMASS1-4 (on a grid's rotation 4, 5, 6: an inertia about that CD axis; scalar points)."""
    ctx.each(("CONM2",), _add_conm2)
    ctx.each(("CONM1",), _add_conm1)
    ctx.each(("CMASS1", "CMASS2", "CMASS3", "CMASS4"), _add_cmass)


def _mass_frame(ctx: Context, m):
    cid = m.int("CID")
    if cid in (-1, 0):
        return np.eye(3)
    coord = coordinate(ctx.grids, cid, m)
    if coord.kind != "rectangular":
        m.fail(f"CID {cid} is not rectangular")
    return coord.axes


def conm2_inertia(fields) -> np.ndarray:
    """(3, 3) inertia of a CONM2's six fields (I11, I21, I22, I31, I32, I33): the products are
    entered negated (MSC QRG CONM2: [[I11, -I21, -I31], [-I21, I22, -I32], [-I31, -I32, I33]])."""
    i11, i21, i22, i31, i32, i33 = (float(v) for v in fields)
    return np.array([[i11, -i21, -i31], [-i21, i22, -i32], [-i31, -i32, i33]])


def _add_conm2(ctx: Context, m) -> None:
    row = ctx.rows(m, ("G",))[0]
    R = _mass_frame(ctx, m)
    offset = np.array([m.real(k) for k in ("X1", "X2", "X3")])
    offset = offset - ctx.grids.xyz[row] if m.int("CID") == -1 else R.T @ offset
    J = conm2_inertia([m.real(k) for k in ("I11", "I21", "I22", "I31", "I32", "I33")])
    J = R.T @ J @ R * ctx.wtmass
    try:
        ctx.builder.add_point_mass(ctx.node[row], m.real("M") * ctx.wtmass, f"CONM2 {m.id()}",
                                   None, offset)  # fmt: skip
    except BayesUpdateError as exc:
        m.fail(_builder_message(exc))
    _add_rotary_inertia(ctx, m, ctx.node[row], J)


def _add_rotary_inertia(ctx: Context, m, node: int, J: np.ndarray) -> None:
    """A CONM2's own inertia J (3, 3), global axes, about its centre of gravity: the rotation
    block [[0, 0], [0, J]] of its 6x6 at the grid whatever the offset (the centre's rotations
    are the grid's), as grounded scalar masses on its principal axes (``fe.scalar_mass``).
    Kept apart from the point mass so that a binding on CONM2 M scales M (and the offset's
    m d^2 terms) but not I11-I33, as a deck with M edited does (MSC QRG CONM2: M and Iij are
    separate fields)."""
    if not np.any(J):
        return
    lam, V = np.linalg.eigh(0.5 * (J + J.T))
    if lam.min() < -1e-12 * max(lam.max(), 1e-300):
        m.fail(f"the inertia is not positive semi-definite (eigenvalue {lam.min():.3g})")
    for k in np.flatnonzero(lam > 1e-14 * lam.max()):
        ctx.builder.add_scalar_mass(node, np.r_[np.zeros(3), V[:, k]], float(lam[k]),
                                    f"CONM2 {m.id()}")  # fmt: skip


def _add_conm1(ctx: Context, m) -> None:
    """CONM1 (MSC QRG: a 6x6 symmetric mass matrix at a grid, in CID; lower triangle Mij).  A
    rigid-body matrix (M_tt = m I, M_tr = -m skew(c), c the offset of the centre of mass) is a
    point mass with its inertia about that centre; any other positive semi-definite matrix is
    the sum of its eigen-terms lambda_k v_k v_k^T, each a grounded scalar mass on the direction
    v_k (6,) of the grid's six DOFs (``fe.elements.scalar_mass``), which is the matrix itself."""
    from bayesupdate.fe.rotations import skew

    row = ctx.rows(m, ("G",))[0]
    R = _mass_frame(ctx, m)
    lower = [m.real(f"M{i}{j}") for i in range(1, 7) for j in range(1, i + 1)]
    M = np.zeros((6, 6))
    M[np.tril_indices(6)] = lower
    M = (M + np.tril(M, -1).T) * ctx.wtmass
    T = np.kron(np.eye(2), R)
    M = T.T @ M @ T
    mass, node = M[0, 0], ctx.node[row]
    if mass > 0 and np.allclose(M[:3, :3], mass * np.eye(3), rtol=1e-12, atol=0):
        S = -M[:3, 3:] / mass  # = skew(c) when M is a rigid body's
        c = np.array([S[2, 1], S[0, 2], S[1, 0]])
        if np.allclose(S, skew(c[None])[0], rtol=1e-12, atol=1e-12 * np.abs(S).max()):
            J = M[3:, 3:] - mass * skew(c[None])[0].T @ skew(c[None])[0]
            try:
                ctx.builder.add_point_mass(node, mass, f"CONM1 {m.id()}", J, c)
                return
            except BayesUpdateError:
                pass  # an inertia that is not PSD about the centre: the general matrix below
    lam, V = np.linalg.eigh(M)
    if lam.min() < -1e-12 * max(lam.max(), 1e-300):
        m.fail(f"the mass matrix is not positive semi-definite (eigenvalue {lam.min():.3g})")
    for k in np.flatnonzero(lam > 1e-14 * lam.max()):
        ctx.builder.add_scalar_mass(node, V[:, k], float(lam[k]), f"CONM1 {m.id()}")


def _add_cmass(ctx: Context, m) -> None:
    """CMASS1-4: a scalar mass (``fe.elements.scalar_mass``) on the DOF of its first end and, with a
    second, between the two (``scalar.ends``: GRID components in their CD frames, scalar
    points); a rotation component makes it a rotary inertia about that axis."""
    value = ctx.prop(m, ("PMASS",)).real("M") if m.name in ("CMASS1", "CMASS3") else m.real("M")
    if value < 0:
        m.fail("a negative mass is not supported")
    points = scalar.ends(ctx, m)
    if not points:
        m.fail("both ends are grounded: give a GRID or SPOINT at one end at least")
    a = points[0]
    b = {}
    if len(points) == 2:
        if points[1].node == a.node and np.allclose(points[1].direction, a.direction):
            m.fail(f"both ends are {a.label} (MSC QRG: the two points must be distinct)")
        b = dict(node_b=points[1].node, component_b=points[1].comp, frame_b=points[1].frame)
    try:
        ctx.builder.add_scalar_mass(a.node, a.comp, value * ctx.wtmass, f"{m.name} {m.id()}",
                                    frame_a=a.frame, **b)  # fmt: skip
    except BayesUpdateError as exc:
        m.fail(_builder_message(exc))
    if any(p.spoint is not None for p in points):
        ctx.spoint_masses.append((value * ctx.wtmass, points))
