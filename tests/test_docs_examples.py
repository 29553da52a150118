"""The docs cannot drift from the code: the README's and the docs' Python examples run, the CLI
reference is the commands' own ``--help``, the result-file layouts are their writers' docstrings,
and the API reference lists every public name.

- Examples: every ```` ```python ```` block of README.md and docs/**/*.md runs, the blocks of one
  file in order in one namespace, inside a temporary folder. A block that is not meant to run
  (a fragment, or one that needs an optional extra or takes minutes) has the line
  ``<!-- no-test -->`` right above its fence; few do.
- CLI: docs/reference/cli.md holds each command's ``--help`` (at 100 columns) between
  ``<!-- help: CMD -->`` and ``<!-- /help -->``; after changing a command, rewrite them with
  ``python tests/test_docs_examples.py --write``.
- Result files: docs/reference/result-files.md holds the docstring of each module that writes
  one (between ``<!-- docstring: MODULE -->`` and ``<!-- /docstring -->``); ``--write`` too.
- API: the public names are every name in an ``__all__`` of the package, and every top-level
  definition (without a leading underscore) of the modules in ``PUBLIC_MODULES``; each must be
  listed under its module's ``::: module`` directive (``members:``) in docs/reference/api/*.md,
  and, on a built site (``BAYESUPDATE_DOCS_SITE``, set by ``.ci/run``), rendered there.
"""

import argparse
import ast
import contextlib
import io
import os
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
CLI_PAGE = DOCS / "reference" / "cli.md"
NO_TEST = "<!-- no-test -->"

#: modules without ``__all__`` whose top-level definitions are public API
PUBLIC_MODULES = (
    "bayesupdate.atomic",
    "bayesupdate.config",
    "bayesupdate.correlation",
    "bayesupdate.errors",
    "bayesupdate.compute.blas",
    "bayesupdate.compute.stop",
    "bayesupdate.modal_data",
    "bayesupdate.model_protocol",
    "bayesupdate.models",
    "bayesupdate.models.exhaust_paper",
    "bayesupdate.units",
    "bayesupdate.inference.evaluators",
    "bayesupdate.fe.frames",
    "bayesupdate.fe.shell_mesh",
    "bayesupdate.fe.standard_sections",
    "bayesupdate.discovery.effects",
    "bayesupdate.pipelines.calibrate",
    "bayesupdate.pipelines.demo",
    "bayesupdate.pipelines.discover",
    "bayesupdate.pipelines.identify",
    "bayesupdate.pipelines.model_source",
    "bayesupdate.fe.reference_memo",
    "bayesupdate.pipelines.sample",
    "bayesupdate.pipelines.simulate",
    "bayesupdate.pipelines.study",
    "bayesupdate.pipelines.surrogates",
)


def doc_files() -> list[Path]:
    return [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]


def python_blocks(text: str) -> list[tuple[int, str]]:
    """(first line number, code) of every ```python block not preceded by ``NO_TEST``."""
    blocks, lines, i = [], text.splitlines(), 0
    while i < len(lines):
        if lines[i].strip() == "```python":
            start = i + 1
            end = next(j for j in range(start, len(lines)) if lines[j].strip() == "```")
            skipped = i > 0 and lines[i - 1].strip() == NO_TEST
            if not skipped:
                blocks.append((start + 1, "\n".join(lines[start:end])))
            i = end
        i += 1
    return blocks


def _with_examples() -> list[Path]:
    return [p for p in doc_files() if python_blocks(p.read_text())]


@pytest.mark.parametrize("path", _with_examples(), ids=lambda p: str(p.relative_to(ROOT)))
def test_examples_run(path, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    namespace = {"__name__": "__docs__"}
    for line, code in python_blocks(path.read_text()):
        where = f"{path.relative_to(ROOT)}:{line}"
        with contextlib.redirect_stdout(io.StringIO()):
            exec(compile(code, where, "exec"), namespace)  # noqa: S102 - the docs' own code


def test_block_extraction_honours_the_no_test_mark():
    text = "a\n```python\nx = 1\n```\n<!-- no-test -->\n```python\nraise\n```\n```toml\n```\n"
    assert python_blocks(text) == [(3, "x = 1")]


# -- the CLI reference -----------------------------------------------------------------------
def help_texts() -> dict[str, str]:
    """``bayesupdate [CMD] --help`` as a 100-column terminal prints it."""
    from bayesupdate.cli import build_parser

    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = "100"
    try:
        parser = build_parser()
        subparsers = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        texts = {"bayesupdate": parser.format_help()}
        texts.update({name: p.format_help() for name, p in subparsers.choices.items()})
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old
    return texts


def _help_block(text: str) -> str:
    return f"```text\n{text.rstrip()}\n```"


HELP_RE = re.compile(r"<!-- help: (\S+) -->\n(.*?)\n<!-- /help -->", re.S)


PYTHON_RE = re.compile(r"<!-- help written by Python (\d+\.\d+) -->")


def _python() -> str:
    return "{}.{}".format(*sys.version_info[:2])


def write_cli_page() -> None:
    texts = help_texts()
    page = PYTHON_RE.sub(f"<!-- help written by Python {_python()} -->", CLI_PAGE.read_text())
    page = HELP_RE.sub(
        lambda m: f"<!-- help: {m[1]} -->\n{_help_block(texts[m[1]])}\n<!-- /help -->", page
    )
    CLI_PAGE.write_text(page)


def test_cli_reference_is_the_commands_help():
    page = CLI_PAGE.read_text()
    written_by = PYTHON_RE.search(page)[1]
    if written_by != _python():  # argparse's layout changes between Python versions
        pytest.skip(f"the help was written by Python {written_by}, this is {_python()}")
    documented = {m[1]: m[2] for m in HELP_RE.finditer(page)}
    texts = help_texts()
    assert sorted(documented) == sorted(texts), "a command is missing from docs/reference/cli.md"
    stale = [name for name, text in texts.items() if documented[name] != _help_block(text)]
    assert not stale, f"{stale}: run python tests/test_docs_examples.py --write"


# -- the result-file layouts ----------------------------------------------------------------
SCHEMA_PAGE = DOCS / "reference" / "result-files.md"
DOCSTRING_RE = re.compile(r"<!-- docstring: (\S+) -->\n(.*?)<!-- /docstring -->", re.S)


def _docstring_block(module: str) -> str:
    text = ast.get_docstring(ast.parse(_module_path(module).read_text()))
    return f"```text\n{text}\n```\n"


def write_schema_page() -> None:
    page = SCHEMA_PAGE.read_text()
    page = DOCSTRING_RE.sub(
        lambda m: f"<!-- docstring: {m[1]} -->\n{_docstring_block(m[1])}<!-- /docstring -->", page
    )
    SCHEMA_PAGE.write_text(page)


def test_result_file_layouts_are_the_writers_docstrings():
    copies = DOCSTRING_RE.findall(SCHEMA_PAGE.read_text())
    assert len(copies) == 3, "the three result files: calibrate/sample, identify, discover"
    stale = [module for module, text in copies if text != _docstring_block(module)]
    assert not stale, f"{stale}: run python tests/test_docs_examples.py --write"


# -- the API reference -----------------------------------------------------------------------
def _module_path(module: str) -> Path:
    base = ROOT / module.replace(".", "/")
    return base / "__init__.py" if base.is_dir() else base.with_suffix(".py")


def _top_level(tree: ast.Module) -> tuple[list[str] | None, list[str]]:
    """(``__all__`` or None, the names defined at top level without a leading underscore)."""
    exported, defined = None, []
    for node in tree.body:
        targets = []
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            targets = [node.name]
        elif isinstance(node, ast.Assign):
            targets = [t.id for t in node.targets if isinstance(t, ast.Name)]
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            targets = [node.target.id]
        if targets == ["__all__"]:
            exported = list(ast.literal_eval(node.value))
        defined += [t for t in targets if not t.startswith("_")]
    return exported, defined


def public_names() -> dict[str, set[str]]:
    """module -> its public names (module docstring)."""
    out = {}
    for path in sorted((ROOT / "bayesupdate").rglob("*.py")):
        exported, _ = _top_level(ast.parse(path.read_text()))
        if exported is not None:
            module = ".".join(path.relative_to(ROOT).with_suffix("").parts)
            out[module.removesuffix(".__init__")] = set(exported)
    for module in PUBLIC_MODULES:
        out[module] = set(_top_level(ast.parse(_module_path(module).read_text()))[1])
    return out


DIRECTIVE_RE = re.compile(r"^::: (\S+)\n((?:[ \t]+.*\n|\n(?=[ \t]))*)", re.M)


def documented_names() -> dict[str, set[str]]:
    """module -> the members its ``::: module`` directives list in docs/reference/api/."""
    out: dict[str, set[str]] = {}
    for page in sorted((DOCS / "reference" / "api").glob("*.md")):
        for match in DIRECTIVE_RE.finditer(page.read_text() + "\n"):
            members = re.findall(r"^\s+- (\S+)\s*$", match[2], re.M)
            out.setdefault(match[1], set()).update(members)
    return out


def _not_in(names: dict[str, set[str]], other: dict[str, set[str]]) -> dict[str, list[str]]:
    """module -> its names in ``names`` that ``other`` lacks (modules with none left out)."""
    gaps = {module: sorted(found - other.get(module, set())) for module, found in names.items()}
    return {module: gap for module, gap in gaps.items() if gap}


def test_api_reference_lists_every_public_name():
    missing = _not_in(public_names(), documented_names())
    assert not missing, f"add to docs/reference/api/ (::: module, options: members): {missing}"


def test_api_reference_lists_no_name_the_code_lacks():
    extra = _not_in(documented_names(), public_names())
    assert not extra, f"documented but not public (renamed or removed?): {extra}"


def test_built_api_reference_renders_every_public_name():
    """On a built site (``.ci/run`` sets BAYESUPDATE_DOCS_SITE after ``mkdocs build``): every
    public name has its heading anchor (a function sharing its module's name, like ``ema.lsce``,
    is rendered from that module)."""
    site = os.environ.get("BAYESUPDATE_DOCS_SITE")
    if not site:
        pytest.skip("set BAYESUPDATE_DOCS_SITE to a built site (mkdocs build -d DIR)")
    html = "".join(p.read_text() for p in (Path(site) / "reference" / "api").glob("*.html"))
    missing = [
        f"{module}.{name}"
        for module, names in public_names().items()
        for name in names
        if f'id="{module}.{name}"' not in html and f'id="{module}.{name}.{name}"' not in html
    ]
    assert not missing, f"not rendered in the API reference: {missing}"


if __name__ == "__main__":
    if sys.argv[1:] == ["--write"]:
        sys.path.insert(0, str(ROOT))
        write_cli_page()
        write_schema_page()
        print(
            f"rewrote the generated blocks of {CLI_PAGE.relative_to(ROOT)} and "
            f"{SCHEMA_PAGE.relative_to(ROOT)}"
        )
    else:
        sys.exit("usage: python tests/test_docs_examples.py --write")
