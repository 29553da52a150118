"""Line-element fields of a Nastran deck as parameters, by re-building the bound elements.

A binding to a PBAR/PBARL/PBEAM/PBEAML/PROD field, or to the MAT1 E or RHO of a line property,
acts on CBAR/CBEAM/CROD/CONROD elements, which ``fe.general`` assembles once.  At each solve,
copies of the bound cards get the parameters' values (``bindings.set_field``, as ``--write-bdf``
writes them), the bound elements alone are converted again on the structure's nodes
(``cards.add_beams``/``add_rods``: sections, offsets, pins, lumped or consistent mass, WTMASS),
and K_L(theta) - K_L(deck) (and M) is added into the assembled matrices at its place in their
pattern.  That is the reading of the edited deck, so exact whatever the field: the Timoshenko
shear parameter 12 EI / (k G A L^2) and a PBARL's section in its dimensions are not affine, and
even A, I, J, E, RHO enter linearly only without shear flexibility.

For the reduced basis (``fe.reduced``), ``affine_line_terms`` finds the fields that do enter
linearly: a shear-rigid PBAR's A, I1, I2, J, a PROD's / CONROD's A and J and every NSM give
K_L(theta) = K_L(deck) + sum_j (theta_j - theta0_j) dK_j (M likewise) exactly, dK_j the
difference quotient over one step.  The sum is checked against re-built elements at seeded
points of the box, so a non-linear field (a PBARL/PBEAML DIM, a shear-flexible PBEAM's A or I,
E and A of the same elements: a product) is found and named, never approximated.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.general import GeneralAssembler
from bayesupdate.fe.structure import StructureBuilder
from bayesupdate.nastran import cards
from bayesupdate.nastran.bindings import _card, set_field
from bayesupdate.nastran.deck import Refusals
from bayesupdate.nastran.frames import read_grids


class LineRebuild:
    """K_L(theta) - K_L(deck), M likewise, of the line elements that ``bindings`` act on.

    deck : the read deck (``deck.Deck``); structure : the structure read from it; bindings :
    {parameter: DeckBinding}, those with ``lines``; keys : (nnz,) row x n_dof + col of the
    assembled pattern the differences are added into (sorted)."""

    def __init__(self, deck, structure, bindings, keys, path):
        self.deck, self.structure, self.path = deck, structure, str(path)
        # an effect's parameters (``fe.model.Binding``: discovery) act on elements of their own
        self.bindings = {k: b for k, b in bindings.items() if getattr(b, "lines", ())}
        eids = sorted({e for b in self.bindings.values() for e in b.lines})
        self.elements = {(c.name, c.id()): c for c in deck.of("CBAR", "CBEAM", "CROD", "CONROD")
                         if c.id() in eids}  # fmt: skip
        refusals = Refusals(self.path)
        self.grids = read_grids(deck, refusals)
        refusals.raise_all()
        grid_of_node = np.asarray(structure.metadata["nastran"]["grid_ids"])
        self.node = -np.ones(len(self.grids.ids), np.int64)
        known = grid_of_node > 0  # a CBUSH's arm ends are nodes of no GRID
        pos = np.searchsorted(self.grids.ids, grid_of_node[known])
        self.node[pos] = np.flatnonzero(known)
        self.keys, self.n = keys, keys.size
        rows = [self.grids.index(cards.element_grids(e), e.label) for e in self.elements.values()]
        self._used = np.unique(self.node[np.concatenate(rows)])
        self._base = self._data(None)

    def delta(self, values) -> tuple[np.ndarray, np.ndarray]:
        """(dK, dM) (nnz,) at the parameter values {name: deck units}."""
        K, M = self._data(values)
        return K - self._base[0], M - self._base[1]

    def _tables(self, values):
        """(properties, materials) {id: card} of the bound elements, the parameters' values
        written in."""
        deck = self.deck
        all_props, all_mats = deck.table(*cards.PROPERTIES), deck.table("MAT1")
        props = {e["PID"]: all_props[e["PID"]]
                 for e in self.elements.values() if e.name != "CONROD"}  # fmt: skip
        mids = {p["MID"] for p in props.values()} | {
            e["MID"] for e in self.elements.values() if e.name == "CONROD"
        }
        mats = {m: all_mats[m] for m in mids if m in all_mats}
        for name, b in self.bindings.items():
            if values is None:
                continue
            table = mats if b.field.card == "MAT1" else props
            for i, nominal in zip(b.field.ids, b.nominal, strict=True):
                card = table.get(i) or _card(deck, b.field, i)
                table[i] = set_field(card, b.field, float(values[name]) * b.coefficient, nominal)
        return props, mats

    def _data(self, values) -> tuple[np.ndarray, np.ndarray]:
        s = self.structure
        builder = StructureBuilder()
        for xyz in s.nodes:
            builder.add_node(xyz)
        meta = s.metadata["nastran"]
        lumped = meta["coupmass"] < 1
        props, mats = self._tables(values)
        refusals = Refusals(self.path)
        ctx = cards.Context(self.elements, props, mats, self.grids, self.node, meta["wtmass"],
                            lumped, builder, refusals)  # fmt: skip
        cards.add_beams(ctx)
        cards.add_rods(ctx)
        refusals.raise_all()
        # a structure uses and connects all its nodes: tie every other node to the first bound
        # one by a spring of 0 (the bound elements may lie in several pieces, both wings)
        for n in np.setdiff1d(np.arange(s.n_nodes), self._used[:1]):
            builder.add_spring(int(n), int(self._used[0]), np.zeros(6), "(not re-built)")
        g = GeneralAssembler(builder.build())
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


def affine_line_terms(rebuild: LineRebuild, defaults, bounds) -> tuple[LineTerm, ...]:
    """The ``LineTerm`` of each parameter of ``rebuild`` ({name: deck value}, {name: (low,
    high)}, deck units).  Checked at seeded points of the box: each parameter alone (the others
    at the deck's values), then all together.  Raises ``BayesUpdateError`` naming the parameter
    (or the product) when the sum misses the re-built elements by more than ``LINEAR_TOL``."""
    names = list(rebuild.bindings)
    theta0 = np.array([defaults[n] for n in names])
    low, high = (np.array([bounds[n][k] for n in names]) for k in (0, 1))
    step = np.where(high > theta0, high, low) - theta0
    terms = []
    for j, name in enumerate(names):
        dK, dM = rebuild.delta(dict(zip(names, theta0 + step[j] * (np.arange(len(names)) == j),
                                        strict=True)))  # fmt: skip
        terms.append(LineTerm(name, float(theta0[j]), dK / step[j], dM / step[j]))
    rng = np.random.default_rng(LINEAR_SEED)
    u = rng.uniform(size=(LINEAR_POINTS, len(names)))
    where = low + u * (high - low)
    for j, name in enumerate(names):  # each alone, the others at the deck's values
        theta = np.where(np.arange(len(names)) == j, where[0], theta0)
        what = f"parameter {name} ({rebuild.bindings[name].target!r}) does not enter"
        _check_linear(rebuild, terms, theta, what)
    if len(names) > 1:
        for theta in where:
            what = f"parameters {', '.join(names)} together do not enter"
            _check_linear(rebuild, terms, theta, what)
    return tuple(terms)


def _check_linear(rebuild: LineRebuild, terms, theta, what: str) -> None:
    exact = rebuild.delta({t.name: v for t, v in zip(terms, theta, strict=True)})
    for which, (x, base) in enumerate(zip(exact, rebuild._base, strict=True)):
        affine = sum(
            (v - t.theta0) * (t.dK, t.dM)[which] for t, v in zip(terms, theta, strict=True)
        )
        miss = np.abs(x - affine).max() / max(np.abs(base).max(initial=0.0), 1e-300)
        if miss > LINEAR_TOL:
            raise BayesUpdateError(
                f"{what} the line elements' {'KM'[which]} linearly (relative miss {miss:.1e}; a "
                "PBARL/PBEAML dimension, a shear-flexible beam's A or I, or E with A or I do not), "
                "so the reduced basis does not cover it"
            )


class LineAssembler(GeneralAssembler):
    """``GeneralAssembler`` whose line elements follow the parameters: ``values`` (set by the
    model before each assembly) go through ``LineRebuild``; the K returned is the very object
    ``solve`` matches its ground springs by."""

    def __init__(self, structure, shell_keys, deck, bindings, path):
        super().__init__(structure, shell_keys)
        keys = self.rows.astype(np.int64) * self.n_dof + self.cols
        # not ``lines``: that is the base class's list of line-element matrices (``fe.energy``)
        self.rebuild = LineRebuild(deck, structure, bindings, keys, path)
        self.values = None

    def assemble(self, props, shell_props=None):
        K, M, elem = super().assemble(props, shell_props)
        if self.values is not None:
            dK, dM = self.rebuild.delta(self.values)
            K.data += dK  # same positions: the pattern's data in its sorted order
            M.data += dM
        return K, M, elem
