"""``bayesupdate identify``: modal parameters from FRFs in UFF 58 files, no pole picking."""

import json

import numpy as np

from bayesupdate.atomic import check_output_path
from bayesupdate.errors import BayesUpdateError

NAME = "identify"
HELP = "identify modes (LSCE or pLSCF + stabilization + LSFD) from FRFs in UFF 58 files"
DESCRIPTION = """Identify natural frequencies, damping ratios and mode shapes from FRFs (UFF 58).

Poles come from global LSCE (default) or pLSCF/PolyMAX (--method plscf) over all FRFs with
orders swept up to --max-order; stable poles are clustered across orders and chosen
automatically.  Several FRF files are one test (e.g. the runs of a roving accelerometer).
Without --band the range is analysed as consecutive narrow bands with limits at sum-FRF
minima.  Shapes by LSFD, mass-normalised by the driving points (without one, shapes stay
unscaled and the output says so); each mode's shape_sd_rel estimates its shape error
(E[1 - MAC] ~ sd^2).  Writes ModalData as HDF5 (--out) and optional plots (--plots DIR).

example: bayesupdate identify test.uff --out modes.h5 --plots plots --json
"""


def _parse_band(text: str | None):
    if text is None:
        return None
    try:
        lo, hi = (float(x) for x in text.split(":"))
    except ValueError:
        raise BayesUpdateError(f"--band {text!r}: give LO:HI in Hz, e.g. 60:500") from None
    return lo, hi


def add_arguments(parser) -> None:
    parser.add_argument(
        "frf_file",
        metavar="FRF.uff",
        nargs="+",
        help="UFF file(s) with dataset-58 FRFs; several files are one test (e.g. roving runs)",
    )
    parser.add_argument("--band", metavar="LO:HI", help="analyse one band [Hz] (default: auto)")
    parser.add_argument(
        "--max-order",
        type=int,
        default=None,
        metavar="N",
        help="highest LSCE polynomial order (default 60 with --band, else 40)",
    )
    parser.add_argument(
        "--method",
        default="lsce",
        choices=("lsce", "plscf"),
        help="pole estimator: LSCE (time domain) or pLSCF/PolyMAX (frequency domain)",
    )
    parser.add_argument("--out", required=True, metavar="modes.h5", help="output HDF5 file")
    parser.add_argument("--plots", metavar="DIR", help="write PNG plots to this folder")
    parser.add_argument("--force", action="store_true", help="overwrite --out if it exists")
    parser.add_argument("--json", action="store_true", help="print the modes as one JSON object")


def run(args) -> int:
    from bayesupdate.ema.frf_set import merge_frf_sets
    from bayesupdate.ema.identify import MAX_SHAPE_SD, identify
    from bayesupdate.ema.modal_h5 import write_modal_h5
    from bayesupdate.ema.uff_io import read_uff58

    out = check_output_path(args.out, args.force)
    band = _parse_band(args.band)
    if args.max_order is not None and args.max_order < 2:
        raise BayesUpdateError(f"--max-order {args.max_order}: must be at least 2")
    frfs, merge_notes = merge_frf_sets([read_uff58(path) for path in args.frf_file])
    result = identify(frfs, band_hz=band, max_order=args.max_order, method=args.method)
    write_modal_h5(out, result.modes)
    if args.plots:
        from pathlib import Path

        from bayesupdate.ema import plots

        folder = Path(args.plots)
        folder.mkdir(parents=True, exist_ok=True)
        plots.plot_stabilization(result, frfs, folder / "stabilization.png")
        plots.plot_frf_fit(result, frfs, folder / "frf_fit.png")
        plots.plot_mac(result.modes.shapes, result.modes.shapes, folder / "automac.png", "AutoMAC")
        try:
            plots.plot_mode_shapes(result.modes, folder / "mode_shapes.png")
        except BayesUpdateError:
            pass  # labels that are not <node><L|H|V> have no geometry to draw
    modes = result.modes
    one_dof = len(modes.dof_labels) < 2  # the phase scatter of one value says nothing
    summary = {
        "modes": [
            {
                "frequency_hz": float(modes.frequencies_hz[r]),
                "damping_ratio": float(modes.damping_ratio[r]),
                "mpc": None if one_dof else float(modes.mpc[r]),
                "shape_sd_rel": float(modes.shape_sd_rel[r]),
                "mass_normalised": bool(modes.extra["mass_normalised"][r]),
                "stable_orders": int(modes.extra["stable_orders"][r]),
            }
            for r in range(modes.n_modes)
        ],
        "dropped_hz": [float(x) for x in result.extra["dropped_hz"]],
        "out": str(out),
    }
    notes = list(merge_notes)
    if one_dof:
        notes.append("MPC not reported: shapes have one DOF, so phase collinearity is undefined")
    if not np.all(modes.extra["mass_normalised"]):
        notes.append(
            "shapes without a driving point are unscaled (largest component 1), "
            "not mass-normalised; measure a driving point to scale them"
        )
    if np.any(modes.extra["shape_sd_fallback"]):
        notes.append(f"shape_sd_rel not estimable for some modes: set to {MAX_SHAPE_SD}")
    if summary["dropped_hz"]:
        notes.append(
            "stable poles dropped as not physical (explain little of the FRF, peak near the "
            "fit residual): " + ", ".join(f"{x:.2f}" for x in summary["dropped_hz"]) + " Hz"
        )
    summary["notes"] = notes
    if args.json:
        print(json.dumps(summary))
    else:
        for r, m in enumerate(summary["modes"], 1):
            mpc_text = "MPC   n/a" if m["mpc"] is None else f"MPC {m['mpc']:.3f}"
            print(
                f"mode {r:2d}: {m['frequency_hz']:9.3f} Hz  zeta {m['damping_ratio']:.4f}  "
                f"{mpc_text}  shape sd {m['shape_sd_rel']:.1e}  "
                f"stable at {m['stable_orders']} orders"
            )
        for note in notes:
            print(f"note: {note}")
        print(f"wrote {out}")
    return 0
