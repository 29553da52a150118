"""Element cards' own fields as parameters, solved without reading the cards again.

A DVCREL1 of the authors' SOL 200 deck (or a binding such as ``CBEAM 2001 W1A``:
``bindings.CARD_FIELDS``) writes a CBAR/CBEAM end offset, a CONM2's M, X1-X3 or I11-I33, or a
CMASS2's M.  ``lines.LineRebuild`` (the reference) writes the values into copies of the cards
and converts them again at every solve: 56 ms on the SOL 200 deck (44 offset beams, 47 mass
cards) a solve, against 8 ms for its eigen-solve.  Their matrices are not affine in these fields (a
beam's length, axis, local frame and lumped end masses follow its offsets; a CONM2's offset x
enters as m skew(x)^T skew(x)), but what the reader makes of the cards is
(``affine_records``):

* a beam's record (``GeneralBeams``: E, G, rho, A, I, J, NSM, its end offsets in basic axes)
  is affine in each card field that sets it, bilinear in two (rho and A: the mass per length);
* a CONM2's mass, offset and inertia tensor (global axes, x WTMASS) are affine in its fields;
* a CMASS2's mass is its M (x WTMASS).

``card_records`` finds those maps once from the reader's records of the bound cards
(``LineRebuild.structure_at``); a solve then derives the rest as the reader does
(``cards.beams.end_geometry``: length, axis and local z from the offset ends and the
orientation vector; lumped end masses (rho A + NSM) L / 2 each, with half the CBEAM twist
inertia ``cards.beams.lumped_twist``), computes the elements in the vectorized kernels
(``general_beam_matrices``; point masses T^T D T, ``point_mass_matrices``, with the inertia J in
D; scalar masses m v v^T, ``ScalarMasses``) and gives the change from the deck's values on
the assembled pattern.
The CONM2 inertia is one block J here where the reader splits it into scalar masses on its
principal axes (``cards.masses``): the same matrix, to round-off.

The whole is checked once at seeded points of the box against ``LineRebuild``: the records to
``affine_records.RECORD_TOL``, the matrices' data to ``LINEAR_TOL`` of their largest entry.
Where either misses (a PBEAML dimension on an offset beam, a field that changes which elements
there are), the reference stays, and ``lines.LineAssembler`` says why.
"""

from dataclasses import dataclass, replace

import numpy as np

from bayesupdate.fe.elements.base import grounded_line_dofs
from bayesupdate.fe.elements.general_beam import general_beam_matrices
from bayesupdate.fe.elements.point_mass import offset_link, point_mass_matrices
from bayesupdate.fe.elements.scalar_mass import ScalarMasses
from bayesupdate.fe.line_update import _positions
from bayesupdate.nastran.affine_records import AffineRecords, fit_records
from bayesupdate.nastran.cards.beams import end_geometry, lumped_twist, orientation_vector
from bayesupdate.nastran.cards.common import _by_id

#: ``GeneralBeams`` fields a card sets (with ``offset``: a bound offset moves it)
BEAM_RECORDS = ("E", "G", "rho", "area", "iy", "iz", "iyz", "torsion", "shear_y", "shear_z",
                "nsm", "torsion_inertia", "offset")  # fmt: skip
#: relative miss allowed between these matrices and the reference's, of the largest entry
LINEAR_TOL = 1e-9
#: the seeded points of the box where the matrices are checked against the reference
CHECK_SEED, CHECK_POINTS = 1, 2


@dataclass(frozen=True)
class Layout:
    """What the parameters may not change, of a reading of the bound cards (a structure of
    them alone, ``LineRebuild.structure_at``): beam nodes (n_b, 2), pins, mass kinds, CBEAM
    flags (n_b,); CONM2 rows of its point masses (n_c,) and nodes; the lumped end masses'
    nodes (2 n_l,); CMASS rows of its scalar masses (n_s,), their nodes (n_s, 2) and DOF
    directions (n_s, 2, 6)."""

    beam_nodes: np.ndarray
    pins: np.ndarray
    mass_kind: np.ndarray
    conm2: np.ndarray
    conm2_nodes: np.ndarray
    lumped_nodes: np.ndarray
    cmass: np.ndarray
    cmass_nodes: np.ndarray
    cmass_direction: np.ndarray

    def same(self, other: "Layout") -> bool:
        return all(np.array_equal(getattr(self, f), getattr(other, f))
                   for f in self.__dataclass_fields__)  # fmt: skip


def layout(probe) -> Layout:
    """The ``Layout`` of a reading ``probe`` (a ``Structure``)."""
    names = np.asarray(probe.parts)
    mass_names = names[probe.mass_part] if probe.mass_part.size else np.zeros(0, str)
    conm2 = np.flatnonzero(np.char.startswith(mass_names.astype(str), "CONM2 "))
    lumped = np.setdiff1d(np.arange(mass_names.size), conm2)
    sm = probe.scalar_masses
    cmass = np.zeros(0, int)
    if sm is not None:
        cmass = np.flatnonzero(np.char.startswith(names[sm.part].astype(str), "CMASS"))
    b = probe.general_beams
    empty = np.zeros((0, 2), int)
    return Layout(
        empty if b is None else b.nodes, np.zeros(0) if b is None else b.pins,
        np.zeros(0) if b is None else b.mass, conm2, probe.mass_node[conm2],
        probe.mass_node[lumped], cmass,
        empty if sm is None else sm.nodes[cmass],
        np.zeros((0, 2, 6)) if sm is None else sm.direction[cmass],
    )  # fmt: skip


def records(probe, lay: Layout) -> dict[str, np.ndarray]:
    """{key: array} the records of a reading ``probe`` (module docstring): "beam.<field>" of
    ``BEAM_RECORDS``; "conm2.mass" (n_c,), "conm2.offset" (n_c, 3), "conm2.inertia" (n_c, 3,
    3), the last the sum of the CONM2's scalar masses on rotations (its principal axes);
    "cmass.mass" (n_s,)."""
    out = {}
    if probe.general_beams is not None:
        out.update({f"beam.{f}": getattr(probe.general_beams, f) for f in BEAM_RECORDS})
    if lay.conm2.size:
        out["conm2.mass"] = probe.mass_value[lay.conm2]
        out["conm2.offset"] = probe.mass_offset[lay.conm2]
        out["conm2.inertia"] = _conm2_inertia(probe, lay.conm2)
    if lay.cmass.size:
        out["cmass.mass"] = probe.scalar_masses.mass[lay.cmass]
    return out


def _conm2_inertia(probe, conm2: np.ndarray) -> np.ndarray:
    """(n_c, 3, 3) each CONM2's inertia about its centre: the sum of its part's scalar masses
    m d d^T on rotations (``cards.masses._add_rotary_inertia``) plus its point mass's own."""
    J = probe.mass_inertia[conm2].copy()
    sm = probe.scalar_masses
    if sm is None:
        return J
    for k, row in enumerate(conm2):
        for e in np.flatnonzero(sm.part == probe.mass_part[row]):
            d = sm.direction[e, 0, 3:]
            J[k] += sm.mass[e] * np.outer(d, d)
    return J


@dataclass(frozen=True, eq=False)
class CardRecords:
    """The bound cards' matrices from ``fit`` (``AffineRecords``) at a point (module
    docstring).

    beams0 : ``GeneralBeams`` of the bound beams at the deck's values (their nodes, pins, mass
    kinds; the other fields follow ``fit``); v : (n_b, 3) orientation vectors in basic; cbeam :
    (n_b,) True for a CBEAM (lumped twist inertia); lumped : (n_l,) the beams with lumped end
    masses; lay : the readings' ``Layout``; nodes : (N, 3) the structure's node coordinates;
    shear, rotary : its beam settings; positions : {kind: (k,) places in the pattern's data};
    nnz : the pattern's size; base : (K, M) (nnz,) of the cards as read (``LineRebuild.base``).
    """

    fit: AffineRecords
    beams0: object
    v: np.ndarray
    cbeam: np.ndarray
    lumped: np.ndarray
    lay: Layout
    nodes: np.ndarray
    shear: bool
    rotary: bool
    positions: dict
    nnz: int
    base: tuple = ()

    def theta(self, values) -> np.ndarray:
        """(p,) the parameters of ``values`` ({name: deck units})."""
        return np.array([float(values[n]) for n in self.fit.names])

    def delta(self, values) -> tuple[np.ndarray, np.ndarray]:
        """(dK, dM) (nnz,) from the deck's values to ``values`` ({name: deck units})."""
        K, M = self.data(self.theta(values))
        return K - self.base[0], M - self.base[1]

    def data(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(K, M) (nnz,) of the bound cards at ``theta`` (p,)."""
        rec, n, pos = self.fit.at(theta), self.nnz, self.positions
        K, M = np.zeros(n), np.zeros(n)
        if "beam" in pos:
            beams, masses = self._beams(rec)
            Kb, Mb = general_beam_matrices(self.nodes, beams, self.shear, self.rotary)
            K += np.bincount(pos["beam"], Kb.ravel(), n)
            M += np.bincount(pos["beam"], Mb.ravel(), n)
            if "lumped" in pos:
                M += np.bincount(pos["lumped"], point_mass_matrices(*masses).ravel(), n)
        if "conm2" in pos:
            Mc = point_mass_matrices(offset_link(rec["conm2.offset"]), rec["conm2.mass"],
                                     rec["conm2.inertia"])  # fmt: skip
            M += np.bincount(pos["conm2"], Mc.ravel(), n)
        if "cmass" in pos:
            lay = self.lay
            scalar = ScalarMasses(lay.cmass_nodes, lay.cmass_direction, rec["cmass.mass"],
                                  np.zeros(lay.cmass.size, int))  # fmt: skip
            M += np.bincount(pos["cmass"], scalar.matrices(self.nodes, None)[1].ravel(), n)
        return K, M

    def _beams(self, rec) -> tuple[object, tuple]:
        """(``GeneralBeams`` at the records, (T, m, J) of their lumped end masses)."""
        b = replace(self.beams0, **{f: rec[f"beam.{f}"] for f in BEAM_RECORDS})
        length, axis, up = end_geometry(self.nodes[b.nodes], b.offset, self.v)
        b = replace(b, up=up)
        k = self.lumped
        line = b.rho[k] * b.area[k] + b.nsm[k]
        twist = 0.5 * lumped_twist(b.rho[k] * (b.iy[k] + b.iz[k]), length[k], axis[k])
        twist[~self.cbeam[k]] = 0.0
        m = np.repeat(0.5 * line * length[k], 2)
        J = np.repeat(twist, 2, axis=0)
        return b, (offset_link(b.offset[k].reshape(-1, 3)), m, J)


def card_records(g, rebuild, defaults, bounds) -> tuple[CardRecords | None, str]:
    """(``CardRecords`` of the cards ``rebuild`` (a ``lines.LineRebuild`` of part "offset" or
    "mass") converts, "") or (None, the reason they keep being converted at every solve).

    g : the ``GeneralAssembler`` of the whole structure (its pattern); defaults, bounds :
    {name: deck value}, {name: (low, high)} (deck units)."""
    names = tuple(rebuild.bindings)
    theta0 = np.array([float(defaults[n]) for n in names])
    low, high = (np.array([float(bounds[n][k]) for n in names]) for k in (0, 1))
    probe0 = rebuild.structure_at(dict(zip(names, theta0, strict=True)))
    lay = layout(probe0)

    def read(theta):
        at = rebuild.structure_at(dict(zip(names, theta, strict=True)))
        return records(at, lay) if lay.same(layout(at)) else None

    fit, reason = fit_records(read, names, theta0, low, high)
    if fit is None:
        return None, reason
    made = _assemble(g, rebuild, probe0, lay, fit)
    if isinstance(made, str):
        return None, made
    # the reference's own base: the cards as read, which the DESVARs' initial values written
    # through their relations need not reproduce (the deck's XINITs and cards differ slightly)
    made = replace(made, base=rebuild.base)
    reason = _check(made, rebuild, low, high)
    return (None, reason) if reason else (made, "")


def reused_records(g, rebuild, known: CardRecords) -> CardRecords | None:
    """``known`` (the ``CardRecords`` of the same deck and bindings on another structure: the
    model before a discovery effect was added) on the assembler ``g`` of the extended
    structure, or None where it does not hold there.  An effect appends nodes and elements, so
    the bound cards read on the extended structure must have the same ``Layout`` on nodes at
    the same places; the fit depends on the cards alone (47 readings of them on the SOL 200
    deck, whose first solve takes 1.3 s), and only the places in the new pattern are found
    again."""
    s, n = g.structure, known.nodes.shape[0]
    if s.nodes.shape[0] < n or not np.array_equal(s.nodes[:n], known.nodes):
        return None
    probe0 = rebuild.structure_at(dict(zip(known.fit.names, known.fit.theta0, strict=True)))
    lay = layout(probe0)
    if not lay.same(known.lay):
        return None
    made = _assemble(g, rebuild, probe0, lay, known.fit)
    return None if isinstance(made, str) else replace(made, base=rebuild.base)


def _assemble(g, rebuild, probe0, lay: Layout, fit: AffineRecords) -> CardRecords | str:
    """The ``CardRecords`` of the fitted records on the pattern of ``g``, or the reason there
    is none (beams that do not match their cards, lumped masses not two per beam)."""
    s, b = g.structure, probe0.general_beams
    keys = g.rows.astype(np.int64) * g.n_dof + g.cols
    pos = {}
    v, cbeam, lumped = np.zeros((0, 3)), np.zeros(0, bool), np.zeros(0, int)
    if b is not None:
        found = _orientations(rebuild, b)
        if isinstance(found, str):
            return found
        v, cbeam = found
        if s.metadata["nastran"]["coupmass"] < 1:  # the reader's lumped end masses
            lumped = np.flatnonzero(b.rho * b.area + b.nsm > 0)
        if not np.array_equal(lay.lumped_nodes, b.nodes[lumped].ravel()):
            return "the bound beams' lumped end masses are not two per beam, in order"
        pos["beam"] = _positions(keys, g.n_dof, b.dofs())
        if lumped.size:
            pos["lumped"] = _positions(keys, g.n_dof, _node_dofs(lay.lumped_nodes))
    elif lay.lumped_nodes.size:
        return "point masses other than CONM2 among the bound mass cards"
    if lay.conm2.size:
        pos["conm2"] = _positions(keys, g.n_dof, _node_dofs(lay.conm2_nodes))
    if lay.cmass.size:
        pos["cmass"] = _positions(keys, g.n_dof, grounded_line_dofs(lay.cmass_nodes))
    return CardRecords(fit, b, v, cbeam, lumped, lay, s.nodes, s.shear, s.rotary_inertia, pos,
                       g.nnz)  # fmt: skip


def _orientations(rebuild, beams) -> tuple[np.ndarray, np.ndarray] | str:
    """((n_b, 3) orientation vectors in basic, (n_b,) CBEAM flags) of the reading's beams, from
    their cards in the reader's order (``cards.common.Context.each``: by id); the reason where
    the cards' grids are not the beams' nodes."""
    cards = [c for _, c in sorted(rebuild.elements.items(), key=_by_id)
             if c.name in ("CBAR", "CBEAM")]  # fmt: skip
    if len(cards) != beams.n_elements:
        return "the bound beams do not match their cards one to one"
    v = np.zeros((len(cards), 3))
    for k, card in enumerate(cards):
        rows, v[k] = orientation_vector(rebuild.grids, card)
        if not np.array_equal(rebuild.node[rows], beams.nodes[k]):
            return "the bound beams do not match their cards one to one"
    return v, np.array([c.name == "CBEAM" for c in cards])


def _node_dofs(nodes: np.ndarray) -> np.ndarray:
    return 6 * np.asarray(nodes)[:, None] + np.arange(6)


def _check(made: CardRecords, rebuild, low, high) -> str:
    """ "" when ``made`` gives the reference's (``rebuild.delta``) change of the matrices at the
    seeded points of the box to ``LINEAR_TOL`` of the largest entry, else the reason."""
    names = made.fit.names
    rng = np.random.default_rng(CHECK_SEED)
    for u in rng.uniform(size=(CHECK_POINTS, len(names))):
        values = dict(zip(names, low + u * (high - low), strict=True))
        for which, (exact, mine, base) in enumerate(
            zip(rebuild.delta(values), made.delta(values), rebuild.base, strict=True)
        ):
            miss = np.abs(exact - mine).max(initial=0.0) / max(np.abs(base).max(initial=0.0),
                                                               1e-300)  # fmt: skip
            if miss > LINEAR_TOL:
                return (f"the element cards' {'KM'[which]} at new values miss the cards read "
                        f"again by {miss:.1e} of its largest entry")  # fmt: skip
    return ""
