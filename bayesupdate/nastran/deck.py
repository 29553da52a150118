"""Reading a Nastran bulk-data deck with pyNastran (an optional extra) and checking its cards.

``read_deck(path)`` returns the cross-referenced pyNastran ``BDF`` (``INCLUDE`` files followed);
every failure is one ``BayesUpdateError`` line.  ``check_cards`` refuses any card outside
``SUPPORTED`` and names it with its file and line: nothing is skipped silently.
"""

import io
import re
import warnings
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np

from bayesupdate.errors import BayesUpdateError

#: file suffixes read as Nastran bulk data
SUFFIXES = (".bdf", ".dat", ".nas", ".blk")

#: cards turned into the FE model (``reader``)
ELEMENT_CARDS = {
    "GRID", "CORD2R", "CORD2C", "CORD2S", "CQUAD4", "CTRIA3", "PSHELL", "MAT1", "CBAR", "CBEAM",
    "PBAR", "PBARL", "PBEAM", "PBEAML", "CROD", "CONROD", "PROD", "CONM2", "CONM1", "CELAS1",
    "CELAS2", "PELAS", "CBUSH", "PBUSH", "RBE2", "RBE3", "RBAR", "SPC", "SPC1", "SPCADD",
    "EIGRL", "EIGR", "PARAM",
}  # fmt: skip
#: design variables: parameters when the study names none (``desvar``)
DESIGN_CARDS = {"DESVAR", "DVPREL1"}
#: cards with no effect on the normal modes: output sets (SET1: test points, ``test_points``),
#: rigid-body reference DOFs (the solver finds the rigid-body modes itself), the end marker
NO_EFFECT_CARDS = {"USET", "USET1", "SUPORT", "SUPORT1", "SET1", "ENDDATA"}
SUPPORTED = ELEMENT_CARDS | NO_EFFECT_CARDS | DESIGN_CARDS
#: PARAMs that change the model (``reader``) and PARAMs that only select output
MODEL_PARAMS = {"WTMASS", "K6ROT", "COUPMASS", "AUTOSPC"}
OUTPUT_PARAMS = {
    "POST", "POSTEXT", "OGEOM", "GRDPNT", "RESCOMP", "OUGCORD", "PRGPST", "NOCOMPS", "PATVER",
    "MAXRATIO", "SRCOMPS", "OMID", "BAILOUT",
}  # fmt: skip


def is_nastran_path(text) -> bool:
    """True if ``text`` names a Nastran deck by its suffix (.bdf, .dat, .nas, .blk)."""
    return isinstance(text, str | Path) and Path(str(text)).suffix.lower() in SUFFIXES


def _pynastran_read_bdf():
    """pyNastran's ``read_bdf``, or a one-line error saying how to install it."""
    # pyNastran 1.4.1 (the latest release) still calls np.in1d, removed in NumPy 2.4; np.isin on
    # the flattened input is the same function (NumPy's own deprecation note)
    if not hasattr(np, "in1d"):
        np.in1d = lambda a, b, assume_unique=False, invert=False: np.isin(  # noqa: NPY201
            np.ravel(a), b, assume_unique=assume_unique, invert=invert
        )
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            from pyNastran.bdf.bdf import read_bdf
    except ImportError as exc:
        raise BayesUpdateError(
            "a Nastran model (.bdf) needs pyNastran: pip install bayesupdate[nastran]"
        ) from exc
    return read_bdf


def read_deck(path):
    """The cross-referenced pyNastran ``BDF`` of the deck at ``path`` (case control included)."""
    path = Path(path)
    if not path.is_file():
        raise BayesUpdateError(f"Nastran model {path}: no such file")
    read_bdf = _pynastran_read_bdf()
    sink = io.StringIO()
    try:
        with warnings.catch_warnings(), redirect_stdout(sink), redirect_stderr(sink):
            warnings.simplefilter("ignore")
            model = read_bdf(str(path), xref=True, punch=_bulk_only(path), debug=None)
    except Exception as exc:  # pyNastran raises many types: name the file and its message
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        raise BayesUpdateError(
            f"Nastran model {path}: pyNastran cannot read it ({type(exc).__name__}: {first[:200]})"
        ) from exc
    check_cards(model, path)
    return model


def _bulk_only(path: Path) -> bool:
    """True for a deck with no executive and case control (no CEND line)."""
    with open(path, errors="replace") as f:
        return not any(line.upper().strip() == "CEND" for line in f)


def check_cards(model, path) -> None:
    """BayesUpdateError naming the first card (and its file:line) that is not supported."""
    names = set(model.card_count) | set(getattr(model, "reject_count", {}))
    unsupported = sorted(n for n in names if n.upper() not in SUPPORTED)
    for name in model.params:
        if name not in MODEL_PARAMS | OUTPUT_PARAMS:
            where = card_location(path, "PARAM", name)
            raise BayesUpdateError(f"{where}: PARAM {name} is not supported")
    if unsupported:
        name = unsupported[0]
        raise BayesUpdateError(
            f"{card_location(path, name)}: card {name} is not supported "
            f"({len(unsupported)} unsupported card type(s): {', '.join(unsupported[:6])})"
        )


_INCLUDE = re.compile(r"^\s*INCLUDE\s+'?([^'\s]+)'?", re.IGNORECASE)


def _deck_lines(path: Path, seen=None):
    """(file, line number, text) of the deck and its INCLUDEd files, in reading order."""
    seen = set() if seen is None else seen
    if path in seen or not path.is_file():
        return
    seen.add(path)
    with open(path, errors="replace") as f:
        for number, line in enumerate(f, start=1):
            yield path, number, line
            m = _INCLUDE.match(line)
            if m:
                yield from _deck_lines((path.parent / m.group(1)).resolve(), seen)


def card_location(path, card: str, field: str | None = None) -> str:
    """'file:line' of the first line that starts with ``card`` (and holds ``field``)."""
    pattern = re.compile(rf"^{re.escape(card)}[\s,*]", re.IGNORECASE)
    for file, number, line in _deck_lines(Path(path).resolve()):
        if pattern.match(line) and (field is None or field.upper() in line.upper()):
            return f"{file.name}:{number}"
    return f"{Path(path).name}"
