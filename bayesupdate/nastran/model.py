"""``NastranModel``: an ``FEModel`` of a Nastran deck whose parameters are deck fields.

Parameters are in the deck's units (``bindings``); each ``DeckBinding`` acts on element masks
of the structure, and the FE value is ``factor`` x the parameter (WTMASS on densities, 1 / the
deck's value for a spring or mass bound absolutely).  Everything else is ``FEModel``'s: shell
thickness enters K and M as exact powers (``fe.general``), so the reduced basis applies; so
does a line-element field that enters K and M linearly (``lines.affine_line_terms``).
"""

import copy
from collections.abc import Mapping
from dataclasses import replace

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.model import PROPERTY_TERMS, AffineTerms, FEModel
from bayesupdate.nastran.bindings import DeckBinding, parse_binding, resolve

#: default bounds of a bound parameter without ``bounds``: this factor range on its default
DEFAULT_RANGE = (0.5, 2.0)
#: the shell parameter column of each property (``FEModel._shell_keys``): overlaps are errors
_COLUMN = dict(thickness=0, youngs_modulus=1, modulus_factor=1, density=2)


class NastranModel(FEModel):
    """``FEModel`` with ``DeckBinding`` parameters (deck units); ``deck`` is the deck's path;
    ``bdf`` its read cards (``deck.Deck``; needed when a binding acts on line elements:
    ``lines``)."""

    def __init__(self, structure, bindings, defaults, bounds, name="deck", deck="", bdf=None):
        self.deck, self.bdf = str(deck), bdf
        super().__init__(structure, bindings, defaults, bounds, name=name)
        if any(getattr(b, "lines", ()) for b in self.bindings.values()):
            from bayesupdate.nastran.lines import LineAssembler

            self._general = LineAssembler(
                structure, self._shell_keys(), bdf, self.bindings, self.deck
            )
            self._assembler = self._general.beams

    def _mask(self, name, binding):
        if not isinstance(binding, DeckBinding):
            return super()._mask(name, binding)
        if binding.shell.any():
            self._shell_masks[name] = binding.shell
        beams = np.zeros(len(self.structure.beam_part), bool)
        if binding.property == "line":  # re-built elements (``lines``): no FE property
            return beams
        family = PROPERTY_TERMS[binding.property][0]
        return {"beam": beams, "mass": binding.mass, "spring": binding.spring}[family]

    def _solve_general(self, p, props, n_modes, energies, method):
        from bayesupdate.nastran.lines import LineAssembler

        if isinstance(self._general, LineAssembler):
            self._general.values = p
        return super()._solve_general(p, props, n_modes, energies, method)

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
        return super().element_properties(self.fe_values(params))

    def shell_properties(self, params=None):
        return super().shell_properties(self.fe_values(params))

    def affine_terms(self) -> AffineTerms:
        """``FEModel.affine_terms`` with each deck parameter's factor in its term's scale; a
        line-element parameter is a "line" term (no elements of its own: ``line_terms`` are
        its matrices), and raises ``BayesUpdateError`` when it does not enter linearly."""
        if any(getattr(b, "lines", ()) for b in self.bindings.values()):
            self.line_terms()  # the linearity check: a one-line reason for full solves
        # a line binding has no FE property: stand in a modulus factor on no beams (a MAT1
        # binding keeps its shell term; its line elements are in ``line_terms`` too)
        lines = {n for n, b in self.bindings.items() if b.property == "line"}
        stand_in = copy.copy(self)
        stand_in.bindings = {
            n: replace(b, property="modulus_factor") if n in lines else b
            for n, b in self.bindings.items()
        }
        terms = FEModel.affine_terms(stand_in)
        scaled = tuple(
            replace(t, property="line", family="line", field="line", enters="linear")
            if t.name in lines
            else replace(t, scale=t.scale * getattr(self.bindings[t.name], "factor", 1.0))
            for t in terms.parameters
        )
        return replace(terms, parameters=scaled)

    def line_terms(self) -> tuple:
        """The exact affine terms of the line-element parameters (``lines.LineTerm``; empty
        without them), computed once; raises when one does not enter linearly."""
        from bayesupdate.nastran.lines import LineAssembler, affine_line_terms

        if not isinstance(self._general, LineAssembler):
            return ()
        if getattr(self, "_line_terms", None) is None:
            rebuild = self._general.rebuild
            self._line_terms = affine_line_terms(rebuild, self._defaults, self._bounds)
        return self._line_terms

    def with_structure(self, structure, bindings=None, defaults=None, bounds=None, name=None):
        """A new model on an extended structure (effects append elements: masks are padded)."""
        b = {k: _pad(v, structure) for k, v in self.bindings.items()}
        b.update(bindings or {})
        d = dict(self._defaults, **(defaults or {}))
        bo = dict(self._bounds, **(bounds or {}))
        return NastranModel(
            structure, b, d, bo, name=name or self.name, deck=self.deck, bdf=self.bdf
        )


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
        if "desvar" in entry:  # a DESVAR x: the field is COEF x (``desvar``)
            c = float(entry["coefficient"])
            b = replace(b, factor=b.factor * c, default=b.default / c, coefficient=c,
                        desvar=int(entry["desvar"]))  # fmt: skip
        low, high = entry.get("bounds") or [b.default * f for f in DEFAULT_RANGE]
        if not low > 0:
            raise BayesUpdateError(
                f"parameter {name}: bounds {[low, high]} for binds {b.target!r}: "
                "the low bound must be > 0 (a thickness, modulus, density or mass)"
            )
        bindings[name], defaults[name], bounds[name] = b, b.default, (low, high)
    _check_overlaps(bindings)
    return bindings, defaults, bounds


def _check_overlaps(bindings: Mapping[str, DeckBinding]) -> None:
    items = list(bindings.items())
    for i, (a, ba) in enumerate(items):
        for b, bb in items[i + 1 :]:
            same = (
                _COLUMN.get(ba.property, -1) == _COLUMN.get(bb.property, -2)
                and (ba.shell & bb.shell).any()
                or (ba.mass & bb.mass).any()
                or (ba.spring & bb.spring).any()
            )
            if same:
                raise BayesUpdateError(
                    f"parameters {a} ({ba.target!r}) and {b} ({bb.target!r}) act on the same "
                    "elements' property; bind each element once"
                )
