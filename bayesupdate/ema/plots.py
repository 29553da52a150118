"""Identification plots (matplotlib, Agg backend): stabilization diagram with CMIF overlay,
CMIF alone, measured vs synthesized FRFs, MAC matrix, mode shapes on the sensor geometry or as
bars over the DOF labels.

Each function writes one PNG file and returns its path; nothing is shown on screen.
"""

import os
from pathlib import Path

import numpy as np

from bayesupdate import plotting
from bayesupdate.correlation import mac_matrix
from bayesupdate.ema.frf_set import FrfSet
from bayesupdate.ema.identify import Identification
from bayesupdate.ema.indicators import cmif
from bayesupdate.ema.uff_io import parse_label


def plot_stabilization(result: Identification, frfs: FrfSet, path) -> Path:
    """Stabilization diagram of every band (poles: o new, x partly stable, + stable) over
    the CMIF (right axis, log), selected modes as red lines, band starts dotted;
    drawn over the analysed bands (lines outside them hold no poles)."""
    fig, ax = plotting.subplots(figsize=(11, 6))
    for d in result.diagrams:
        partly = ~d.stable & (d.stable_frequency | d.stable_damping | d.stable_vector)
        new = ~(d.stable | partly)
        ax.plot(d.frequency_hz[new], d.order[new], "o", ms=2, color="0.7", mfc="none")
        ax.plot(d.frequency_hz[partly], d.order[partly], "x", ms=3, color="tab:orange")
        ax.plot(d.frequency_hz[d.stable], d.order[d.stable], "+", ms=5, color="tab:green")
    for p in result.selected:
        ax.axvline(p.frequency_hz, color="tab:red", lw=0.6)
    for band_lo, _ in result.bands_hz[1:]:  # where each automatic band after the first starts
        ax.axvline(band_lo, color="0.5", lw=0.8, ls=":")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("model order (o new, x partly stable, + stable)")
    lo = min(b[0] for b in result.bands_hz)
    hi = max(b[1] for b in result.bands_hz)
    ax.set_xlim(lo, hi)
    _plot_cmif(ax.twinx(), frfs, (lo, hi))
    ax.set_title("stabilization diagram and CMIF")
    return _save(fig, path)


def _plot_cmif(ax, frfs: FrfSet, span_hz) -> None:
    """Up to 3 CMIF curves on ``ax`` (log), over the lines in span_hz only so that the
    y-scale follows them."""
    f = frfs.frequencies_hz
    sel = (f >= span_hz[0]) & (f <= span_hz[1])
    sv = cmif(frfs)
    for row in sv[: min(3, sv.shape[0])]:
        # an exact zero (e.g. accelerance at 0 Hz) is left out, not put at 1e-300
        ax.semilogy(f[sel], np.where(row[sel] > 0, row[sel], np.nan), lw=0.7)
    ax.set_ylabel("CMIF singular values")


def plot_cmif(frfs: FrfSet, path, band_hz=None) -> Path:
    """CMIF of the FRF set over band_hz (default: all lines); the band, when given, shaded."""
    f = frfs.frequencies_hz
    fig, ax = plotting.subplots(figsize=(11, 4))
    _plot_cmif(ax, frfs, (f[0], f[-1]))
    if band_hz is not None:
        ax.axvspan(band_hz[0], band_hz[1], color="tab:blue", alpha=0.08, label="band")
        ax.legend()
    ax.set_xlim(f[0], f[-1])
    ax.set_xlabel("frequency [Hz]")
    ax.set_title("CMIF of the measured FRFs")
    return _save(fig, path)


def plot_shape_bars(labels, shapes: np.ndarray, frequencies_hz, path) -> Path:
    """Real shapes (n_dof, m) as bars over the DOF labels, one panel per mode; works for any
    labels (no geometry needed) and for a single DOF."""
    shapes = np.atleast_2d(np.asarray(shapes, dtype=float))
    n_dof, m = shapes.shape
    ncol = min(2, max(m, 1))
    nrow = max(int(np.ceil(m / ncol)), 1)
    width = min(max(4.0, 0.35 * n_dof + 1.5), 9.0)
    fig, axes = plotting.subplots(
        nrow, ncol, figsize=(width * ncol, 2.3 * nrow), squeeze=False, sharey=True
    )
    x = np.arange(n_dof)
    for r in range(m):
        ax = axes.flat[r]
        colors = np.where(shapes[:, r] >= 0, "tab:blue", "tab:red")
        ax.bar(x, shapes[:, r], color=colors, width=0.7)
        ax.axhline(0, color="0.4", lw=0.6)
        ax.set_ylim(-1.1, 1.1)
        ax.set_title(f"mode {r + 1}: {frequencies_hz[r]:.2f} Hz", fontsize=9)
        if n_dof <= 60:  # beyond that the labels overlap; the table gives them
            ax.set_xticks(x, [str(lab) for lab in labels], fontsize=7, rotation=90)
        ax.grid(axis="y", color="0.9", lw=0.5)
    for ax in list(axes.flat)[m:]:
        ax.axis("off")
    return _save(fig, path)


def plot_frf_fit(result: Identification, frfs: FrfSet, path, rows=None) -> Path:
    """Measured vs synthesized FRF magnitude for up to 6 rows (default: the worst fits)."""
    lo, hi = result.fit_range_hz
    sel = (frfs.frequencies_hz >= lo - 1e-9) & (frfs.frequencies_hz <= hi + 1e-9)
    if rows is None:
        rows = np.argsort(result.frf_correlation)[:6]
    fig, axes = plotting.subplots(len(rows), 1, figsize=(10, 2.2 * len(rows)), squeeze=False)
    for ax, k in zip(axes[:, 0], rows, strict=True):
        ax.semilogy(frfs.frequencies_hz[sel], np.abs(frfs.frf[k, sel]), label="measured")
        ax.semilogy(
            frfs.frequencies_hz[sel], np.abs(result.synthesized[k]), "--", label="synthesized"
        )
        ax.set_ylabel(f"{frfs.response_labels[k]}/{frfs.reference_labels[k]}")
        ax.set_title(f"FRAC {result.frf_correlation[k]:.4f}", fontsize=8)
    axes[0, 0].legend()
    axes[-1, 0].set_xlabel("frequency [Hz]")
    return _save(fig, path)


def plot_mac(shapes_a: np.ndarray, shapes_b: np.ndarray, path, title: str = "MAC") -> Path:
    """MAC matrix of two shape sets as an image with values."""
    mac = mac_matrix(shapes_a, shapes_b)
    fig, ax = plotting.subplots(figsize=(6, 5))
    im = ax.imshow(mac, vmin=0, vmax=1, cmap="viridis", origin="lower")
    for (i, j), v in np.ndenumerate(mac):
        ax.text(
            j, i, f"{v:.2f}", ha="center", va="center", fontsize=6, color="w" if v < 0.5 else "k"
        )
    ax.set_xlabel("mode (set B)")
    ax.set_ylabel("mode (set A)")
    ax.set_title(title)
    fig.colorbar(im, ax=ax)
    return _save(fig, path)


def plot_mode_shapes(modes, path, coordinates: dict | None = None) -> Path:
    """Real parts of the shapes drawn on the sensor geometry, one panel per mode.

    coordinates : {node number: (x, y, z)} [m]; the nodes are drawn along x in node order.  Without
    coordinates the node number is the abscissa.  V (z) and H (y) components are two curves.
    """
    from bayesupdate.ema.lsfd import realize

    shapes = realize(np.asarray(modes.shapes, dtype=complex))
    parsed = [parse_label(lab) for lab in modes.dof_labels]
    m = modes.n_modes
    ncol = min(4, m)
    nrow = int(np.ceil(m / ncol))
    fig, axes = plotting.subplots(nrow, ncol, figsize=(3.2 * ncol, 2.4 * nrow), squeeze=False)
    for r in range(m):
        ax = axes.flat[r]
        for d, name in ((3, "V"), (2, "H"), (1, "L")):
            idx = [i for i, (_, dd) in enumerate(parsed) if dd == d]
            if not idx:
                continue
            nodes = np.array([parsed[i][0] for i in idx])
            x = np.array([coordinates[n][0] for n in nodes]) if coordinates else nodes
            order = np.argsort(x)
            ax.plot(x[order], shapes[idx][order, r], "o-", ms=3, label=name)
        ax.axhline(0, color="0.6", lw=0.5)
        ax.set_title(f"{modes.frequencies_hz[r]:.2f} Hz", fontsize=9)
    for ax in list(axes.flat)[m:]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7)
    return _save(fig, path)


def _save(fig, path) -> Path:
    path = Path(path)
    os.makedirs(path.parent, exist_ok=True)
    fig.tight_layout()
    return plotting.save(fig, path)
