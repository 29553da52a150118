"""How far the shell exhaust's calibrated design variables move under the model-form spread of its
geometry and of its connection stiffnesses (the uncertainty study on the shell model;
point optima only, the posterior version of ``studies/uncertainty_study.py`` is not run
for the shell model).

    for g in 1 2 3; do PYTHONPATH=. OPENBLAS_NUM_THREADS=1 python studies/exhaust_shell_front.py \\
        exhaust_shell --mesh-density 16 --geometry $g --starts 2 --max-nfev 150 --weights 0 \\
        --out opt_g$g.json; done
    PYTHONPATH=. python studies/exhaust_shell_uncertainty.py front_exhaust_shell16.json \\
        opt_g1.json opt_g2.json opt_g3.json

The connection stiffnesses floated (``--connections``): all six pipe-to-body connection springs
of ``exhaust_shell`` (``connection_k_rot``) at each given value [N m/rad], each calibrated the same
way (``exhaust_shell_front.optimum_and_front``: mass kept, mesh density 16, its own certified
basis, no front), one record per value written to ``--out-dir``, then compared with the first:

    PYTHONPATH=. OPENBLAS_NUM_THREADS=1 python studies/exhaust_shell_uncertainty.py \
        --connections 1e8 1e6 3e5 1e5 --out-dir conn

The first file is the reference (the best geometry, or the first value); each file is a
``studies/exhaust_shell_front.py`` record (its "optimum": the mass-kept optimum against seed
Table 2).  Prints, per design variable, each optimum, its shift from the reference [%], and the
spread (largest minus smallest over all files, in % of the reference), beside seed Table 3.
"""

import argparse
import json
from pathlib import Path

import numpy as np

from bayesupdate.models.exhaust_paper import DESIGN_VARIABLES, TABLE3_INITIAL_SI, TABLE3_OPTIMUM_SI


def read_optima(paths) -> list[tuple[str, dict]]:
    """(label, optimum record) of each file: the label is its geometry (best without one) and
    its connection stiffness when set."""
    out = []
    for path in paths:
        doc = json.loads(Path(path).read_text())
        label = f"geometry {doc['options'].get('geometry', 'best')}"
        if "connection_k_rot" in doc["options"]:
            label += f", connections {doc['options']['connection_k_rot']:.0e} N m/rad"
        out.append((label, doc["optimum"]))
    return out


def calibrate_connections(values, out_dir: Path, starts: int, max_nfev: int) -> list[Path]:
    """One mass-kept optimum of ``exhaust_shell`` (mesh density 16) per connection stiffness in
    ``values`` [N m/rad] (all six connections at it), each written as a front record."""
    from exhaust_shell_front import optimum_and_front  # studies/ is the script's folder

    out_dir.mkdir(parents=True, exist_ok=True)
    paths = []
    for k in values:
        args = argparse.Namespace(
            model="exhaust_shell", starts=starts, max_nfev=max_nfev, refine=False, weights=0
        )
        path = out_dir / f"opt_connections_{k:.0e}.json"
        options = {"mesh_density": 16, "connection_k_rot": float(k)}
        write = lambda record, p=path: p.write_text(json.dumps(record, default=float))  # noqa: E731
        optimum_and_front(args, options, write)
        paths.append(path)
    return paths


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
    ap.add_argument("files", nargs="*", help="optimum records; the first is the reference")
    ap.add_argument(
        "--connections", nargs="+", type=float, help="calibrate at these connection stiffnesses"
    )
    ap.add_argument("--out-dir", type=Path, default=Path("connections"))
    ap.add_argument("--starts", type=int, default=2)
    ap.add_argument("--max-nfev", type=int, default=150)
    args = ap.parse_args()
    files = list(args.files)
    if args.connections:
        files += calibrate_connections(args.connections, args.out_dir, args.starts, args.max_nfev)
    optima = read_optima(files)
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
