"""What several commands share: their common arguments, the study they build from a study file
and flags, the model and data of ``correlate`` / ``sensitivity``, and what they print at the end.

No command module imports another; each imports what it shares from here.  The model itself is
resolved in one place, ``pipelines.model_source``.
"""

import json
import sys
from dataclasses import replace
from pathlib import Path

from bayesupdate.errors import BayesUpdateError


# --- arguments -----------------------------------------------------------------------------
def seed_value(text: str) -> int:
    """An argparse type: a random seed, an integer >= 0 (numpy's generators take no other)."""
    import argparse

    try:
        seed = int(text)
    except ValueError:
        seed = -1
    if seed < 0:
        raise argparse.ArgumentTypeError(f"{text!r}: give an integer >= 0")
    return seed


def add_study_arguments(parser, sampling: bool = False) -> None:
    """Arguments shared by calibrate, sample and discover."""
    parser.add_argument(
        "study", nargs="?", help="TOML study file (docs/reference/study-file.md); optional"
    )
    parser.add_argument("--model", help="built-in model name or package.module:function")
    parser.add_argument("--data", help="test data: paper:ema, a CSV frequency table, .h5 or .uff")
    parser.add_argument("--out", help="result file (HDF5)")
    parser.add_argument("--force", action="store_true", help="overwrite an existing --out")
    parser.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    parser.add_argument("--seed", type=seed_value, help="random seed (optimizer and sampler)")
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
    """--workers / --scheduler: where independent tasks run (``compute.executors``)."""
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


def add_correlate_arguments(parser) -> None:
    """The inputs and outputs of ``correlate`` (and ``sensitivity``, which adds its own)."""
    parser.add_argument("study", nargs="?", help="TOML study file ([model], [data]); optional")
    parser.add_argument("--model", help="built-in model, Nastran deck or package.module:function")
    parser.add_argument("--data", help="test modes: .h5 or .uff (shapes), a CSV table, paper:ema")
    parser.add_argument(
        "--test-points",
        metavar="FILE",
        help="Nastran deck: test node -> GRID table (CSV 'point,grid[,frame]' or TOML)",
    )
    parser.add_argument(
        "--geometry",
        metavar="FILE",
        help="test geometry (UFF 15/2411/2420/82 .unv/.uff or CSV): aligned (auto) and paired "
        "with the model instead of the study's [test] table",
    )
    parser.add_argument(
        "--length-unit",
        metavar="UNIT",
        help="--geometry's length unit where the file has no UFF 164 record (mm, m, in, ft)",
    )
    parser.add_argument(
        "--pair-tolerance",
        metavar="LENGTH",
        help="--geometry: farthest a test point may lie from the model (e.g. '5 mm'; 0.01 m)",
    )
    parser.add_argument(
        "--mac-threshold",
        type=float,
        default=None,
        metavar="X",
        help="refuse pairs below this MAC (default: the study's [pairing] mac_threshold, 0.6)",
    )
    parser.add_argument(
        "--frequency-window",
        type=float,
        default=None,
        metavar="W",
        help="refuse pairs with |f_model / f_test - 1| > W (default: the study's [pairing] "
        "frequency_window, 0.5; inf: none)",
    )
    parser.add_argument(
        "--extra-modes",
        type=int,
        default=None,
        metavar="N",
        help="model modes computed beyond the test's highest (default: the study's [pairing] "
        "extra_modes, 2)",
    )
    parser.add_argument("--out", help="result file (HDF5)")
    parser.add_argument("--report", metavar="DIR", help="write DIR/report.html and DIR/report.md")
    parser.add_argument("--force", action="store_true", help="overwrite --out / --report files")
    parser.add_argument("--json", action="store_true", help="print one JSON object on stdout")


# --- values of arguments -------------------------------------------------------------------


def plot_folder(folder, flag: str = "--plots"):
    """The folder a command writes figures (or the demo its files) to, made and write-probed
    before any work (a file, or a place nothing can be written, is one error line); None for
    None."""
    from bayesupdate.atomic import make_writable_folder

    if folder is None:
        return None
    path = Path(folder)
    if path.exists() and not path.is_dir():
        raise BayesUpdateError(f"{flag} {path}: is a file; give a folder")
    try:
        make_writable_folder(path)
    except OSError:
        raise BayesUpdateError(f"{flag} {path}: cannot write there; choose another") from None
    return path


def parse_band(text: str | None) -> tuple[float, float] | None:
    """``--band LO:HI`` [Hz] -> (lo, hi); None without one; one-line error otherwise."""
    if text is None:
        return None
    try:
        lo, hi = (float(x) for x in text.split(":"))
    except ValueError:
        raise BayesUpdateError(f"--band {text!r}: give LO:HI in Hz, e.g. 60:500") from None
    return lo, hi


def deck_set_values(items) -> dict[str, float]:
    """``--set`` items on a Nastran deck -> {name: value}: plain numbers in the deck's units (a
    unit suffix is refused: the deck's unit system is its own); one-line error otherwise."""
    params = {}
    for item in items:
        name, _, value = item.partition("=")
        try:
            params[name.strip()] = float(value)
        except ValueError:
            raise BayesUpdateError(
                f"--set {item!r}: give NAME=VALUE, a plain number in the deck's units"
            ) from None
    return params


def compute_from_args(args, study):
    """``ComputeSettings`` from --workers/--scheduler, the study's [compute] table and
    $BAYESUPDATE_SCHEDULER (``config.compute_settings``)."""
    from bayesupdate.config import compute_settings

    return compute_settings(
        getattr(args, "workers", None),
        getattr(args, "scheduler", None),
        study.extensions.get("compute"),
    )


# --- the study -----------------------------------------------------------------------------


def study_from_args(args):
    """StudyConfig from a study file and/or --model/--data flags (flags win); the optimizer's and
    sampler's flags (--seed, --starts, --steps, --walkers, --moves, --full, --no-polish) where
    the command has them."""
    return study_file(
        args,
        optimizer__seed=args.seed,
        optimizer__starts=args.starts,
        sampler__seed=args.seed,
        sampler__steps=getattr(args, "steps", None),
        sampler__walkers=getattr(args, "walkers", None),
        sampler__moves=getattr(args, "moves", None),
        sampler__reduced=False if getattr(args, "full", False) else None,
        optimizer__polish=False if getattr(args, "no_polish", False) else None,
    )


def study_file(args, **changes):
    """The study file (or the default study) with --model, --data, --no-mass and ``changes``
    (``config.with_overrides``: ``section__key=value``, None left out) applied in one step;
    --data replaces inline data of the study file entirely, with its choice of modes."""
    from bayesupdate.config import StudyConfig, load_study, with_overrides

    if args.study is None and args.model is None:
        raise BayesUpdateError(f"{args.command}: give a STUDY.toml or --model (and --data)")
    study = load_study(args.study) if args.study else StudyConfig()
    study = with_overrides(
        study,
        model__source=args.model,
        data__source=args.data,
        objective__use_measured_mass=False if getattr(args, "no_mass", False) else None,
        **changes,
    )
    if args.data is not None and study.data.frequencies_hz is not None:
        cleared = dict(frequencies_hz=None, weights=None, sd_hz=None, modes=None)
        study = replace(study, data=replace(study.data, **cleared))
    return study


def correlate_study(args):
    """(study, data): the study of ``correlate`` / ``sensitivity`` (a study file and/or
    --model/--data/--test-points/--geometry; flags win) and its test data with the study's
    ``[data] modes`` (``inference.data.select_modes``; a mode the source lacks: one-line
    error), so only those test modes are paired and reported."""
    from bayesupdate.inference.data import load_modal_data, select_modes

    study = _with_geometry(study_file(args), args)
    if args.test_points:
        from bayesupdate.nastran.test_points import read_test_points

        points = read_test_points(args.test_points)
        study = replace(study, model=replace(study.model, test_points=points))
    cfg = study.data
    data, numbers = select_modes(load_modal_data(cfg.as_source()), cfg.selection(), cfg.label)
    return study, data, numbers


def correlate_settings(args, study):
    """The ``pipelines.correlate.CorrelateSettings`` of ``correlate`` / ``sensitivity``: the
    study's ``[pairing]`` mac_threshold, frequency_window and extra_modes (the rules and the
    model modes ``calibrate``, ``sample`` and ``discover`` pair with), each overridden by its
    flag; a bad flag value: one line naming the flag."""
    from bayesupdate.inference.pairing import PairingRules, check_rules
    from bayesupdate.pipelines.correlate import CorrelateSettings

    cfg = study.pairing
    threshold = cfg.mac_threshold if args.mac_threshold is None else args.mac_threshold
    window = cfg.frequency_window if args.frequency_window is None else args.frequency_window
    check_rules(threshold, window, ("--mac-threshold", "--frequency-window"))
    extra = cfg.extra_modes if args.extra_modes is None else args.extra_modes
    return CorrelateSettings(PairingRules(threshold, window), extra)


def _with_geometry(study, args):
    """The study with ``--geometry`` (and its unit and tolerance) as its ``[test]`` table."""
    from bayesupdate.config import parse_test_table

    geometry = getattr(args, "geometry", None)
    unit, tol = getattr(args, "length_unit", None), getattr(args, "pair_tolerance", None)
    if not geometry:
        if unit or tol:
            raise BayesUpdateError(f"{args.command}: --length-unit and --pair-tolerance need "
                                   "--geometry")  # fmt: skip
        return study
    table = {"geometry": geometry, "length_unit": unit, "pair_tolerance": tol}
    table = {k: v for k, v in table.items() if v is not None}
    return replace(study, test=parse_test_table(table, "--geometry"))


# --- what commands print -------------------------------------------------------------------


def report_refused(problem) -> None:
    """The test modes the pairing refused at the reference design, one line each on stderr."""
    pairing = problem.pairing
    for refused in pairing.refused:
        print(f"pairing: {refused.message(pairing.rules)}", file=sys.stderr)


def report_warnings(warnings) -> None:
    """One ``warning:`` line per warning on stderr."""
    for line in warnings:
        print(f"warning: {line}", file=sys.stderr)


def write_bdf(path, model, values) -> None:
    """``--write-bdf``: the Nastran deck with ``values`` in its bound fields (no path: nothing)."""
    if path:
        from bayesupdate.nastran.writer import write_updated_deck

        write_updated_deck(model, values, path)


def emit(args, record: dict, text: str, report) -> int:
    """What a command that writes a result file and a report prints at its end: with
    ``args.json`` ``record`` (plus ``out`` and ``report``) as one JSON object, else ``text``
    and a "wrote PATH" line per file written; 0."""
    if args.json:
        record.update(out=args.out, report=None if report is None else str(report))
        print(json.dumps(record))
        return 0
    print(text)
    for path in (args.out, report):
        if path:
            print(f"wrote {path}")
    return 0


def check_outputs(args, resume: bool = False) -> None:
    """Refuse ``--out``, and ``--write-bdf`` where the command has it, naming a file that is
    there, unless ``--force`` (``resume``: the partial result ``--out`` names may be there).
    Commands call it before their heavy imports (seconds), so a file in the way is said at
    once (``atomic.check_output_path``)."""
    from bayesupdate.atomic import check_output_path

    names = ("out", "report", "plots", "write_bdf")
    values = [getattr(args, name, None) for name in names]
    for name, value in zip(names, values, strict=True):
        if value is not None and not str(value).strip():  # "" is no path, not "no output"
            raise BayesUpdateError(f"--{name.replace('_', '-')}: give a path, not an empty text")
    if args.out:
        check_output_path(args.out, args.force or resume)
    if getattr(args, "write_bdf", None):
        check_output_path(args.write_bdf, args.force)
    given = [Path(value).resolve() for value in values if value]
    if len(set(given)) < len(given):
        raise BayesUpdateError(
            "--out, --report, --plots and --write-bdf name the same path; give each its own"
        )
