"""UFF (universal file) I/O through pyuff: dataset 58 (FRFs) and 55 (modes).

DOF labels map to UFF node/direction: ``"7V"`` = node 7, direction 3 (+Z); ``"7H"`` = node 7,
direction 2 (+Y); ``"7L"`` = node 7, direction 1 (+X).  A negative direction on reading flips
the FRF sign.  pyuff pitfalls guarded here: it writes NaN silently as 0 (we refuse NaN/inf
before writing), it chokes on numpy integer node numbers (cast to int), it returns a single set
as a dict instead of a list (wrapped), and a truncated or corrupt file raises arbitrary errors
(turned into one BayesUpdateError); pyuff also silently drops a dataset cut off at the end of
a truncated file, so the ``-1`` delimiters are counted first; entity names longer than 10
characters shift its fixed-width fields (we leave them at the default); it prints some datasets
(groups, 2467) to stdout as it reads them (``bayesupdate.uff_read`` drops that); and its writer
lays out complex modes (dataset 55, analysis type 3) in a form its reader refuses, while it
reads test programs' exports of them.  Dataset 58 records that are not FRFs (time responses,
spectra) are refused with what they hold.
"""

import os
import re
import warnings

import numpy as np

from bayesupdate.atomic import atomic_path
from bayesupdate.ema.frf_set import FrfSet
from bayesupdate.errors import BayesUpdateError
from bayesupdate.modal_data import ModalData
from bayesupdate.uff_read import quiet_read

DIRECTION_OF_LETTER = {"L": 1, "H": 2, "V": 3}
LETTER_OF_DIRECTION = {v: k for k, v in DIRECTION_OF_LETTER.items()}
#: UFF ordinate specific data type of each FRF kind (8 displacement, 11 velocity, 12 accel.)
ORDINATE_TYPE = {"receptance": 8, "mobility": 11, "accelerance": 12}
KIND_OF_ORDINATE = {v: k for k, v in ORDINATE_TYPE.items()}


def parse_label(label: str) -> tuple[int, int]:
    """``"7V"`` -> (7, 3); BayesUpdateError for labels that are not <number><L|H|V>."""
    match = re.fullmatch(r"(\d+)([LHV])", str(label).strip().upper())
    if not match:
        raise BayesUpdateError(
            f"DOF label {label!r}: UFF needs <node number><L|H|V>, e.g. '7V'; rename the DOF"
        )
    return int(match.group(1)), DIRECTION_OF_LETTER[match.group(2)]


def make_label(node, direction) -> str:
    """(7, 3) -> ``"7V"``; the sign of the direction is dropped."""
    d = abs(int(direction))
    if d not in LETTER_OF_DIRECTION:
        what = "a scalar, no direction" if d == 0 else "a rotation" if d <= 6 else "no axis"
        raise BayesUpdateError(
            f"UFF node {int(node)} direction {direction} ({what}): only translations 1..3 "
            "(+-) are supported"
        )
    return f"{int(node)}{LETTER_OF_DIRECTION[d]}"


def _check_delimiters(path: str | os.PathLike) -> None:
    """Every dataset sits between two ``-1`` lines; a truncated file breaks that pattern."""
    with open(path, "rb") as fh:
        lines = [line.strip() for line in fh.read().splitlines() if line.strip()]
    n_delim = sum(1 for line in lines if line == b"-1")
    if not lines or n_delim < 2 or n_delim % 2 or lines[-1] != b"-1":
        raise BayesUpdateError(
            f"{path}: UFF datasets are not closed by '-1' lines; the file is truncated or corrupt"
        )


def _read_sets(path: str | os.PathLike) -> list[dict]:
    if not os.path.isfile(path):
        raise BayesUpdateError(f"{path}: file not found")
    _check_delimiters(path)
    try:
        # a non-finite value makes pyuff's numpy complain; read_uff58 reports it as one error
        with warnings.catch_warnings(), np.errstate(invalid="ignore", over="ignore"):
            warnings.simplefilter("ignore", RuntimeWarning)
            sets = quiet_read(path)
    except Exception as exc:  # pyuff raises anything on a truncated or corrupt file
        raise BayesUpdateError(
            f"{path}: not a readable UFF file ({type(exc).__name__}); is it truncated?"
        ) from None
    if isinstance(sets, dict):  # pyuff returns one set as a bare dict
        sets = [sets]
    return list(sets)


#: SI unit text of each FRF kind's response, for the ordinate label
UNIT_OF_KIND = {"receptance": "m", "mobility": "m/s", "accelerance": "m/s^2"}


def write_uff58(
    path: str | os.PathLike,
    frfs: FrfSet,
    channel_names: list[str] | None = None,
    single: bool = False,
) -> None:
    """Write every FRF of ``frfs`` as a dataset 58 (complex, even abscissa) atomically, with
    its coherence (function type 6) when the set has one.  channel_names (n_frf,) go to the
    id3 line (e.g. ``"Accel1/Force"``); units are SI, named in the axis labels.  single:
    single precision (ordinate data type 5, 6 significant digits, half the size of the
    default double precision, type 6)."""
    import pyuff

    if not np.all(np.isfinite(frfs.frf)):  # pyuff would write NaN as 0 without a word
        raise BayesUpdateError(f"{path}: FRFs contain NaN or inf; refusing to write them")
    datasets = []
    functions = [(4, frfs.frf)]
    if frfs.coherence is not None:
        functions.append((6, frfs.coherence))
    for (func, values), k in ((fv, k) for fv in functions for k in range(frfs.n_frf)):
        rn, rd = parse_label(frfs.response_labels[k])
        fn, fd = parse_label(frfs.reference_labels[k])
        datasets.append(
            pyuff.prepare_58(
                func_type=func,
                rsp_node=int(rn),
                rsp_dir=int(rd),
                ref_node=int(fn),
                ref_dir=int(fd),
                ordinate_spec_data_type=ORDINATE_TYPE[frfs.kind] if func == 4 else 0,
                orddenom_spec_data_type=13 if func == 4 else 0,
                abscissa_spec_data_type=18,
                ordinate_axis_units_lab=UNIT_OF_KIND[frfs.kind] if func == 4 else "-",
                orddenom_axis_units_lab="N" if func == 4 else "-",
                abscissa_axis_units_lab="Hz",
                data=np.asarray(values[k], dtype=complex if func == 4 else float),
                ord_data_type=(5 if func == 4 else 2) if single else None,
                x=np.asarray(frfs.frequencies_hz, dtype=float),
                abscissa_spacing=1,
                abscissa_min=float(frfs.frequencies_hz[0]),
                abscissa_inc=float(frfs.df_hz),
                id1=f"{'FRF' if func == 4 else 'COH'} {frfs.response_labels[k]}/"
                f"{frfs.reference_labels[k]}",
                id2=(frfs.source or "bayesupdate")[:80],
                id3=(channel_names[k] if channel_names else "NONE")[:80],
            )
        )
    with atomic_path(path, suffix=".uff") as tmp:
        tmp.unlink()  # pyuff appends to an existing file
        pyuff.UFF(str(tmp)).write_sets(datasets, mode="add", force_double=not single)


def read_uff58(path: str | os.PathLike) -> FrfSet:
    """Read all FRF datasets (58, function type 4) of a UFF file into one FrfSet."""
    sets = [s for s in _read_sets(path) if s.get("type") == 58]
    if not sets:
        raise BayesUpdateError(f"{path}: holds no dataset 58 (FRF); export the FRFs as UFF 58")
    frf_sets = [s for s in sets if int(s.get("func_type", 4)) == 4]
    if not frf_sets:  # a writer that leaves the function type general (0): taken as FRFs
        frf_sets = [s for s in sets if int(s.get("func_type", 4)) == 0]
    if not frf_sets:
        raise BayesUpdateError(_not_frfs(path, sets))
    x0 = np.asarray(frf_sets[0]["x"], dtype=float)
    rows, resp, ref = [], [], []
    for s in frf_sets:
        x = np.asarray(s["x"], dtype=float)
        if x.shape != x0.shape or not np.allclose(x, x0, rtol=1e-9, atol=1e-9):
            raise BayesUpdateError(f"{path}: FRFs have different frequency axes; resample them")
        data = np.asarray(s["data"])
        if data.shape != x0.shape:
            raise BayesUpdateError(
                f"{path}: a dataset 58 has {data.size} values for "
                f"{x0.size} frequencies; the file is corrupt"
            )
        sign = np.sign(int(s["rsp_dir"])) * np.sign(int(s["ref_dir"]))
        with np.errstate(invalid="ignore"):  # NaN/inf are rejected by FrfSet with one message
            rows.append(sign * data)
        try:
            resp.append(make_label(s["rsp_node"], s["rsp_dir"]))
            ref.append(make_label(s["ref_node"], s["ref_dir"]))
        except BayesUpdateError as exc:
            raise BayesUpdateError(f"{path}: an FRF's {exc}") from None
    kind = KIND_OF_ORDINATE.get(int(frf_sets[0].get("ordinate_spec_data_type", 12)), "accelerance")
    coherence = _coherence(sets, resp, ref, x0)
    return FrfSet(
        frequencies_hz=x0,
        frf=np.array(rows),
        response_labels=tuple(resp),
        reference_labels=tuple(ref),
        kind=kind,
        coherence=coherence,
        source=os.path.basename(str(path)),
    )


#: UFF dataset 58 function types (record 6, field 1) other than the FRF (4)
FUNCTION_TYPES = {1: "time responses", 2: "auto-spectra", 3: "cross-spectra",
                  5: "transmissibilities", 6: "coherences", 7: "auto-correlations",
                  8: "cross-correlations", 9: "power spectral densities",
                  10: "energy spectral densities", 12: "spectra",
                  18: "mode indicator functions", 24: "shock response spectra"}  # fmt: skip


def _not_frfs(path, sets: list[dict]) -> str:
    """The message for a UFF file whose datasets 58 hold no FRF (function type 4): what they
    hold instead, and what to do with it."""
    kinds = sorted({int(s.get("func_type", 0)) for s in sets})
    held = ", ".join(FUNCTION_TYPES.get(k, f"function type {k}") for k in kinds)
    advice = ("estimate FRFs from them with 'bayesupdate frf'" if kinds == [1]
              else "export the FRFs (function type 4)")  # fmt: skip
    return (
        f"{path}: its {len(sets)} dataset(s) 58 hold {held}, not FRFs (function type 4); {advice}"
    )


def _coherence(sets: list[dict], resp: list, ref: list, x0: np.ndarray) -> np.ndarray | None:
    """Coherence rows (function type 6) matching every FRF's labels and axis, else None."""
    found = {}
    for s in sets:
        if int(s.get("func_type", 0)) != 6 or np.asarray(s["x"]).shape != x0.shape:
            continue
        try:
            key = (make_label(s["rsp_node"], s["rsp_dir"]), make_label(s["ref_node"], s["ref_dir"]))
        except BayesUpdateError:
            continue
        found[key] = np.clip(np.real(np.asarray(s["data"], dtype=complex)), 0.0, 1.0)
    rows = [found.get(pair) for pair in zip(resp, ref, strict=True)]
    return None if any(r is None for r in rows) else np.array(rows)


def write_uff55(path: str | os.PathLike, modes: ModalData) -> None:
    """Write modes as dataset 55 (normal modes, 3 translations per node; real shapes).

    Complex shapes are realized first (rotated to their best real line).  Missing DOFs of a
    node are written as 0; on reading, a DOF that is 0 in every mode is dropped.
    """
    import pyuff

    from bayesupdate.ema.lsfd import realize

    if modes.shapes is None:
        raise BayesUpdateError(f"{path}: modal data has no shapes; UFF 55 needs them")
    shapes = realize(modes.shapes) if np.iscomplexobj(modes.shapes) else np.asarray(modes.shapes)
    if not np.all(np.isfinite(shapes)):
        raise BayesUpdateError(f"{path}: shapes contain NaN or inf; refusing to write them")
    parsed = [parse_label(lab) for lab in modes.dof_labels]
    nodes = sorted({n for n, _ in parsed})
    node_row = {n: i for i, n in enumerate(nodes)}
    damping = modes.damping_ratio if modes.damping_ratio is not None else np.zeros(modes.n_modes)
    datasets = []
    for r in range(modes.n_modes):
        comp = np.zeros((len(nodes), 3))
        for (n, d), value in zip(parsed, shapes[:, r], strict=True):
            comp[node_row[n], d - 1] = value
        datasets.append(
            pyuff.prepare_55(
                model_type=1,
                analysis_type=2,
                data_ch=2,
                spec_data_type=8,
                data_type=2,
                n_data_per_node=3,
                load_case=1,
                mode_n=r + 1,
                freq=float(modes.frequencies_hz[r]),
                modal_m=1.0,
                modal_damp_vis=float(damping[r]),
                modal_damp_his=0.0,
                node_nums=np.array([int(n) for n in nodes]),
                r1=comp[:, 0],
                r2=comp[:, 1],
                r3=comp[:, 2],
                r4=np.zeros(len(nodes)),
                r5=np.zeros(len(nodes)),
                r6=np.zeros(len(nodes)),
                id1=f"mode {r + 1}",
                id2=(modes.source or "bayesupdate")[:80],
                id3="NONE",
                id4="NONE",
                id5="NONE",
            )
        )
    with atomic_path(path, suffix=".uff") as tmp:
        tmp.unlink()
        pyuff.UFF(str(tmp)).write_sets(datasets, mode="add")


def read_uff55(path: str | os.PathLike) -> ModalData:
    """Read dataset-55 modes into ModalData (labels like ``"7V"``; all-zero DOFs dropped).

    Normal modes (analysis type 2) give their frequency and viscous damping ratio and real
    shapes; complex modes (analysis type 3, as modal test software exports identified modes)
    their eigenvalue lambda = -zeta omega_n + i omega_n sqrt(1 - zeta^2), read as the natural
    frequency |lambda| / 2 pi and the damping ratio -Re(lambda) / |lambda| (the convention of
    ``ema.lsce``), and complex shapes.  Other analysis types (static, transient, frequency
    response) hold no modes and are refused by name."""
    sets = [s for s in _read_sets(path) if s.get("type") == 55]
    if not sets:
        raise BayesUpdateError(f"{path}: holds no dataset 55 (modes)")
    kinds = sorted({int(s.get("analysis_type", 2)) for s in sets} - {2, 3})
    if kinds:
        raise BayesUpdateError(
            f"{path}: its datasets 55 of analysis type {kinds} hold no modes; modes are "
            "analysis type 2 (normal) or 3 (complex)"
        )
    nodes = np.asarray(sets[0]["node_nums"]).astype(int)
    kind = complex if any(int(s.get("analysis_type", 2)) == 3 for s in sets) else float
    cols, freq, damp = [], [], []
    for s in sets:
        if not np.array_equal(np.asarray(s["node_nums"]).astype(int), nodes):
            raise BayesUpdateError(f"{path}: modes are given at different nodes")
        cols.append(np.stack([np.asarray(s[f"r{d}"], dtype=kind) for d in (1, 2, 3)], axis=1))
        f, zeta = _frequency_damping(s)
        freq.append(f)
        damp.append(zeta)
    stack = np.stack(cols, axis=-1)  # (n_node, 3, m)
    labels, shapes = [], []
    for d in (3, 2, 1):  # V first, then H, then L, node order within each
        for i, n in enumerate(nodes):
            if np.any(stack[i, d - 1] != 0):
                labels.append(make_label(n, d))
                shapes.append(stack[i, d - 1])
    order = np.argsort(freq)
    return ModalData(
        frequencies_hz=np.array(freq)[order],
        damping_ratio=np.array(damp)[order],
        shapes=np.array(shapes)[:, order],
        dof_labels=tuple(labels),
        source=os.path.basename(str(path)),
    )


def _frequency_damping(s: dict) -> tuple[float, float]:
    """(natural frequency [Hz], viscous damping ratio) of one dataset 55: a normal mode's
    own, or from a complex mode's eigenvalue lambda [rad/s]: |lambda| / 2 pi, -Re / |lambda|."""
    if int(s.get("analysis_type", 2)) == 2:
        return float(s["freq"]), float(s.get("modal_damp_vis", 0.0))
    lam = complex(s["eig"])
    zeta = -lam.real / abs(lam) if lam != 0 else 0.0
    return abs(lam) / (2 * np.pi), zeta
