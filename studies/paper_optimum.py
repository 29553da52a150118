"""Seed Tables 3 and 4 reproduced beside ours: the exhaust calibrated to the EMA of Table 2.

    .venv/bin/python studies/paper_optimum.py [--geometry two_design] [--starts 16]
        [--front-geometries table1 two_design] [--out studies/out/paper_optimum]

Steps: (1) multi-start bounded least squares on seed eq. 19 with the measured mass (12.29 kg) as
a response (the paper kept the mass as a response); pairing tracked by the model's own shapes at
the initial design, so a hidden mode swap is reported; (2) Table 3 (design variables, the way each
moves) and Table 4 (frequencies) side by side; (3) the front of Expr against the mass error of
every geometry in ``--front-geometries``, on one figure with the paper's point; (4) the same
calibration on the runner-up geometries of the FE fit (model-form uncertainty).  Writes
``summary.json``, ``front.png`` and one HDF5 result per geometry.
"""

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from bayesupdate.fe.reduced import reduced_model_for  # noqa: E402
from bayesupdate.inference import (  # noqa: E402
    CalibrationSettings,
    ObjectiveSpec,
    build_problem,
    calibrate,
    load_modal_data,
    objective_expr,
    pareto_front_mass,
    write_result,
)
from bayesupdate.models import get_model  # noqa: E402
from bayesupdate.models.exhaust_paper import (  # noqa: E402
    DESIGN_VARIABLES,
    EXPR_FINAL_REPORTED,
    MEASURED_MASS_KG,
    OPTIMUM_MASS_KG,
    TABLE3_INITIAL_SI,
    TABLE3_OPTIMUM_SI,
    TABLE4_FINAL_HZ,
)


def calibrate_exhaust(geometry, starts: int, seed: int, mass_weight: float, full=False):
    """Mass-kept multi-start optimum.  Unless ``full``, the starts search on the certified reduced
    model (14 modes, tol 1e-4, ~20x faster) and every end near the best is polished on the full
    model (``calibrate(..., refine=...)``), so the reported optimum is the full model's.
    Returns (full problem, reduced problem or None, result)."""
    fe = get_model("exhaust", geometry=geometry)
    data = load_modal_data("paper:ema")
    objective = ObjectiveSpec(mass_target_kg=MEASURED_MASS_KG, mass_weight=mass_weight)
    problem = build_problem(fe, data, None, pairing="tracked", objective=objective)
    if full:
        return problem, None, calibrate(problem, CalibrationSettings(starts=starts, seed=seed))
    rom = reduced_model_for(fe, tol=1e-4, seed=0, n_modes=14)
    search = build_problem(rom, data, None, pairing="tracked", objective=objective)
    settings = CalibrationSettings(starts=starts, seed=seed)
    return problem, search, calibrate(search, settings, refine=problem)


def front_problems(geometry, mass_weight: float, full: bool):
    """(full problem, reduced search problem or None) of ``geometry`` with the mass kept, as
    ``calibrate_exhaust`` builds them, without calibrating."""
    fe = get_model("exhaust", geometry=geometry)
    data = load_modal_data("paper:ema")
    objective = ObjectiveSpec(mass_target_kg=MEASURED_MASS_KG, mass_weight=mass_weight)
    problem = build_problem(fe, data, None, pairing="tracked", objective=objective)
    if full:
        return problem, None
    rom = reduced_model_for(fe, tol=1e-4, seed=0, n_modes=14)
    return problem, build_problem(rom, data, None, pairing="tracked", objective=objective)


def table3(result) -> list[dict]:
    rows = []
    for name in DESIGN_VARIABLES:
        ours = result.parameters.get(name)
        start, paper = TABLE3_INITIAL_SI[name], TABLE3_OPTIMUM_SI[name]
        rows.append(
            {
                "name": name,
                "initial": start,
                "paper": paper,
                "ours": ours,
                "same_direction": None
                if ours is None
                else bool(np.sign(ours - start) == np.sign(paper - start)),
            }
        )
    return rows


def print_table4(best) -> None:
    """Per mode: EMA, the paper's FE optimum (Table 4), ours (error %, MAC, model mode), and a
    warning when the optimum swaps modes."""
    for i, row in enumerate(best.table.rows()):
        print(
            f"{row['mode']:3d} {row['test_hz']:8.2f} {TABLE4_FINAL_HZ[i]:8.2f} "
            f"{row['model_hz']:8.2f}"
            f" ({row['error_pct']:+6.2f} %, MAC {row['mac']:.3f}, mode {row['model_mode']})"
        )
    if best.swapped:
        print("WARNING: the optimum swaps modes relative to the initial design (see model mode)")


def best_summary(best) -> dict:
    """The optimum's numbers for summary.json (a ``CalibrationResult``)."""
    return {
        "parameters": best.parameters,
        "objective": float(best.expr),
        "mass_kg": best.mass_kg,
        "frequencies_hz": best.frequencies_hz.tolist(),
        "starts": best.starts,
        "converged_starts": best.converged_starts,
        "swapped": best.swapped,
    }


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--geometry", default="best", help="exhaust geometry (e.g. two_design)")
    parser.add_argument(
        "--front-geometries",
        nargs="*",
        default=None,
        help="geometries whose fronts share the figure (default: --geometry alone)",
    )
    parser.add_argument("--starts", type=int, default=16)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--mass-weight", type=float, default=10.0)
    parser.add_argument("--runner-ups", type=int, default=2)
    parser.add_argument("--full", action="store_true", help="full FE solves (no reduced model)")
    parser.add_argument("--out", default="studies/out/paper_optimum")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    problem, search, best = calibrate_exhaust(
        args.geometry, args.starts, args.seed, args.mass_weight, args.full
    )
    write_result(out / "optimum_best.h5", problem, best, vars(args), command="paper_optimum")
    print(
        f"Expr (eq. 19, Table 2) = {best.expr:.4f}   paper: {EXPR_FINAL_REPORTED} "
        f"(Table 4 columns give {objective_expr(TABLE4_FINAL_HZ, problem.data.frequencies_hz):.4f})"
    )
    print(
        f"mass = {best.mass_kg:.3f} kg   measured {MEASURED_MASS_KG}, "
        f"paper optimum {OPTIMUM_MASS_KG}"
    )
    print(f"starts reaching the best (Expr within 1 %): {best.converged_starts}/{best.starts}")
    span = problem.upper - problem.lower
    close = best.end_objectives <= 1.01 * best.objective
    spread = np.ptp(best.end_points[close], axis=0) / span if close.sum() > 1 else np.zeros(5)
    print(
        "  their spread (% of each bound's width): "
        + ", ".join(f"{n} {100 * s:.1f}" for n, s in zip(best.names, spread, strict=True))
        + (
            "\n  (on the Table-1 geometry the optimum lies on the kink where the tracked pairing"
            " of modes 6/7 flips, in a flat thickness-density valley; see"
            " tests/test_calibration_exhaust.py)"
            if args.geometry in ("best", "table1", "0")
            else ""
        )
    )
    print("\nTable 3 (SI)            initial      paper       ours   same direction")
    rows = table3(best)
    for r in rows:
        print(
            f"{r['name']:26s} {r['initial']:9.4g} {r['paper']:10.4g} {r['ours']:10.4g}   "
            f"{r['same_direction']}"
        )
    print(
        "\nTable 4: mode, EMA, paper FE optimum, ours (error %, MAC vs initial shape, model mode)"
    )
    print_table4(best)

    # the front's points are TRF ends (no Nelder-Mead polish, ~10x cheaper): each may sit up
    # to ~3 % above its polished value on the mode 6/7 kink, far less than the front's range
    fronts = {}
    for geometry in args.front_geometries or [args.geometry]:
        if geometry == args.geometry:
            front_problem = search or problem
        else:
            p_g, s_g = front_problems(geometry, args.mass_weight, args.full)
            front_problem = s_g or p_g
        fronts[geometry] = pareto_front_mass(
            front_problem,
            MEASURED_MASS_KG,
            starts=max(args.starts // 2, 4),
            seed=args.seed,
            polish=False,
        )
    front = fronts[next(iter(fronts))] if args.geometry not in fronts else fronts[args.geometry]
    fig, ax = plt.subplots(figsize=(6, 4))
    for geometry, points in fronts.items():
        points = sorted(points, key=lambda p: p["mass_error_pct"])
        ax.plot(
            [p["mass_error_pct"] for p in points],
            [p["expr"] for p in points],
            "o-",
            label=f"beam exhaust, geometry {geometry}",
        )
    ax.axhline(0.0406, color="grey", lw=0.8, ls=":")
    ax.axvspan(-1.5, 1.5, color="grey", alpha=0.1, label="mass within 1.5 %")
    ax.plot(
        100 * (OPTIMUM_MASS_KG - MEASURED_MASS_KG) / MEASURED_MASS_KG,
        EXPR_FINAL_REPORTED,
        "r*",
        ms=14,
        label="paper (Table 3/4)",
    )
    ax.set_xlabel("mass error against 12.29 kg [%]")
    ax.set_ylabel("Expr (seed eq. 19, Table 2)")
    ax.set_yscale("log")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "front.png", dpi=110)

    runner_ups = []
    set_name = args.geometry.partition(":")[0]
    set_name = "best" if set_name.isdigit() else set_name
    for k in range(1, args.runner_ups + 1):
        try:
            _, _, r_k = calibrate_exhaust(
                f"{set_name}:{k}", args.starts, args.seed, args.mass_weight, args.full
            )
        except Exception as exc:  # a geometry that is not stored: report and go on
            print(f"geometry {k}: skipped ({exc})")
            continue
        shift = {
            n: (r_k.parameters[n] - best.parameters[n]) / best.parameters[n] for n in best.names
        }
        runner_ups.append(
            {
                "geometry": k,
                "expr": r_k.expr,
                "mass_kg": r_k.mass_kg,
                "parameters": r_k.parameters,
                "relative_shift": shift,
                "swapped": r_k.swapped,
            }
        )
        print(
            f"geometry {k}: Expr {r_k.expr:.4f}, mass {r_k.mass_kg:.3f} kg, largest shift "
            f"{max(abs(v) for v in shift.values()):.1%}"
        )
    summary = {
        "best": {**best_summary(best), "table3": rows, "residuals": best.table.rows()},
        "geometry": args.geometry,
        "front": front,
        "fronts": fronts,
        "runner_ups": runner_ups,
    }
    (out / "summary.json").write_text(json.dumps(summary, indent=1, default=float))


if __name__ == "__main__":
    main()
