"""The report section comparing the two exhausts : the choice (``better_exhaust``'s rule),
Table 1, the speed, the calibrated optima and the fronts, from the records of
``pipelines.exhaust_comparison``."""

from pathlib import Path

import numpy as np

from bayesupdate.models import exhaust_paper as paper
from bayesupdate.pipelines.exhaust_comparison import MODELS, ExhaustRecord, better_exhaust
from bayesupdate.report.document import Figure, Section, Table


def _table1(records) -> Table:
    a, b = (records[m] for m in MODELS)
    rows = [
        (i + 1, f, fa, ea, fb, eb)
        for i, (f, fa, ea, fb, eb) in enumerate(
            zip(paper.TABLE1_FEA_HZ, a.frequencies_hz, a.table1_error_pct, b.frequencies_hz,
                b.table1_error_pct, strict=True)
        )
    ]  # fmt: skip
    rows.append(("RMS / max [%]", "", a.table1_rms_pct, a.table1_max_pct, b.table1_rms_pct,
                 b.table1_max_pct))  # fmt: skip
    rows.append(("mass [kg] (seed 12.29)", "", a.mass_kg, "", b.mass_kg, ""))
    return Table(
        ("mode", "seed Table 1 [Hz]", f"{a.name} [Hz]", "error [%]", f"{b.name} [Hz]",
         "error [%]"),
        tuple(rows),
        caption="Both exhausts at the initial design against seed Table 1 (each solved here)",
    )  # fmt: skip


def _speed(records) -> Table:
    rows = tuple(
        (r.name, r.n_dof, r.build_s, r.solve_s, r.solves) for r in (records[m] for m in MODELS)
    )
    return Table(
        ("model", "DOFs", "build [s]", "solve, 12 modes [s] (median)", "solves timed"),
        rows,
        caption="Speed of one full solve, measured in this run (wall time; the load of the "
        "machine is not controlled)",
    )


def _calibrated(records) -> list:
    rows = [
        (r.name, c.expr, paper.EXPR_FINAL_REPORTED, c.mass_kg, c.swapped, Path(c.source).name)
        for r in (records[m] for m in MODELS)
        if (c := r.calibrated) is not None
    ]
    missing = [m for m in MODELS if records[m].calibrated is None]
    blocks = []
    if rows:
        blocks.append(
            Table(
                ("model", "Expr vs Table 2", "seed Expr", "mass [kg]", "mode swap", "source"),
                tuple(rows),
                caption="Calibrated against seed Table 2 with the measured 12.29 kg kept (source: "
                "the file read, or how this run computed it)",
            )
        )
    if missing:
        blocks.append(
            f"No calibration file given for {', '.join(missing)}: its optimum and front are not "
            "shown (studies/exhaust_shell_front.py MODEL --out FILE writes one)."
        )
    return blocks


def plot_fronts(records, path) -> Path | None:
    """Expr against the mass error of every model with a front, and the paper's point."""
    fronts = [(r.name, r.calibrated.front) for r in records.values() if r.calibrated and
              r.calibrated.front]  # fmt: skip
    if not fronts:
        return None
    from bayesupdate import plotting

    fig, ax = plotting.subplots(figsize=(6.5, 4))
    for name, front in fronts:
        x, y = np.array(front).T
        ax.plot(x, y, "o-", label=name)
    m0, m1 = paper.MEASURED_MASS_KG, paper.OPTIMUM_MASS_KG
    ax.plot(100 * (m1 - m0) / m0, paper.EXPR_FINAL_REPORTED, "r*", ms=14, label="seed (Table 3)")
    ax.set_xlabel("mass error against the measured 12.29 kg [%]")
    ax.set_ylabel("Expr (seed eq. 19) vs Table 2")
    ax.grid(alpha=0.3)
    ax.legend()
    return plotting.save(fig, path, tight=True)


def comparison_section(records: dict[str, ExhaustRecord], out, folder=None) -> Section:
    """The report section: the choice, Table 1, speed, the calibrated optima and the fronts (a
    figure ``exhaust_fronts.png`` in ``folder``, default the report folder ``out``, when a record
    has a front)."""
    winner, reason = better_exhaust(records)
    blocks = [f"Which exhaust reproduces the paper better, by the numbers: {reason}."]
    blocks += [_table1(records), _speed(records), *_calibrated(records)]
    png = plot_fronts(records, Path(folder or out) / "exhaust_fronts.png")
    if png is not None:
        caption = (
            "The front of Expr against the mass error (each point a fit with another weight of "
            "the mass term), both models on the same axes, and the seed's optimum."
        )
        blocks.append(Figure(str(png.relative_to(out)), caption))
    return Section("The two exhausts side by side (beam and shell)", tuple(blocks))
