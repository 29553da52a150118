"""Importing the package's plotting modules, and drawing with them, leaves a user's matplotlib
backend as it was and pyplot unimported (no ``matplotlib.use`` at import, no pyplot figure
registry: ``bayesupdate.plotting``)."""

import subprocess
import sys
from pathlib import Path

import numpy as np

import bayesupdate

PACKAGE = Path(bayesupdate.__file__).parent


def _plotting_modules() -> list[str]:
    """Every module of the package whose source imports matplotlib or ``plotting``."""
    out = []
    for path in sorted(PACKAGE.rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        if "import matplotlib" in text or "from matplotlib" in text or "import plotting" in text:
            rel = path.relative_to(PACKAGE.parent).with_suffix("")
            out.append(".".join(rel.parts))
    return out


def test_the_plotting_modules_are_found():
    modules = _plotting_modules()
    for name in ("ema.plots", "discovery.plots", "inference.plots", "report.fe_figures",
                 "report.energy_maps", "report.exhaust_comparison", "plotting"):  # fmt: skip
        assert f"bayesupdate.{name}" in modules


def test_importing_and_drawing_keep_the_users_backend(tmp_path):
    modules = _plotting_modules()
    png = tmp_path / "drawn.png"
    script = f"""
import importlib, sys
import matplotlib
matplotlib.use("svg")  # a user's choice, not Agg
for name in {modules!r}:
    importlib.import_module(name)
from bayesupdate import plotting
fig, ax = plotting.subplots(figsize=(3, 2))
ax.plot([0, 1], [1, 0])
plotting.save(fig, {str(png)!r})
print(matplotlib.get_backend(), "matplotlib.pyplot" in sys.modules)
"""
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True, timeout=120
    )
    assert done.stdout.split() == ["svg", "False"], done.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"  # written through the Agg canvas


def test_saved_figure_has_the_asked_pixels(tmp_path):
    from matplotlib.image import imread

    from bayesupdate import plotting

    fig, ax = plotting.subplots(figsize=(3, 2))
    ax.plot([0, 1], [1, 0])
    img = imread(plotting.save(fig, tmp_path / "a.png", dpi=50))
    assert img.shape[:2] == (100, 150)  # 2 in x 50 dpi, 3 in x 50 dpi
    assert np.ptp(img[..., :3]) > 0  # something was drawn
