"""``NastranModel``: an ``FEModel`` of a Nastran deck whose parameters are deck fields.

Parameters are in the deck's units (``bindings``); each ``DeckBinding`` acts on element masks
of the structure, and the FE value is ``factor`` x the parameter (WTMASS on densities, 1 / the
deck's value for a spring or mass bound absolutely).  Everything else is ``FEModel``'s: shell
thickness enters K and M as exact powers (``fe.assembly``), so the reduced basis applies; so
does a line-element field that enters K and M linearly (``lines.affine_line_terms``).
"""

import copy
from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.model import PROPERTY_TERMS, AffineTerms, FEModel
from bayesupdate.fe.sparse_modal import MechanismError
from bayesupdate.nastran.bindings import (
    SIGNED_FIELDS,
    DeckBinding,
    n_solids,
    parse_binding,
    relation_default,
    resolve,
    solid_families,
    solid_part,
)
from bayesupdate.nastran.reader import node_namer

#: default bounds of a bound parameter without ``bounds``: this factor range on its default
DEFAULT_RANGE = (0.5, 2.0)
#: the shell parameter column of each property (``FEModel._shell_keys``): overlaps are errors
_COLUMN = dict(thickness=0, youngs_modulus=1, modulus_factor=1, density=2)


class NastranModel(FEModel):
    """``FEModel`` with ``DeckBinding`` parameters (deck units); ``deck`` is the deck's path;
    ``bdf`` its read cards (``deck.Deck``; needed when a binding acts on line elements:
    ``lines``)."""

    #: a deck of a few hundred DOFs: banded block Krylov, ~3x faster than dense LAPACK at the
    #: mAEWing1 deck's 354 (``fe.eigen_small``; ``benchmarks/deck_eigen_routes.py``)
    small_method = "krylov"

    def __init__(self, structure, bindings, defaults, bounds, name="deck", deck="", bdf=None,
                 lines_from=None):  # fmt: skip
        """``lines_from``: the ``LineAssembler`` of the model this one extends
        (``with_structure``), whose line records are taken over where they hold."""
        self.deck, self.bdf = str(deck), bdf
        bindings = {n: _own_modulus(b, bdf, structure) for n, b in bindings.items()}
        super().__init__(structure, bindings, defaults, bounds, name=name)
        # the re-built elements are the deck's at each binding's own deck value (a factor's 1,
        # a relation's (value - C0) / COEF), whatever the parameter's default (an effect's
        # start, e.g. 0.8)
        rebuilt = {n: b for n, b in self.bindings.items()
                   if getattr(b, "lines", ()) or getattr(b, "relations", ())}  # fmt: skip
        self._line_defaults = dict(self._defaults)
        self._line_defaults.update({n: b.default for n, b in rebuilt.items()})
        if rebuilt:
            from bayesupdate.nastran.lines import LineAssembler

            self._general = LineAssembler(
                structure,
                self._shell_keys(),
                bdf,
                self.bindings,
                self.deck,
                self._line_defaults,
                self._bounds,
                known=lines_from,
            )
            self._assembler = self._general

    def line_parts(self) -> list[str]:
        """The parts of line elements (``"PBEAM 1003"``: a property's CBARs, CBEAMs or CRODs)
        whose modulus a ``modulus_factor`` binding (``Binding(part, "modulus_factor")``, e.g.
        discovery's ``stiffness_change``) may scale (``bindings.modulus_binding``), in part
        order; not those whose elements already follow a bound E or G (a MAT1 E / G binding,
        or such a factor)."""
        from bayesupdate.nastran.bindings import (
            LINE_PROPERTIES,
            DeckField,
            is_own_modulus,
            line_elements,
        )

        s = self.structure
        if self.bdf is None:
            return []
        used = set()
        for family in (s.general_beams, s.rods):
            if family is not None:
                used |= {s.parts[i] for i in np.unique(family.part)}
        taken = set()
        for b in self.bindings.values():
            f = getattr(b, "field", None)
            if f is not None and (
                is_own_modulus(f) or (f.card == "MAT1" and f.field in ("E", "G"))
            ):
                taken |= set(b.lines)
        out = []
        for part in s.parts:
            card, _, pid = part.partition(" ")
            if part not in used or card not in LINE_PROPERTIES or not pid.isdigit():
                continue
            elements = line_elements(self.bdf, DeckField(part, card, (int(pid),), "E", True))
            if elements and not taken & set(elements):
                out.append(part)
        return out

    def _mask(self, name, binding):
        if not isinstance(binding, DeckBinding):
            return super()._mask(name, binding)
        if binding.shell.any():
            self._shell_masks[name] = binding.shell
        beams = np.zeros(len(self.structure.beam_part), bool)
        if binding.property == "line":  # re-built elements (``lines``): no FE property
            return beams
        family = PROPERTY_TERMS[binding.property][0]
        if family in (cls.family for cls in solid_families()):
            return binding.solid[solid_part(self.structure, family)]
        return {"beam": beams, "mass": binding.mass, "spring": binding.spring}[family]

    def _companions(self, name, binding):
        """A deck material's further solid families (``DeckBinding.companions``): each one's
        part of its ``solid`` mask (``bindings.solid_part``), to its factor x the value."""
        if not isinstance(binding, DeckBinding):
            return ()
        parts = ((prop, solid_part(self.structure, PROPERTY_TERMS[prop][0]), factor)
                 for prop, factor in binding.companions)  # fmt: skip
        return tuple((prop, binding.solid[part], factor) for prop, part, factor in parts)

    def _solve_general(self, p, props, n_modes, energies, method):
        from bayesupdate.nastran.lines import LineAssembler

        if isinstance(self._general, LineAssembler):
            self._general.values = p
        try:
            result = super()._solve_general(p, props, n_modes, energies, method)
        except MechanismError as exc:  # named by the deck's GRIDs, not the solver's nodes
            raise exc.named(self.node_name) from None
        if not self._spoint_mass().any():
            return result
        mass, cog = _without(self._spoint_mass(), result.mass_kg, result.centre_of_gravity)
        return replace(result, mass_kg=mass, centre_of_gravity=cog)

    def node_name(self, node: int) -> str:
        """The deck's name of the solver's node ``node`` (``reader.node_namer``: "GRID 12",
        "SPOINT 7", or a CBUSH arm's end)."""
        meta = self.structure.metadata.get("nastran", {})
        grids = {i: int(g) for i, g in enumerate(meta.get("grid_ids", ())) if g > 0}
        spoints = {n: s for s, (n, _) in meta.get("spoint_dofs", {}).items()}
        return node_namer(grids, spoints)(node)

    # -- scalar points carry no rigid-body mass (``cards.scalar``) ---------------------------------
    def _spoint_mass(self) -> np.ndarray:
        """(6, 6) the share of scalar masses on scalar points in R^T M R (zeros without)."""
        meta = self.structure.metadata.get("nastran", {})
        return np.asarray(meta.get("spoint_rigid_mass", np.zeros((6, 6))), float)

    def total_mass(self, params=None):
        """``FEModel.total_mass`` without the scalar points' masses (MSC's weight generator
        uses grids only)."""
        mass, cog = super().total_mass(params)
        if not self._spoint_mass().any():
            return mass, cog
        return _without(self._spoint_mass(), mass, cog)

    def mass_properties(self, params=None):
        """``FEModel.mass_properties`` without the scalar points' masses."""
        if not self._spoint_mass().any():
            return super().mass_properties(params)
        from bayesupdate.fe.mass_properties import (
            MassProperties,
            from_rigid_mass,
            rigid_body_mass_matrix,
        )

        Mr = rigid_body_mass_matrix(self.matrices(params)[1], self.structure.nodes)
        Mr = Mr - self._spoint_mass()
        if np.trace(Mr[:3, :3]) <= 1e-12 * np.trace(self._spoint_mass()[:3, :3]):
            # masses on scalar points only (a scalar-only deck): no rigid-body mass, as MSC's
            # weight generator prints it
            return MassProperties(0.0, np.zeros(3), np.zeros((3, 3)))
        return from_rigid_mass(Mr)

    def mass_properties_function(self):
        """``FEModel.mass_properties_function``; with scalar-point masses, ``mass_properties``
        itself (the affine terms would count them)."""
        if self._spoint_mass().any():
            return self.mass_properties
        return super().mass_properties_function()

    def matrices(self, params: Mapping[str, float] | None = None):
        """``FEModel.matrices`` with the line elements at ``params`` too (``lines``)."""
        from bayesupdate.nastran.lines import LineAssembler

        if isinstance(self._general, LineAssembler):
            self._general.values = self.full_parameters(params)
        return super().matrices(params)

    def fe_values(self, params: Mapping[str, float] | None) -> dict[str, float]:
        """The FE model's values (factor x parameter) of the full parameter set at ``params``."""
        p = self.full_parameters(params)
        out = {}
        for name, value in p.items():
            b = self.bindings[name]
            if not isinstance(b, DeckBinding):
                out[name] = value
                continue
            if b.property == "thickness" and not value > 0:
                raise BayesUpdateError(
                    f"parameter {name} = {value:g}: binds {b.target!r}; a thickness must be > 0"
                )
            out[name] = value * b.factor
        return out

    def element_properties(self, params=None):
        values = self.fe_values(params)
        # an element card's own field (an offset: any sign) sets no FE property; its cards
        # check it when they are converted again (``lines.LineRebuild``)
        for name, b in self.bindings.items():
            if getattr(b, "relations", ()) and np.isfinite(values[name]):
                values[name] = 1.0
        return super().element_properties(values)

    def shell_properties(self, params=None):
        return super().shell_properties(self.fe_values(params))

    def affine_terms(self) -> AffineTerms:
        """``FEModel.affine_terms`` with each deck parameter's factor in its term's scale; a
        line-element parameter is a "line" term (no elements of its own: ``line_terms`` are
        its matrices where it enters linearly, ``line_groups`` interpolate them otherwise)."""
        # a line binding has no FE property: stand in a modulus factor on no beams (a MAT1
        # binding keeps its shell term; its line elements are in ``line_terms`` too)
        lines = {n for n, b in self.bindings.items() if b.property == "line"}
        stand_in = copy.copy(self)
        stand_in.bindings = {
            n: replace(b, property="modulus_factor") if n in lines else b
            for n, b in self.bindings.items()
        }
        terms = FEModel.affine_terms(stand_in)
        # (a line parameter's further solid families keep their terms, scaled as any other)
        scaled = tuple(
            replace(t, property="line", family="line", field="line", enters="linear")
            if t.name in lines and t.property == "modulus_factor"
            else replace(t, scale=t.scale * getattr(self.bindings[t.name], "factor", 1.0))
            for t in terms.parameters
        )
        return replace(terms, parameters=scaled)

    def line_terms(self) -> tuple:
        """The exact affine terms of the line-element parameters (``lines.LineTerm``), computed
        once; empty without them, and empty when one does not enter linearly (``line_groups``
        then interpolate them; ``line_nonlinear`` says which)."""
        from bayesupdate.nastran.lines import LineAssembler, affine_line_terms

        if not isinstance(self._general, LineAssembler):
            return ()
        if getattr(self, "_line_terms", None) is None:
            try:
                self._line_terms = affine_line_terms(
                    self._general, self._line_defaults, self._bounds
                )
            except BayesUpdateError as exc:
                self._line_terms, self.line_nonlinear = (), str(exc)
        return self._line_terms

    def line_groups(self, bounds, interp_tol: float) -> tuple:
        """The interpolated ``lines.LineGroup`` s of line-element parameters that do not enter
        K and M linearly, over the box ``bounds`` ({name: (low, high)}, deck units) to
        ``interp_tol`` (``reduced.affine``); empty when every line parameter is linear.  Kept
        per box and tolerance (the reduced basis and its total mass use the same)."""
        from bayesupdate.nastran.lines import interpolated_line_groups

        self.line_terms()
        if not getattr(self, "line_nonlinear", ""):
            return ()
        names = list(self._general.bindings)
        key = (tuple((n, *map(float, bounds[n])) for n in names), float(interp_tol))
        cache = self.__dict__.setdefault("_line_groups", {})
        if key not in cache:
            box = {n: bounds[n] for n in names}
            cache[key] = interpolated_line_groups(
                self._general, self._line_defaults, box, interp_tol
            )
        return cache[key]

    def line_mass_change(self, params) -> float:
        """Total mass change [deck mass] of the bound line elements from the deck's values to
        ``params`` (all names), for parameters in ``line_groups``: interpolated where a box
        built holds the point, else from the elements themselves."""
        from bayesupdate.fe.reduced.mass import _translational_mass

        if not getattr(self, "line_nonlinear", ""):
            return 0.0
        for groups in getattr(self, "_line_groups", {}).values():
            # a group that moves no mass (I, J: rotary inertia only) needs no weights
            moving = [grp for grp in groups if np.any(grp.dm)]
            values = [np.array([[params[n] for n in grp.names]]) for grp in moving]
            if all(grp.holds(v) for v, grp in zip(values, moving, strict=True)):
                return float(sum((grp.weights(v) @ grp.dm)[0]
                                 for v, grp in zip(values, moving, strict=True)))  # fmt: skip
        g = self._general
        dM = g.line_delta({n: params[n] for n in g.bindings})[1]
        return _translational_mass(g, np.arange(g.nnz), dM)

    def with_structure(self, structure, bindings=None, defaults=None, bounds=None, name=None):
        """A new model on an extended structure (effects append elements: masks are padded)."""
        b = {k: _pad(v, structure) for k, v in self.bindings.items()}
        b.update(bindings or {})
        d = dict(self._defaults, **(defaults or {}))
        bo = dict(self._bounds, **(bounds or {}))
        from bayesupdate.nastran.lines import LineAssembler

        # an effect leaves the deck's bound line elements as they are: their records are
        # not found again for each candidate (``lines.reused_fields`` checks that they hold)
        known = self._general if isinstance(self._general, LineAssembler) else None
        return NastranModel(structure, b, d, bo, name=name or self.name, deck=self.deck,
                            bdf=self.bdf, lines_from=known)  # fmt: skip


def _own_modulus(binding, bdf, structure):
    """A plain ``Binding(part, "modulus_factor")`` on a part of line elements (``"PBEAM
    1003"``: a discovery effect's) as the ``DeckBinding`` that scales their E and G
    (``bindings.modulus_binding``); any other binding as it is."""
    from bayesupdate.nastran.bindings import LINE_PROPERTIES, modulus_binding

    if (
        isinstance(binding, DeckBinding)
        or bdf is None
        or getattr(binding, "property", "") != "modulus_factor"
        or str(binding.target).partition(" ")[0] not in LINE_PROPERTIES
    ):
        return binding
    return modulus_binding(str(binding.target), bdf, structure)


def _without(share: np.ndarray, mass: float, cog) -> tuple[float, np.ndarray]:
    """(mass, centre of gravity) less a (6, 6) rigid-body mass ``share`` about the origin
    (``fe.mass_properties``: m = trace / 3 of its translational block, m c from its coupling
    block); a zero mass keeps the origin as its centre."""
    m = mass - float(np.trace(share[:3, :3]) / 3.0)
    moment = mass * np.asarray(cog, float) - np.array([share[1, 5], share[2, 3], share[0, 4]])
    return m, (moment / m if m > 0 else np.zeros(3))


def _pad(binding, structure):
    if not isinstance(binding, DeckBinding):
        return binding

    def grow(mask, n):
        return np.concatenate([mask, np.zeros(n - mask.size, bool)])

    n_shell = 0 if structure.shells is None else structure.shells.n_elements
    return replace(
        binding,
        shell=grow(binding.shell, n_shell),
        mass=grow(binding.mass, len(structure.mass_part)),
        spring=grow(binding.spring, len(structure.spring_part)),
        solid=grow(binding.solid, n_solids(structure)),
    )


def deck_bindings(parameters: Mapping, bdf, structure) -> tuple[dict, dict, dict]:
    """(bindings, defaults, bounds) of the study's ``{name: {binds, bounds, ...}}`` tables."""
    bindings, defaults, bounds = {}, {}, {}
    for name, entry in parameters.items():
        if "binds" not in entry:
            raise BayesUpdateError(
                f"parameter {name}: a Nastran model's parameters need binds = 'CARD ids FIELD', "
                'e.g. binds = "PSHELL 3 T"'
            )
        b = resolve(parse_binding(entry["binds"], name), bdf, structure, name)
        if "relations" in entry:  # element-card fields set as C0_i + COEF_i x (``desvar``)
            rel = tuple((str(c), int(i), str(f), float(c0), float(k))
                        for c, i, f, c0, k in entry["relations"])  # fmt: skip
            b = replace(b, relations=rel, default=relation_default(bdf, rel),
                        desvar=int(entry["desvar"]))  # fmt: skip
        elif "coefficients" in entry:  # line fields set as C0_i + COEF_i x (``desvar``)
            coefs, c0 = (tuple(float(v) for v in entry[k]) for k in ("coefficients", "offsets"))
            x0 = [(n - o) / c for n, o, c in zip(b.nominal, c0, coefs, strict=True)]
            b = replace(b, default=float(np.mean(x0)), coefficients=coefs, offsets=c0,
                        desvar=int(entry["desvar"]))  # fmt: skip
        elif "desvar" in entry:  # a DESVAR x: the field is COEF x (``desvar``)
            c = float(entry["coefficient"])
            b = replace(b, factor=b.factor * c, default=b.default / c, coefficient=c,
                        desvar=int(entry["desvar"]))  # fmt: skip
        low, high = _bounds(name, entry, b)
        bindings[name], defaults[name], bounds[name] = b, b.default, (low, high)
    bindings = _masses_with_cards(bindings, bdf)
    _check_overlaps(bindings)
    return bindings, defaults, bounds


def _bounds(name: str, entry: Mapping, b: DeckBinding) -> tuple[float, float]:
    """The study's bounds, or ``DEFAULT_RANGE`` x the default; a field that is > 0 in any
    sensible deck (thickness, modulus, density, mass) needs low > 0, an inertia or scalar mass
    low >= 0, an offset (``bindings.SIGNED_FIELDS``) explicit bounds low < high."""
    signed = bool(b.relations) and all(f in SIGNED_FIELDS for _, _, f, _, _ in b.relations)
    if signed and not entry.get("bounds"):
        raise BayesUpdateError(
            f"parameter {name}: binds {b.target!r} (an offset, any sign): give bounds = [low, high]"
        )
    low, high = entry.get("bounds") or [b.default * f for f in DEFAULT_RANGE]
    if signed and not low < high:
        raise BayesUpdateError(f"parameter {name}: bounds {[low, high]}: give low < high")
    if not signed and not (low >= 0 if b.relations else low > 0):
        raise BayesUpdateError(
            f"parameter {name}: bounds {[low, high]} for binds {b.target!r}: "
            + ("the low bound must be >= 0 (an inertia or mass)" if b.relations else
               "the low bound must be > 0 (a thickness, modulus, density or mass)")
        )  # fmt: skip
    return float(low), float(high)


def _masses_with_cards(bindings: dict, bdf) -> dict:
    """The CONM2 M bindings (a mass factor) on CONM2s that another parameter re-builds (an
    offset or inertia: ``relations``) written into the card too: a factor on the read mass
    would miss the m x and m x^2 terms of the new offset (MSC QRG CONM2)."""
    rebuilt = {(c, i) for b in bindings.values() for c, i, *_ in b.relations}
    out = dict(bindings)
    for name, b in bindings.items():
        f = b.field
        if b.relations or (f.card, f.field) != ("CONM2", "M"):
            continue
        if not any(("CONM2", i) in rebuilt for i in f.ids):
            continue
        coef = [n if f.scale else b.coefficient for n in b.nominal]
        rel = tuple(("CONM2", i, "M", 0.0, float(k)) for i, k in zip(f.ids, coef, strict=True))
        out[name] = replace(b, property="line", mass=np.zeros_like(b.mass), factor=1.0,
                            relations=rel)  # fmt: skip
    return out


def _overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two element masks share an element (masks of no elements share none)."""
    return a.size == b.size and bool((a & b).any())


def _check_overlaps(bindings: Mapping[str, DeckBinding]) -> None:
    """Refuse two parameters that set one thing: a property of the same shells, point masses,
    springs or solids (their MAT1 E or RHO), or the same field of one card (the last would
    win, the other seem insensitive)."""
    items = list(bindings.items())
    for i, (a, ba) in enumerate(items):
        for b, bb in items[i + 1 :]:
            same_card_field = bool(_targets(ba) & _targets(bb))
            same = (
                (_COLUMN.get(ba.property, -1) == _COLUMN.get(bb.property, -2)
                 and (ba.shell & bb.shell).any())
                or (ba.mass & bb.mass).any()
                or (ba.spring & bb.spring).any()
                or (ba.field.field == bb.field.field and _overlap(ba.solid, bb.solid))
                or same_card_field
            )  # fmt: skip
            if same:
                raise BayesUpdateError(
                    f"parameters {a} ({ba.target!r}) and {b} ({bb.target!r}) act on the same "
                    "elements' property; bind each element once"
                )


def _targets(b: DeckBinding) -> set:
    """{(card, id, field)} a binding writes (its relations, or its field on each id)."""
    if b.relations:
        return {(c, i, f) for c, i, f, _, _ in b.relations}
    return {(b.field.card, i, b.field.field) for i in b.field.ids}
