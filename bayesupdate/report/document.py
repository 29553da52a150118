"""The content of a report as plain data: sections holding paragraphs, tables and figures.

Built by pure functions from results; ``bayesupdate.report.render`` turns it into files.
"""

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Table:
    """A table: column headers, rows of cells (str or numbers), an optional caption."""

    headers: tuple[str, ...]
    rows: tuple[tuple, ...]
    caption: str = ""


@dataclass(frozen=True)
class Figure:
    """A figure stored as a PNG file (path relative to the report folder) with a caption."""

    path: str
    caption: str


@dataclass(frozen=True)
class Alert:
    """A statement the reader must not miss (e.g. a posterior that missed its targets)."""

    text: str


@dataclass(frozen=True)
class Section:
    """A titled section: an ordered list of blocks (str paragraphs, Alerts, Tables, Figures)."""

    title: str
    blocks: tuple = field(default_factory=tuple)


@dataclass(frozen=True)
class Document:
    title: str
    subtitle: str
    sections: tuple[Section, ...]


def fmt(value, digits: int = 4) -> str:
    """Compact number formatting for tables (strings pass through)."""
    if isinstance(value, str):
        return value
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    v = float(value)
    if v != v:
        return "nan"
    if v == 0 or 1e-3 <= abs(v) < 1e5:
        return f"{v:.{digits}g}"
    return f"{v:.{max(digits - 1, 1)}e}"
