"""Figures of an FE model for reports: layout with sensors, mode shapes on the structure, strain
energy per part.  Each function draws one PNG (matplotlib, Agg) and returns its path."""

from pathlib import Path

import matplotlib
import numpy as np

from bayesupdate import plotting


def _save(fig, path) -> Path:
    return plotting.save(fig, path, tight=True)


def _draw_beams(ax, xy, beam_nodes, **style):
    segments = xy[beam_nodes]  # (E, 2, 2)
    for seg in segments:
        ax.plot(seg[:, 0], seg[:, 1], **style)


def plot_layout(structure, path) -> Path:
    """Plan (x-y) and elevation (x-z) of the structure with the sensor points numbered."""
    fig, axes = plotting.subplots(2, 1, figsize=(9, 5.2), sharex=True)
    nodes = structure.nodes
    points = {}
    for label, node in zip(structure.sensor_labels, structure.sensor_node, strict=True):
        points[label.rstrip("VHX")] = node
    for ax, (i, j, name) in zip(
        axes, [(0, 1, "plan: y [m]"), (0, 2, "elevation: z [m]")], strict=True
    ):
        _draw_beams(ax, nodes[:, [i, j]], structure.beam_nodes, color="0.35", lw=2)
        for num, node in points.items():
            ax.plot(nodes[node, i], nodes[node, j], "o", color="tab:red", ms=4)
            ax.annotate(
                num,
                nodes[node, [i, j]],
                textcoords="offset points",
                xytext=(2, 4),
                fontsize=7,
                color="tab:red",
            )
        ax.set_ylabel(name)
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("x [m] (manifold -> tail)")
    axes[0].set_title("FE model layout and the 20 sensor points")
    return _save(fig, path)


def plot_fe_mode_shapes(structure, result, path, n_show: int = 6) -> Path:
    """First ``n_show`` elastic modes drawn on the structure: each in the view where it moves
    most (plan for horizontal modes, elevation for vertical ones)."""
    nodes = structure.nodes
    shapes = result.modes.shapes
    n_show = min(n_show, shapes.shape[1])
    cols = 2
    rows = int(np.ceil(n_show / cols))
    fig, axes = plotting.subplots(rows, cols, figsize=(11, 2.3 * rows), squeeze=False)
    span = np.ptp(nodes[:, 0])
    for k in range(n_show):
        ax = axes.flat[k]
        uy = shapes[6 * np.arange(len(nodes)) + 1, k]
        uz = shapes[6 * np.arange(len(nodes)) + 2, k]
        horizontal = np.sum(uy**2) >= np.sum(uz**2)
        j, u = (1, uy) if horizontal else (2, uz)
        scale = 0.12 * span / max(np.abs(u).max(), 1e-300)
        deformed = nodes[:, [0, j]].copy()
        deformed[:, 1] += scale * u
        _draw_beams(ax, nodes[:, [0, j]], structure.beam_nodes, color="0.75", lw=1.5)
        _draw_beams(ax, deformed, structure.beam_nodes, color="tab:blue", lw=2)
        ax.set_title(
            f"mode {k + 1}: {result.frequencies_hz[k]:.2f} Hz, "
            f"{'horizontal (plan)' if horizontal else 'vertical (elevation)'}",
            fontsize=9,
        )
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xticks([])
        ax.set_yticks([])
    for k in range(n_show, rows * cols):
        axes.flat[k].axis("off")
    fig.suptitle("FE mode shapes (grey: undeformed)")
    return _save(fig, path)


def plot_strain_energy(result, path) -> Path:
    """Stacked bars: share of each mode's strain energy per part (seed section 3.2)."""
    e = result.energies
    shares = e.strain_by_part
    keep = np.flatnonzero(shares.max(axis=1) >= 0.02)
    fig, ax = plotting.subplots(figsize=(9, 3.8))
    bottom = np.zeros(shares.shape[1])
    modes = np.arange(1, shares.shape[1] + 1)
    cmap = matplotlib.colormaps["tab20"]
    for c, k in enumerate(keep):
        ax.bar(modes, shares[k], bottom=bottom, label=e.parts[k], color=cmap(c % 20))
        bottom += shares[k]
    ax.set_xlabel("mode")
    ax.set_ylabel("strain energy share")
    ax.set_xticks(modes)
    ax.set_title("Where each mode works the structure (parts with >= 2 % in some mode)")
    ax.legend(fontsize=7, ncol=2, bbox_to_anchor=(1.01, 1), loc="upper left")
    return _save(fig, path)
