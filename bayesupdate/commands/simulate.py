"""``bayesupdate simulate``: a virtual roving-hammer test of a built-in model, to UFF 58."""

import json

import numpy as np

NAME = "simulate"
HELP = "virtual impact test of a model (optionally with a hidden effect) -> FRFs in UFF 58"
DESCRIPTION = """Simulate the seed's modal test on a built-in FE model: roving hammer over the 20
sensor points, one fixed accelerometer per set (a vertical set with its driving point at 1V and a
horizontal set at 1H), 19 V + 20 H FRFs (+1 cross FRF tying the two sets), 0-150 Hz, modal
damping 0.5-3 %, relative measurement noise on the time signals.  UFF node numbers are the
sensor numbers; direction 3 is V (z), 2 is H (y).

Examples:
  bayesupdate simulate --model exhaust --out test.uff
  bayesupdate simulate --model exhaust --set t_cold_pipe=1.3mm \\
      --effect joint_flexibility@cold_pipe/main_muffler:k_rot=2e3 --noise 0.01 --seed 3 \\
      --out hidden.uff --json
  bayesupdate simulate --geometry tail_length=0.15 --out longer_tail.uff

--geometry changes one quantity of the exhaust's fitted geometry (metres, names as in
bayesupdate/data/exhaust_geometry.json) in the 'true' structure only: a change outside the
discovery library, for testing that discovery does not name what is not there."""


def add_arguments(parser):
    parser.add_argument("--model", default="exhaust", help="built-in model (default exhaust)")
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
    parser.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
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
    from bayesupdate.models import get_model
    from bayesupdate.pipelines.simulate import VirtualTestSettings, simulate_test
    from bayesupdate.units import parse_assignments

    if not (0.0 <= args.noise < 1.0):
        raise BayesUpdateError(f"--noise must be in [0, 1), got {args.noise}")
    if args.modes < 1:
        raise BayesUpdateError(f"--modes must be >= 1, got {args.modes}")
    out = check_output_path(args.out, force=args.force)
    effects = tuple(parse_effect_spec(spec) for spec in args.effect)
    params = parse_assignments(args.set)
    model = get_model(args.model, **true_geometry(args.model, args.geometry))
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
        "reference_points": {"V": test.reference_points[0], "H": test.reference_points[1]},
    }
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"wrote {summary['n_frf']} FRFs x {summary['n_lines']} lines to {out}")
        print(
            "true modes in band [Hz]: "
            + ", ".join(f"{f:.2f}" for f in summary["true_frequencies_hz"])
        )
    return 0
