"""Discovery plots (matplotlib, Agg): residuals per mode before/after, the localization map
along the structure, the candidate ranking.  Each function returns the Figure; ``save_plots``
writes all three as PNG into a folder."""

from pathlib import Path

import numpy as np

from bayesupdate import plotting


def plot_residuals(result):
    """Relative error [%] per mode, baseline vs re-calibrated, with the +-2 noise band."""
    fig, ax = plotting.subplots(figsize=(7, 3.5))
    m = result.baseline.residual_rel.size
    x = np.arange(1, m + 1)
    ax.bar(x - 0.2, 100 * result.baseline.residual_rel, 0.4, label="baseline")
    label = "after: " + (result.named.label if result.named else "(nothing named)")
    ax.bar(x + 0.2, 100 * result.final.residual_rel, 0.4, label=label)
    band = 200 * result.noise.scale
    ax.fill_between(x, -band, band, step="mid", color="grey", alpha=0.2, label="2 x noise")
    for mode in result.flags.flagged_modes:
        ax.annotate("*", (mode, 0), ha="center", va="bottom", color="red")
    ax.axhline(0, color="k", lw=0.5)
    ax.set(xlabel="test mode (* flagged)", ylabel="error [%]", title=f"verdict: {result.verdict}")
    ax.set_xticks(x)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def plot_localization(result, structure=None):
    """Score-test chi^2 drop of the best effect at each location, drawn at its position on the
    structure (x: along the car, y: lateral), over the beam elements."""
    loc = result.localization
    fig, ax = plotting.subplots(figsize=(8, 3.5))
    if structure is not None:
        segs = structure.nodes[structure.beam_nodes]
        for seg in segs:
            ax.plot(seg[:, 0], seg[:, 1], color="0.6", lw=1)
    pts = [(name, score, kind) for name, score, kind in loc.locations if name in loc.positions]
    if pts:
        xyz = np.array([loc.positions[name] for name, _, _ in pts], float)
        scores = np.array([s for _, s, _ in pts])
        ok = np.all(np.isfinite(xyz), axis=1)
        sc = ax.scatter(
            xyz[ok, 0],
            xyz[ok, 1],
            s=20 + 200 * scores[ok] / max(scores.max(), 1e-12),
            c=scores[ok],
            cmap="viridis",
            zorder=3,
        )
        fig.colorbar(sc, ax=ax, label="score chi^2 drop")
        for (name, _, _), p, good in list(zip(pts, xyz, ok, strict=True))[:6]:
            if good:
                ax.annotate(
                    name, (p[0], p[1]), fontsize=7, xytext=(3, 3), textcoords="offset points"
                )
    ax.set(xlabel="x [m]", ylabel="y [m]", title="localization (score test, best effect per place)")
    ax.set_aspect("equal", adjustable="datalim")
    fig.tight_layout()
    return fig


def plot_ranking(result, top: int = 12):
    """ln Bayes factor vs the baseline of the refitted candidates, with the threshold
    (``threshold_log_odds`` minus the prior log odds of one candidate)."""
    fits = result.fits[:top]
    fig, ax = plotting.subplots(figsize=(7, 0.35 * max(len(fits), 3) + 1.2))
    values = [result.log_bayes_factor(f) for f in fits]
    y = np.arange(len(fits))[::-1]
    colors = ["C2" if result.named is f else "C0" for f in fits]
    ax.barh(y, values, color=colors)
    ax.set_yticks(y, [f"{f.label}{' (quick)' if f.stage == 'quick' else ''}" for f in fits])
    # the threshold is on the posterior log odds; on the Bayes-factor axis it sits higher by
    # the (negative) prior log odds of a candidate
    bar = result.settings.verdict.threshold_log_odds - result.prior_log_odds
    ax.axvline(bar, color="r", ls="--", label=f"threshold (ln BF {bar:.1f})")
    ax.axvline(0, color="k", lw=0.5)
    ax.set(xlabel="ln Bayes factor vs baseline (Laplace)", title="candidate ranking")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def save_plots(result, folder, structure=None) -> list[Path]:
    """Write residuals.png, localization.png, ranking.png into ``folder`` (created)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for name, fig in (
        ("residuals", plot_residuals(result)),
        ("localization", plot_localization(result, structure)),
        ("ranking", plot_ranking(result)),
    ):
        out.append(plotting.save(fig, folder / f"{name}.png"))
    return out
