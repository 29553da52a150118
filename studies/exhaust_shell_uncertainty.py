"""How far the shell exhaust's calibrated design variables move under the model-form spread of its
geometry (issue 20, "the uncertainty study on the shell model"; point optima only, the
posterior version of ``studies/uncertainty_study.py`` is not run for the shell model).

    for g in 1 2 3; do PYTHONPATH=. OPENBLAS_NUM_THREADS=1 python studies/exhaust_shell_front.py \\
        exhaust_shell --mesh-density 16 --geometry $g --starts 2 --max-nfev 150 --weights 0 \\
        --out opt_g$g.json; done
    PYTHONPATH=. python studies/exhaust_shell_uncertainty.py front_exhaust_shell16.json \\
        opt_g1.json opt_g2.json opt_g3.json

The first file is the reference (the best geometry); each file is a ``studies/
exhaust_shell_front.py`` record (its "optimum": the mass-kept optimum against seed Table 2).
Prints, per design variable, each geometry's optimum, its shift from the reference [%], and the
spread (largest minus smallest over all files, in % of the reference), beside seed Table 3.
"""

import argparse
import json
from pathlib import Path

import numpy as np

from bayesupdate.paper import DESIGN_VARIABLES, TABLE3_INITIAL_SI, TABLE3_OPTIMUM_SI


def read_optima(paths) -> list[tuple[str, dict]]:
    """(label, optimum record) of each file: the label is its geometry (best without one)."""
    out = []
    for path in paths:
        doc = json.loads(Path(path).read_text())
        label = f"geometry {doc['options'].get('geometry', 'best')}"
        out.append((label, doc["optimum"]))
    return out


def shift_table(optima) -> list[dict]:
    """One row per design variable: values, shifts from the first optimum [%], spread [%]."""
    rows = []
    for name in DESIGN_VARIABLES:
        values = np.array([opt["parameters"][name] for _, opt in optima])
        ref = values[0]
        rows.append(
            {
                "name": name,
                "values": values,
                "shift_pct": 100 * (values / ref - 1),
                "spread_pct": 100 * np.ptp(values) / ref,
                "initial": TABLE3_INITIAL_SI[name],
                "paper": TABLE3_OPTIMUM_SI[name],
            }
        )
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="+", help="optimum records; the first is the reference")
    args = ap.parse_args()
    optima = read_optima(args.files)
    print("      " + "  ".join(f"{label}: Expr {o['expr']:.4f}, {o['mass_kg']:.3f} kg"
                               for label, o in optima))  # fmt: skip
    for r in shift_table(optima):
        cells = "  ".join(
            f"{v:10.4g} ({s:+6.1f} %)" for v, s in zip(r["values"], r["shift_pct"], strict=True)
        )
        print(f"{r['name']:26s} {cells}  spread {r['spread_pct']:5.1f} %   "
              f"(Table 3: {r['initial']:.4g} -> {r['paper']:.4g})")  # fmt: skip


if __name__ == "__main__":
    main()
