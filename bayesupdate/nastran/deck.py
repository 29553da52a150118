"""A Nastran deck's files read into cards: executive, case control, ``BEGIN BULK`` .. ``ENDDATA``.

``read_deck(path)`` follows ``INCLUDE`` (quoted or not, continued over lines, relative to the
including file; a name missing in its exact letter case is found in another, with a note),
reads SOL and the case control's METHOD, SPC and SET selections (the first subcase over the
global ones), and joins each card's continuation lines (``bulk``): a line whose first field is
blank or starts with ``+`` / ``*`` continues the card above it, whatever its marker says, so
decks that reuse one marker on every card (``+cb1``) read as MSC reads them.

``check_cards`` sorts every card into read (``SUPPORTED``), listed with no effect on the normal
modes (``NO_EFFECT_CARDS``, the design model ``DESIGN_CARDS``, ``IGNORED_PARAMS``) and refused
(any other card; any PARAM outside ``MODEL_PARAMS`` and ``IGNORED_PARAMS``).  Refusals are
collected over the whole deck (``Refusals``) and raised together as one ``BayesUpdateError``,
each with its file:line.
"""

import re
from dataclasses import dataclass, field
from pathlib import Path

from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran.bulk import Card, CardError, card_name, split_line, with_fields
from bayesupdate.nastran.cards import FAMILIES as FAMILIES_OF_CARDS

#: file suffixes read as Nastran bulk data
SUFFIXES = (".bdf", ".dat", ".nas", ".blk")

#: cards turned into the FE model (``reader``; the elements of each ``cards`` family)
ELEMENT_CARDS = {
    "GRID", "CORD2R", "CORD2C", "CORD2S", "CORD1R", "CORD1C", "CORD1S", "CQUAD4", "CTRIA3",
    "PSHELL", "PCOMP", "PCOMPG", "MAT1", "MAT8", "PBAR", "PBARL", "PBEAM", "PBEAML", "PROD",
    "PMASS", "PELAS", "PBUSH",
    "SPC", "SPC1", "SPCADD", "MPC", "MPCADD", "EIGRL", "EIGR", "PARAM",
} | {name for family in FAMILIES_OF_CARDS for name in family.CARDS}  # fmt: skip
#: design variables and relations: parameters when the study names none (``desvar``)
DESIGN_CARDS = {"DESVAR", "DVPREL1", "DVMREL1", "DVCREL1", "DVGRID"}
#: the deck's own optimization problem (SOL 200): read and listed, not used
OBJECTIVE_CARDS = {"DRESP1", "DRESP2", "DRESP3", "DCONSTR", "DCONADD", "DEQATN", "DOPTPRM",
                   "DTABLE", "DLINK", "DSCREEN"}  # fmt: skip
#: cards that add no element: output sets (SET1: test points, ``test_points``), rigid-body
#: reference DOFs (SUPORT: the reader then asks for MSC's rigid set, ``reader``), the end marker
NO_EFFECT_CARDS = {"USET", "USET1", "SUPORT", "SUPORT1", "SET1", "ENDDATA"}
#: cards of other analyses, read and listed once as ignored: the real normal modes of SOL 103
#: are those of K and M alone (MSC QRG, each card's remarks: they are selected from the case
#: control of the solutions that use them).  Loads change the modes only as a preload
#: (STATSUB, refused in the case control); damping elements enter only the damped, complex or
#: response solutions; the aeroelastic model only SOL 144-146 (its splines read the structure's
#: GRIDs, they do not add to K or M)
IGNORED_CARDS = {
    "static and dynamic loads": {
        "FORCE", "FORCE1", "FORCE2", "MOMENT", "MOMENT1", "MOMENT2", "PLOAD", "PLOAD1", "PLOAD2",
        "PLOAD4", "GRAV", "ACCEL", "ACCEL1", "RFORCE", "LOAD", "LSEQ", "DLOAD", "RLOAD1",
        "RLOAD2", "TLOAD1", "TLOAD2", "DAREA", "DPHASE", "DELAY", "SPCD", "TEMP", "TEMPD",
        "RANDPS", "TABRND1", "TABLED1", "TABLED2", "TABLED3", "TABLED4",
    },
    "other solutions' controls": {
        "FREQ", "FREQ1", "FREQ2", "FREQ3", "FREQ4", "FREQ5", "TSTEP", "NLPARM", "EIGB", "EIGC",
        "TABDMP1",
    },
    "damping elements": {"CDAMP1", "CDAMP2", "CDAMP3", "CDAMP4", "PDAMP", "CVISC", "PVISC"},
    "the aeroelastic model": {
        "AERO", "AEROS", "CAERO1", "CAERO2", "CAERO3", "CAERO4", "CAERO5", "PAERO1", "PAERO2",
        "PAERO3", "PAERO4", "PAERO5", "SPLINE1", "SPLINE2", "SPLINE3", "SPLINE4", "SPLINE5",
        "SET2", "AESURF", "AESURFS", "AELIST", "AEFACT", "AESTAT", "AELINK", "AEPARM",
        "AECOMP", "AECOMPL", "MKAERO1", "MKAERO2", "FLUTTER", "FLFACT", "GUST", "TRIM",
        "DIVERG", "CSSCHD", "MONPNT1", "MONPNT2", "MONPNT3", "MONDSP1", "UXVEC",
    },
    "plot and output": {"PLOTEL", "PLOTEL3", "PLOTEL4", "CBARAO", "EPOINT"},
    "material tables (read only by MATT and MATS cards, refused here)": {
        "TABLEM1", "TABLEM2", "TABLEM3", "TABLEM4",
    },
}  # fmt: skip
#: MDLPRM (MSC's model parameters): only the HDF5 output settings (HDF5, H5...) are ignored; any
#: other MDLPRM may change the model (offsets, shell formulation) and is refused, named
MDLPRM_OUTPUT = re.compile(r"^(HDF5|H5\w*)$")
#: DMI matrices the aeroelastic solutions read by these names (MSC QRG, Aeroelastic Analysis:
#: downwash, force and pressure corrections): ignored; a DMI of any other name is refused
AERO_DMI = {"W2GJ", "FA2J", "WKK", "WTFACT"}
SUPPORTED = (ELEMENT_CARDS | NO_EFFECT_CARDS | DESIGN_CARDS | OBJECTIVE_CARDS
             | {"MDLPRM", "DMI", "DMIG"}
             | set().union(*IGNORED_CARDS.values()))  # fmt: skip
#: PARAMs that shape the model (``reader``)
MODEL_PARAMS = {"WTMASS", "K6ROT", "COUPMASS", "AUTOSPC"}
#: PARAMs with no effect on real eigenvalues and shapes (MSC QRG, Parameters): output requests
#: and formats (POST, POSTEXT, OGEOM, OUGCORD, PATVER, ...), printing (PRTMAXIM, PRGPST, ...),
#: the weight summary's reference point (GRDPNT), aeroelastic velocity units (VREF, AUNITS),
#: checks that only print or stop (MAXRATIO, BAILOUT, EPZERO), restart and database control,
#: SOL 200 print and punch control, residual vectors (RESVEC: responses, not eigenpairs),
#: LGDISP (nonlinear solutions only), the modes a modal response solution keeps (LMODES), the
#: unit system's label (UNITSYS), the aeroelastic Mach check, gust, dynamic pressure and
#: monitor point units (OMACHPR, GUSTAERO, Q, MPTUNIT), sparse data recovery (SPARSEDR)
IGNORED_PARAMS = {
    "POST", "POSTEXT", "OGEOM", "GRDPNT", "RESCOMP", "OUGCORD", "PRGPST", "NOCOMPS", "PATVER",
    "MAXRATIO", "SRCOMPS", "OMID", "BAILOUT", "PRTMAXIM", "VREF", "AUNITS", "PRTGPL", "PRTEQXIN",
    "PRTGPDT", "PRTCSTM", "PRTBGPDT", "PRTGPTT", "PRTMGG", "PRTPG", "EPZERO", "DBALL", "DBUP",
    "DBDICT", "DBCCONV", "OPPHIPA", "OUNIT1", "OUNIT2", "ITAPE", "POSTOUT", "NASPRT",
    "DESPCH", "DESPCH1", "OPTEXIT", "PRTRESLT", "SOFTEXIT", "DDRMM", "OG", "CURVPLOT",
    "USETPRT", "USETSEL", "SEMAPPRT", "ERROR", "PRINT", "LGDISP",
    "RESVEC", "RESVINER", "CHECKOUT", "NEWSEQ", "SEQOUT", "TINY", "LMODES", "UNITSYS",
    "OMACHPR", "GUSTAERO", "SPARSEDR", "Q", "MPTUNIT", "OIBULK",
}  # fmt: skip
# any other PARAM may change the normal modes and is not modelled: refused, named (e.g. G, W3,
# W4: damping; SNORM: shell normals)


def is_nastran_path(text) -> bool:
    """True if ``text`` names a Nastran deck by its suffix (.bdf, .dat, .nas, .blk)."""
    return isinstance(text, str | Path) and Path(str(text)).suffix.lower() in SUFFIXES


@dataclass
class Refusals:
    """Every refusal of a deck, collected over the whole read and raised once (``raise_all``)."""

    path: str
    items: list = field(default_factory=list)

    def add(self, message: str) -> None:
        if message not in self.items:
            self.items.append(message)

    def card(self, card: Card, message: str) -> None:
        self.add(f"{card.where} {card.label}: {message}")

    def guard(self, function, *args):
        """``function(*args)``; a ``CardError`` is recorded and None returned."""
        try:
            return function(*args)
        except CardError as exc:
            self.add(str(exc))
            return None

    def raise_all(self) -> None:
        if self.items:
            n = len(self.items)
            raise BayesUpdateError(
                f"Nastran model {self.path}: {n} card(s) refused: " + "; ".join(self.items)
            )


@dataclass(frozen=True)
class Deck:
    """A read deck: ``cards`` in reading order, ``sol``, the case control's ``case``
    selections ({'METHOD': 101, 'SPC': 1}) and ``case_sets`` ({SET id: ids}), ``notes`` for the
    user, ``files`` read (main file first)."""

    path: str
    sol: str | None
    case: dict
    case_sets: dict
    cards: tuple[Card, ...]
    notes: tuple[str, ...]
    files: tuple[str, ...]
    _index: dict = field(default_factory=dict, repr=False, compare=False)

    def of(self, *names: str) -> list[Card]:
        """Cards named ``names``, in reading order."""
        return [c for c in self.cards if c.name in names]

    def table(self, *names: str) -> dict[int, Card]:
        """{id: card} of the cards named ``names`` (one id space: elements, properties, ...);
        a second card with an id refuses it (``duplicates``)."""
        key = tuple(sorted(names))
        if key not in self._index:
            out = {}
            for c in self.of(*names):
                try:
                    i = c.id()
                except CardError:
                    continue
                out.setdefault(i, c)
            self._index[key] = out
        return self._index[key]

    def params(self) -> dict[str, Card]:
        """{PARAM name: its card} (the first card of each name)."""
        out = {}
        for c in self.of("PARAM"):
            out.setdefault(str(c.value(0)).upper(), c)
        return out

    def param(self, name: str, default):
        card = self.params().get(name)
        if card is None:
            return default
        value = card.value(1)
        return default if value is None else value

    @property
    def elements(self) -> dict[int, Card]:
        """{id: card} of the elements (lines, shells, springs; ``FAMILIES``)."""
        return self.table(*FAMILIES["element"])

    @property
    def masses(self) -> dict[int, Card]:
        return self.table(*FAMILIES["mass element"])

    @property
    def properties(self) -> dict[int, Card]:
        return self.table(*FAMILIES["property"])

    @property
    def materials(self) -> dict[int, Card]:
        return self.table(*FAMILIES["material"])

    def count(self) -> dict[str, int]:
        out = {}
        for c in self.cards:
            out[c.name] = out.get(c.name, 0) + 1
        return dict(sorted(out.items()))


#: id families: two cards of one family may not share an id
FAMILIES = {
    "element": ("CQUAD4", "CTRIA3", "CBAR", "CBEAM", "CROD", "CONROD", "CBUSH", "CELAS1",
                "CELAS2", "CELAS3", "CELAS4", "CTETRA", "CHEXA", "CTUBE", "CSHEAR"),
    "mass element": ("CONM2", "CONM1", "CMASS1", "CMASS2", "CMASS3", "CMASS4"),
    "rigid element": ("RBE2", "RBE3", "RBAR"),
    "property": ("PSHELL", "PCOMP", "PCOMPG", "PBAR", "PBARL", "PBEAM", "PBEAML", "PROD", "PBUSH",
                 "PELAS", "PMASS", "PSOLID", "PTUBE", "PSHEAR"),
    "material": ("MAT1", "MAT8"),
    "grid": ("GRID",),
    "coordinate system": ("CORD2R", "CORD2C", "CORD2S", "CORD1R", "CORD1C", "CORD1S"),
    "design variable": ("DESVAR",),
}  # fmt: skip


# -- files and INCLUDE --------------------------------------------------------------------------
_INCLUDE = re.compile(r"^\s*INCLUDE\s*(.*)$", re.IGNORECASE)


def _find(path: Path, notes: list) -> Path | None:
    """``path``, or the file whose name matches it in another letter case (a note)."""
    if path.is_file():
        return path
    parent = path.parent if path.parent.is_dir() else _find_dir(path.parent)
    if parent is None:
        return None
    for entry in sorted(parent.iterdir()):
        if entry.name.lower() == path.name.lower() and entry.is_file():
            notes.append(f"INCLUDE {path.name}: read {entry.name} (the name in another case)")
            return entry
    return None


def _find_dir(path: Path) -> Path | None:
    if path.is_dir():
        return path
    parent = _find_dir(path.parent) if path.parent != path else None
    if parent is None:
        return None
    for entry in parent.iterdir():
        if entry.name.lower() == path.name.lower() and entry.is_dir():
            return entry
    return None


def _include_name(first: str, lines: list[str], i: int) -> tuple[str, int]:
    """(file name, index of the INCLUDE's last line): a quoted name may run over lines (each
    line's blanks at its ends dropped), an unquoted one is the first word."""
    text = first.split("$", 1)[0].strip() if not first.lstrip().startswith("'") else first.strip()
    if not text.startswith("'"):
        return text.split()[0] if text else "", i
    name = text[1:]
    while "'" not in name and i + 1 < len(lines):
        i += 1
        name += lines[i].strip()
    return name.split("'", 1)[0], i


def include_at(path: Path, lines: list[str], i: int, notes=None) -> tuple[Path | None, int]:
    """(the file an INCLUDE at line ``i`` of ``path`` names, or None when line ``i`` is no
    INCLUDE or the file is missing in every letter case; index of the INCLUDE's last line)."""
    m = _INCLUDE.match(lines[i]) if lines[i][:1] in "iI " else None
    if m is None:
        return None, i
    name, last = _include_name(m.group(1), lines, i)
    target = _find(path.parent / name, [] if notes is None else notes) if name else None
    return target, last


def _lines(path: Path, refusals: Refusals, notes: list, files: list, stack=()):
    """(file, line number, text) of ``path`` with its INCLUDEs expanded, in reading order."""
    if path in stack:
        refusals.add(f"{path.name}: INCLUDEs itself (through {', '.join(p.name for p in stack)})")
        return
    files.append(str(path))
    lines = path.read_text(errors="replace").splitlines()
    i = 0
    while i < len(lines):
        m = _INCLUDE.match(lines[i]) if lines[i][:1] in "iI " else None
        if m is None:
            yield str(path), i + 1, lines[i]
            i += 1
            continue
        target, last = include_at(path, lines, i, notes)
        if target is None:
            name = _include_name(m.group(1), lines, i)[0]
            refusals.add(f"{path.name}:{i + 1} INCLUDE {name!r}: no such file "
                         f"in {path.parent} (in any letter case)")  # fmt: skip
        else:
            yield from _lines(target, refusals, notes, files, (*stack, path))
        i = last + 1


# -- executive and case control -----------------------------------------------------------------
def _words(text: str) -> str:
    return text.split("$", 1)[0].strip().upper()


#: case control commands that change the real normal modes and are not modelled (by their
#: first four letters, as Nastran reads them)
CASE_REFUSED = {
    "STATSUB": "a preloaded subcase (its differential stiffness changes the modes) is not "
    "supported",
}


def _case_control(lines) -> tuple[dict, dict]:
    """(selections of the first subcase over the global ones, {SET id: ints}) of case control
    lines (file, line, text); ``changes`` in the selections: (file:line, command) of each
    command in ``CASE_REFUSED``."""
    scopes, current = {0: {}}, 0
    sets, pending, changes, matrices = {}, None, [], set()
    for file, number, text in lines:
        words = _words(text)
        if not words:
            continue
        if pending is not None:  # a SET list continued after a trailing comma
            sets[pending] += _ints(words)
            pending = pending if words.endswith(",") else None
            continue
        refused = [c for c in CASE_REFUSED if words.startswith(c[:4])]
        m = re.match(r"^(K2GG|M2GG)\s*=\s*(.*)$", words)
        if m:  # in any subcase, as STATSUB: "K2GG = 1.5*KAX, KBX" names KAX and KBX
            matrices.update(re.findall(r"(?<![\w.])[A-Z][A-Z0-9_]*", m.group(2)))
        if refused:  # in any subcase: the deck is meant for that solution
            changes.append((f"{Path(file).name}:{number}", refused[0]))
        m = re.match(r"^SUBCASE\s+(\d+)", words)
        if m:
            current = int(m.group(1))
            scopes.setdefault(current, {})
            continue
        m = re.match(r"^SET\s+(\d+)\s*=\s*(.*)$", words)
        if m:
            sid = int(m.group(1))
            sets[sid] = _ints(m.group(2))
            pending = sid if m.group(2).endswith(",") else None
            continue
        m = re.match(r"^([A-Z0-9]+)(?:\([^)]*\))?\s*=\s*(\S+)", words)
        if m:
            scopes[current][m.group(1)[:4]] = m.group(2)
    first = min((k for k in scopes if k > 0), default=0)
    chosen = {**scopes[0], **scopes[first]}
    case = {"changes": tuple(changes)} if changes else {}
    if matrices:
        case["K2GG/M2GG"] = tuple(sorted(matrices))
    for key, name in (("METH", "METHOD"), ("SPC", "SPC"), ("MPC", "MPC")):
        if key in chosen and chosen[key].isdigit():
            case[name] = int(chosen[key])
    return case, {k: tuple(v) for k, v in sets.items()}


def _ints(text: str) -> list[int]:
    """Integers of a SET list ('1, 2, 10 THRU 14', EXCEPT not expanded)."""
    out, tokens = [], [t for t in re.split(r"[,\s]+", text) if t]
    k = 0
    while k < len(tokens):
        if k + 2 < len(tokens) and tokens[k + 1] == "THRU" and tokens[k].isdigit():
            out += range(int(tokens[k]), int(tokens[k + 2]) + 1)
            k += 3
        else:
            out += [int(tokens[k])] if tokens[k].isdigit() else []
            k += 1
    return out


# -- bulk data ----------------------------------------------------------------------------------
def _cards(lines, refusals: Refusals) -> list[Card]:
    """The bulk-data cards of lines (file, line, text), continuations joined (module doc)."""
    cards, current = [], None  # current: [name, raw fields, file, line, last line]
    for file, number, text in lines:
        body = text.split("$", 1)[0].expandtabs(8).rstrip()
        if not body.strip():
            continue
        if body.strip().upper().startswith("ENDDATA"):
            break
        try:
            head, data, _ = split_line(body)
        except ValueError as exc:
            refusals.add(f"{Path(file).name}:{number}: {exc}")
            continue
        name = card_name(head)
        if name:
            if current is not None:
                cards.append(Card(current[0], tuple(current[1]), current[2], current[3],
                                  current[4]))  # fmt: skip
            current = [name, list(data), file, number, number]
        elif current is None or current[2] != file:
            refusals.add(f"{Path(file).name}:{number}: a continuation line with no card above it")
        else:
            current[1] += data
            current[4] = number
    if current is not None:
        cards.append(Card(current[0], tuple(current[1]), current[2], current[3], current[4]))
    return [_trimmed(c) for c in cards]


def _trimmed(card: Card) -> Card:
    raw = list(card.raw)
    while raw and not raw[-1].strip():
        raw.pop()
    return Card(card.name, tuple(raw), card.file, card.line, card.end)


def _split(all_lines) -> tuple[list, list, list]:
    """(executive, case control, bulk) lines: CEND ends the executive, BEGIN BULK the case
    control; a file with neither is all bulk data."""
    upper = [_words(t) for _, _, t in all_lines]
    cend = next((k for k, w in enumerate(upper) if w == "CEND"), None)
    begin = next((k for k, w in enumerate(upper) if w.startswith("BEGIN") and "BULK" in w), None)
    if begin is None:
        if cend is not None:
            return all_lines[:cend], all_lines[cend + 1 :], []
        return [], [], all_lines
    if cend is None or cend > begin:
        return [], all_lines[:begin], all_lines[begin + 1 :]
    return all_lines[:cend], all_lines[cend + 1 : begin], all_lines[begin + 1 :]


def read_deck(path, refusals: Refusals | None = None) -> Deck:
    """The ``Deck`` of the file at ``path``; its refusals go into ``refusals`` (raised here
    when none is given)."""
    path = Path(path)
    if not path.is_file():
        raise BayesUpdateError(f"Nastran model {path}: no such file")
    own = refusals is None
    refusals = Refusals(str(path)) if own else refusals
    notes, files = [], []
    all_lines = list(_lines(path.resolve(), refusals, notes, files))
    executive, case_lines, bulk = _split(all_lines)
    sol = next((w.split()[1] for w in map(_words, (t for _, _, t in executive))
                if w.startswith("SOL ") and len(w.split()) > 1), None)  # fmt: skip
    case, sets = _case_control(case_lines)
    cards = _grdset(_cards(bulk, refusals), notes)
    deck = Deck(str(path), sol, case, sets, tuple(cards), tuple(notes), tuple(files))
    _check_duplicates(deck, refusals)
    if own:
        refusals.raise_all()
    return deck


def _grdset(cards: list[Card], notes: list) -> list[Card]:
    """The cards with each GRID's blank CP, CD, PS and SEID taken from the GRDSET card (MSC QRG
    GRDSET: the defaults of those fields; its own fields sit where GRID's do), which is then
    dropped; without a GRDSET the cards as they are."""
    grdset = [c for c in cards if c.name == "GRDSET"]
    if not grdset:
        return cards
    defaults = {i: grdset[0].raw[i].strip() for i in (1, 5, 6, 7)
                if i < len(grdset[0].raw) and grdset[0].raw[i].strip()}  # fmt: skip
    notes.append(f"GRDSET {grdset[0].where}: its CP, CD, PS, SEID fill the GRIDs' blank ones")
    out = []
    for c in cards:
        if c.name == "GRID":
            blank = {i: v for i, v in defaults.items() if i >= len(c.raw) or not c.raw[i].strip()}
            c = with_fields(c, blank) if blank else c
        if c.name != "GRDSET":
            out.append(c)
    return out


def _check_duplicates(deck: Deck, refusals: Refusals) -> None:
    for family, names in FAMILIES.items():
        seen = {}
        for c in deck.of(*names):
            try:
                i = c.id()
            except CardError as exc:
                refusals.add(str(exc))
                continue
            first = seen.setdefault(i, c)
            if first is not c and (first.name, first.raw) != (c.name, c.raw):
                refusals.card(c, f"{family} id {i} is also {first.label} at {first.where}")


def _matrix_notes(deck: Deck, refusals: Refusals) -> list[str]:
    """Refuse the direct matrix input that changes K or M (into ``refusals``): a DMI other than
    the aeroelastic corrections, a DMIG that the case control's K2GG or M2GG adds to K or M
    (MSC QRG, K2GG and M2GG).  Returns notes on those ignored: a DMIG that no K2GG or M2GG
    selects enters only other solutions (K2PP, M2PP, B2PP: dynamic response, with extra points;
    B2GG, K42GG: damping; loads), or none."""
    notes = []
    dmi = {c: str(c.raw[0]).strip().upper() for c in deck.of("DMI")}
    for c, name in dmi.items():
        if name not in AERO_DMI:
            refusals.card(c, f"DMI {name} is not supported (only the aeroelastic corrections "
                             "W2GJ, FA2J, WKK and WTFACT are ignored)")  # fmt: skip
    aero = sorted(set(dmi.values()) & AERO_DMI)
    if aero:
        notes.append(f"DMI {', '.join(aero)} (aeroelastic corrections) ignored")
    selected = set(deck.case.get("K2GG/M2GG", ()))
    dmig = {c: str(c.raw[0]).strip().upper() for c in deck.of("DMIG")}
    for c, name in dmig.items():
        if name in selected:
            refusals.card(c, f"DMIG {name} is not supported: the case control's K2GG or M2GG "
                             "adds it to K or M (it would change the model)")  # fmt: skip
    unused = sorted(set(dmig.values()) - selected)
    if unused:
        notes.append(f"DMIG {', '.join(unused)} ignored: no K2GG or M2GG selects it (K2PP, "
                     "M2PP, B2PP, B2GG and loads enter only other solutions)")  # fmt: skip
    return notes


def check_cards(deck: Deck, refusals: Refusals) -> list[str]:
    """Refuse unsupported cards and PARAMs (into ``refusals``); returns the notes listing
    what is read but ignored (once each)."""
    notes = []
    unsupported = [c for c in deck.cards if c.name not in SUPPORTED]
    for c in unsupported:
        refusals.card(c, f"card {c.name} is not supported (it would change the model)")
    ignored = []
    for name, c in deck.params().items():
        if name in IGNORED_PARAMS:
            ignored.append(name)
        elif name not in MODEL_PARAMS:
            refusals.card(c, f"PARAM {name} is not supported (it may change the normal modes)")
    if ignored:
        notes.append(f"PARAM {', '.join(sorted(ignored))} ignored (no effect on normal modes)")
    group_of = {name: what for what, names in IGNORED_CARDS.items() for name in names}
    found: dict[str, list[str]] = {}
    for c in deck.cards:  # one pass over the deck, in the groups' order below
        if c.name in group_of:
            found.setdefault(group_of[c.name], []).append(c.name)
    for what in (w for w in IGNORED_CARDS if w in found):
        notes.append(f"{len(found[what])} card(s) of {what} ignored (no effect on the real "
                     f"normal modes): {', '.join(sorted(set(found[what])))}")  # fmt: skip
    for c in deck.of("MDLPRM"):
        keys = [str(k).strip().upper() for k in c.raw[::2] if str(k).strip()]
        for key in (k for k in keys if not MDLPRM_OUTPUT.match(k)):
            refusals.card(c, f"MDLPRM {key} is not supported (it may change the normal modes)")
    if deck.of("MDLPRM"):
        notes.append("MDLPRM HDF5 output settings ignored (no effect on normal modes)")
    notes += _matrix_notes(deck, refusals)
    for where, command in deck.case.get("changes", ()):
        refusals.add(f"{where} case control {command}: {CASE_REFUSED[command]}")
    objective = sorted({c.name for c in deck.cards if c.name in OBJECTIVE_CARDS})
    if objective:
        n = sum(1 for c in deck.cards if c.name in OBJECTIVE_CARDS)
        notes.append(f"the deck's own objective (not used): {n} cards {', '.join(objective)}")
    if deck.of("SUPORT", "SUPORT1"):
        notes.append(
            "SUPORT: every rigid motion the structure allows is a rigid mode (as MSC's SUPORT "
            "makes it, also where soft springs to ground strain it); the elastic modes are "
            "solved on the rest"
        )
    return notes
