"""``bayesupdate modes``: the FE modal analysis of a built-in model at a parameter point."""

import json

import numpy as np

from bayesupdate.commands._shared import deck_set_values
from bayesupdate.units import parse_assignments

NAME = "modes"
HELP = "FE normal modes of a built-in model or a Nastran deck (frequencies, mass, energies)"
DESCRIPTION = """Free-free modal analysis (seed section 3, eqs 1-2) of a built-in model, or of a
Nastran deck (.bdf, .dat, .nas, .blk), read by bayesupdate's own bulk-data reader.

Examples:
  bayesupdate modes --model exhaust
  bayesupdate modes --model exhaust --set t_hot_pipe=2.08mm --set rho_catalyst=8.9e-9t/mm3 --json
  bayesupdate modes --model exhaust.bdf --modes 10 --json
  bayesupdate modes --model exhaust.bdf --set "PSHELL 3 T=0.0595" --json
  bayesupdate modes --model exhaust_shell --sed-map sed/

A Nastran deck is solved in its own units (the JSON's "mass" is in its "mass_unit", and a deck
whose PARAM WTMASS is 1/g also gives its "weight"; "units" says which system was recognized)
with its SPC set, PARAM WTMASS and EIGRL count; its --set names are deck fields
("PSHELL 3 T=0.0595", "MAT1 2 E scale=1.1"), plain numbers in the deck's units.
The JSON also gives the centre of gravity "cg" ("cg_unit") and the inertia about it ("inertia":
ixx, iyy, izz, ixy, ixz, iyz in "inertia_unit"; products with Nastran's CONM2 sign; a WTMASS
deck also gives "inertia_weight" as MSC's grid point weight generator prints it).

Values are SI unless a unit is given (mm, t/mm3, kg/m3, GPa, ...).  Without --json a table shows
each mode's frequency and the share of its strain energy in each part (seed section 3.2).
--sed-map DIR writes, for a model with shells, one PNG per mode: the modal strain energy per unit
area of every shell element drawn on the mesh (seed Fig. 6)."""


def add_arguments(parser):
    parser.add_argument(
        "--model", default="exhaust", help="built-in model name or Nastran deck (default exhaust)"
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help='parameter value, repeatable (e.g. t_hot_pipe=2.08mm; a deck: "PSHELL 3 T=0.06")',
    )
    parser.add_argument(
        "--modes", type=int, default=None, help="number of elastic modes (12; a deck: its EIGRL)"
    )
    parser.add_argument(
        "--geometry",
        default=None,
        help="exhaust only: table1 (default), two_design, NAME:k (k-th runner-up), or an index",
    )
    parser.add_argument(
        "--sed-map",
        default=None,
        metavar="DIR",
        help="models with shells: write each mode's strain-energy density map (PNG) into DIR",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object")


def run(args) -> int:
    from bayesupdate.errors import BayesUpdateError

    if args.modes is not None and args.modes < 1:
        raise BayesUpdateError(f"--modes must be >= 1, got {args.modes}")
    model, params = _model_and_values(args)
    if not hasattr(model, "solve"):
        raise BayesUpdateError(f"model {args.model!r} is not an FE model; 'modes' needs one")
    deck = model.structure.metadata.get("nastran", {})
    n_modes = args.modes or deck.get("n_modes") or 12
    if args.sed_map is not None:
        _check_sed_map(model, args)
    result = model.solve(params, n_modes=n_modes, energies=not args.json or bool(args.sed_map))
    if args.sed_map is not None:
        _write_sed_maps(model, result, args.sed_map)
    if args.json:
        out = {
            "frequencies_hz": [round(float(f), 6) for f in result.frequencies_hz],
            "rigid_modes": int(result.modes.n_rigid),
            **mass_record(result.mass_kg, deck.get("units")),
            **inertia_record(model.mass_properties(params), deck.get("units")),
            "n_dof": int(model.structure.n_dof),
            "parameters": {k: float(v) for k, v in result.parameters.items()},
        }
        if deck:
            out.update(units=deck["units"], notes=deck["notes"])
        print(json.dumps(out))
        return 0
    print(format_modes_table(result, deck.get("units"), model.mass_properties(params)))
    return 0


def mass_record(mass: float, units: dict | None) -> dict:
    """The JSON's mass in the model's own units: ``mass`` and ``mass_unit`` always;
    ``mass_kg`` only where that unit is kg (a built-in model, an SI deck); ``weight`` and
    ``weight_unit`` for a deck whose mass input is weight (PARAM WTMASS = 1/g)."""
    unit = "kg" if units is None else units["mass"]
    out = {"mass": float(mass), "mass_unit": unit}
    if unit == "kg":
        out["mass_kg"] = float(mass)
    if units is not None and units.get("weight"):
        out.update(weight=float(mass) / units["wtmass"], weight_unit=units["weight"])
    return out


def inertia_record(props, units: dict | None) -> dict:
    """The JSON's centre of gravity and inertia about it (``fe.mass_properties``) in the
    model's own units: ``cg`` (3,) with ``cg_unit``, ``inertia`` {ixx, iyy, izz, ixy, ixz,
    iyz} (products as Nastran's CONM2 / weight generator I(S): Ixy = integral of x y dm) with
    ``inertia_unit``; a deck whose mass input is weight (PARAM WTMASS) also gives
    ``inertia_weight`` (inertia / WTMASS, as MSC's grid point weight generator prints it) in
    ``inertia_weight_unit``."""
    from bayesupdate.inference.mass_properties import model_units

    names = model_units(units)
    values = props.as_dict()
    # + 0.0: a product that is -0.0 prints as 0.0
    inertia = {k: values[k] + 0.0 for k in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")}
    out = {
        "cg": [float(c) + 0.0 for c in props.cg],
        "cg_unit": names.length,
        "inertia": inertia,
        "inertia_unit": names.inertia,
    }
    if units is not None and units.get("weight"):
        out["inertia_weight"] = {k: v / units["wtmass"] for k, v in inertia.items()}
        out["inertia_weight_unit"] = f"{units['weight']} {units['length']}^2"
    return out


def _model_and_values(args):
    """(model, parameter values): a built-in model with SI ``--set`` values, or a Nastran deck
    whose ``--set`` names are bindings (``"PSHELL 3 T=0.06"``), plain numbers in its units
    (``pipelines.model_source.resolve_model``)."""
    from bayesupdate.errors import BayesUpdateError
    from bayesupdate.pipelines.model_source import is_deck, resolve_model

    if is_deck(args.model):
        if args.geometry is not None:
            raise BayesUpdateError("--geometry: only the exhaust model has a geometry")
        params = deck_set_values(args.set)
        tables = {n: {"binds": n} for n in params}
        return resolve_model(args.model, tables, needs_parameters=False), params
    options = {} if args.geometry is None else {"geometry": _geometry(args.geometry)}
    return resolve_model(args.model, options=options), parse_assignments(args.set)


def _check_sed_map(model, args) -> None:
    """--sed-map needs shells and a folder it may write into (checked before the solve)."""
    from pathlib import Path

    from bayesupdate.errors import BayesUpdateError
    from bayesupdate.report.energy_maps import has_shells

    if not has_shells(model.structure):
        raise BayesUpdateError(
            f"--sed-map: model {args.model!r} has no shell elements; the map needs a shell "
            "model (e.g. --model exhaust_shell)"
        )
    folder = Path(args.sed_map)
    if folder.exists() and not folder.is_dir():
        raise BayesUpdateError(f"--sed-map {folder}: is a file; give a folder")


def _write_sed_maps(model, result, folder) -> None:
    """One PNG per mode into ``folder``; the files go to stderr (stdout keeps the table/JSON)."""
    import sys

    from bayesupdate.errors import BayesUpdateError
    from bayesupdate.report.energy_maps import write_energy_density_maps

    try:
        written = write_energy_density_maps(model.structure, result, folder)
    except OSError as exc:
        raise BayesUpdateError(f"--sed-map {folder}: cannot write there ({exc.strerror})") from None
    print(f"strain-energy density maps: {len(written)} PNG files in {folder}", file=sys.stderr)


def _geometry(text):
    return int(text) if text.lstrip("-").isdigit() else text


def format_modes_table(result, units: dict | None = None, props=None) -> str:
    """Readable table: mode, frequency, and strain-energy share per part (% of the mode);
    the mass and centre of gravity in the model's units (a deck's ``units`` record; SI), and
    the inertia about the centre of gravity where ``props`` (``fe.mass_properties``) is given."""
    energies = result.energies
    parts = list(energies.parts)
    shares = energies.strain_by_part * 100.0
    keep = np.flatnonzero(shares.max(axis=1) >= 1.0)  # parts that carry >= 1 % in some mode
    short = [p if len(p) <= 12 else p[:11] + "." for p in (parts[i] for i in keep)]
    mass_unit, length = ("kg", "m") if units is None else (units["mass"], units["length"])
    weight = ""
    if units is not None and units.get("weight"):
        weight = f" (weight {result.mass_kg / units['wtmass']:.4f} {units['weight']})"
    lines = [
        f"mass {result.mass_kg:.6g} {mass_unit}{weight}, centre of gravity "
        f"({', '.join(f'{c:.3f}' for c in result.centre_of_gravity)}) {length}",
        *([] if props is None else [_inertia_line(props, units)]),
        "strain-energy share of each part [% of the mode]",
        f"{'mode':>4} {'f [Hz]':>9}  " + " ".join(f"{s:>12}" for s in short),
    ]
    for i, f in enumerate(result.frequencies_hz):
        lines.append(f"{i + 1:>4} {f:>9.3f}  " + " ".join(f"{shares[k, i]:>12.1f}" for k in keep))
    lines.append("parameters: " + ", ".join(f"{k}={v:.6g}" for k, v in result.parameters.items()))
    return "\n".join(lines)


def _inertia_line(props, units: dict | None) -> str:
    """One line: the inertia about the centre of gravity in the model's units."""
    record = inertia_record(props, units)
    values = ", ".join(f"{k} {v:.6g}" for k, v in record["inertia"].items())
    return f"inertia about the centre of gravity: {values} {record['inertia_unit']}"
