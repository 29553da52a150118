"""The report of ``bayesupdate identify --report DIR``: the data, the modes and how well they are
known, their shapes over the response DOFs, the stabilization diagram, the FRF synthesis and the
AutoMAC.

:func:`identify_document` builds the content from an identification (pure);
:func:`write_identify_report` draws the figures into ``DIR/figures`` and writes
``DIR/report.html`` (self-contained) and ``DIR/report.md``.
"""

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bayesupdate.atomic import make_writable_folder
from bayesupdate.ema.frf_set import FrfSet
from bayesupdate.ema.identify import Identification
from bayesupdate.ema.lsfd import realize
from bayesupdate.errors import BayesUpdateError
from bayesupdate.pipelines.identify import identification_notes, mpc_reasons
from bayesupdate.report.document import Alert, Document, Figure, Section, Table

METHOD_TEXT = {
    "lsce": "LSCE (least-squares complex exponential, time domain)",
    "plscf": "pLSCF / PolyMAX (poly-reference least-squares complex frequency domain, "
    "Peeters et al. 2004)",
}

#: figure name -> (file under DIR/figures, caption)
FIGURES = {
    "stabilization": (
        "stabilization.png",
        "Stabilization diagram over the analysed band(s): poles of every model order (o new, "
        "x stable in part, + stable in frequency, damping and vector), the CMIF (right axis) "
        "and the selected modes (red lines).",
    ),
    "shapes": (
        "shapes.png",
        "Mode shapes over the response DOFs: realized (rotated to the best real line), "
        "largest value +1.",
    ),
    "frf_fit": (
        "frf_fit.png",
        "Measured vs synthesized FRFs over the LSFD fit range (the worst fits by FRAC, up to 6).",
    ),
    "automac": ("automac.png", "AutoMAC of the identified (complex) shapes."),
    "cmif": ("cmif.png", "CMIF of the measured FRFs (the band, when given, shaded)."),
}

#: what a DOF label's direction letter means (UFF node/direction, see ema.uff_io)
_DIRECTIONS = "DOF labels are <node><direction>: V = +Z, H = +Y, L = +X (UFF node/direction)."


@dataclass(frozen=True)
class IdentifyInput:
    """What ``identify`` was given.

    files : the FRF files as the user named them; file_sets : the FrfSet read from each;
    frfs : their merged set (the one identified); method : ``"lsce"`` or ``"plscf"``;
    band_hz : (lo, hi) [Hz] or None (automatic bands); max_order : int or None (default);
    merge_notes : notes from merging the files; out : the HDF5 file written.
    """

    files: tuple[str, ...]
    file_sets: tuple[FrfSet, ...]
    frfs: FrfSet
    method: str
    band_hz: tuple[float, float] | None = None
    max_order: int | None = None
    merge_notes: tuple[str, ...] = ()
    out: str = ""


def normalized_shapes(shapes: np.ndarray) -> np.ndarray:
    """Real shapes (n_dof, m): each column realized (:func:`~bayesupdate.ema.lsfd.realize`)
    and divided by its value of largest magnitude, so that value is +1 (a zero column stays
    zero)."""
    real = np.atleast_2d(realize(np.asarray(shapes, dtype=complex)))
    if real.size == 0:
        return real
    peak = real[np.argmax(np.abs(real), axis=0), np.arange(real.shape[1])]
    return real / np.where(peak != 0, peak, 1.0)


def _freq(x) -> str:
    return f"{float(x):.6g}"


def modes_table(modes) -> Table:
    """One row per mode: frequency, damping, MPC (or why not), stable orders, shape_sd_rel,
    scaling.  Numbers are those written to the HDF5 file, at 6 / 4 / 3 / 2 significant
    digits."""
    extra = modes.extra
    damping = modes.damping_ratio if modes.damping_ratio is not None else [np.nan] * modes.n_modes
    sd = modes.shape_sd_rel if modes.shape_sd_rel is not None else [np.nan] * modes.n_modes
    orders = extra.get("stable_orders", [None] * modes.n_modes)
    massnorm = extra.get("mass_normalized", [False] * modes.n_modes)
    reasons = mpc_reasons(modes)
    rows = tuple(
        (
            r + 1,
            _freq(modes.frequencies_hz[r]),
            f"{100 * float(damping[r]):.4g}",
            f"{float(modes.mpc[r]):.3f}" if reasons[r] is None else f"n/a ({reasons[r]})",
            "-" if orders[r] is None else int(orders[r]),
            f"{float(sd[r]):.2g}",
            "mass-normalized" if massnorm[r] else "unscaled",
        )
        for r in range(modes.n_modes)
    )
    return Table(
        (
            "mode",
            "frequency [Hz]",
            "damping ratio [%]",
            "MPC",
            "stable orders",
            "shape_sd_rel",
            "shape scaling",
        ),
        rows,
        caption="Identified modes (MPC: 1 = real mode; shape_sd_rel: relative shape error, "
        "E[1 - MAC] ~ shape_sd_rel^2)",
    )


def shapes_table(modes) -> Table:
    """One row per response DOF, one column per mode: the normalized real shape."""
    shapes = normalized_shapes(modes.shapes)
    headers = ("DOF",) + tuple(
        f"mode {r + 1} ({modes.frequencies_hz[r]:.2f} Hz)" for r in range(modes.n_modes)
    )
    rows = tuple(
        (str(label),) + tuple(f"{v:+.3f}" for v in shapes[i])
        for i, label in enumerate(modes.dof_labels)
    )
    return Table(headers, rows, caption="Mode shapes (realized, largest value +1)")


#: below this MPC a shape is far from a real (normal) mode: its realized values drop much
MIN_REAL_MPC = 0.8
#: above this shape_sd_rel (E[1 - MAC] ~ 0.09) a shape's values are rough
MAX_GOOD_SHAPE_SD = 0.3


def _shape_cautions(modes) -> tuple[str, ...]:
    """Sentences naming the modes whose realized shape is far from the identified one (low
    MPC) or poorly known (large shape_sd_rel)."""
    out = []
    reasons = mpc_reasons(modes)
    if modes.mpc is not None:
        low = [
            r + 1
            for r in range(modes.n_modes)
            if reasons[r] is None and modes.mpc[r] < MIN_REAL_MPC
        ]
        if low:
            out.append(
                f"Mode(s) {', '.join(map(str, low))}: MPC below {MIN_REAL_MPC}, the identified "
                "shape is strongly complex and the realized values below drop its quadrature "
                "part."
            )
    if modes.shape_sd_rel is not None:
        rough = [r + 1 for r in range(modes.n_modes) if modes.shape_sd_rel[r] > MAX_GOOD_SHAPE_SD]
        if rough:
            out.append(
                f"Mode(s) {', '.join(map(str, rough))}: shape_sd_rel above "
                f"{MAX_GOOD_SHAPE_SD}, read their values as rough."
            )
    return tuple(out)


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")


def _labels(labels) -> str:
    return ", ".join(dict.fromkeys(labels))


def _files_table(inp: IdentifyInput) -> Table:
    rows = tuple(
        (
            name,
            s.n_frf,
            f"{s.frequencies_hz[0]:g}..{s.frequencies_hz[-1]:g}",
            f"{s.df_hz:.4g}",
            _labels(s.reference_labels),
            _labels(s.response_labels),
            "yes" if s.coherence is not None else "no",
        )
        for name, s in zip(inp.files, inp.file_sets, strict=True)
    )
    return Table(
        ("file", "FRFs", "lines [Hz]", "step [Hz]", "references", "responses", "coherence"),
        rows,
        caption="FRF files (one test)",
    )


def _sets_text(frfs: FrfSet) -> str:
    parts = []
    for s in frfs.sets():
        dp = "with" if s["driving_row"] is not None else "without"
        parts.append(
            f"{s['fixed']} fixed, {len(s['roving'])} roving ({_labels(s['roving'])}), "
            f"{dp} a driving point"
        )
    return "Test sets (one per fixed DOF): " + "; ".join(parts) + "."


def _analysis_text(inp: IdentifyInput, result: Identification | None) -> str:
    band = (
        f"the band {inp.band_hz[0]:g}..{inp.band_hz[1]:g} Hz given with --band"
        if inp.band_hz is not None
        else "automatic consecutive narrow bands (limits at sum-FRF minima)"
    )
    text = f"Method: {METHOD_TEXT.get(inp.method, inp.method)}, on {band}"
    if result is None:
        return text + "."
    bands = ", ".join(f"{lo:.4g}..{hi:.4g}" for lo, hi in result.bands_hz)
    orders = max((int(np.max(d.order)) for d in result.diagrams if d.order.size), default=0)
    lo, hi = result.fit_range_hz
    return (
        f"{text}: analysed band(s) {bands} Hz, model orders up to {orders}; stable poles "
        f"clustered across orders and selected automatically; residues by LSFD over "
        f"{lo:.4g}..{hi:.4g} Hz."
    )


def _frf_table(inp: IdentifyInput, result: Identification) -> Table:
    frfs = inp.frfs
    names = np.repeat(np.array(inp.files, dtype=object), [s.n_frf for s in inp.file_sets])
    lo, hi = result.fit_range_hz
    sel = (frfs.frequencies_hz >= lo) & (frfs.frequencies_hz <= hi)
    coh = None if frfs.coherence is None else np.mean(frfs.coherence[:, sel], axis=1)
    rows = tuple(
        (
            frfs.response_labels[k],
            frfs.reference_labels[k],
            str(names[k]) if k < names.size else "",
            "-" if coh is None else f"{coh[k]:.3f}",
            f"{result.frf_correlation[k]:.4f}",
        )
        for k in range(frfs.n_frf)
    )
    return Table(
        ("response", "reference", "file", "mean coherence (fit range)", "FRAC"),
        rows,
        caption="FRFs: coherence of the estimate and correlation of the synthesis (1 = same)",
    )


def data_section(inp: IdentifyInput, result: Identification | None) -> Section:
    """Files, FRF counts, references, responses, test sets, band(s), method."""
    f = inp.frfs
    summary = (
        f"{_count(f.n_frf, 'FRF')} ({f.kind}) from {_count(len(inp.files), 'file')}, on the "
        f"lines {f.frequencies_hz[0]:g}..{f.frequencies_hz[-1]:g} Hz (step {f.df_hz:.4g} Hz, "
        f"{f.frequencies_hz.size} lines). References: {_labels(f.reference_labels)}. "
        f"Response DOFs ({len(set(f.response_labels))}): {_labels(f.response_labels)}. "
        + _DIRECTIONS
    )
    blocks = [summary, _files_table(inp), _sets_text(f), _analysis_text(inp, result)]
    if result is not None:
        blocks.append(_frf_table(inp, result))
    return Section("Data and method", tuple(blocks))


def _figure(figures: dict, name: str) -> tuple:
    return (Figure(figures[name], FIGURES[name][1]),) if name in figures else ()


def run_groups_section(result: Identification) -> Section | None:
    """The run groups (:mod:`bayesupdate.ema.run_groups`) and per mode each group's frequency,
    damping and MPC, the spread, and the MPC with one pole over all runs; None with one
    group."""
    rg = result.extra.get("run_groups")
    extra = result.modes.extra
    if rg is None or "group_frequencies_hz" not in extra:
        return None
    n_groups = len(rg.groups)
    heads = ["mode", "frequency [Hz]", "sd [Hz]"]
    for k in range(n_groups):
        heads += [f"group {k + 1} [Hz]", f"group {k + 1} damping [%]", f"group {k + 1} MPC"]
    heads += ["spread [Hz]", "MPC one pole", "MPC assembled", "own poles"]
    rows = []
    for r in range(result.modes.n_modes):
        row = [r + 1, _freq(result.modes.frequencies_hz[r]),
               f"{float(result.modes.identification_sd_hz[r]):.2g}"]  # fmt: skip
        for k in range(n_groups):
            mark = "" if extra["group_sees"][r, k] else " (not seen)"
            row += [
                f"{float(extra['group_frequencies_hz'][r, k]):.4f}{mark}",
                f"{100 * float(extra['group_damping_ratio'][r, k]):.3g}",
                f"{float(extra['group_mpc'][r, k]):.3f}",
            ]
        row += [
            f"{float(extra['frequency_spread_hz'][r]):.3g}",
            f"{float(extra['mpc_one_pole'][r]):.3f}",
            f"{float(result.modes.mpc[r]):.3f}",
            "yes" if extra["group_poles_used"][r] else "no",
        ]
        rows.append(tuple(row))
    how = "found where poles shift between runs" if rg.automatic else "given with --groups"
    files = "; ".join(
        f"group {k + 1}: files " + ", ".join(str(j + 1) for j in g.files)
        for k, g in enumerate(rg.groups)
    )
    text = (
        f"{n_groups} run groups ({how}): {files}. Each group's poles are refined on its own "
        "FRFs; where a mode's group frequencies spread by a half-power half-width or more "
        "('own poles'), each group's residues are fitted at its own pole, and the shapes "
        "assembled over the groups. The frequency reported is the groups' random-effects mean, "
        "its sd holds the spread between groups. Consistency: the MPC of each group's part "
        "of the shape and of the assembly, beside the MPC with one pole over all runs."
    )
    table = Table(tuple(heads), tuple(rows), caption="Modes per run group")
    return Section("Run groups", (text, table))


def identify_document(
    inp: IdentifyInput,
    result: Identification | None,
    figures: dict | None = None,
    failure: str | None = None,
) -> Document:
    """The report's content.  figures : {name in FIGURES: path relative to the report
    folder} of the figures drawn; result None with ``failure`` (the error message) gives the
    data, the failure and the CMIF only."""
    figures = figures or {}
    title = "bayesupdate identify: " + ", ".join(Path(p).name for p in inp.files)
    sections = [data_section(inp, result)]
    if result is None:
        sections.append(
            Section(
                "No modes",
                (Alert(failure or "identification failed"), *_figure(figures, "cmif")),
            )
        )
        return Document(title, f"{METHOD_TEXT.get(inp.method, inp.method)}", tuple(sections))
    modes = result.modes
    notes = identification_notes(result, inp.merge_notes)
    sections += [
        Section("Notes", tuple(f"Note: {n}." for n in notes) or ("No notes.",)),
        Section(
            "Modes",
            ((f"Written to {inp.out}.",) if inp.out else ())
            + (modes_table(modes), *_figure(figures, "automac")),
        ),
        *((grp,) if (grp := run_groups_section(result)) is not None else ()),
        Section(
            "Mode shapes",
            (
                f"Shapes at {_count(len(modes.dof_labels), 'DOF')} (the roving DOFs of the "
                f"test sets) for {_count(modes.n_modes, 'mode')}. " + _DIRECTIONS,
                *_shape_cautions(modes),
                shapes_table(modes),
                *_figure(figures, "shapes"),
            ),
        ),
        Section("Stabilization diagram", _figure(figures, "stabilization")),
        Section("FRF synthesis", _figure(figures, "frf_fit")),
    ]
    subtitle = f"{modes.n_modes} modes by {METHOD_TEXT.get(inp.method, inp.method)}"
    return Document(title, subtitle, tuple(sections))


def check_report_folder(folder, force: bool) -> Path:
    """Make the report folder before any work; refuse to overwrite a report unless force."""
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise BayesUpdateError(f"--report {folder}: is a file; give a folder")
    for name in ("report.html", "report.md"):
        if (folder / name).exists() and not force:
            raise BayesUpdateError(
                f"--report {folder}: {name} already exists; use --force to overwrite it"
            )
    try:
        make_writable_folder(folder)
        (folder / "figures").mkdir(exist_ok=True)
    except OSError:
        raise BayesUpdateError(f"--report {folder}: cannot write there; choose another") from None
    return folder


def _draw(folder: Path, inp: IdentifyInput, result: Identification | None) -> dict:
    """Draw the figures into folder/figures; {name: path relative to folder}."""
    from bayesupdate.ema import plots

    path = {name: folder / "figures" / FIGURES[name][0] for name in FIGURES}
    if result is None:
        plots.plot_cmif(inp.frfs, path["cmif"], inp.band_hz)
        drawn = ["cmif"]
    else:
        modes = result.modes
        plots.plot_stabilization(result, inp.frfs, path["stabilization"])
        plots.plot_shape_bars(
            modes.dof_labels, normalized_shapes(modes.shapes), modes.frequencies_hz, path["shapes"]
        )
        plots.plot_frf_fit(result, inp.frfs, path["frf_fit"])
        plots.plot_mac(modes.shapes, modes.shapes, path["automac"], "AutoMAC")
        drawn = ["stabilization", "shapes", "frf_fit", "automac"]
    return {name: str(path[name].relative_to(folder)) for name in drawn}


def write_identify_report(
    folder, inp: IdentifyInput, result: Identification | None, failure: str | None = None
) -> tuple[Path, Path]:
    """Draw the figures and write ``folder/report.html`` and ``folder/report.md``; returns
    their paths.  The folder must have passed :func:`check_report_folder`."""
    from bayesupdate.report.render import write_report

    folder = Path(folder)
    figures = _draw(folder, inp, result)
    return write_report(identify_document(inp, result, figures, failure), folder)
