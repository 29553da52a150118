"""``bayesupdate frf``: FRFs (UFF 58) from force and response time signals."""

import numpy as np

from bayesupdate.atomic import check_output_path
from bayesupdate.commands._shared import parse_band
from bayesupdate.errors import BayesUpdateError

NAME = "frf"
HELP = "estimate FRFs (H1/H2, coherence) from force and response time signals"
DESCRIPTION = """Estimate FRFs from one force and its responses; write them as UFF 58.

Input: UFF 58 time records (channels named by DOF label, e.g. 25V, or id line), or .mat /
.npz / .h5 variables (a 1-D variable, VAR:j for column j of a 2-D one, or a column name listed
in a string variable such as MATLAB's chanInNameList); several SIGNALS files are repetitions.
Hammer tests (--method impact, or auto for an impulsive force): hits detected, double impacts
left out, force window and, when the response has not died out, an exponential window (its
added damping is stated).  Sine sweeps (--method sweep, or auto when every short spectrum of
the force holds one line): one whole-record spectrum per repetition (a sweep is a transient
inside its record; Welch segments cut the ringing of lightly damped modes from its cause).
Random, burst, periodic chirp (--method welch, or auto otherwise, or with --df): Hann segments
with 50 % overlap.  H1 by default (--estimator h2 for force noise); coherence (over the
segments, hits or repetitions; none from a single spectrum) is written beside each FRF (UFF
58, function type 6).  Units are converted to SI from --force-unit / --response-unit and the
sensitivities; the lines written are those the force excites (its autospectrum envelope
within 30 dB of its in-band level; for a sweep, not above its fundamental: the lines above
hold the shaker's harmonics) unless --band.  Lines lie on the record's grid k/T (T the
record length), so runs of one test share them even where each run's force excites from a
different lowest line; identify uses the lines all its files share.

example (one GVT run, volts, 0.4684 V/lbf, 1.028 V/g):
  bayesupdate frf run_Run1.mat --force-channel Force --response Accel1=1V --response Accel2=2V \\
      --reference 25V --force-unit lbf --force-sensitivity 0.4684 --response-unit g \\
      --response-sensitivity 1.028 --out run1.uff
"""

#: unit -> (factor to SI, FRF kind of a response in it)
RESPONSE_UNITS = {
    "m/s2": (1.0, "accelerance"),
    "g": (9.80665, "accelerance"),
    "mm/s2": (1e-3, "accelerance"),
    "m/s": (1.0, "mobility"),
    "mm/s": (1e-3, "mobility"),
    "m": (1.0, "receptance"),
    "mm": (1e-3, "receptance"),
    "um": (1e-6, "receptance"),
}
FORCE_UNITS = {"N": 1.0, "kN": 1e3, "lbf": 4.4482216152605}


def add_arguments(parser) -> None:
    parser.add_argument(
        "time_file",
        metavar="SIGNALS",
        nargs="+",
        help="UFF 58 time records, .mat/.npz/.h5; several files are repetitions (averaged)",
    )
    parser.add_argument("--force-channel", required=True, metavar="CH", help="force channel")
    parser.add_argument(
        "--response",
        action="append",
        required=True,
        metavar="CH[=DOF]",
        help="response channel and its DOF label, e.g. Accel1=1V (repeat per response)",
    )
    parser.add_argument("--reference", metavar="DOF", help="DOF label of the force (e.g. 25V)")
    parser.add_argument("--out", required=True, metavar="FRF.uff", help="output UFF 58 file")
    parser.add_argument("--method", default="auto", choices=("auto", "impact", "sweep", "welch"))
    parser.add_argument("--estimator", default="h1", choices=("h1", "h2"))
    parser.add_argument(
        "--window",
        default="hann",
        choices=("hann", "rect"),
        help="Welch window (rect: a sweep wholly inside each record, with --df 1/record)",
    )
    parser.add_argument("--fs", type=float, metavar="HZ", help="sample rate if the file has none")
    parser.add_argument("--time", metavar="VAR", help="time variable giving the sample rate")
    parser.add_argument("--df", type=float, metavar="HZ", help="Welch line spacing [Hz]")
    parser.add_argument("--record", type=float, metavar="S", help="impact record length [s]")
    parser.add_argument("--tau", type=float, metavar="S", help="exponential window time const.")
    parser.add_argument("--band", metavar="LO:HI", help="lines to write [Hz] (default: excited)")
    parser.add_argument("--force-unit", default="N", choices=sorted(FORCE_UNITS))
    parser.add_argument("--response-unit", default="m/s2", choices=sorted(RESPONSE_UNITS))
    parser.add_argument("--force-sensitivity", type=float, default=1.0, metavar="X",
                        help="file units per force unit (e.g. 0.4684 V/lbf)")  # fmt: skip
    parser.add_argument("--response-sensitivity", type=float, default=1.0, metavar="X",
                        help="file units per response unit (e.g. 1.028 V/g)")  # fmt: skip
    parser.add_argument("--force", action="store_true", help="overwrite --out if it exists")


def _responses(specs: list[str]) -> tuple[list[str], list[str]]:
    from bayesupdate.ema.uff_io import parse_label

    names, labels = [], []
    for spec in specs:
        name, _, label = spec.partition("=")
        label = label or name
        try:
            parse_label(label)
        except BayesUpdateError:
            raise BayesUpdateError(
                f"--response {spec!r}: give CHANNEL=DOF with a DOF label like 1V (node + L/H/V)"
            ) from None
        names.append(name)
        labels.append(label.strip().upper())
    return names, labels


def _check_numbers(args) -> None:
    for flag, value in (
        ("--force-sensitivity", args.force_sensitivity),
        ("--response-sensitivity", args.response_sensitivity),
        ("--df", args.df),
        ("--record", args.record),
        ("--tau", args.tau),
    ):
        if value is not None and not (np.isfinite(value) and value > 0):
            runs = ", ".join(str(p) for p in args.time_file)
            raise BayesUpdateError(f"{runs}: {flag} {value:g} must be a positive number")


def run(args) -> int:
    from bayesupdate.ema.frf_estimation import frf_from_signals
    from bayesupdate.ema.uff_io import parse_label

    out = check_output_path(args.out, args.force)
    _check_numbers(args)
    names, labels = _responses(args.response)
    reference = (args.reference or args.force_channel).strip().upper()
    try:
        parse_label(reference)
    except BayesUpdateError:
        raise BayesUpdateError(
            f"--reference: force channel {args.force_channel!r} is no DOF label; give "
            "--reference DOF (e.g. 25V)"
        ) from None
    runs, notes, fs = _read_runs(args, names)
    force = np.array([r[0].data for r in runs]) / args.force_sensitivity
    force = force * FORCE_UNITS[args.force_unit]
    scale, kind = RESPONSE_UNITS[args.response_unit]
    resp = np.array([[c.data for c in r[1:]] for r in runs]).transpose(1, 0, 2)
    resp = resp / args.response_sensitivity * scale
    segment = None if args.df is None else int(round(fs / args.df))
    with np.errstate(all="ignore"):  # spectra of silent lines: handled, not worth a warning
        est = frf_from_signals(
            force, resp, fs, args.method, segment, args.record, args.tau, args.window
        )
    f, coh = est.frequencies_hz, est.coherence
    lo, hi = _lines_to_write(args, est)
    keep = (f >= lo) & (f <= hi) & (f > 0)
    if keep.sum() < 4:
        raise BayesUpdateError(f"--band {lo:g}:{hi:g}: holds fewer than 4 FRF lines")
    h = (est.h1 if args.estimator == "h1" else est.h2)[:, keep]
    coh = None if coh is None else coh[:, keep]
    _write(out, f[keep], h, coh, labels, reference, kind, runs[0], args)
    notes += est.notes
    if est.sweep_top_hz is not None and args.band is None and f[-1] > est.sweep_top_hz:
        notes.append(
            f"lines above the sweep's top ({est.sweep_top_hz:.3g} Hz) hold its harmonics "
            "(shaker distortion), not excitation: not written"
        )
    for note in notes:
        print(f"note: {note}")
    for i, (lab, ch) in enumerate(zip(labels, names, strict=True)):
        level = "n/a" if coh is None else f"{np.mean(coh[i]):.3f}"
        print(f"FRF {lab}/{reference} ({ch}/{args.force_channel}): mean coherence {level}")
    print(f"{len(labels)} FRFs, {f[keep][0]:g}..{f[keep][-1]:g} Hz, {kind}; wrote {out}")
    return 0


def _read_runs(args, names: list[str]) -> tuple[list, list[str], float]:
    """Force and response channels of each SIGNALS file (repetitions: same rate and length),
    notes on them, and the sample rate [Hz]."""
    from bayesupdate.ema.time_data import check_channels, read_channels

    runs, notes = [], []
    for path in args.time_file:
        channels = read_channels(path, [args.force_channel, *names], args.time, args.fs)
        notes += check_channels(channels, path)
        runs.append(channels)
    first = runs[0][0]
    fs = first.sample_rate_hz
    for path, chans in zip(args.time_file[1:], runs[1:], strict=True):
        if abs(chans[0].sample_rate_hz - fs) > 1e-9 * fs or chans[0].data.size != first.data.size:
            raise BayesUpdateError(
                f"{path}: {chans[0].data.size} samples at {chans[0].sample_rate_hz:g} Hz, but "
                f"{args.time_file[0]} has {first.data.size} at {fs:g} Hz; repetitions must match"
            )
    return runs, notes, fs


def _lines_to_write(args, est) -> tuple[float, float]:
    """(lo, hi) [Hz]: --band, or the lines the force excites (below a sweep's top)."""
    from bayesupdate.ema.excitation import excited_band

    if args.band is not None:
        return parse_band(args.band)
    return excited_band(est.frequencies_hz, est.force_autospectrum, sweep_top_hz=est.sweep_top_hz)


def _write(out, f, h, coh, labels, reference, kind, channels, args) -> None:
    from bayesupdate.ema.frf_set import FrfSet
    from bayesupdate.ema.uff_io import write_uff58

    source = f"{args.force_channel}->" + ",".join(c.name for c in channels[1:])
    frfs = FrfSet(f, h, tuple(labels), (reference,) * len(labels), kind, coh, source[:80])
    write_uff58(out, frfs, channel_names=[f"{c.name}/{args.force_channel}" for c in channels[1:]])
