"""Line-element fields of a Nastran deck as parameters: the bound elements' records follow the
parameters, and only their matrices are computed again.

A binding to a PBAR/PBARL/PBEAM/PBEAML/PROD field, or to the MAT1 E or RHO of a line property,
acts on CBAR/CBEAM/CROD/CONROD elements, which ``fe.assembly`` assembles once.  Two ways give
their matrices at new values, both the reading of the deck written with them:

* ``LineRebuild`` (the reference): copies of the bound cards get the parameters' values
  (``bindings.set_field``, as ``--write-bdf`` writes them) and the bound elements alone are
  converted again on the structure's nodes (``cards.add_beams``/``add_rods``: sections,
  offsets, pins, lumped or consistent mass, WTMASS); about 2 ms of card reading per element.
* ``LineFields`` (the default): the converted elements' records (``GeneralBeams`` E, G, rho, A,
  I, J, shear factors, NSM, twist inertia; ``Rods``; the lumped end masses of COUPMASS < 1) are
  affine in each card field the reader maps them from (A -> area, I1 -> iz and rho (I1 + I2),
  E -> E and, G blank, G = E / 2(1 + NU), RHO -> rho and the lumped masses, NSM).  The map is
  found once from ``LineRebuild`` (the deck's records and one step per parameter) and checked at
  seeded points of the box against it; then a solve writes the records (a matrix-vector
  product) and recomputes the bound elements in the vectorized kernels (``fe.line_update``):

      K(theta) = K(deck) + sum_e P_e^T (K_e(records(theta)) - K_e(records(deck))) P_e,

  M likewise, P_e the element's positions in the general CSR pattern (exactly K(deck) at the
  deck's values).  The elements' matrices stay exact whatever the field: the Timoshenko shear
  parameter 12 EI / (k G A L^2) is not affine, its records are.  Records that are products of
  two bound fields (RHO and A or I1 of the same elements: rho A, the twist inertia
  rho (I1 + I2)) are bilinear: one more re-build per pair of parameters gives the
  cross terms, checked at the same seeded points.  A field whose records are neither (a
  PBARL/PBEAML dimension: A, I are polynomials in it) keeps ``LineRebuild`` at every solve.

For the reduced basis (``fe.reduced``), ``affine_line_terms`` finds the fields that enter K and M
linearly (a shear-rigid PBAR's A, I1, I2, J, a PROD's A and J, every NSM):
K_L(theta) = K_L(deck) + sum_j (theta_j - theta0_j) dK_j exactly; the others get
``interpolated_line_groups``: the bound elements grouped by the parameters acting on them, each
group's K, M interpolated in log(theta) on Chebyshev points (``fe.reduced.interpolation``) to
the reduced model's ``interp_tol``, as the built-in models' non-linear beam parameters are.
"""

from dataclasses import dataclass, replace

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.assembly import GeneralAssembler
from bayesupdate.fe.line_update import LineUpdate, PointMassValues
from bayesupdate.fe.structure import StructureBuilder
from bayesupdate.nastran import cards
from bayesupdate.nastran.affine_records import AffineRecords, fit_records
from bayesupdate.nastran.bindings import (
    LINE_ELEMENTS,
    MASS_CARDS,
    _card,
    is_own_modulus,
    set_field,
    with_own_material,
    write_relations,
)
from bayesupdate.nastran.card_records import card_records, reused_records
from bayesupdate.nastran.cards.masses import add as add_masses
from bayesupdate.nastran.deck import Refusals
from bayesupdate.nastran.frames import read_grids


def _mass_cards(b) -> bool:
    """True for a binding that writes point-mass cards (CONM2, CMASS2: ``bindings.MASS_CARDS``)."""
    return any(c in MASS_CARDS for c, *_ in getattr(b, "relations", ()))


def _offset_elements(bindings) -> set:
    """Ids of the CBAR / CBEAM elements whose own fields (offsets) a binding writes."""
    return {i for b in bindings.values() for c, i, *_ in getattr(b, "relations", ())
            if c in LINE_ELEMENTS}  # fmt: skip


class LineRebuild:
    """K_L(theta) - K_L(deck), M likewise, of the line elements that ``bindings`` act on, by
    converting their cards again (module docstring).  ``part``: "line", the bound line elements
    whose own cards no binding writes; "offset", those whose own cards (offsets) a binding
    writes (``DeckBinding.relations``), with every binding acting on them; "mass", the CONM2 /
    CMASS2 cards whose own fields a binding writes.  The three share no element, so their
    changes add up.

    deck : the read deck (``deck.Deck``); structure : the structure read from it; bindings :
    {parameter: DeckBinding}; keys : (nnz,) row x n_dof + col of the assembled pattern the
    differences are added into (sorted)."""

    def __init__(self, deck, structure, bindings, keys, path, part="line"):
        self.deck, self.structure, self.path = deck, structure, str(path)
        offsets = _offset_elements(bindings)
        if part == "mass":
            self.bindings = {k: b for k, b in bindings.items() if _mass_cards(b)}
            keys_ = {(c, i) for b in self.bindings.values() for c, i, *_ in b.relations
                     if c in MASS_CARDS}  # fmt: skip
            self.elements = {k: deck.table(k[0])[k[1]] for k in sorted(keys_)}
        else:
            # an effect's parameters (``fe.model.Binding``: discovery) act on elements of
            # their own: no ``lines``
            mine = (lambda e: e in offsets) if part == "offset" else (lambda e: e not in offsets)
            self.bindings = {k: b for k, b in bindings.items()
                             if any(mine(e) for e in getattr(b, "lines", ()))}  # fmt: skip
            eids = {e for b in self.bindings.values() for e in b.lines if mine(e)}
            self.elements = {(c.name, c.id()): c for c in deck.of(*LINE_ELEMENTS, "CONROD")
                             if c.id() in eids}  # fmt: skip
        self._last = (None, None)  # (values of its bindings, (dK, dM)) of the last ``delta``
        refusals = Refusals(self.path)
        self.grids = read_grids(deck, refusals)
        refusals.raise_all()
        grid_of_node = np.asarray(structure.metadata["nastran"]["grid_ids"])
        self.node = -np.ones(len(self.grids.ids), np.int64)
        known = grid_of_node > 0  # a CBUSH's arm ends are nodes of no GRID
        pos = np.searchsorted(self.grids.ids, grid_of_node[known])
        self.node[pos] = np.flatnonzero(known)
        self.keys, self.n = keys, keys.size
        self._base = None

    @property
    def probe0(self):
        """The bound elements re-built at the deck's values (``structure_at(None)``), once."""
        if getattr(self, "_probe0", None) is None:
            self._probe0 = self.structure_at(None)
        return self._probe0

    @property
    def base(self) -> tuple[np.ndarray, np.ndarray]:
        """(K, M) (nnz,) of the bound elements at the deck's values."""
        if self._base is None:
            self._base = self._data(None)
        return self._base

    def delta(self, values) -> tuple[np.ndarray, np.ndarray]:
        """(dK, dM) (nnz,) at the parameter values {name: deck units}; the last one is kept
        (a step of other parameters converts nothing again).  Callers only read it."""
        key = tuple(float(values[n]) for n in self.bindings)
        if key != self._last[0]:
            K, M = self._data(values)
            self._last = (key, (K - self.base[0], M - self.base[1]))
        return self._last[1]

    def _tables(self, values):
        """(elements, properties, materials) {key: card} of the bound elements, the
        parameters' values written in (element-card fields: ``bindings.write_relations``)."""
        deck = self.deck
        all_props, all_mats = deck.table(*cards.PROPERTIES), deck.table("MAT1")
        lines = [e for e in self.elements.values() if e.name in LINE_ELEMENTS]
        props = {e["PID"]: all_props[e["PID"]] for e in lines}
        mids = {p["MID"] for p in props.values()} | {
            e["MID"] for e in self.elements.values() if e.name == "CONROD"
        }
        mats = {m: all_mats[m] for m in mids if m in all_mats}
        elements = dict(self.elements)
        if values is None:
            return elements, props, mats
        own = {n: b for n, b in self.bindings.items() if is_own_modulus(b.field)}
        for name, b in self.bindings.items():
            if name in own:
                continue
            if b.relations:
                write_relations(deck, b, float(values[name]), elements)
                continue
            table = mats if b.field.card == "MAT1" else props
            for k, (i, nominal) in enumerate(zip(b.field.ids, b.nominal, strict=True)):
                card = table.get(i) or _card(deck, b.field, i)
                table[i] = set_field(card, b.field, b.value_of(k, float(values[name])), nominal)
        # a property's own modulus last: its copy of the MAT1 takes the MAT1's bound values
        for name, b in own.items():
            for i in b.field.ids:
                props[i], mats = with_own_material(props[i], mats, float(values[name]))
        return elements, props, mats

    def structure_at(self, values):
        """The bound elements alone (and their lumped end masses) converted from their cards
        with ``values`` written in ({name: deck units}; None: the deck's), on all the
        structure's nodes: a part of a structure, so not checked for connectivity (the whole
        deck was, when it was read)."""
        s = self.structure
        builder = StructureBuilder()
        for xyz in s.nodes:
            builder.add_node(xyz)
        meta = s.metadata["nastran"]
        lumped = meta["coupmass"] < 1
        elements, props, mats = self._tables(values)
        refusals = Refusals(self.path)
        ctx = cards.Context(elements, props, mats, self.grids, self.node, meta["wtmass"],
                            lumped, builder, refusals)  # fmt: skip
        cards.add_beams(ctx)
        cards.add_rods(ctx)
        add_masses(ctx)
        refusals.raise_all()
        return builder.build(check=False)

    def _data(self, values) -> tuple[np.ndarray, np.ndarray]:
        s = self.structure
        g = GeneralAssembler(self.structure_at(values))
        K, M, _ = g.assemble(g.beams.default_properties())
        keep = (K.data != 0) | (M.data != 0)  # the padding's zeros need no place
        mine = (g.rows.astype(np.int64) * s.n_dof + g.cols)[keep]
        pos = np.searchsorted(self.keys, mine)
        if np.any(pos >= self.n) or np.any(self.keys[np.minimum(pos, self.n - 1)] != mine):
            raise BayesUpdateError(
                f"Nastran model {self.path}: a bound line element gains entries outside the "
                "deck's pattern (a mass or stiffness that is 0 in the deck); bind another field"
            )
        return np.bincount(pos, K.data[keep], self.n), np.bincount(pos, M.data[keep], self.n)


#: ``GeneralBeams`` / ``Rods`` fields a card value sets (the others: nodes, axes, offsets, pins,
#: mass kind, stay those of the element)
BEAM_VALUES = ("E", "G", "rho", "area", "iy", "iz", "iyz", "torsion", "shear_y", "shear_z",
               "nsm", "torsion_inertia")  # fmt: skip
ROD_VALUES = ("E", "G", "rho", "area", "torsion", "nsm")
_BEAM_FIXED = ("nodes", "up", "offset", "pins", "mass", "taper")
_FAMILIES = ("beam", "rod", "mass")


@dataclass(frozen=True, eq=False)
class LineFields:
    """The bound line elements' records as affine (or bilinear) functions of the parameters
    (module docstring), and their matrices from them.

    fit : the records' map (``affine_records.AffineRecords``, keys "<family>.<field>" of
    ``_fields``); beams, rods, masses : indices of the bound general beams, rods and lumped
    point masses in the structure; records0 : (GeneralBeams | None, Rods | None,
    PointMassValues) at the parameters' deck values (their fixed fields: nodes, axes, offsets);
    update : ``LineUpdate`` of those elements on the general pattern."""

    fit: AffineRecords
    beams: np.ndarray
    rods: np.ndarray
    masses: np.ndarray
    records0: tuple
    update: LineUpdate

    @property
    def names(self) -> tuple[str, ...]:
        return self.fit.names

    def theta(self, values) -> np.ndarray:
        """(p,) the parameters of ``values`` ({name: deck units}; None: the deck's)."""
        if values is None:
            return self.fit.theta0
        return np.array([float(values[n]) for n in self.names])

    def records(self, theta: np.ndarray) -> tuple:
        """(GeneralBeams | None, Rods | None, PointMassValues) of the bound elements at
        ``theta`` (p,)."""
        at = self.fit.at(theta)
        out = []
        for family, rec in zip(_FAMILIES, self.records0, strict=True):
            if rec is not None:
                keys = {f: f"{family}.{f}" for f in _fields(family)}
                moved = {f: at[k] for f, k in keys.items() if k in self.fit.moving}
                rec = replace(rec, **moved)
            out.append(rec)
        return tuple(out)

    def contribution(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(K, M) (nnz,) of the bound elements (and their lumped masses) at ``theta``."""
        beams, rods, masses = self.records(theta)
        return self.update.contribution(beams, rods, masses)


def _rows(rec, rows):
    if isinstance(rec, PointMassValues):
        return PointMassValues(rec.mass[rows], rec.inertia[rows])
    return type(rec)(**{k: getattr(rec, k)[rows] for k in rec.__dataclass_fields__})


def _bound_rows(structure, probe) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Indices of the probe's (``LineRebuild.structure_at``) beams, rods and point masses in
    the structure (matched by part, in order); None when they do not match one to one."""
    full, mine = np.asarray(structure.parts), np.asarray(probe.parts)
    out = []
    for fam in ("general_beams", "rods", "mass"):
        if fam == "mass":
            names_p, names_s = mine[probe.mass_part], full[structure.mass_part]
        else:
            rec_p, rec_s = getattr(probe, fam), getattr(structure, fam)
            names_p = mine[rec_p.part] if rec_p is not None else np.zeros(0, str)
            names_s = full[rec_s.part] if rec_s is not None else np.zeros(0, str)
        rows = np.flatnonzero(np.isin(names_s, names_p)) if names_p.size else np.zeros(0, int)
        if rows.size != names_p.size or np.any(names_s[rows] != names_p):
            return None
        out.append(rows)
    return tuple(out)


def _values(probe, family: str):
    """The record of ``family`` of a probe structure (all its elements)."""
    if family == "beam":
        return probe.general_beams
    if family == "rod":
        return probe.rods
    return PointMassValues(probe.mass_value, probe.mass_inertia)


def _fields(family: str) -> tuple[str, ...]:
    return {"beam": BEAM_VALUES, "rod": ROD_VALUES, "mass": ("mass", "inertia")}[family]


def _same_layout(structure, probe, rows) -> bool:
    """The probe's elements are the structure's at ``rows``: same nodes, axes, offsets, pins,
    mass kind (beams), same nodes and offsets (masses)."""
    b, r, m = rows
    if b.size:
        sb, pb = structure.general_beams, probe.general_beams
        if any(not np.array_equal(getattr(sb, f)[b], getattr(pb, f)) for f in _BEAM_FIXED):
            return False
    if r.size:
        sr, pr = structure.rods, probe.rods
        if any(not np.array_equal(getattr(sr, f)[r], getattr(pr, f)) for f in ("nodes", "lumped")):
            return False
    return np.array_equal(structure.mass_node[m], probe.mass_node) and np.array_equal(
        structure.mass_offset[m], probe.mass_offset
    )


def _matched_rows(s, probe0) -> tuple | str:
    """The rows of the probe's (``LineRebuild.structure_at(None)``) elements in the structure
    ``s`` (``_bound_rows``), checked: same layout and the same values as read from the deck;
    else the reason they are not."""
    rows = _bound_rows(s, probe0)
    if rows is None or not _same_layout(s, probe0, rows):
        return "the re-built elements do not match the read ones one to one"
    read = dict(beam=s.general_beams, rod=s.rods,
                mass=PointMassValues(s.mass_value, s.mass_inertia))  # fmt: skip
    for f, r in zip(("beam", "rod", "mass"), rows, strict=True):
        if r.size and any(
            not np.array_equal(getattr(_rows(read[f], r), x), getattr(_values(probe0, f), x))
            for x in _fields(f)
        ):
            return "the re-built elements' values differ from the read ones"
    return rows


def reused_fields(known: LineFields, probe0, g) -> "LineFields | None":
    """``known`` (the ``LineFields`` of the same deck and bindings on another structure, e.g.
    the model before an effect was added) on the assembler ``g`` of an extended structure, or
    None when ``line_fields`` could find other ones there: the bound elements must sit at the
    same rows with the same layout and deck values (``_matched_rows`` against ``probe0``, the
    bound elements re-built at the deck's values).  The records, slopes and cross terms depend
    only on the bound cards and those elements, so they are the ones ``line_fields`` would find
    again (six re-builds of the cards, ~0.1 s each on the mAEWing1 deck); only the positions
    in the new pattern (``LineUpdate``) are new.  An effect appends masses, springs or
    elements of its own, so this holds for the discovery library's candidates."""
    rows = _matched_rows(g.structure, probe0)
    if isinstance(rows, str):
        return None
    if any(not np.array_equal(a, b) for a, b in zip(rows, (known.beams, known.rods,
                                                          known.masses), strict=True)):  # fmt: skip
        return None
    update = LineUpdate(g, beams=rows[0], rods=rows[1], masses=rows[2])
    return replace(known, update=update)


def line_fields(g, rebuild: LineRebuild, defaults, bounds) -> tuple["LineFields | None", str]:
    """(``LineFields`` of the bound elements, "") or (None, the reason) when their records are
    not affine (or bilinear) in the parameters (then ``LineRebuild`` re-converts the cards at
    every solve).  g : the ``GeneralAssembler`` of the whole structure; defaults, bounds :
    {name: deck value}, {name: (low, high)} (deck units)."""
    names = tuple(rebuild.bindings)
    theta0 = np.array([float(defaults[n]) for n in names])
    low, high = (np.array([float(bounds[n][k]) for n in names]) for k in (0, 1))
    s = g.structure
    rows = _matched_rows(s, rebuild.probe0)
    if isinstance(rows, str):
        return None, rows
    families = [f for f, r in zip(_FAMILIES, rows, strict=True) if r.size]

    def read(theta):
        probe = rebuild.structure_at(dict(zip(names, theta, strict=True)))
        if not _same_layout(s, probe, rows):
            return None
        return {f"{f}.{x}": getattr(_values(probe, f), x) for f in families for x in _fields(f)}

    # the records at theta0 anchor the map: an absolute value bound on cards whose deck
    # values differ (one I1 for seven PBEAMs) writes theta0 into all of them, not the deck's
    fit, reason = fit_records(read, names, theta0, low, high)
    if fit is None:
        return None, reason
    at0 = rebuild.structure_at(dict(zip(names, theta0, strict=True)))
    no_mass = PointMassValues(np.zeros(0), np.zeros((0, 3, 3)))
    records0 = tuple(_values(at0, f) if f in families else None for f in _FAMILIES[:2])
    records0 += (_values(at0, "mass") if "mass" in families else no_mass,)
    update = LineUpdate(g, beams=rows[0], rods=rows[1], masses=rows[2])
    return LineFields(fit, *rows, records0, update), ""


#: relative round-off allowed between the affine sum and the re-built elements (exact: ~1e-15)
LINEAR_TOL = 1e-9
#: the seeded points of the box where the affine sum is checked
LINEAR_SEED, LINEAR_POINTS = 0, 3


@dataclass(frozen=True)
class LineTerm:
    """One parameter's exact affine line term: K_L(theta) - K_L(deck) = (theta - theta0) dK
    (summed over the parameters), M likewise; dK, dM (nnz,) on the general CSR pattern."""

    name: str
    theta0: float
    dK: np.ndarray
    dM: np.ndarray


def affine_line_terms(lines: "LineAssembler", defaults, bounds) -> tuple[LineTerm, ...]:
    """The ``LineTerm`` of each line parameter of ``lines`` ({name: deck value}, {name: (low,
    high)}, deck units).  Checked at seeded points of the box: each parameter alone (the others
    at the deck's values), then all together.  Raises ``BayesUpdateError`` naming the parameter
    (or the product) when the sum misses the re-built elements by more than ``LINEAR_TOL``."""
    names = list(lines.bindings)
    theta0 = np.array([defaults[n] for n in names])
    low, high = (np.array([bounds[n][k] for n in names]) for k in (0, 1))
    step = np.where(high > theta0, high, low) - theta0
    terms = []
    for j, name in enumerate(names):
        dK, dM = lines.line_delta(dict(zip(names, theta0 + step[j] * (np.arange(len(names)) == j),
                                           strict=True)))  # fmt: skip
        terms.append(LineTerm(name, float(theta0[j]), dK / step[j], dM / step[j]))
    rng = np.random.default_rng(LINEAR_SEED)
    u = rng.uniform(size=(LINEAR_POINTS, len(names)))
    where = low + u * (high - low)
    for j, name in enumerate(names):  # each alone, the others at the deck's values
        theta = np.where(np.arange(len(names)) == j, where[0], theta0)
        what = f"parameter {name} ({lines.bindings[name].target!r}) does not enter"
        _check_linear(lines, terms, theta, what)
    if len(names) > 1:
        for theta in where:
            what = f"parameters {', '.join(names)} together do not enter"
            _check_linear(lines, terms, theta, what)
    return tuple(terms)


def _check_linear(lines: "LineAssembler", terms, theta, what: str) -> None:
    exact = lines.line_delta({t.name: v for t, v in zip(terms, theta, strict=True)})
    for which, (x, base) in enumerate(zip(exact, lines.line_base(), strict=True)):
        affine = sum(
            (v - t.theta0) * (t.dK, t.dM)[which] for t, v in zip(terms, theta, strict=True)
        )
        miss = np.abs(x - affine).max() / max(np.abs(base).max(initial=0.0), 1e-300)
        if miss > LINEAR_TOL:
            raise BayesUpdateError(
                f"{what} the line elements' {'KM'[which]} linearly (relative miss {miss:.1e}; a "
                "PBARL/PBEAML dimension, a shear-flexible beam's A or I, E with A or I, a CONM2 "
                "or beam offset do not), so the reduced basis does not cover it"
            )


class LineAssembler(GeneralAssembler):
    """``GeneralAssembler`` whose line elements follow the parameters: ``values`` ({name: deck
    units}, set by the model before each assembly; None: the deck's).  The change of the bound
    elements from the deck's values is added to the deck's assembly: with ``fields``
    (``LineFields``) their matrices at the new records less those at the deck's (module
    docstring), without (records not affine: ``fields_note`` says why) ``LineRebuild.delta``.
    The element cards whose own fields are bound (``cards``: offsets, CONM2, CMASS2) add their
    change from ``card_records`` (``nastran.card_records``), or ``LineRebuild.delta`` where
    those records do not hold (``card_notes`` says why).  At the deck's values the change is
    exactly 0, so the bound model is the deck to the bit.  The K returned is the very object
    ``solve`` matches its ground springs by.

    fast : False keeps ``LineRebuild`` at every solve (the reference, for checks).  The
    ``LineFields`` and card records are found at the first point away from the deck's values
    (a ``modes`` run at the deck's values converts nothing again).  known : the
    ``LineAssembler`` of the same deck and bindings on the structure this one extends
    (``NastranModel.with_structure``): its ``LineFields`` and card records are taken over where
    they hold (``reused_fields``, ``card_records.reused_records``), not found again.

    The last assembly is kept, keyed by the values and the property arrays it was made from:
    an evaluation asks for K and M at one point up to three times (the eigen-solve, then the
    mass properties of the fit's residuals and of the likelihood: ``model.mass_properties``),
    and the bound elements' recomputation is most of an assembly.  The matrices returned are
    shared between those callers, which only read them."""

    def __init__(self, structure, shell_keys, deck, bindings, path, defaults, bounds, fast=True,
                 known=None):  # fmt: skip
        super().__init__(structure, shell_keys)
        keys = self.rows.astype(np.int64) * self.n_dof + self.cols
        # not ``lines``: that is the base class's list of line-element matrices (``fe.energy``)
        self.rebuild = LineRebuild(deck, structure, bindings, keys, path)
        #: the line elements whose offsets are bound and the CONM2 / CMASS2 cards whose own
        #: fields are, converted again at every solve (their records are not affine: a beam's
        #: lumped end masses follow its offset length); they share no element with ``rebuild``
        self.cards = [LineRebuild(deck, structure, bindings, keys, path, part=part)
                      for part in ("offset", "mass")]  # fmt: skip
        self.cards = [r for r in self.cards if r.bindings]
        mine = {k: b for r in (self.rebuild, *self.cards) for k, b in r.bindings.items()}
        #: {name: DeckBinding} of every parameter re-built here, in the model's order
        self.bindings = {n: b for n, b in bindings.items() if n in mine}
        self.values = None
        self._box = (defaults, bounds)
        self._fields = None if fast else (None, "the reference path was asked for")
        self._fast, self._card_records, self._card_notes = fast, None, []
        if not self.rebuild.bindings:
            self._fields = (None, "no line element is bound")
        same = fast and _same_box(known, deck, self.bindings, self._box)
        self._known = known if same else None
        #: the element-card records the extended model found already (``card_records``)
        self._known_cards = known._card_records if same else None
        self._last = (None, None)  # (key, (K, M, elem)) of the last assembly

    @property
    def fields(self) -> "LineFields | None":
        """The bound elements' ``LineFields``; None when their records are not affine in the
        parameters (``fields_note`` says why) or the reference path was asked for."""
        if self._fields is None and self._known is not None and self._known.fields is not None:
            known = self._known.rebuild.probe0
            reused = reused_fields(self._known.fields, known, self)
            self._fields = None if reused is None else (reused, "")
        self._known = None  # taken over or not: the other model is not held
        if self._fields is None:
            self._fields = line_fields(self, self.rebuild, *self._box)
        return self._fields[0]

    @property
    def fields_note(self) -> str:
        """Why there are no ``fields`` ("" when there are)."""
        return "" if self.fields is not None else self._fields[1]

    def line_base(self) -> tuple[np.ndarray, np.ndarray]:
        """(K, M) (nnz,) of the bound elements (and lumped masses, and the bound mass cards)
        at the deck's values."""
        if not self.rebuild.bindings:
            K, M = np.zeros(self.nnz), np.zeros(self.nnz)
        elif self.fields is None:
            K, M = self.rebuild.base
        else:
            K, M = self.fields.update.contribution()
        for part in self.cards:
            K, M = K + part.base[0], M + part.base[1]
        return K, M

    def line_delta(self, values) -> tuple[np.ndarray, np.ndarray]:
        """(dK, dM) (nnz,) of the bound elements (and mass cards) from the deck's values to
        ``values``."""
        if not self.rebuild.bindings:
            dK, dM = np.zeros(self.nnz), np.zeros(self.nnz)
        elif self.fields is None:
            dK, dM = self.rebuild.delta(values)
        else:
            K, M = self.fields.contribution(self.fields.theta(values))
            K0, M0 = self.fields.update.base
            dK, dM = K - K0, M - M0
        for part, fast in zip(self.cards, self.card_records, strict=True):
            cK, cM = (part if fast is None else fast).delta(values)
            dK, dM = dK + cK, dM + cM
        return dK, dM

    @property
    def card_records(self) -> list:
        """Per part of ``cards``: its ``card_records.CardRecords`` (the cards' matrices from
        records fitted once), or None where they are read again at every solve (the
        reference path, or ``card_notes`` says why)."""
        if self._card_records is None:
            known = self._known_cards or [None] * len(self.cards)
            found = [self._records_of(part, k) for part, k in zip(self.cards, known, strict=True)]
            self._card_records = [f for f, _ in found]
            self._card_notes = [why for _, why in found]
            self._known_cards = None  # taken over or not: the other model's are not held
        return self._card_records

    def _records_of(self, part, known) -> tuple:
        """(``CardRecords`` of ``part``, "") or (None, why not); ``known``: the records of
        the model this one extends, taken over where they hold (``reused_records``)."""
        if not self._fast:
            return None, "the reference path was asked for"
        reused = None if known is None else reused_records(self, part, known)
        return (reused, "") if reused is not None else card_records(self, part, *self._box)

    @property
    def card_notes(self) -> list[str]:
        """Per part of ``cards``: why its cards are read again at every solve ("" where not)."""
        return self._card_notes if self.card_records is not None else []

    def assemble(self, props, shell_props=None):
        key = _assembly_key(self.values, self.bindings, props, shell_props)
        if key == self._last[0]:
            return self._last[1]
        K, M, elem = super().assemble(props, shell_props)
        defaults = self._box[0]
        if self.values is not None and any(self.values[n] != defaults[n]
                                           for n in self.bindings):  # fmt: skip
            dK, dM = self.line_delta(self.values)
            K.data += dK  # same positions: the pattern's data in its sorted order
            M.data += dM
        self._last = (key, (K, M, elem))
        return K, M, elem


def _same_box(known, deck, bindings, box) -> bool:
    """``known`` (a ``LineAssembler`` or None) reads the same deck with the same line bindings:
    the same bound fields (in the same order, with their coefficients, deck values and
    elements), defaults and bounds."""
    if known is None or known.rebuild.deck is not deck:
        return False

    def key(assembler_bindings, defaults, bounds):
        return [(n, b.field, b.coefficient, tuple(b.nominal), tuple(b.lines), b.relations,
                 float(defaults[n]), tuple(map(float, bounds[n])))
                for n, b in assembler_bindings.items()]  # fmt: skip

    return key(bindings, *box) == key(known.bindings, *known._box)  # noqa: SLF001


def _assembly_key(values, names, props, shell_props) -> tuple:
    """What an assembly depends on: the bound line fields' values and the exact bytes of the
    element property arrays (``fe.assembly.ElementProperties``, shell (t, E, rho))."""
    line = None if values is None else tuple(float(values[n]) for n in names)
    arrays = [*props.values.values(), *(shell_props or ())]
    return line, tuple(np.ascontiguousarray(a).tobytes() for a in arrays)


@dataclass(frozen=True, eq=False)
class LineGroup:
    """Line parameters acting on the same elements, their change of K and M interpolated in
    log(theta) (``interpolated_line_groups``).

    names : the parameters (tensor axes, in this order); log_pieces : per axis (2,) log of the
    box (low, high); degrees : per axis the Chebyshev degree; dK, dM : (n_nodes, nnz) the
    change from the deck's values at the tensor nodes (``interpolation.tensor_weights`` order),
    on the general CSR pattern; dm : (n_nodes,) the total mass change there [deck mass]."""

    names: tuple[str, ...]
    log_pieces: tuple[np.ndarray, ...]
    degrees: tuple[int, ...]
    dK: np.ndarray
    dM: np.ndarray
    dm: np.ndarray

    def holds(self, values: np.ndarray) -> bool:
        """True if every row of ``values`` (B, len(names)) lies in the group's box."""
        low, high = (np.exp([p[k] for p in self.log_pieces]) for k in (0, 1))
        slack = 1e-12  # the box's own ends, through exp(log(.))
        return bool(np.all((values >= low * (1 - slack)) & (values <= high * (1 + slack))))

    def weights(self, values: np.ndarray) -> np.ndarray:
        """(B, n_nodes) interpolation weights at ``values`` (B, len(names)) > 0."""
        from bayesupdate.fe.reduced.interpolation import tensor_weights

        return tensor_weights(values, self.log_pieces, self.degrees)


def interpolated_line_groups(lines: LineAssembler, defaults, bounds, tol: float):
    """``LineGroup`` s of the line parameters of ``lines`` over the box ``bounds`` ({name:
    (low, high)}, deck units; defaults {name: deck value}): the parameters grouped where their
    elements overlap (a MAT1 and a PBEAM of that MID), so that the groups' changes add up to
    the whole change exactly; in each group the degree per axis is the smallest of
    ``reduced.affine.DEGREES`` that reproduces K and M to ``tol`` (relative to the largest
    entry the group touches) at seeded points, then the tensor product is checked and raised
    as for the built-in models' interpolated beams (``fe.reduced.affine``).  Raises
    ``BayesUpdateError`` when no degree reaches ``tol``."""
    from bayesupdate.fe.reduced.affine import N_TEST, TEST_SEED

    bindings = lines.bindings
    groups, rng = [], np.random.default_rng(TEST_SEED)
    elements = {n: set(b.lines) | {(c, i) for c, i, *_ in b.relations}
                for n, b in bindings.items()}  # fmt: skip
    for names in _overlapping(elements):
        search = _GroupSearch(lines, defaults, names, bounds, tol, N_TEST)
        degrees = [search.axis_degree(i, rng) for i in range(len(names))]
        groups.append(search.tensor(degrees, rng))
    return tuple(groups)


def _overlapping(elements: dict) -> list[tuple[str, ...]]:
    """The parameters (keys of ``elements``: {name: element ids}) in groups of overlapping
    element sets (connected components), each in the given order."""
    names = list(elements)
    label = list(range(len(names)))
    for i in range(len(names)):
        for j in range(i):
            if elements[names[i]] & elements[names[j]]:
                old, new = label[i], label[j]
                label = [new if x == old else x for x in label]
    return [tuple(n for n, x in zip(names, label, strict=True) if x == k)
            for k in dict.fromkeys(label)]  # fmt: skip


class _GroupSearch:
    """The interpolation degrees of one ``LineGroup`` (``interpolated_line_groups``)."""

    def __init__(self, lines, defaults, names, bounds, tol, n_test):
        from bayesupdate.fe.reduced.mass import _translational_mass

        self.lines, self.defaults, self.names, self.tol, self.n_test = (
            lines, defaults, names, tol, n_test)  # fmt: skip
        self.low = np.array([float(bounds[n][0]) for n in names])
        self.high = np.array([float(bounds[n][1]) for n in names])
        if np.any(self.low <= 0):
            raise BayesUpdateError(f"reduced model: the lower bounds of {names} must be > 0")
        self.log_pieces = tuple(np.log([lo, hi]) for lo, hi in zip(self.low, self.high,
                                                                    strict=True))  # fmt: skip
        self.base = lines.line_base()
        self.mass = lambda dM: _translational_mass(lines, np.arange(lines.nnz), dM)

    def changes(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(dK, dM) (n, nnz) at ``points`` (n, len(names)), the other parameters at the
        deck's values."""
        out = [self.lines.line_delta({**self.defaults, **dict(zip(self.names, row, strict=True))})
               for row in points]  # fmt: skip
        return np.array([k for k, _ in out]), np.array([m for _, m in out])

    def error(self, weights, nodes, test) -> tuple[float, np.ndarray, np.ndarray]:
        """(largest relative error at ``test`` (n, len(names)), node dK, node dM) of the
        interpolant with ``weights`` (n, n_nodes) on ``nodes``; relative to the largest entry
        of K (M) the group touches."""
        Kn, Mn = self.changes(nodes)
        Kt, Mt = self.changes(test)
        err = 0.0
        for approx, exact, base in ((weights @ Kn, Kt, self.base[0]),
                                    (weights @ Mn, Mt, self.base[1])):  # fmt: skip
            touched = np.abs(exact).max(axis=0) > 0
            if touched.any():
                scale = np.abs(base[touched] + exact[:, touched]).max()
                err = max(err, float(np.abs(approx - exact).max() / max(scale, 1e-300)))
        return err, Kn, Mn

    def axis_degree(self, i: int, rng) -> int:
        """Smallest degree reaching ``tol`` along axis ``i``, the others at mid-box."""
        from bayesupdate.fe.reduced.affine import DEGREES
        from bayesupdate.fe.reduced.interpolation import barycentric_weights, piecewise_nodes

        mid = np.sqrt(self.low * self.high)
        test = np.tile(mid, (self.n_test, 1))
        test[:, i] = np.exp(rng.uniform(*self.log_pieces[i], self.n_test))
        for degree in DEGREES:
            nodes = np.tile(mid, (degree + 1, 1))
            nodes[:, i] = np.exp(piecewise_nodes(self.log_pieces[i], degree))
            w = barycentric_weights(np.log(test[:, i]), self.log_pieces[i], degree)
            if self.error(w, nodes, test)[0] < self.tol:
                return degree
        raise BayesUpdateError(
            f"reduced model: interpolation in {self.names[i]} does not reach {self.tol:g} at "
            f"degree {DEGREES[-1]}; use the full model (--full)"
        )

    def tensor(self, degrees: list[int], rng) -> LineGroup:
        """The group on the tensor product of the 1-D degrees (raised by 4 up to 3 times)."""
        from bayesupdate.fe.reduced.interpolation import piecewise_nodes, tensor_weights

        test = np.exp(np.column_stack([rng.uniform(*p, self.n_test) for p in self.log_pieces]))
        for _ in range(4):
            axes = [np.exp(piecewise_nodes(p, d))
                    for p, d in zip(self.log_pieces, degrees, strict=True)]  # fmt: skip
            grid = np.stack([m.ravel() for m in np.meshgrid(*axes, indexing="ij")], axis=1)
            w = tensor_weights(test, self.log_pieces, degrees)
            err, Kn, Mn = self.error(w, grid, test)
            if err < self.tol:
                dm = np.array([self.mass(d) for d in Mn])
                return LineGroup(self.names, self.log_pieces, tuple(degrees), Kn, Mn, dm)
            degrees = [d + 4 for d in degrees]
        raise BayesUpdateError(
            f"reduced model: tensor interpolation in {list(self.names)} has error {err:.1e} > "
            f"{self.tol:g}; use the full model (--full)"
        )
