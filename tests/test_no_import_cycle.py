"""No import cycle anywhere in the package: the module import graph of ``bayesupdate`` is acyclic.

The graph is read from the source, not from a run: every ``import`` and ``from ... import``
statement of every module (``ast``), at top level or inside a function, a class or an ``if``
(a deferred import that would hide a cycle counts the same).  An edge A -> B means module A
names module B: ``import bayesupdate.x.y`` and ``from bayesupdate.x import y`` (when ``y`` is
a submodule) give ``bayesupdate.x.y``; ``from bayesupdate.x import name`` gives
``bayesupdate.x`` (the package's ``__init__``); relative imports are resolved.  Importing a
submodule also runs its parents' ``__init__``, but that implicit step is not an edge (every
submodule would otherwise form a cycle with a package that re-exports it).  Imports made from
strings (``importlib.import_module``, the CLI's command discovery) are not seen.

A cycle is found by a depth-first search (Tarjan's strongly connected components: a component
with more than one module, or a module importing itself, is a cycle).
"""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = "bayesupdate"


def module_files(root: Path = ROOT, package: str = PACKAGE) -> dict[str, Path]:
    """Dotted module name -> source file for every ``.py`` file of ``package`` under ``root``."""
    out = {}
    for path in sorted((root / package).rglob("*.py")):
        parts = list(path.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _resolve(module: str, is_package: bool, level: int, target: str | None) -> str:
    """The absolute name of a (possibly relative, ``level`` dots) ``from`` import's module."""
    if level == 0:
        return target or ""
    base = module.split(".") if is_package else module.split(".")[:-1]
    base = base[: len(base) - (level - 1)]
    return ".".join(base + ([target] if target else []))


def imported_modules(module: str, path: Path, known: set[str]) -> set[str]:
    """The package modules that ``module`` (source ``path``) imports anywhere in its body."""
    out = set()
    is_package = path.name == "__init__.py"
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            source = _resolve(module, is_package, node.level, node.module)
            for alias in node.names:
                child = f"{source}.{alias.name}"
                out.add(child if child in known else source)
    return {name for name in out if name in known and name != module} | (
        {module} if module in out else set()
    )


def import_graph(root: Path = ROOT, package: str = PACKAGE) -> dict[str, set[str]]:
    """module -> the package modules it imports (module docstring)."""
    files = module_files(root, package)
    known = set(files)
    return {module: imported_modules(module, path, known) for module, path in files.items()}


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of ``graph`` that are cycles (Tarjan 1972, SIAM J.
    Comput. 1(2) 146-160), each sorted, iteratively (no recursion limit)."""
    index, low, on_stack, stack, found = {}, {}, set(), [], []
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1 or node in graph.get(node, ()):
                    found.append(sorted(component))
    return found


def test_the_package_has_no_import_cycle():
    graph = import_graph()
    assert len(graph) > 100  # the whole package was read
    assert cycles(graph) == []


def test_a_cycle_is_found_however_deep_and_wherever_the_import_is(tmp_path):
    """A three-module cycle closed by an import inside a function, a relative import and a
    ``from package import submodule``; a fourth module hangs off it without closing a cycle."""
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("from pkg.sub.c import VALUE\n")
    (pkg / "a.py").write_text("from pkg.sub import b\n")
    (pkg / "sub" / "b.py").write_text("def f():\n    from . import c\n    return c\n")
    (pkg / "sub" / "c.py").write_text("VALUE = 1\nif VALUE:\n    import pkg.a\n")
    (pkg / "d.py").write_text("from pkg.sub import VALUE\nfrom pkg import a\n")
    graph = import_graph(tmp_path, "pkg")
    assert graph["pkg.a"] == {"pkg.sub.b"}
    assert graph["pkg.sub.b"] == {"pkg.sub.c"}
    assert graph["pkg.sub.c"] == {"pkg.a"}
    assert graph["pkg.d"] == {"pkg.sub", "pkg.a"}
    assert cycles(graph) == [["pkg.a", "pkg.sub.b", "pkg.sub.c"]]
    (pkg / "sub" / "c.py").write_text("VALUE = 1\n")
    assert cycles(import_graph(tmp_path, "pkg")) == []


def test_a_module_importing_itself_is_a_cycle():
    assert cycles({"m": {"m"}, "n": set()}) == [["m"]]
