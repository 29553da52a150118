"""The two exhausts side by side: Table 1 and the speed of each (computed here), the
calibrated optimum and the front of each (read from files), and which one reproduces the paper
better by the numbers (``pipelines.exhaust_comparison.better_exhaust``).  Writes report.html and
report.md (``report.exhaust_comparison``) into --out.

    PYTHONPATH=. OPENBLAS_NUM_THREADS=1 python studies/exhaust_shell_compare.py \\
        --result exhaust=studies/out/front_exhaust.json \\
        --result exhaust_shell=studies/out/front_exhaust_shell.json --out studies/out/compare

A result is a front file of ``studies/exhaust_shell_front.py`` (optimum and front) or a
``bayesupdate calibrate --out`` HDF5 file (optimum only).
"""

import argparse
from pathlib import Path

from bayesupdate.pipelines.exhaust_comparison import better_exhaust, compare_exhausts
from bayesupdate.report.document import Document
from bayesupdate.report.exhaust_comparison import comparison_section
from bayesupdate.report.render import write_report


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--result", action="append", default=[], metavar="MODEL=FILE")
    ap.add_argument("--mesh-density", type=int, default=None, help="exhaust_shell (default 32)")
    ap.add_argument("--solves", type=int, default=3, help="solves timed per model (3)")
    ap.add_argument("--out", required=True, help="report folder")
    args = ap.parse_args()
    files = dict(item.split("=", 1) for item in args.result)
    options = {} if args.mesh_density is None else {"mesh_density": args.mesh_density}
    records = compare_exhausts(files, {"exhaust_shell": options}, args.solves)
    for r in records.values():
        line = (
            f"{r.name:14s} {r.n_dof:6d} DOFs  Table 1 RMS {r.table1_rms_pct:.2f} %, max "
            f"{r.table1_max_pct:.2f} %, mass {r.mass_kg:.3f} kg; build {r.build_s:.1f} s, "
            f"solve {r.solve_s:.2f} s (median of {r.solves})"
        )
        if r.calibrated is not None:
            c = r.calibrated
            line += f"; calibrated Expr {c.expr:.4f}, mass {c.mass_kg:.3f} kg"
        print(line)
    winner, reason = better_exhaust(records)
    print(f"choice: {winner}: {reason}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    doc = Document(
        "The seed's exhaust: beam and shell models side by side",
        "Table 1 and speed computed in this run, calibrations read from files",
        (comparison_section(records, out),),
    )
    print("report:", *write_report(doc, out))


if __name__ == "__main__":
    main()
