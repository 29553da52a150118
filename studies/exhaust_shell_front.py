"""The calibrated optimum and the front of Expr against the mass error of one exhaust model, as a
file the comparison of the two exhausts reads (``report.exhaust_comparison``).

    PYTHONPATH=. OPENBLAS_NUM_THREADS=1 python studies/exhaust_shell_front.py exhaust \\
        --out studies/out/front_exhaust.json
    PYTHONPATH=. OPENBLAS_NUM_THREADS=1 python studies/exhaust_shell_front.py exhaust_shell \\
        --mesh-density 16 --out studies/out/front_exhaust_shell.json

As ``studies/paper_optimum.py`` does for the beam model: the problem against seed Table 2 with the
measured 12.29 kg kept (mass term, weight 10; tracked pairing at the initial design); the
multi-start search on the certified reduced basis (14 modes, tol 1e-4), its ends polished on the
full model with ``--refine`` (the optimum; without, its basis error is checked by a full solve);
then the front: the same fit for each weight of the mass term (``inference.pareto_front_mass``,
ends not polished: each point may sit a few % above its polished value). Writes one JSON,
rewritten after every step (an interrupted run keeps its points): {"model", "options", "basis",
"optimum": {"expr", "mass_kg", "parameters", "swapped", "polished_on_full_model",
"basis_error_at_optimum"}, "front": [{"mass_weight", "expr", "mass_kg", "mass_error_pct",
"parameters", "swapped"}], "wall_s"}.
"""

import argparse
import json
import time
from pathlib import Path

import numpy as np

from bayesupdate.fe.reduced import reduced_model_for
from bayesupdate.inference import (
    CalibrationSettings,
    ObjectiveSpec,
    build_problem,
    calibrate,
    load_modal_data,
    pareto_front_mass,
)
from bayesupdate.models import get_model
from bayesupdate.models.exhaust_paper import MEASURED_MASS_KG


def _problems(name: str, options: dict):
    """(full problem, problem on the certified basis, the basis) against Table 2, mass kept."""
    fe = get_model(name, **options)
    data = load_modal_data("paper:ema")
    objective = ObjectiveSpec(mass_target_kg=MEASURED_MASS_KG, mass_weight=10.0)
    problem = build_problem(fe, data, None, pairing="tracked", objective=objective)
    rom = reduced_model_for(fe, tol=1e-4, seed=0, n_modes=14)
    search = build_problem(rom, data, None, pairing="tracked", objective=objective)
    return problem, search, rom


def optimum_and_front(args, options: dict, write) -> dict:
    """The mass-kept optimum, then the front one weight at a time; ``write(record)`` after each
    step, so an interrupted run keeps what it computed."""
    t0 = time.perf_counter()
    problem, search, rom = _problems(args.model, options)
    print(f"{args.model}: basis {rom.summary()} after {time.perf_counter() - t0:.0f} s", flush=True)
    fit = CalibrationSettings(starts=args.starts, seed=0, max_nfev=args.max_nfev)
    best = calibrate(search, fit, refine=problem if args.refine else None)
    _, error = rom.certify_at(best.theta[None, :], best.names)
    record = {
        "model": args.model, "options": options, "basis": rom.summary(),
        "optimum": {"expr": best.expr, "mass_kg": best.mass_kg, "parameters": best.parameters,
                    "swapped": best.swapped, "polished_on_full_model": args.refine,
                    "basis_error_at_optimum": float(error)},
        "front": [], "wall_s": time.perf_counter() - t0,
    }  # fmt: skip
    print(f"{args.model}: optimum Expr {best.expr:.4f}, mass {best.mass_kg:.3f} kg", flush=True)
    write(record)
    for w in np.geomspace(1e-3, 1e3, args.weights):
        (point,) = pareto_front_mass(
            search, MEASURED_MASS_KG, [w], starts=args.starts, polish=False
        )
        record["front"].append(point)
        record["wall_s"] = time.perf_counter() - t0
        err = point["mass_error_pct"]
        print(f"  weight {w:8.3g}: Expr {point['expr']:.4f}, mass error {err:+.2f} %, "
              f"swapped {point['swapped']}", flush=True)  # fmt: skip
        write(record)
    return record


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("model", choices=("exhaust", "exhaust_shell"))
    ap.add_argument("--mesh-density", type=int, default=None, help="exhaust_shell only")
    ap.add_argument("--geometry", type=int, default=None, help="a runner-up geometry (1, 2, 3)")
    ap.add_argument("--starts", type=int, default=4, help="optimizer starts per fit (4)")
    ap.add_argument("--max-nfev", type=int, default=None, help="evaluations per start")
    ap.add_argument("--refine", action="store_true", help="polish the optimum on the full model")
    ap.add_argument(
        "--weights", type=int, default=9, help="mass-term weights 1e-3..1e3 (9; 0: no front)"
    )
    ap.add_argument("--out", required=True, help="the JSON file to write")
    args = ap.parse_args()
    options = {} if args.mesh_density is None else {"mesh_density": args.mesh_density}
    if args.geometry is not None:
        options["geometry"] = args.geometry
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)

    def write(record):
        out.write_text(json.dumps(record, indent=1, default=float))

    record = optimum_and_front(args, options, write)
    print(f"wrote {out} ({record['wall_s']:.0f} s)")


if __name__ == "__main__":
    main()
