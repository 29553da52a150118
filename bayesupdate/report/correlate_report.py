"""The reports of ``bayesupdate correlate --report DIR`` and ``bayesupdate sensitivity --report
DIR``.

correlate: the inputs and the test-point mapping, the frequency table of the paired modes, the
MAC matrix as a picture (pairs outlined), the pairs with swaps, refused and unpaired modes, the
paired shapes side by side at the test DOFs, COMAC per test DOF as a chart, the orthogonality
checks through the SEREP TAM.  sensitivity: the normalized sensitivity matrix as a heat map, its
singular values and directions, the confounded groups and the suggested parameter set.

:func:`correlate_document` / :func:`sensitivity_document` build the content (pure); the
``write_*`` functions draw the figures into ``DIR/figures`` (matplotlib's object API: no global
state) and write ``DIR/report.html`` (self-contained) and ``DIR/report.md``.
"""

from pathlib import Path

import numpy as np

from bayesupdate.report.document import Alert, Document, Figure, Section, Table
from bayesupdate.report.render import write_report

FIGURES = {
    "mac": ("mac.png", "MAC of the test modes (rows) against the model modes (columns); the "
            "accepted pairs are outlined."),
    "shapes": ("shapes.png", "Paired shapes at the test DOFs: test (bars, realized and scaled "
               "onto the model shape by the modal scale factor) and model (dots)."),
    "comac": ("comac.png", "COMAC per test DOF over the paired modes (1 = test and model agree "
              "at that DOF over all pairs)."),
    "points": ("points.png", "The test points on the model (plan and side view, the model's "
               "frame and units): model nodes grey, each test point at its paired model point, "
               "coloured by its lowest COMAC, labelled by its test node."),
    "sensitivity": ("sensitivity.png", "Normalized sensitivities (d f / f) / (d p / p) of the "
                    "paired frequencies (rows) to the candidate parameters (columns)."),
}  # fmt: skip


def _figure(name: str, drawn: dict) -> tuple:
    return (Figure(drawn[name], FIGURES[name][1]),) if name in drawn else ()


def _frequency_table(result) -> Table:
    pairs = result.pairs
    rows = tuple(
        (result.number(t), int(m) + 1, f"{result.test_hz[t]:.4f}", f"{result.model_hz[m]:.4f}",
         f"{e:+.2f}", "-" if v != v else f"{v:.3f}")
        for t, m, e, v in zip(pairs.test, pairs.model, result.error_pct, pairs.mac, strict=True)
    )  # fmt: skip
    return Table(
        ("test mode", "model mode", "test [Hz]", "model [Hz]", "difference [%]", "MAC"),
        rows,
        caption=f"Paired modes (pairing: {pairs.method}); difference = (model - test) / test",
    )


def _pairs_text(result) -> tuple:
    pairs = result.pairs
    parts = []
    if pairs.swapped:
        named = ", ".join(f"test {result.number(t)} - model {m + 1}" for t, m in pairs.swapped)
        parts.append(f"Swapped (model mode out of the test's order): {named}.")
    for t, m, v in pairs.refused:
        parts.append(
            f"Refused: test mode {result.number(t)}, best model mode {m + 1} at MAC {v:.3f}."
        )
    unpaired = (
        ("test", [result.number(t) for t in pairs.unpaired_test]),
        ("model", [m + 1 for m in pairs.unpaired_model]),
    )
    for name, numbers in unpaired:
        if numbers:
            parts.append(f"Unpaired {name} modes: {', '.join(map(str, numbers))}.")
    return tuple(parts) or ("Every test mode is paired, none out of order.",)


def _transform_text(result) -> str:
    """The test-to-model transform in words: identity, or its rotation and shift rows and fit."""
    T = np.asarray(result.mapping.transform, float)
    if np.allclose(T, np.eye(4)):
        return "transform: identity"
    rows = "; ".join(" ".join(f"{v:.4g}" for v in row) for row in T[:3])
    rms = result.mapping.rms_residual
    fit = "" if rms is None else f", rms residual {rms:.3g}"
    return f"transform test -> model [{rows}]{fit}"


def _points_table(result) -> Table:
    rows = tuple(
        (p.dof, p.test_node, "-" if p.model_node is None else p.model_node,
         "-" if p.model_xyz is None else ", ".join(f"{v:.4g}" for v in p.model_xyz),
         "-" if p.direction is None else ", ".join(f"{v:+.3f}" for v in p.direction),
         "-" if p.distance is None else f"{p.distance:.4g}")
        for p in result.mapping.points
    )  # fmt: skip
    return Table(
        ("test DOF", "test node", "model node", "model xyz", "direction", "distance"),
        rows,
        caption=f"Test DOFs on the model ({result.mapping.source}; {_transform_text(result)})",
    )


def _matrix_table(x: np.ndarray, caption: str) -> Table:
    rows = tuple((f"pair {i + 1}", *(f"{v:+.3f}" for v in row)) for i, row in enumerate(x))
    headers = ("", *(f"pair {j + 1}" for j in range(x.shape[1])))
    return Table(headers, rows, caption=caption)


def _orthogonality_blocks(result) -> tuple:
    blocks = []
    pairs = result.pairs
    if result.pseudo_orthogonality is not None:
        blocks.append(_matrix_table(result.pseudo_orthogonality, "Pseudo-orthogonality of the "
                      "paired model modes through the SEREP TAM (identity: the test DOFs "
                      "separate them)"))  # fmt: skip
    if result.cross_orthogonality is not None:
        x = result.cross_orthogonality
        rows = tuple(
            (f"test {pairs.test[i] + 1}", *(f"{v:+.3f}" for v in row)) for i, row in enumerate(x)
        )
        headers = ("", *(f"model {pairs.model[j] + 1}" for j in range(x.shape[1])))
        blocks.append(
            Table(
                headers,
                rows,
                caption="Cross-orthogonality test vs model through "
                "the SEREP TAM (acceptance often |diagonal| >= 0.9, |off| <= 0.1)",
            )
        )
    return tuple(blocks) or ("No orthogonality check (see the notes).",)


def correlate_document(result, figures: dict | None = None) -> Document:
    """The correlate report's content; figures : {name in FIGURES: path relative to the
    folder} of the figures drawn."""
    drawn = figures or {}
    worst = ", ".join(f"{d} ({c:.3f})" for d, c in result.worst_points(3))
    sections = (
        Section("Inputs", (f"Model: {result.model}. Test: {result.data} "
                           f"({result.test_hz.size} modes, {len(result.dof_labels)} DOFs).",
                           _points_table(result))),
        Section("Frequencies", (_frequency_table(result),)),
        Section("MAC and pairs", (*_figure("mac", drawn), *_pairs_text(result))),
        Section("Paired shapes", _figure("shapes", drawn) or ("The test has no shapes.",)),
        Section("COMAC", (*((f"Lowest COMAC: {worst}.",) if worst else ()),
                          *_figure("comac", drawn), *_figure("points", drawn))),
        Section("Orthogonality (SEREP TAM)", _orthogonality_blocks(result)),
        Section("Notes", tuple(Alert(n) for n in result.notes) or ("No notes.",)),
    )  # fmt: skip
    return Document(f"bayesupdate correlate: {result.model}", f"against {result.data}", sections)


def _new_figure(width: float, height: float):
    from matplotlib.figure import Figure as MplFigure

    return MplFigure(figsize=(width, height))


def _draw_mac(result, path: Path) -> None:
    from matplotlib.patches import Rectangle

    fig = _new_figure(6.5, 5.2)
    ax = fig.add_subplot()
    im = ax.imshow(result.mac, vmin=0, vmax=1, cmap="viridis", origin="lower", aspect="auto")
    for t, m in zip(result.pairs.test, result.pairs.model, strict=True):
        ax.add_patch(Rectangle((m - 0.5, t - 0.5), 1, 1, fill=False, edgecolor="red", lw=1.5))
    if result.mac.size <= 400:
        for (i, j), v in np.ndenumerate(result.mac):
            ax.text(j, i, f"{v:.2f}", ha="center", va="center", fontsize=6,
                    color="w" if v < 0.5 else "k")  # fmt: skip
    ax.set_xticks(range(result.model_hz.size), [f"{j + 1}" for j in range(result.model_hz.size)])
    ax.set_yticks(range(result.test_hz.size), [f"{i + 1}" for i in range(result.test_hz.size)])
    ax.set_xlabel("model mode")
    ax.set_ylabel("test mode")
    fig.colorbar(im, ax=ax, label="MAC")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def _draw_shapes(result, path: Path) -> None:
    pairs = result.pairs
    k = pairs.test.size
    ncol = min(2, k)
    nrow = int(np.ceil(k / ncol))
    n = len(result.dof_labels)
    fig = _new_figure(min(max(4.0, 0.3 * n + 1.5), 9.0) * ncol, 1.9 * nrow + 0.8)
    # shared axes and a fixed layout: tight_layout over many labelled panels costs seconds
    axes = fig.subplots(nrow, ncol, squeeze=False, sharex=True, sharey=True)
    fig.subplots_adjust(left=0.05, right=0.99, top=1 - 0.35 / (1.9 * nrow + 0.8), hspace=0.45,
                        bottom=0.7 / (1.9 * nrow + 0.8), wspace=0.05)  # fmt: skip
    x = np.arange(n)
    for r, (t, m) in enumerate(zip(pairs.test, pairs.model, strict=True)):
        ax = axes.flat[r]
        model = result.model_shapes[:, m]
        test = result.test_shapes[:, t]
        msf = float(test @ model) / float(test @ test) if test @ test > 0 else 1.0
        peak = max(np.abs(model).max(), 1e-300)
        ax.bar(x, msf * test / peak, color="tab:blue", width=0.7, label="test")
        ax.plot(x, model / peak, "o", color="tab:red", ms=3, label="model")
        ax.axhline(0, color="0.4", lw=0.6)
        title = f"test {result.number(t)} ({result.test_hz[t]:.2f} Hz) - model {m + 1} "
        ax.set_title(f"{title}({result.model_hz[m]:.2f} Hz), MAC {pairs.mac[r]:.3f}", fontsize=8)
    for ax in axes.flat[k:]:
        ax.axis("off")
    if n <= 60:
        for ax in axes[-1]:
            ax.set_xticks(x, list(result.dof_labels), fontsize=6, rotation=90)
    axes.flat[0].legend(fontsize=7)
    fig.savefig(path, dpi=90)


def _draw_comac(result, path: Path) -> None:
    n = len(result.dof_labels)
    fig = _new_figure(min(max(5.0, 0.22 * n + 2), 12.0), 3.0)
    ax = fig.add_subplot()
    ax.bar(np.arange(n), result.comac, color="tab:green", width=0.7)
    ax.set_ylim(0, 1.05)
    ax.set_ylabel("COMAC")
    if n <= 80:
        ax.set_xticks(np.arange(n), list(result.dof_labels), fontsize=6, rotation=90)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def _point_comac(result) -> dict:
    """{test node: its lowest COMAC over its DOFs} (1 where no COMAC was computed)."""
    out: dict = {}
    values = result.comac if result.comac is not None else np.ones(len(result.dof_labels))
    for p in result.mapping.points:
        c = float(values[result.dof_labels.index(p.dof)]) if p.dof in result.dof_labels else 1.0
        out[p.test_node] = min(out.get(p.test_node, 1.0), c)
    return out


def _draw_points(result, path: Path) -> None:
    nodes = result.model_nodes
    placed = {p.test_node: p.model_xyz for p in result.mapping.points if p.model_xyz is not None}
    comac = _point_comac(result)
    xyz = np.array(list(placed.values()))
    colour = [comac[k] for k in placed]
    fig = _new_figure(9.0, 4.2)
    for k, (a, b, name) in enumerate(((0, 1, "plan (x, y)"), (0, 2, "side (x, z)"))):
        ax = fig.add_subplot(1, 2, k + 1)
        ax.scatter(nodes[:, a], nodes[:, b], s=3, c="0.75", label="model nodes")
        sc = ax.scatter(xyz[:, a], xyz[:, b], s=28, c=colour, cmap="RdYlGn", vmin=0, vmax=1,
                        edgecolors="k", linewidths=0.4, label="test points")  # fmt: skip
        for label, (x, y) in zip(placed, xyz[:, [a, b]], strict=True):
            ax.annotate(str(label), (x, y), fontsize=6, xytext=(2, 2), textcoords="offset points")
        ax.set_title(name, fontsize=9)
        ax.set_aspect("equal", adjustable="datalim")
    fig.colorbar(sc, ax=fig.axes, label="lowest COMAC of the point")
    fig.savefig(path, dpi=110)


def _has_points(result) -> bool:
    placed = any(p.model_xyz is not None for p in result.mapping.points)
    return result.model_nodes is not None and placed


def _draw_correlation(folder: Path, result) -> dict:
    drawn = {}
    steps = {"mac": (_draw_mac, result.mac is not None),
             "shapes": (_draw_shapes, result.test_shapes is not None and result.pairs.test.size),
             "comac": (_draw_comac, result.comac is not None),
             "points": (_draw_points, _has_points(result))}  # fmt: skip
    for name, (draw, wanted) in steps.items():
        if wanted:
            path = folder / "figures" / FIGURES[name][0]
            draw(result, path)
            drawn[name] = str(path.relative_to(folder))
    return drawn


def write_correlate_report(folder, result) -> tuple[Path, Path]:
    """Draw the figures and write ``folder/report.html`` and ``report.md``; the folder must have
    passed ``identify_report.check_report_folder``."""
    folder = Path(folder)
    return write_report(correlate_document(result, _draw_correlation(folder, result)), folder)


# -- sensitivity -----------------------------------------------------------------------------
def _sensitivity_table(result) -> Table:
    rows = tuple(
        (f"{result.frequencies_hz[i]:.3f}", *(f"{v:+.3f}" for v in row))
        for i, row in enumerate(result.matrix)
    )
    return Table(("mode [Hz]", *result.names), rows,
                 caption="Normalized sensitivities (d f / f) / (d p / p)")  # fmt: skip


def _singular_table(result) -> Table:
    rows = tuple(
        (k + 1, f"{s:.4g}", f"{s / result.singular_values[0]:.3g}",
         "seen" if k < result.rank else "not seen",
         ", ".join(f"{w:+.2f} {n}" for n, w in result.direction_terms(k)))
        for k, s in enumerate(result.singular_values)
    )  # fmt: skip
    return Table(("direction", "singular value", "relative", "test", "parameter combination"),
                 rows, caption="Singular values of the sensitivity matrix and their directions "
                 "(right singular vectors, in log-parameters)")  # fmt: skip


def sensitivity_document(result, figures: dict | None = None) -> Document:
    """The sensitivity report's content (``pipelines.sensitivity.Sensitivity``)."""
    drawn = figures or {}
    groups = [" + ".join(g) for g in result.groups]
    sections = (
        Section("Sensitivities", (f"Model: {result.model}; {len(result.names)} candidates, "
                                  f"{result.frequencies_hz.size} modes; method: {result.method}.",
                                  *_figure("sensitivity", drawn), _sensitivity_table(result))),
        Section("What the test can see", (_singular_table(result),)),
        Section("Confounded parameters", tuple(f"Moves frequencies as one direction: {g}."
                                               for g in groups) or ("None.",)),
        Section("Suggested parameters", (
            "A suggestion, by QR with column pivoting of the sensitivity matrix (Businger & "
            "Golub 1965): " + ", ".join(result.suggested) + ".",)),
        Section("Notes", tuple(Alert(n) for n in result.notes) or ("No notes.",)),
    )  # fmt: skip
    return Document(f"bayesupdate sensitivity: {result.model}", "before updating", sections)


def _draw_heat_map(result, path: Path) -> None:
    s = result.matrix
    fig = _new_figure(min(2.5 + 0.6 * s.shape[1], 14.0), min(1.5 + 0.35 * s.shape[0], 10.0))
    ax = fig.add_subplot()
    bound = max(float(np.abs(s).max()), 1e-12)
    im = ax.imshow(s, cmap="RdBu_r", vmin=-bound, vmax=bound, aspect="auto")
    ax.set_xticks(range(s.shape[1]), list(result.names), rotation=60, ha="right", fontsize=7)
    ax.set_yticks(range(s.shape[0]), [f"{f:.1f} Hz" for f in result.frequencies_hz], fontsize=7)
    fig.colorbar(im, ax=ax, label="(df/f) / (dp/p)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def write_sensitivity_report(folder, result) -> tuple[Path, Path]:
    """Draw the heat map and write ``folder/report.html`` and ``report.md``."""
    folder = Path(folder)
    path = folder / "figures" / FIGURES["sensitivity"][0]
    _draw_heat_map(result, path)
    figures = {"sensitivity": str(path.relative_to(folder))}
    return write_report(sensitivity_document(result, figures), folder)
