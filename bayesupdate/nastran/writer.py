"""The user's deck written back with calibrated values in its bound fields (``--write-bdf``).

The deck is read again and each bound card gets the parameter's value (or, for a ``scale``
binding, the factor times the card's own value; for a DESVAR, C0 + COEF x its value in each
related field, element cards' own fields too, and the DESVAR's XINIT the value). The deck's own
text is then copied line for line with only those cards replaced, each by a large-field card
(16-character fields, ``bulk.real16``: the shortest repr or 11-15 digits, the fixed form
where it holds more) of all its fields:
comments, card order and every other card stay as they were. A bound card in an ``INCLUDE``d
file is replaced in that file's text, which is written in place of its ``INCLUDE`` line (the
output is one file); the other ``INCLUDE`` lines stay, with the file's absolute path when the
output is written in another folder.
"""

from pathlib import Path

from bayesupdate.atomic import atomic_path
from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran.bindings import (
    DeckBinding,
    _card,
    is_own_modulus,
    set_field,
    write_relations,
)
from bayesupdate.nastran.bulk import large_field_text, with_fields
from bayesupdate.nastran.deck import include_at, read_deck


def write_updated_deck(model, values, out) -> Path:
    """Write ``model.deck`` with ``values`` ({parameter: value, deck units}) to ``out``."""
    path = getattr(model, "deck", None)
    if not path:
        raise BayesUpdateError("--write-bdf: the model is not a Nastran deck (model.source)")
    deck = read_deck(path)
    changed = {}  # (card name, id) -> the card with its new values
    for name, binding in model.bindings.items():
        if not isinstance(binding, DeckBinding) or name not in values:
            continue
        if is_own_modulus(binding.field):
            raise BayesUpdateError(
                f"--write-bdf: {name} scales the modulus of {binding.field.card} "
                f"{binding.field.ids[0]}'s elements alone, which no card field holds; write the "
                "deck without that effect"
            )
        value = float(values[name])
        if binding.relations:  # element-card fields: C0 + COEF x on each card (``bindings``)
            write_relations(deck, binding, value, changed)
        else:
            _write_field(deck, binding, value, changed)
        if binding.desvar is not None:  # the design variable's start, as Nastran reads it
            dv = deck.table("DESVAR")[binding.desvar]
            changed[("DESVAR", binding.desvar)] = with_fields(dv, {dv.position("XINIT"): value})
    return _write(deck, changed, out)


def _write_field(deck, binding: DeckBinding, value: float, changed: dict) -> None:
    """``changed`` with the binding's field at ``value`` on each of its cards."""
    for k, (i, nominal) in enumerate(zip(binding.field.ids, binding.nominal, strict=True)):
        key = (binding.field.card, i)
        card = changed.get(key) or _card(deck, binding.field, i)
        changed[key] = set_field(card, binding.field, binding.value_of(k, value), nominal)


def write_design_deck(path, out, values=None) -> Path:
    """Write the deck at ``path`` with its DESVARs at ``values`` ({DESVAR id or label: value};
    XINIT where not given) to ``out``: every DVPREL1 / DVMREL1 / DVCREL1 relation's field set to
    C0 + sum(COEF_i x_i) (``desvar.design_cards``) and each DESVAR's XINIT to its value, so that
    reading it gives the model SOL 200 builds at those values; the rest as ``write_updated_deck``
    copies it."""
    from bayesupdate.nastran.desvar import design_cards, design_values

    deck = read_deck(path)
    changed = design_cards(deck, values)
    for i, value in design_values(deck, values).items():
        dv = deck.table("DESVAR")[i]
        changed[("DESVAR", i)] = with_fields(dv, {dv.position("XINIT"): float(value)})
    return _write(deck, changed, out)


def _write(deck, changed: dict, out) -> Path:
    """The deck's text with the ``changed`` cards ({key: card}) written to ``out``."""
    out = Path(out)
    by_file = {}
    for card in changed.values():
        by_file.setdefault(card.file, []).append(card)
    text = _text(Path(deck.files[0]), by_file, out.resolve().parent)
    try:
        with atomic_path(out) as tmp:
            Path(tmp).write_text(text)
    except OSError as exc:
        raise BayesUpdateError(f"--write-bdf {out}: cannot write ({exc.strerror})") from exc
    return out


def _text(path: Path, by_file: dict, folder: Path) -> str:
    """``path``'s text with its changed cards replaced and the INCLUDEs holding changed cards
    written in (module docstring)."""
    lines = path.read_text(errors="replace").splitlines(keepends=True)
    replace = {c.line - 1: c for c in by_file.get(str(path), [])}
    out, i = [], 0
    while i < len(lines):
        if i in replace:
            card = replace[i]
            out.append(large_field_text(card))
            i = card.end
            continue
        target, last = include_at(path, lines, i)
        if target is not None and _holds_changes(target, by_file):
            out.append(_text(target, by_file, folder))
        elif target is not None and path.parent.resolve() != folder:
            out.append(f"INCLUDE '{target.resolve()}'\n")
        else:
            out += lines[i : last + 1]
        i = last + 1
    text = "".join(out)
    return text if text.endswith("\n") or not text else text + "\n"


def _holds_changes(path: Path, by_file: dict, stack=()) -> bool:
    """True if ``path`` or a file it INCLUDEs holds a changed card."""
    if str(path) in by_file:
        return True
    if path in stack:
        return False
    lines = path.read_text(errors="replace").splitlines(keepends=True)
    i = 0
    while i < len(lines):
        target, last = include_at(path, lines, i)
        if target is not None and _holds_changes(target, by_file, (*stack, path)):
            return True
        i = last + 1
    return False
