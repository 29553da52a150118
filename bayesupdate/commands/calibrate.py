"""``bayesupdate calibrate``: point optimum of seed eq. 19 (multi-start bounded least squares)."""

import json
import sys

from bayesupdate.commands._shared import (
    add_compute_arguments,
    add_full_argument,
    add_study_arguments,
    add_write_bdf_argument,
    check_outputs,
    compute_from_args,
    report_refused,
    report_warnings,
    study_from_args,
    write_bdf,
)

NAME = "calibrate"
HELP = "point optimum of the model against test frequencies (seed eq. 19), multi-start"
DESCRIPTION = """Calibrate a model to test modal data: bounded least squares on the weighted
relative frequency errors (seed eq. 19), from a seeded space-filling set of starts, each end
polished by Nelder-Mead (tracked pairings put optima on kinks where gradients stall).  Built-in FE
models search on a certified reduced basis and polish every end on the full model; --full searches
on full solves throughout.

  bayesupdate calibrate study.toml --out result.h5
  bayesupdate calibrate --model exhaust --data paper:ema --out result.h5 --json

A measured mass in the data (paper:ema carries the seed's 12.29 kg) is data too: the objective
gets a mass term (weight 10, [objective] mass_weight) unless --no-mass.

Measured mass properties ([data] mass = "13.76 lb", cg, inertia, each with its unit and sd) are
data too: each adds a residual to the objective and a block to the likelihood.

Test data with shapes pair by MAC: at the reference design a test mode whose best pair has a
MAC below [pairing] mac_threshold (0.6) or a model frequency outside [pairing]
frequency_window (+-50 %) is refused, named on stderr and left out.  [data] modes = [1, 7, 10]
chooses the source's test modes (numbered as identify --json lists them), [data] weights one
weight per chosen mode.

--json prints {"parameters", "objective" (eq. 19 alone), "mass_kg", "measured_mass_kg",
"frequencies_hz", "targets_hz", "test_modes", "starts", "converged_starts", "pairing"
({"method", "mac_threshold", "frequency_window", "refused"}), "warnings",
"mass_properties" ([{name, measured, predicted, unit, sd}] at the optimum, in the model's own
units)}.  The residual table (test, model, error %, MAC) is printed otherwise, with a
warning when modes are swapped.
Warnings (stderr, "warnings", the result file): an optimum on a bound, a paired MAC below the
threshold or a pair outside the window at the optimum, fewer than half the starts at the
best."""


def add_arguments(parser) -> None:
    add_study_arguments(parser)
    add_compute_arguments(parser)
    add_full_argument(parser)
    add_write_bdf_argument(parser)
    parser.add_argument(
        "--no-polish",
        action="store_true",
        help="skip the Nelder-Mead polish of each start (faster; ends may stop on a kink); on a "
        "reduced basis the ends near the best are still polished on the full model",
    )


def calibration_json(result, problem, warnings=()) -> dict:
    """The ``calibrate --json`` object of a ``CalibrationResult`` of
    ``problem``, with the run's ``warnings`` (``inference.checks``)."""
    from bayesupdate.inference.mass_properties import mass_property_report

    return {
        "parameters": result.parameters,
        "objective": float(result.expr),
        "mass_kg": None if result.mass_kg is None else float(result.mass_kg),
        "frequencies_hz": [float(f) for f in result.frequencies_hz],
        "targets_hz": [float(f) for f in result.table.test_hz],
        "starts": int(result.starts),
        "converged_starts": int(result.converged_starts),
        "measured_mass_kg": problem.data.mass_kg,
        "mass_weight": problem.objective.mass_weight,
        "mass_properties": mass_property_report(problem, {**problem.fixed, **result.parameters}),
        "test_modes": [int(n) for n in problem.mode_numbers],
        "pairing": problem.pairing.to_dict(),
        "warnings": list(warnings),
    }


def _g(value) -> str:
    return "n/a" if value is None else f"{value:.6g}"


def run(args) -> int:
    check_outputs(args)  # before the imports below
    from bayesupdate.compute import progress
    from bayesupdate.compute.settings import open_executor
    from bayesupdate.inference.checks import calibration_warnings
    from bayesupdate.inference.results import write_result
    from bayesupdate.pipelines.calibrate import run_calibration
    from bayesupdate.pipelines.study import prepare

    study = study_from_args(args)
    compute = compute_from_args(args, study)
    prepared = prepare(study, effects=tuple(args.effect))
    report_refused(prepared.problem)
    with open_executor(compute) as executor:
        result = run_calibration(prepared, executor)
        where = executor.describe()
    warnings = calibration_warnings(prepared.problem, result)
    timings = progress.timings()
    if args.out:
        write_result(args.out, prepared.problem, result, study.to_dict(), command=NAME,
                     warnings=warnings, timings=timings)  # fmt: skip
    write_bdf(args.write_bdf, prepared.problem.model, result.parameters)
    report_warnings(warnings)
    if args.json:
        out = calibration_json(result, prepared.problem, warnings)
        print(json.dumps({**out, "compute": where, "timings": timings}))
    else:
        print(
            f"objective (seed eq. 19): {result.expr:.5g}   starts: {result.converged_starts}"
            f"/{result.starts} reach the best (within 1 %)"
        )
        for name, value in result.parameters.items():
            print(f"  {name} = {value:.6g}")
        if result.mass_kg is not None:
            measured = prepared.problem.data.mass_kg
            unit = prepared.problem.objective.mass_unit
            seen = "" if measured is None else f" (measured {measured:.4g} {unit})"
            print(f"  mass = {result.mass_kg:.4g} {unit}{seen}")
        report = calibration_json(result, prepared.problem)["mass_properties"]
        for row in (r for r in report if r["name"] != "mass"):
            print(f"  {row['name']} = {_g(row['predicted'])} {row['unit']} (measured "
                  f"{row['measured']:.6g} +- {row['sd']:.3g})")  # fmt: skip
        print(result.table.format())
        if result.failed_evaluations:
            print(
                f"model failed at {result.failed_evaluations} of {result.evaluations} points",
                file=sys.stderr,
            )
    return 0
