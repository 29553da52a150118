"""Write a ``Document`` as a self-contained HTML page (figures embedded as base64 PNG) and as
Markdown next to it (figures linked).  Files are written atomically."""

import base64
import html
from pathlib import Path

from bayesupdate.atomic import atomic_path
from bayesupdate.report.document import Alert, Document, Figure, Table, fmt

_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;max-width:1100px;
margin:2em auto;
padding:0 1em;color:#1d2330;line-height:1.45}
h1{margin-bottom:.1em}h2{border-bottom:2px solid #d8dde6;padding-bottom:.2em;margin-top:1.8em}
.subtitle{color:#5a6577;margin-top:0}
table{border-collapse:collapse;margin:.8em 0;font-size:.92em}
th,td{border:1px solid #d8dde6;padding:.3em .6em;text-align:right}
th{background:#f1f4f9}td:first-child,th:first-child{text-align:left}
caption{caption-side:top;text-align:left;font-weight:600;padding:.3em 0}
figure{margin:1.2em 0}figure img{max-width:100%;border:1px solid #e3e7ee}
figcaption{color:#5a6577;font-size:.9em}
nav ul{columns:2;list-style:none;padding-left:0}nav a{text-decoration:none}
.warning{border-left:6px solid #c62828;background:#fdecea;padding:.6em 1em;font-weight:600}
"""


def _table_html(t: Table) -> str:
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in t.headers)
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(fmt(c))}</td>" for c in row) + "</tr>" for row in t.rows
    )
    cap = f"<caption>{html.escape(t.caption)}</caption>" if t.caption else ""
    return f"<table>{cap}<thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _figure_html(f: Figure, folder: Path) -> str:
    data = base64.b64encode((folder / f.path).read_bytes()).decode("ascii")
    return (
        f'<figure><img alt="{html.escape(f.caption)}" src="data:image/png;base64,{data}">'
        f"<figcaption>{html.escape(f.caption)}</figcaption></figure>"
    )


def to_html(doc: Document, folder: Path) -> str:
    parts = [
        f"<!doctype html><html><head><meta charset='utf-8'><title>{html.escape(doc.title)}"
        f"</title><style>{_CSS}</style></head><body>",
        f"<h1>{html.escape(doc.title)}</h1><p class='subtitle'>{html.escape(doc.subtitle)}</p>",
        "<nav><ul>"
        + "".join(
            f"<li><a href='#s{i}'>{html.escape(s.title)}</a></li>"
            for i, s in enumerate(doc.sections)
        )
        + "</ul></nav>",
    ]
    for i, section in enumerate(doc.sections):
        parts.append(f"<h2 id='s{i}'>{html.escape(section.title)}</h2>")
        for block in section.blocks:
            if isinstance(block, Table):
                parts.append(_table_html(block))
            elif isinstance(block, Figure):
                parts.append(_figure_html(block, folder))
            elif isinstance(block, Alert):
                parts.append(f"<p class='warning'>Warning: {html.escape(block.text)}</p>")
            else:
                parts.append(f"<p>{html.escape(str(block))}</p>")
    parts.append("</body></html>")
    return "\n".join(parts)


def to_markdown(doc: Document) -> str:
    lines = [f"# {doc.title}", "", f"*{doc.subtitle}*", ""]
    for section in doc.sections:
        lines += [f"## {section.title}", ""]
        for block in section.blocks:
            if isinstance(block, Table):
                if block.caption:
                    lines += [f"**{block.caption}**", ""]
                lines.append("| " + " | ".join(str(h) for h in block.headers) + " |")
                lines.append("|" + "---|" * len(block.headers))
                lines += ["| " + " | ".join(fmt(c) for c in row) + " |" for row in block.rows]
                lines.append("")
            elif isinstance(block, Figure):
                lines += [f"![{block.caption}]({block.path})", "", f"*{block.caption}*", ""]
            elif isinstance(block, Alert):
                lines += [f"> **Warning:** {block.text}", ""]
            else:
                lines += [str(block), ""]
    return "\n".join(lines)


def write_report(doc: Document, folder: str | Path, stem: str = "report") -> tuple[Path, Path]:
    """Write ``stem.html`` and ``stem.md`` into ``folder`` (figures must already be there)."""
    folder = Path(folder)
    out_html, out_md = folder / f"{stem}.html", folder / f"{stem}.md"
    with atomic_path(out_html) as tmp:
        tmp.write_text(to_html(doc, folder), encoding="utf-8")
    with atomic_path(out_md) as tmp:
        tmp.write_text(to_markdown(doc), encoding="utf-8")
    return out_html, out_md
