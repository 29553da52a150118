"""``bayesupdate simulate``: a virtual roving-hammer test of a model or Nastran deck, to UFF 58."""

import json

import numpy as np

from bayesupdate.commands._shared import deck_set_values, seed_value

NAME = "simulate"
HELP = "virtual impact test of a model or deck (optionally with a hidden effect) -> UFF 58"
DESCRIPTION = """Simulate the seed's modal test on an FE model (built-in, or a Nastran deck): roving
hammer over the 20 sensor points (a deck: its test points), one fixed accelerometer per set (a
vertical set with its driving point at 1V and a horizontal set at 1H), 19 V + 20 H FRFs (+1
cross FRF tying the two sets), 0-150 Hz, modal damping 0.5-3 %, relative measurement noise on
the time signals.  UFF node numbers are the sensor numbers; direction 3 is V (z), 2 is H (y).

Examples:
  bayesupdate simulate --model exhaust --out test.uff
  bayesupdate simulate --model exhaust --set t_cold_pipe=1.3mm \\
      --effect joint_flexibility@cold_pipe/main_muffler:k_rot=2e3 --noise 0.01 --seed 3 \\
      --out hidden.uff --json
  bayesupdate simulate --geometry tail_length=0.15 --out longer_tail.uff

A Nastran deck has no sensor layout of its own: give its test points (test node -> GRID id) in a
--test-points file or the --study's [model.test_points]; V (z) and H (y) are measured at each
point, in the basic frame or the GRID's output (CD) frame (frame = "output").  --set names the
study's bound parameters, or is a binding itself, in the deck's units:
  bayesupdate simulate --model exhaust.bdf --test-points points.csv \\
      --set "PSHELL 3 T=0.0595" --out test.uff
  bayesupdate simulate --study study.toml --set t_3=0.0595 --out test.uff

--geometry changes one quantity of the exhaust's fitted geometry (metres, names as in
bayesupdate/data/exhaust_geometry.json) in the 'true' structure only: a change outside the
discovery library, for testing that discovery does not name what is not there."""


def add_arguments(parser):
    parser.add_argument(
        "--model",
        default=None,
        help="built-in model or Nastran deck (.bdf/.dat/.nas/.blk); default: the --study's "
        "[model] source, else exhaust",
    )
    parser.add_argument(
        "--study",
        metavar="FILE",
        help="Nastran deck: take the model, its [model.test_points] and its bound [parameters] "
        "(--set NAME=VALUE names them) from this study file",
    )
    parser.add_argument(
        "--test-points",
        metavar="FILE",
        help="Nastran deck: test points (CSV rows 'point,grid[,frame]', or TOML "
        '"12" = 1012 / set = 5); V (z) and H (y) are measured at each',
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="parameter value of the 'true' structure (repeatable)",
    )
    parser.add_argument(
        "--effect",
        action="append",
        default=[],
        metavar="SPEC",
        help="hidden effect KIND@LOCATION[:name=value] (repeatable)",
    )
    parser.add_argument(
        "--geometry",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="exhaust only: a geometry quantity of the 'true' structure in metres (repeatable)",
    )
    parser.add_argument(
        "--noise", type=float, default=0.01, help="relative time-signal noise (default 0.01)"
    )
    parser.add_argument("--seed", type=seed_value, default=0, help="random seed (default 0)")
    parser.add_argument(
        "--modes",
        type=int,
        default=20,
        help="modes superposed (default 20; those above 150 Hz act as residuals)",
    )
    parser.add_argument("--out", required=True, help="output UFF file (dataset 58)")
    parser.add_argument("--force", action="store_true", help="overwrite --out if it exists")
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def true_geometry(model_name: str, assignments: list[str]) -> dict:
    """The model options of ``--geometry NAME=VALUE`` (exhaust only): {} without any, else
    {"geometry": the best-fit geometry with those quantities replaced}."""
    from bayesupdate.errors import BayesUpdateError
    from bayesupdate.models.exhaust import fitted_geometry, full_geometry

    if not assignments:
        return {}
    if model_name != "exhaust":
        raise BayesUpdateError(
            f"--geometry: only the exhaust model has a geometry, not {model_name!r}"
        )
    geometry = fitted_geometry("best")
    for text in assignments:
        name, _, value = text.partition("=")
        try:
            number = float(value)
        except ValueError:
            raise BayesUpdateError(f"--geometry {text!r}: give NAME=VALUE in metres") from None
        if not (np.isfinite(number) and number > 0):
            raise BayesUpdateError(f"--geometry {text!r}: the value must be a length > 0 m")
        geometry[name.strip()] = number
    full_geometry(geometry)  # unknown names: one-line error naming them
    return {"geometry": geometry}


def run(args) -> int:
    from bayesupdate.atomic import check_output_path
    from bayesupdate.discovery.effects import parse_effect_spec
    from bayesupdate.ema.uff_io import write_uff58
    from bayesupdate.errors import BayesUpdateError
    from bayesupdate.pipelines.simulate import VirtualTestSettings, simulate_test

    if not (0.0 <= args.noise < 1.0):
        raise BayesUpdateError(f"--noise must be in [0, 1), got {args.noise}")
    if args.modes < 1:
        raise BayesUpdateError(f"--modes must be >= 1, got {args.modes}")
    out = check_output_path(args.out, force=args.force)
    effects = tuple(parse_effect_spec(spec) for spec in args.effect)
    model, params = tested_model(args)
    settings = VirtualTestSettings(params, effects, args.noise, args.seed, args.modes)
    test = simulate_test(model, settings)
    frfs = test.frfs
    write_uff58(out, frfs)
    in_band = test.frequencies_hz <= frfs.frequencies_hz[-1]
    summary = {
        "out": str(out),
        "n_frf": int(frfs.n_frf),
        "n_lines": int(frfs.frequencies_hz.size),
        "effects": list(test.effects),
        "geometry": list(args.geometry),
        "true_frequencies_hz": [round(float(f), 6) for f in test.frequencies_hz[in_band]],
        "true_damping_ratio": [round(float(z), 6) for z in test.damping_ratio[in_band]],
        "mass_kg": float(test.mass_kg),
        "parameters": {k: float(v) for k, v in test.parameters.items()},
        "reference_points": {"V": test.reference_points[0], "H": test.reference_points[1]},
    }
    deck = model.structure.metadata.get("nastran") if hasattr(model, "structure") else None
    if deck:  # a deck's mass is in its own units
        summary["units"] = deck["units"]
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"wrote {summary['n_frf']} FRFs x {summary['n_lines']} lines to {out}")
        print(
            "true modes in band [Hz]: "
            + ", ".join(f"{f:.2f}" for f in summary["true_frequencies_hz"])
        )
    return 0


def tested_model(args):
    """(model, true parameters) of ``simulate``'s arguments: a built-in model with ``--set``
    values (SI units), or a Nastran deck measured at its test points (``--test-points``, else the
    ``--study``'s [model.test_points]) whose ``--set`` names are the study's bound parameters or
    bindings themselves (``--set "PSHELL 3 T=0.06"``), values in the deck's units."""
    from bayesupdate.config import load_study
    from bayesupdate.errors import BayesUpdateError
    from bayesupdate.pipelines.model_source import deck_test_model, is_deck, resolve_model
    from bayesupdate.units import parse_assignments

    study = load_study(args.study) if args.study else None
    source = args.model or (study.model.source if study else "exhaust")
    if not is_deck(source):
        if study or args.test_points:
            raise BayesUpdateError(
                f"--study / --test-points: only for a Nastran deck model, not {source!r}"
            )
        model = resolve_model(source, options=true_geometry(source, args.geometry))
        if not hasattr(model, "solve"):
            raise BayesUpdateError(f"model {source!r} is not an FE model; 'simulate' needs one")
        return model, parse_assignments(args.set)
    from bayesupdate.nastran.test_points import read_test_points

    if args.geometry:
        raise BayesUpdateError("--geometry: only the exhaust model has a geometry")
    tables = dict(study.parameters) if study else {}
    params = deck_set_values(args.set)
    for name in params:
        tables.setdefault(name, {"binds": name})  # not a study parameter: a binding itself
    table = read_test_points(args.test_points) if args.test_points else None
    if table is None and study:
        table = study.model.test_points
    return deck_test_model(source, tables, table), params
