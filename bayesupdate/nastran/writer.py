"""The user's deck written back with calibrated values in its bound fields (``--write-bdf``).

The deck is read again with pyNastran and each bound card gets the parameter's value (or, for a
``scale`` binding, the factor times the card's own value; for a DESVAR, COEF x its value, and
the DESVAR's XINIT the value).  The deck's own text is then copied line for line with only those
cards replaced, each by pyNastran's large-field (16-character, full precision) text of it:
comments, card order and every other card stay as they were.  When a bound card is not in the
deck's main file (an INCLUDEd file) or shares its line with another (PELAS), pyNastran's writer
writes the whole deck instead (one file, INCLUDEs merged, cards grouped by type).
"""

from pathlib import Path

from bayesupdate.atomic import atomic_path
from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran.bindings import DeckBinding, _card, set_field
from bayesupdate.nastran.deck import read_deck


def write_updated_deck(model, values, out) -> Path:
    """Write ``model.deck`` with ``values`` ({parameter: value, deck units}) to ``out``."""
    deck = getattr(model, "deck", None)
    if not deck:
        raise BayesUpdateError("--write-bdf: the model is not a Nastran deck (model.source)")
    bdf = read_deck(deck)
    changed = []  # (card name, id, pyNastran card)
    for name, binding in model.bindings.items():
        if not isinstance(binding, DeckBinding) or name not in values:
            continue
        value = float(values[name])
        for i, nominal in zip(binding.field.ids, binding.nominal, strict=True):
            card = _card(bdf, binding.field, i)
            set_field(card, binding.field, value * binding.coefficient, nominal)
            changed.append((binding.field.card, i, card))
        if binding.desvar is not None:  # the design variable's start, as Nastran reads it
            bdf.desvars[binding.desvar].xinit = value
            changed.append(("DESVAR", binding.desvar, bdf.desvars[binding.desvar]))
    out = Path(out)
    text = _patched_text(Path(deck), changed)
    try:
        with atomic_path(out) as tmp:
            if text is None:
                bdf.write_bdf(str(tmp), size=16, is_double=False, enddata=True)
            else:
                Path(tmp).write_text(text)
    except OSError as exc:
        raise BayesUpdateError(f"--write-bdf {out}: cannot write ({exc.strerror})") from exc
    return out


def _patched_text(path: Path, changed) -> str | None:
    """The main file's text with each changed card replaced; None if one cannot be found."""
    with open(path, errors="replace") as f:
        lines = f.readlines()
    spans = []
    for name, cid, card in changed:
        if name == "PELAS":
            return None
        span = _card_span(lines, name, cid)
        if span is None:
            return None
        spans.append((*span, card.write_card(size=16)))
    for start, stop, new in sorted(spans, reverse=True):
        lines[start:stop] = [new if new.endswith("\n") else new + "\n"]
    return "".join(lines)


def _head(line: str) -> tuple[str, str]:
    """(card name, first field) of a small-field, large-field or free-field line."""
    text = line.rstrip("\r\n")
    if "," in text[:10]:
        parts = text.split(",")
        return parts[0].strip().upper().rstrip("*"), parts[1].strip() if len(parts) > 1 else ""
    name = text[:8].strip().upper()
    width = 16 if name.endswith("*") else 8
    return name.rstrip("*"), text[8 : 8 + width].strip()


def _is_continuation(line: str) -> bool:
    text = line.rstrip("\r\n")
    return bool(text.strip()) and (text[0] in "+*," or not text[:8].strip())


def _card_span(lines, name: str, cid: int):
    """(first line, line after the last continuation) of card ``name`` ``cid``, or None."""
    for i, line in enumerate(lines):
        card, first = _head(line)
        if card == name and first.isdigit() and int(first) == int(cid):
            j = i + 1
            while j < len(lines) and _is_continuation(lines[j]):
                j += 1
            return i, j
    return None
