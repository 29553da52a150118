"""What an import loads (facts of ``sys.modules`` in a fresh interpreter, not times): reading a
study file (``bayesupdate.config``) loads neither the discovery workflow nor ``scipy.stats``
(over a second each, measured by ``benchmarks/import_time.py``), nor emcee; the lazy names of
the ``inference`` and ``discovery`` packages (PEP 562 ``__getattr__``) are the objects of the
modules they come from, and the list of them agrees with the ``TYPE_CHECKING`` block that shows
those imports to type checkers and to the import-graph checks (``tests/test_no_import_cycle.py``,
``lint-imports``)."""

import ast
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: loaded by none of the imports below (a second or more each, or the sampler's whole stack)
HEAVY = ("bayesupdate.discovery.workflow", "scipy.stats", "emcee", "arviz_base", "matplotlib")


def loaded_after(code: str) -> set[str]:
    """The module names in ``sys.modules`` after running ``code`` in a fresh interpreter that
    imports this checkout's package."""
    probe = f"{code}\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))"
    env = dict(os.environ, PYTHONPATH=str(ROOT), OPENBLAS_NUM_THREADS="1")
    done = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, env=env, cwd=ROOT, check=True
    )
    return set(json.loads(done.stdout.splitlines()[-1]))


@pytest.mark.parametrize(
    "code",
    [
        "import bayesupdate.config",
        "from bayesupdate.discovery import DiscoverySettings\n"
        "from bayesupdate.discovery.effects import parse_effect_spec",
        "from bayesupdate.inference import (CalibrationSettings, FunctionModel, Prior,\n"
        "    load_modal_data, pair_modes, prior_from_mapping)\n"
        "prior_from_mapping({'kind': 'lognormal', 'mu': 0.0, 'sigma': 1.0}, (0.5, 2.0))\n"
        "CalibrationSettings(starts=4)",
        "from bayesupdate.inference import convergence",
        # what calibrate loads: the study's move scheme is checked and an optimum written
        # without the sampler (``inference.move_kinds``; ``results`` types it lazily)
        "import bayesupdate.pipelines.calibrate, bayesupdate.inference.results\n"
        "from bayesupdate.commands import calibrate",
    ],
)
def test_light_imports_load_no_heavy_package(code):
    loaded = loaded_after(code)
    assert "bayesupdate" in loaded  # the probe ran the package
    assert [name for name in HEAVY if name in loaded] == []


def _type_checking_names(package: str) -> dict[str, str]:
    """name -> submodule of the ``from ... import`` statements under ``if TYPE_CHECKING:`` in
    ``package``'s ``__init__``."""
    path = ROOT.joinpath(*package.split("."), "__init__.py")
    out = {}
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.If) and getattr(node.test, "id", "") == "TYPE_CHECKING":
            for statement in node.body:
                for alias in statement.names:
                    out[alias.name] = statement.module.rsplit(".", 1)[1]
    return out


@pytest.mark.parametrize("package", ["bayesupdate.inference", "bayesupdate.discovery"])
def test_every_public_name_is_its_modules_object(package):
    import importlib

    module = importlib.import_module(package)
    lazy = _type_checking_names(package)
    assert lazy and set(lazy) <= set(module.__all__)
    for name in module.__all__:
        value = getattr(module, name)
        if name in lazy:
            assert value is getattr(importlib.import_module(f"{package}.{lazy[name]}"), name)
    assert set(module.__all__) <= set(dir(module))
    with pytest.raises(AttributeError, match="no attribute 'not_a_name'"):
        module.not_a_name  # noqa: B018


def test_inference_sources_are_the_type_checking_block():
    from bayesupdate import inference

    from_data = {name: mod for mod, names in inference._SOURCES.items() for name in names}
    assert from_data == _type_checking_names("bayesupdate.inference")
    # the names bound at import (tmcmc's) and the lazy ones together are the public list
    eager = {"TMCMCResult", "TMCMCSettings", "tmcmc"}
    assert sorted(set(from_data) | eager) == sorted(inference.__all__)


def test_tmcmc_stays_the_function_when_its_module_is_imported_first():
    """``tmcmc`` is a submodule's name too: importing the submodule first must not replace the
    package's function (it is bound at import for that reason)."""
    code = (
        "import bayesupdate.inference.tmcmc\n"
        "from bayesupdate.inference import tmcmc\n"
        "assert callable(tmcmc) and tmcmc.__name__ == 'tmcmc', tmcmc"
    )
    assert "bayesupdate.inference.tmcmc" in loaded_after(code)


@pytest.mark.parametrize("command", ["calibrate", "sample", "discover", "correlate", "sensitivity"])
def test_an_output_in_the_way_is_refused_before_the_commands_heavy_imports(command, tmp_path):
    """``--out`` naming an existing file (no ``--force``) is refused, exit 2, before the
    command loads the pipelines, the model or scipy (seconds: a typo costs no wait)."""
    out = tmp_path / "there.h5"
    out.write_bytes(b"")
    code = (
        "import contextlib, io\nfrom bayesupdate.cli import main\nerr = io.StringIO()\n"
        "with contextlib.redirect_stderr(err):\n"
        f"    rc = main([{command!r}, '--model', 'exhaust', '--data', 'paper:ema', '--out', "
        f"{str(out)!r}])\n"
        "assert rc == 2 and 'already exists; use --force' in err.getvalue(), (rc, err.getvalue())"
    )
    loaded = loaded_after(code)
    assert [n for n in ("bayesupdate.pipelines.study", "scipy.linalg", *HEAVY) if n in loaded] == []
