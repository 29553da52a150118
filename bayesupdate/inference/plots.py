"""Figures from a result file (``read_result`` dict): trace, pair, predictive, residuals, and
the design variables beside a published reference design (``DesignReference``).

All functions take the dict returned by ``results.read_result`` and return a matplotlib Figure
(Agg backend, nothing shown); ``save_all`` writes the set as PNG files.  A reference design is
given by the caller (e.g. the seed's Table 3 in ``models.exhaust_paper``): this
module knows no model or paper.
"""

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bayesupdate import plotting


@dataclass(frozen=True)
class DesignReference:
    """A published design to draw the posterior against.  initial, optimum : {parameter name:
    value} (SI; the initial values normalize both axes); label : what the optimum is (legend)."""

    initial: Mapping[str, float]
    optimum: Mapping[str, float]
    label: str


def _posterior(result: dict):
    post = result["posterior"]
    names = list(post["attrs"]["names"])
    return names, post["chain"], int(post["attrs"]["burn"])


def plot_trace(result: dict):
    """Every walker's path per parameter; the warm-up is shaded."""
    names, chain, burn = _posterior(result)
    fig, axes = plotting.subplots(
        len(names), 1, figsize=(8, 1.8 * len(names)), sharex=True, squeeze=False
    )
    for j, (ax, name) in enumerate(zip(axes[:, 0], names, strict=True)):
        ax.plot(chain[:, :, j], lw=0.4, alpha=0.5)
        ax.axvspan(0, burn, color="0.9", zorder=-1)
        ax.set_ylabel(name)
    axes[-1, 0].set_xlabel("step")
    fig.tight_layout()
    return fig


def plot_pair(result: dict, max_points: int = 4000, seed: int = 0):
    """Corner plot: histograms on the diagonal, scatter of post-burn-in draws below; only the
    lower triangle has axes, each column shares its x-axis and each row its y-axis, so tick
    labels are drawn on the outer edge only (as corner plots are read)."""
    from matplotlib.ticker import MaxNLocator

    names, chain, burn = _posterior(result)
    flat = chain[burn:].reshape(-1, chain.shape[-1])
    rng = np.random.default_rng(seed)
    pick = flat[rng.choice(flat.shape[0], size=min(max_points, flat.shape[0]), replace=False)]
    d = len(names)
    fig = plotting.figure(figsize=(2.2 * d, 2.2 * d))
    grid = fig.add_gridspec(d, d, left=0.09, right=0.98, bottom=0.08, top=0.98, hspace=0.1,
                            wspace=0.1)  # fmt: skip
    columns: dict = {}
    for i in range(d):
        row = None  # the row's first scatter: the row's y-axis
        for j in range(i + 1):
            ax = fig.add_subplot(grid[i, j], sharex=columns.get(j), sharey=row if j < i else None)
            columns.setdefault(j, ax)
            if i == j:
                ax.hist(flat[:, i], bins=50, color="C0")
                ax.tick_params(left=False, labelleft=False)  # counts: only the shape matters
            else:
                ax.plot(pick[:, j], pick[:, i], ".", ms=1, alpha=0.3)
                row = row or ax
                ax.tick_params(labelleft=j == 0)
                ax.yaxis.set_major_locator(MaxNLocator(4))
                if j == 0:
                    ax.set_ylabel(names[i])
            ax.xaxis.set_major_locator(MaxNLocator(4))
            ax.tick_params(labelbottom=i == d - 1)
            if i == d - 1:
                ax.set_xlabel(names[j])
                ax.tick_params(axis="x", labelrotation=30)
    return fig


def plot_predictive(result: dict, prob: float = 0.9):
    """Posterior predictive frequencies per mode (median, ``prob`` interval) against the test,
    as relative error [%] so all modes share one axis."""
    test = result["inputs"]["frequencies_hz"]
    pred = result["posterior"]["predictions"]
    fig, ax = plotting.subplots(figsize=(8, 3.5))
    modes = np.arange(1, test.size + 1)
    lo, hi = 50 * (1 - prob), 100 - 50 * (1 - prob)
    for key, colour, label, shift in (
        ("predictive_hz", "C0", f"predictive {prob:.0%}", -0.1),
        ("frequencies_hz", "C1", f"model {prob:.0%}", 0.1),
    ):
        err = 100 * (pred[key] - test) / test
        med = np.median(err, axis=0)
        band = np.percentile(err, [lo, hi], axis=0)
        ax.errorbar(
            modes + shift,
            med,
            yerr=[med - band[0], band[1] - med],
            fmt="o",
            color=colour,
            label=label,
            capsize=3,
        )
    ax.axhline(0, color="k", lw=0.8, label="test")
    ax.set_xlabel("mode")
    ax.set_ylabel("(f - f_test) / f_test [%]")
    ax.set_xticks(modes)
    ax.legend()
    fig.tight_layout()
    return fig


def plot_residuals(result: dict):
    """Per-mode error [%] at the optimum; bars are labelled with MAC and swapped modes flagged."""
    table = result["optimum"]["residuals"]
    modes = np.arange(1, table["test_hz"].size + 1)
    swapped = table["model_mode"] != modes
    fig, ax = plotting.subplots(figsize=(8, 3.5))
    ax.bar(modes, table["error_pct"], color=np.where(swapped, "C3", "C0"))
    for m, err, mac in zip(modes, table["error_pct"], table["mac"], strict=True):
        if np.isfinite(mac):
            ax.annotate(f"{mac:.2f}", (m, err), ha="center", va="bottom", fontsize=7)
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xlabel("test mode (red: paired with a swapped model mode)")
    ax.set_ylabel("error at optimum [%]")
    ax.set_xticks(modes)
    fig.tight_layout()
    return fig


def plot_design_vs_reference(result: dict, reference: DesignReference):
    """Posterior of each design variable (normalized by the reference's initial value) beside
    the reference optimum (e.g. the seed's Table 3); only parameters the reference names.  None
    if there are none."""
    initial, optimum = reference.initial, reference.optimum
    names, chain, burn = _posterior(result)
    shared = [n for n in names if n in optimum and n in initial]
    if not shared:
        return None
    flat = chain[burn:].reshape(-1, chain.shape[-1])
    fig, ax = plotting.subplots(figsize=(8, 3.5))
    data = [flat[:, names.index(n)] / initial[n] for n in shared]
    ax.violinplot(data, showmedians=True)
    x = np.arange(1, len(shared) + 1)
    ax.plot(
        x,
        [optimum[n] / initial[n] for n in shared],
        "r*",
        ms=12,
        label=reference.label,
    )
    opt = dict(
        zip(result["optimum"]["attrs"]["parameter_names"], result["optimum"]["theta"], strict=True)
    )
    ax.plot(x, [opt[n] / initial[n] for n in shared], "kx", ms=9, label="our optimum")
    ax.set_xticks(x, shared, rotation=20)
    ax.set_ylabel("value / reference initial")
    ax.legend()
    fig.tight_layout()
    return fig


def save_all(
    result: dict, folder: str | Path, reference: DesignReference | None = None
) -> list[Path]:
    """Write every applicable figure as PNG into ``folder``; returns the paths.  With a
    ``reference`` design whose names the result shares, also ``design_vs_reference.png``."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    makers = {"residuals": plot_residuals}
    if "posterior" in result and "autocorr_time" in result["posterior"]:
        makers.update(trace=plot_trace, pair=plot_pair)
        if reference is not None:
            makers["design_vs_reference"] = lambda r: plot_design_vs_reference(r, reference)
        if "predictions" in result["posterior"]:
            makers["predictive"] = plot_predictive
    paths = []
    for name, maker in makers.items():
        fig = maker(result)
        if fig is None:
            continue
        paths.append(plotting.save(fig, folder / f"{name}.png"))
    return paths
