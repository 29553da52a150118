"""Nastran bulk-data fields and cards: small-field, large-field and free-field lines, numbers.

MSC Nastran Quick Reference Guide, "Bulk Data Entry Format": a card is a name and data fields,
8 per physical line; small-field lines have 8-character fields (columns 9-72), large-field
lines (name or continuation marker ending in ``*``) 16-character fields, four per line, and
free-field lines separate fields with commas.  Columns 1-8 of a continuation line hold its
marker (``+...``, ``*...``) or are blank; column 73-80 (field 10) holds the next marker and is
not data.  A ``$`` starts a comment.  Tabs stop every 8 columns.

Numbers are read as Nastran reads them: an integer has no decimal point; a real may drop the
``E`` of its exponent (``1.0-3`` = 0.001, ``.5+2`` = 50.) or use ``D`` (``1.D4``).

``Card`` keeps its raw fields and the file and line of its first line; ``FIELDS`` is each card's
field table (QRG names, ``NAME=default`` where a blank field has a default), so a converter reads
``card["PID"]`` and the card's own name and place go into any error (``CardError``).
"""

import re
from dataclasses import dataclass
from functools import cache, lru_cache

#: an integer field (no decimal point, no exponent)
_INT = re.compile(r"^[+-]?\d+$")
#: a real field: mantissa, then an exponent with E or D (sign optional) or a bare signed one
_REAL = re.compile(r"^([+-]?(?:\d+\.\d*|\.\d+|\d+))(?:[ED]([+-]?\d+)|([+-]\d+))?$")
#: a character field: a letter, then letters, digits, '_', '(', ')', '.', '-', '+'
_TEXT = re.compile(r"^[A-Z][A-Z0-9_().+\-]*$")


class CardError(Exception):
    """One card's refusal: 'file:line CARD id: message' (collected, never shown alone)."""


@lru_cache(maxsize=1 << 16)
def parse_number(text: str):
    """int, float, str (upper case) or None of one field's text (module docstring); a
    ``ValueError`` for text that is none of these.  Kept for the last 65,536 texts: a deck's
    fields repeat, and a bound model reads its bound cards again (``lines.LineRebuild``)."""
    s = text.strip().upper()
    if not s:
        return None
    if _INT.match(s):
        return int(s)
    m = _REAL.match(s)
    if m:
        exponent = m.group(2) or m.group(3)
        return float(m.group(1) + ("e" + exponent if exponent else ""))
    if _TEXT.match(s):
        return s
    raise ValueError(f"{text.strip()!r} is not a Nastran number or word")


def _spec(text: str) -> tuple[tuple[str, object], ...]:
    """Field table ``"EID PID GA GB OFFT=GGG"`` -> ((name, default), ...); '-' = unused."""
    out = []
    for token in text.split():
        name, _, default = token.partition("=")
        out.append((name, parse_number(default) if default else None))
    return tuple(out)


_W = "W1A=0. W2A=0. W3A=0. W1B=0. W2B=0. W3B=0."
#: field tables of the cards read (MSC Nastran Quick Reference Guide; positions from field 2,
#: eight per line).  Repeated groups (RBE2 GMi, SPC1 Gi, PBEAM stations, PBUSH K/B/M lines,
#: PBARL/PBEAML DIMi, RBE3 weights, PCOMP/PCOMPG plies) are read from ``Card.values`` by their
#: converters.
FIELDS = {
    name: _spec(text)
    for name, text in {
        "GRID": "ID CP=0 X1=0. X2=0. X3=0. CD=0 PS SEID",
        "CORD2R": "CID RID=0 A1 A2 A3 B1 B2 B3 C1 C2 C3",
        "CORD2C": "CID RID=0 A1 A2 A3 B1 B2 B3 C1 C2 C3",
        "CORD2S": "CID RID=0 A1 A2 A3 B1 B2 B3 C1 C2 C3",
        "CORD1R": "CIDA G1A G2A G3A CIDB G1B G2B G3B",
        "CORD1C": "CIDA G1A G2A G3A CIDB G1B G2B G3B",
        "CORD1S": "CIDA G1A G2A G3A CIDB G1B G2B G3B",
        "MAT1": "MID E G NU RHO=0. A TREF GE ST SC SS MCSID",
        "CQUAD4": "EID PID G1 G2 G3 G4 THETA ZOFFS=0. - TFLAG=0 T1 T2 T3 T4",
        "CTRIA3": "EID PID G1 G2 G3 THETA ZOFFS=0. - - TFLAG=0 T1 T2 T3",
        "PSHELL": "PID MID1 T MID2 12IT3=1. MID3 TST=0.833333 NSM=0. Z1 Z2 MID4",
        "PCOMP": "PID Z0 NSM=0. SB FT TREF GE LAM",
        "PCOMPG": "PID Z0 NSM=0. SB FT TREF GE LAM",
        "MAT8": "MID E1 E2 NU12=0. G12 G1Z G2Z RHO=0. A1 A2 TREF XT XC YT YC S GE F12 STRN",
        "CBAR": "EID PID GA GB X1 X2 X3 OFFT=GGG PA PB " + _W,
        "CBEAM": "EID PID GA GB X1 X2 X3 OFFT=GGG PA PB " + _W + " SA SB",
        "PBAR": "PID MID A=0. I1=0. I2=0. J=0. NSM=0. - C1 C2 D1 D2 E1 E2 F1 F2 K1 K2 I12=0.",
        "PBARL": "PID MID GROUP=MSCBML0 TYPE",
        "PBEAML": "PID MID GROUP=MSCBML0 TYPE",
        "PBEAM": "PID MID A=0. I1=0. I2=0. I12=0. J=0. NSM=0.",
        "CROD": "EID PID G1 G2",
        "PROD": "PID MID A=0. J=0. C NSM=0.",
        "CONROD": "EID G1 G2 MID A=0. J=0. C NSM=0.",
        "CTUBE": "EID PID G1 G2",
        "PTUBE": "PID MID OD T NSM=0. OD2",
        "CONM2": "EID G CID=0 M=0. X1=0. X2=0. X3=0. - I11=0. I21=0. I22=0. I31=0. I32=0. I33=0.",
        "CONM1": "EID G CID=0 M11=0. M21=0. M22=0. M31=0. M32=0. M33=0. M41=0. M42=0. "
        "M43=0. M44=0. M51=0. M52=0. M53=0. M54=0. M55=0. M61=0. M62=0. M63=0. M64=0. M65=0. "
        "M66=0.",
        "CMASS1": "EID PID G1 C1 G2 C2",
        "CMASS2": "EID M=0. G1 C1 G2 C2",
        "PMASS": "PID M",
        "CELAS1": "EID PID G1 C1 G2 C2",
        "CELAS2": "EID K G1 C1 G2 C2 GE S",
        "PELAS": "PID K GE S",
        "CELAS3": "EID PID S1 S2",
        "CELAS4": "EID K S1 S2",
        "CMASS3": "EID PID S1 S2",
        "CMASS4": "EID M S1 S2",
        "SPOINT": "ID1",
        "CBUSH": "EID PID GA GB X1 X2 X3 CID S=0.5 OCID=-1 S1 S2 S3",
        "CTETRA": "EID PID G1 G2 G3 G4 G5 G6 G7 G8 G9 G10",
        "CHEXA": "EID PID " + " ".join(f"G{i}" for i in range(1, 21)),
        "PSOLID": "PID MID CORDM=0 IN STRESS ISOP FCTN=SMECH",
        "CSHEAR": "EID PID G1 G2 G3 G4",
        "PSHEAR": "PID MID T NSM=0. F1 F2 F3 F4",
        "RBE2": "EID GN CM",
        "RBAR": "EID GA GB CNA CNB CMA CMB ALPHA",
        "RBE3": "EID - REFGRID REFC",
        "SPC": "SID G1 C1 D1 G2 C2 D2",
        "SPC1": "SID C",
        "SPCADD": "SID",
        "SUPORT": "ID1 C1 ID2 C2 ID3 C3 ID4 C4",
        "SUPORT1": "SID",
        "EIGRL": "SID V1 V2 ND MSGLVL MAXSET SHFSCL NORM",
        "EIGR": "SID METHOD F1 F2 NE ND - - NORM G C",
        "PARAM": "N V1 V2",
        "SET1": "SID",
        "DESVAR": "ID LABEL XINIT XLB=-1.e20 XUB=1.e20 DELXV DDVAL",
        "DVPREL1": "ID TYPE PID PNAME PMIN PMAX C0=0.",
        "DVMREL1": "ID TYPE MID MPNAME MPMIN MPMAX C0=0.",
        "DVCREL1": "ID TYPE EID CPNAME CPMIN CPMAX C0=0.",
    }.items()
}
#: names of a field by position where the table's name depends on the value (X1 or G0)
ALIASES = {"G0": "X1"}


@dataclass(frozen=True)
class Card:
    """One bulk-data card: ``name`` (upper case, no '*'), ``raw`` its data fields as text (field
    2 on, eight per physical line, continuation markers dropped), ``file`` and ``line`` of its
    first line; ``end`` the line number of its last line (``writer``)."""

    name: str
    raw: tuple[str, ...]
    file: str
    line: int
    end: int = 0

    @property
    def type(self) -> str:
        """The card's name (as ``name``)."""
        return self.name

    @property
    def where(self) -> str:
        """'file:line' (the file's name) of the card's first line."""
        return f"{self.file.rsplit('/', 1)[-1]}:{self.line}"

    def fail(self, message: str):
        """Raise ``CardError`` for this card: 'file:line NAME id: message'."""
        raise CardError(f"{self.where} {self.label}: {message}")

    @property
    def label(self) -> str:
        first = self.raw[0].strip() if self.raw else ""
        if self.name == "PARAM":
            return f"PARAM {first.upper()}"
        return f"{self.name} {first}".strip()

    def value(self, i: int):
        """Parsed field ``i`` (0 = field 2), None when blank or past the end."""
        if i >= len(self.raw):
            return None
        try:
            return parse_number(self.raw[i])
        except ValueError as exc:
            self.fail(f"field {_field_number(i)}: {exc}")

    def values(self, start: int = 0, stop: int | None = None) -> list:
        """Parsed fields ``start`` to ``stop`` (0 = field 2)."""
        stop = len(self.raw) if stop is None else stop
        return [self.value(i) for i in range(start, stop)]

    def position(self, name: str) -> int:
        """The raw index of field ``name`` of the card's table (``FIELDS``)."""
        i = _positions(self.name).get(ALIASES.get(name, name))
        if i is None:
            self.fail(f"has no field {ALIASES.get(name, name)}")
        return i

    def __getitem__(self, name: str):
        """Field ``name`` of the card's table (``FIELDS``), its default where blank."""
        i = self.position(name)
        v = self.value(i)
        return FIELDS[self.name][i][1] if v is None else v

    def is_blank(self, name: str) -> bool:
        return self.value(self.position(name)) is None

    def int(self, name: str, positive: bool = False) -> int:
        """Integer field ``name`` (its default where blank); refused when not an integer."""
        v = self[name]
        if not isinstance(v, int) or (positive and v <= 0):
            self.fail(f"{name} = {v!r}: give {'a positive' if positive else 'an'} integer")
        return v

    def real(self, name: str) -> float:
        """Real field ``name`` (its default where blank; an integer is accepted as a real)."""
        v = self[name]
        if isinstance(v, bool) or not isinstance(v, int | float):
            self.fail(f"{name} = {v!r}: give a real number")
        return float(v)

    def id(self) -> int:
        """The card's id (field 2)."""
        v = self.value(0)
        if not isinstance(v, int):
            self.fail(f"field 2 = {v!r}: give an integer id")
        return v


@cache
def _positions(card: str) -> dict[str, int]:
    """{field name: its first raw index} of a card's table (``FIELDS``)."""
    out = {}
    for i, (name, _) in enumerate(FIELDS.get(card, ())):
        out.setdefault(name, i)
    return out


def _field_number(i: int) -> str:
    """Nastran's name of data field ``i``: 'k' on the first line, 'k of continuation n'."""
    line, k = divmod(i, 8)
    return str(k + 2) if line == 0 else f"{k + 2} of continuation {line}"


def split_line(text: str) -> tuple[str, list[str], bool]:
    """(first field, data fields, large) of one physical line (comment and tabs removed).

    Free field (a comma in the first 10 columns): up to 8 data fields after the first (a ninth
    is the continuation marker);
    small field: 8 of 8 characters; large field: 4 of 16 characters (a first field ending with
    '*', or a continuation's starting with it: '*     FM' continues a large-field card)."""
    if "," in text[:10]:
        parts = text.split(",")
        head = parts[0].strip()
        large = head.endswith("*") or head.startswith("*")
        n = 4 if large else 8
        data = [p.strip() for p in parts[1 : 1 + n]]
        extra = [p for p in parts[1 + n :] if p.strip()]
        if len(extra) > 1 or (extra and not extra[0].strip().startswith(("+", "*"))):
            raise ValueError(f"more than {n} data fields on one free-field line")
        return head, data + [""] * (n - len(data)), large
    head = text[:8].strip()
    large = head.endswith("*") or head.startswith("*")
    width = 16 if large else 8
    body = text[8:72].ljust(64)
    return head, [body[k : k + width] for k in range(0, 64, width)], large


def card_name(head: str) -> str:
    """The card name of a first field ('CONM2*' -> 'CONM2', and 'CORD2R *', a large-field
    name with its star in column 8, -> 'CORD2R'); '' for a continuation."""
    if not head or head[0] in "+*":
        return ""
    return head.rstrip("*").rstrip().upper()


def real16(value: float) -> str:
    """A real in at most 16 characters with as many digits as fit: Python's shortest repr when
    it fits, else whichever of the fixed form ('-1.1746955442270') and Nastran's exponent form
    without 'E' ('-1.234567890123-5') reads back closer to the value (the fixed form keeps two
    more digits where the exponent is small: a written offset or factor then holds 13-14
    digits, not 11)."""
    v = float(value)
    text = repr(v)
    if len(text) <= 16 and ("." in text or "e" in text):
        return text
    forms = [_exponent16(v)]
    fixed = f"{v:.{max(15 - len(f'{v:.0f}'), 0)}f}"
    if len(fixed) <= 16 and "." in fixed:
        forms.append(fixed)
    return min(forms, key=lambda t: abs(parse_number(t) - v))


def _exponent16(v: float) -> str:
    """``v`` in Nastran's exponent form without 'E', as many digits as fit 16 characters."""
    for digits in range(15, 0, -1):
        mantissa, exponent = f"{v:.{digits}e}".split("e")
        text = f"{mantissa}{int(exponent):+d}"
        if len(text) <= 16:
            return text
    raise ValueError(f"{v!r} does not fit a large field")


def with_fields(card: Card, changes: dict[int, object]) -> Card:
    """A copy of ``card`` with raw fields ``{index: value}`` replaced (reals written by
    ``real16``; the copy keeps the card's file and lines)."""
    raw = list(card.raw)
    raw += [""] * (max(changes, default=-1) + 1 - len(raw))
    for i, v in changes.items():
        raw[i] = real16(v) if isinstance(v, float) else ("" if v is None else str(v))
    return Card(card.name, tuple(raw), card.file, card.line, card.end)


def large_field_text(card: Card) -> str:
    """The card as large-field lines ('NAME*' then '*' continuations, 4 fields of 16)."""
    raw = [r.strip() for r in card.raw]
    # a free-field value longer than a large field (a full repr) is written in 16 characters
    raw = [real16(parse_number(r)) if len(r) > 16 else r for r in raw]
    raw += [""] * ((-len(raw) % 4) if raw else 4)
    lines = []
    for k in range(0, len(raw), 4):
        head = f"{card.name}*" if k == 0 else "*"
        lines.append(head.ljust(8) + "".join(f.ljust(16) for f in raw[k : k + 4]).rstrip())
    return "\n".join(lines) + "\n"
