"""The house plan holds: the layer contracts in pyproject.toml ([tool.importlinter],
e.g. ``ema`` imports no ``fe``, ``inference`` no ``discovery``/``models``/``config``, nothing below
the edge imports ``commands``, ``cli``, ``report`` or a plots module) are kept, and vulture finds
no dead code in the package, tests, studies and benchmarks (names only used from outside, such
as dataclass fields users read and emcee's move API, are listed in vulture_whitelist.py), and no
function of the package is over 60 lines."""

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_import_layer_contracts_are_kept(capsys):
    from importlinter.cli import lint_imports

    code = lint_imports(config_filename=str(ROOT / "pyproject.toml"), no_cache=True, no_logo=True)
    out = capsys.readouterr().out
    assert code == 0, out
    import tomllib

    contracts = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]
    assert "0 broken" in out and f"{len(contracts['contracts'])} kept" in out
    # the rooms' own contracts are there (a contract deleted from pyproject.toml would pass)
    kinds = {c["name"]: c["type"] for c in contracts["contracts"]}
    assert kinds["compute imports nothing above the core"] == "forbidden"
    elements = (
        "element families import nothing above fe (nor fe's assembly, model or reduced basis)"
    )
    assert kinds[elements] == "forbidden"
    assert kinds["the core imports nothing of the package above it (compute included)"] == (
        "forbidden"
    )
    acyclic = [c for c in contracts["contracts"] if c["type"] == "acyclic_siblings"]
    assert [c["ancestors"] for c in acyclic] == [["bayesupdate"]]
    models = "models imports no nastran (a deck is resolved beside the built-in models: "
    assert kinds[models + "pipelines.model_source)"] == "forbidden"
    independent = "no command imports another (what they share is commands._shared)"
    assert kinds[independent] == "independence"
    assert len(contracts["contracts"]) == 12


def test_every_command_module_is_in_the_independence_contract():
    """A new command is covered too: every public module of ``commands/`` is listed in the
    contract that no command imports another."""
    import tomllib

    contracts = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]
    (independent,) = [c for c in contracts["contracts"] if c["type"] == "independence"]
    public = {
        f"bayesupdate.commands.{p.stem}"
        for p in (ROOT / "bayesupdate" / "commands").glob("*.py")
        if not p.stem.startswith("_")
    }
    assert set(independent["modules"]) == public


def test_no_dead_code():
    from vulture.core import Vulture

    vulture = Vulture()
    paths = ["bayesupdate", "tests", "studies", "benchmarks", "vulture_whitelist.py"]
    vulture.scavenge([str(ROOT / p) for p in paths])
    unused = [
        f"{Path(item.filename).relative_to(ROOT)}:{item.first_lineno} {item.name}"
        for item in vulture.get_unused_code(min_confidence=60)
    ]
    assert unused == []


def test_no_function_in_the_package_is_over_60_lines():
    """Every function of the package is at most 60 lines (signature, docstring and body),
    so each one reads on one screen; measured 2026-11-24: the longest is 60."""
    import ast

    long = []
    for path in sorted((ROOT / "bayesupdate").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                lines = node.end_lineno - node.lineno + 1
                if lines > 60:
                    long.append(f"{path.relative_to(ROOT)}:{node.lineno} {node.name} ({lines})")
    assert long == []
