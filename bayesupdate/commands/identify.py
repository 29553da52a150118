"""``bayesupdate identify``: modal parameters from FRFs in UFF 58 files, no pole picking."""

import json
import sys
from pathlib import Path

from bayesupdate.atomic import check_output_path
from bayesupdate.commands._shared import parse_band, plot_folder
from bayesupdate.errors import BayesUpdateError

NAME = "identify"
HELP = "identify modes (LSCE or pLSCF + stabilization + LSFD) from FRFs in UFF 58 files"
DESCRIPTION = """Identify natural frequencies, damping ratios and mode shapes from FRFs (UFF 58).

Poles come from global LSCE (default) or pLSCF/PolyMAX (--method plscf) over all FRFs with
orders swept up to --max-order; stable poles are clustered across orders and chosen
automatically.  Several FRF files are one test (e.g. the runs of a roving accelerometer):
their common lines are used (starts a whole number of lines apart within UFF's 6-digit
rounding), and the runs are grouped where a mode's pole shifts between them by more than
its sd and its half-power half-width (or by --groups); each group's poles and residues are
estimated apart, the shapes assembled, and the spread and per-group MPC reported.
The range (all lines, or --band) is analysed as consecutive narrow bands with limits at
sum-FRF minima.  Shapes by LSFD, mass-normalized by the driving points (without one, shapes stay
unscaled and the output says so); each mode's shape_sd_rel estimates its shape error
(E[1 - MAC] ~ sd^2).  Writes ModalData as HDF5 (--out), optional plots (--plots DIR) and an
optional report (--report DIR: report.html, self-contained, and report.md with the data, the
modes table, the shapes over the response DOFs, the stabilization diagram, the FRF synthesis
and the AutoMAC).

examples:
  bayesupdate identify test.uff --out modes.h5 --plots plots --json
  bayesupdate identify run1.uff run2.uff run3.uff --band 3:35 --out gvt.h5 --report gvt_report
"""


def add_arguments(parser) -> None:
    parser.add_argument(
        "frf_file",
        metavar="FRF.uff",
        nargs="+",
        help="UFF file(s) with dataset-58 FRFs; several files are one test (e.g. roving runs)",
    )
    parser.add_argument(
        "--band",
        metavar="LO:HI",
        help="range to analyse [Hz], split into narrow bands like the whole axis (default: all)",
    )
    parser.add_argument(
        "--max-order",
        type=int,
        default=None,
        metavar="N",
        help="highest polynomial order per band (default 40)",
    )
    parser.add_argument(
        "--method",
        default="lsce",
        choices=("lsce", "plscf"),
        help="pole estimator: LSCE (time domain) or pLSCF/PolyMAX (frequency domain)",
    )
    parser.add_argument(
        "--groups",
        metavar="G",
        help="run groups by file position, e.g. 1-5,6-10 (default: found where poles shift)",
    )
    parser.add_argument("--out", required=True, metavar="modes.h5", help="output HDF5 file")
    parser.add_argument("--plots", metavar="DIR", help="write PNG plots to this folder")
    parser.add_argument(
        "--report",
        metavar="DIR",
        help="write DIR/report.html (self-contained) and DIR/report.md: data, modes, shapes "
        "per DOF, stabilization diagram, FRF synthesis, AutoMAC",
    )
    parser.add_argument(
        "--force",
        action="store_true",
        help="overwrite --out (and the --report files) if they exist",
    )
    parser.add_argument("--json", action="store_true", help="print the modes as one JSON object")


def _write_plots(folder, result, frfs) -> None:
    from pathlib import Path

    from bayesupdate.ema import plots

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    plots.plot_stabilization(result, frfs, folder / "stabilization.png")
    plots.plot_frf_fit(result, frfs, folder / "frf_fit.png")
    plots.plot_mac(result.modes.shapes, result.modes.shapes, folder / "automac.png", "AutoMAC")
    try:
        plots.plot_mode_shapes(result.modes, folder / "mode_shapes.png")
    except BayesUpdateError:
        pass  # labels that are not <node><L|H|V> have no geometry to draw


def _identify(args, request, data, inp):
    """The identify pipeline on the merged set; on failure with --report, a report of the data
    and the failure is written before the error goes to the CLI."""
    from bayesupdate.pipelines.identify import identify_frfs
    from bayesupdate.report.identify_report import write_identify_report

    try:
        return identify_frfs(data, request)
    except BayesUpdateError as exc:
        if args.report:
            html, _ = write_identify_report(args.report, inp, None, failure=str(exc))
            print(f"report (no modes): {html}", file=sys.stderr)
        raise


def run(args) -> int:
    from bayesupdate.compute import progress
    from bayesupdate.ema.modal_h5 import write_modal_h5
    from bayesupdate.ema.run_groups import parse_groups
    from bayesupdate.pipelines.identify import IdentifyRequest, identify_summary, read_frf_files
    from bayesupdate.report.identify_report import (
        IdentifyInput,
        check_report_folder,
        write_identify_report,
    )

    out = check_output_path(args.out, args.force)
    if Path(out).resolve() in {Path(f).resolve() for f in args.frf_file}:
        raise BayesUpdateError(f"--out {args.out}: is an input FRF file; give another name")
    groups = parse_groups(args.groups, len(args.frf_file))
    request = IdentifyRequest(
        tuple(args.frf_file), parse_band(args.band), args.max_order, args.method, groups
    )
    if args.report:
        check_report_folder(args.report, args.force)
    plot_folder(args.plots)
    data = read_frf_files(request.files)
    inp = IdentifyInput(
        files=data.files,
        file_sets=data.file_sets,
        frfs=data.frfs,
        method=request.method,
        band_hz=request.band_hz,
        max_order=request.max_order,
        merge_notes=data.merge_notes,
        out=str(out),
    )
    run_ = _identify(args, request, data, inp)
    result = run_.identification
    timings = progress.timings()
    write_modal_h5(out, result.modes, timings)
    if args.plots:
        _write_plots(args.plots, result, data.frfs)
    report = write_identify_report(args.report, inp, result)[0] if args.report else None
    summary = identify_summary(result, out, run_.notes, report)
    summary["timings"] = timings
    if args.json:
        print(json.dumps(summary))
        return 0
    _print_modes(summary, out, report)
    return 0


def _print_modes(summary: dict, out, report) -> None:
    """The terminal table of the modes, the notes and the files written."""
    for r, m in enumerate(summary["modes"], 1):
        mpc_text = "MPC   n/a" if m["mpc"] is None else f"MPC {m['mpc']:.3f}"
        print(
            f"mode {r:2d}: {m['frequency_hz']:9.3f} Hz  zeta {m['damping_ratio']:.4f}  "
            f"{mpc_text}  shape sd {m['shape_sd_rel']:.1e}  "
            f"stable at {m['stable_orders']} orders"
        )
    for note in summary["notes"]:
        print(f"note: {note}")
    print(f"wrote {out}")
    if report is not None:
        print(f"report: {report}")
