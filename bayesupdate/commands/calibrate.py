"""``bayesupdate calibrate``: point optimum of seed eq. 19 (multi-start bounded least squares)."""

import json
import sys

from bayesupdate.errors import BayesUpdateError

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
({"method", "mac_threshold", "frequency_window", "refused"}), "warnings", "mass_properties"
([{name, measured, predicted, unit, sd}] at the optimum, in the model's own units)}.  The
residual table (test, model, error %, MAC) is printed otherwise, with a warning when modes are
swapped.  Warnings (stderr, "warnings", the result file): an optimum on a bound, a paired MAC
below the threshold or a pair outside the window at the optimum, fewer than half the starts at
the best."""


def add_study_arguments(parser, sampling: bool = False) -> None:
    """Arguments shared by calibrate and sample."""
    parser.add_argument(
        "study", nargs="?", help="TOML study file (docs/reference/study-file.md); optional"
    )
    parser.add_argument("--model", help="built-in model name or package.module:function")
    parser.add_argument("--data", help="test data: paper:ema, a CSV frequency table, .h5 or .uff")
    parser.add_argument("--out", help="result file (HDF5)")
    parser.add_argument("--force", action="store_true", help="overwrite an existing --out")
    parser.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    parser.add_argument("--seed", type=int, help="random seed (optimizer and sampler)")
    parser.add_argument("--starts", type=int, help="number of optimizer starts")
    parser.add_argument(
        "--no-mass",
        action="store_true",
        help="ignore the data's measured mass (by default it is data: a mass term in the "
        "objective and, with its sd, in the likelihood)",
    )
    parser.add_argument(
        "--effect",
        action="append",
        default=[],
        metavar="SPEC",
        help="extend the model by an effect KIND@LOCATION[:name=value] (repeatable), e.g. one "
        "named by 'discover'",
    )
    if sampling:
        parser.add_argument("--steps", type=int, help="step budget of the sampler")
        parser.add_argument("--walkers", type=int, help="number of walkers")
        parser.add_argument("--resume", action="store_true", help="continue a partial --out")
        parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def add_compute_arguments(parser) -> None:
    """--workers / --scheduler: where independent tasks run (``parallel_executor``)."""
    parser.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="run independent tasks in N local processes (default: the study's [compute], "
        "else $BAYESUPDATE_SCHEDULER, else serial); results are the same bits",
    )
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run independent tasks on the workers of a Dask scheduler, e.g. tcp://head:8786 "
        "(pip install 'bayesupdate[dask]')",
    )


def compute_from_args(args, study):
    """``ComputeSettings`` from --workers/--scheduler, the study's [compute] table and
    $BAYESUPDATE_SCHEDULER (``parallel_executor.compute_settings``)."""
    from bayesupdate.parallel_executor import compute_settings

    return compute_settings(
        getattr(args, "workers", None),
        getattr(args, "scheduler", None),
        study.extensions.get("compute"),
    )


def study_from_args(args):
    """StudyConfig from a study file and/or --model/--data flags (flags win)."""
    from bayesupdate.config import StudyConfig, load_study, with_overrides

    if args.study is None and args.model is None:
        raise BayesUpdateError(f"{NAME}: give a STUDY.toml or --model (and --data)")
    study = load_study(args.study) if args.study else StudyConfig()
    changes = {
        "model__source": args.model,
        "data__source": args.data,
        "optimizer__seed": args.seed,
        "optimizer__starts": args.starts,
        "sampler__seed": args.seed,
        "sampler__steps": getattr(args, "steps", None),
        "sampler__walkers": getattr(args, "walkers", None),
        "sampler__reduced": False if getattr(args, "full", False) else None,
        "optimizer__polish": False if getattr(args, "no_polish", False) else None,
        "objective__use_measured_mass": False if getattr(args, "no_mass", False) else None,
    }
    study = with_overrides(study, **changes)
    # --data replaces inline data of the study file entirely, with its choice of modes
    if args.data is not None and study.data.frequencies_hz is not None:
        from dataclasses import replace

        study = replace(
            study,
            data=replace(study.data, frequencies_hz=None, weights=None, sd_hz=None, modes=None),
        )
    return study


def write_bdf(path, model, values) -> None:
    """``--write-bdf``: the Nastran deck with ``values`` in its bound fields (no path: nothing)."""
    if path:
        from bayesupdate.nastran.writer import write_updated_deck

        write_updated_deck(model, values, path)


def add_write_bdf_argument(parser) -> None:
    parser.add_argument(
        "--write-bdf",
        metavar="FILE",
        help="Nastran deck model: write the deck with the calibrated values (calibrate: the "
        "optimum; sample: the posterior mean) in its bound fields",
    )


def add_full_argument(parser) -> None:
    parser.add_argument(
        "--full",
        action="store_true",
        help="full FE solves (no certified reduced basis) for FE models and Nastran decks",
    )


def add_arguments(parser) -> None:
    add_study_arguments(parser)
    add_compute_arguments(parser)
    add_full_argument(parser)
    add_write_bdf_argument(parser)
    parser.add_argument(
        "--no-polish",
        action="store_true",
        help="skip the Nelder-Mead polish of each start (faster; ends may stop on a kink)",
    )


def report_refused(problem) -> None:
    """The test modes the pairing refused at the reference design, one line each on stderr."""
    pairing = problem.pairing
    for refused in pairing.refused:
        print(f"pairing: {refused.message(pairing.rules)}", file=sys.stderr)


def report_warnings(warnings) -> None:
    """One ``warning:`` line per warning on stderr."""
    for line in warnings:
        print(f"warning: {line}", file=sys.stderr)


def calibration_json(result, problem, warnings=()) -> dict:
    """The ``calibrate --json`` object (issue 4 item 10) of a ``CalibrationResult`` of
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
        "test_modes": [int(n) for n in problem.mode_numbers],
        "pairing": problem.pairing.to_dict(),
        "warnings": list(warnings),
        "mass_properties": mass_property_report(problem, {**problem.fixed, **result.parameters}),
    }


def _g(value) -> str:
    return "n/a" if value is None else f"{value:.6g}"


def run(args) -> int:
    from bayesupdate.atomic import check_output_path
    from bayesupdate.inference.checks import calibration_warnings
    from bayesupdate.inference.results import write_result
    from bayesupdate.parallel_executor import open_executor
    from bayesupdate.pipelines.calibrate import run_calibration
    from bayesupdate.pipelines.study import prepare

    study = study_from_args(args)
    if args.out:
        check_output_path(args.out, args.force)
    if args.write_bdf:
        check_output_path(args.write_bdf, args.force)
    compute = compute_from_args(args, study)
    prepared = prepare(study, effects=tuple(args.effect))
    report_refused(prepared.problem)
    with open_executor(compute) as executor:
        result = run_calibration(prepared, executor)
        where = executor.describe()
    warnings = calibration_warnings(prepared.problem, result)
    if args.out:
        write_result(args.out, prepared.problem, result, study.to_dict(), command=NAME,
                     warnings=warnings)  # fmt: skip
    write_bdf(args.write_bdf, prepared.problem.model, result.parameters)
    report_warnings(warnings)
    if args.json:
        out = calibration_json(result, prepared.problem, warnings)
        print(json.dumps({**out, "compute": where}))
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
