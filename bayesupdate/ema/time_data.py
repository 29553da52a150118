"""Time signals for FRF estimation: named channels read from UFF 58 time records, ``.mat``,
``.npz`` or ``.h5``, checked before any spectrum is taken.

A channel is named on the command line.  In a UFF file it is the DOF label of a time record
(``"25V"``: node 25, +Z) or its id line; in a ``.mat`` / ``.npz`` / ``.h5`` file it is a 1-D
variable, ``VAR:j`` (column j, from 0, of a 2-D variable), or a column name listed in a
string variable as long as one 2-D variable has columns (the ``chanInNameList`` of a MATLAB DAQ
script).  The sample rate comes from the UFF abscissa step, a time variable named by
``--time`` (it must be there, and agree with a stored rate), a stored rate (a scalar named
``fs``, ``sample_rate``, ...), a variable named ``t``, ``time...`` or ``timeIn_s``, or, for a file
with none of these, ``--fs``.  An ``--fs`` that disagrees with the file's own rate is refused: a
wrong rate scales every frequency found.
"""

import os
from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError

#: names (any case, after the last "/") of a variable holding a file's sample rate [Hz]
RATE_NAMES = ("fs", "sample_rate", "samplerate", "sampling_rate")

#: a signal that meets its extreme value this many times or more is clipped (flat tops); real
#: records checked (GVT, plate) meet theirs once or twice
FLAT_TOP_SAMPLES = 4


@dataclass(frozen=True)
class Channel:
    """One time signal: data (n_t,) in the file's unit, sample_rate_hz, unit text, name."""

    name: str
    data: np.ndarray
    sample_rate_hz: float
    unit: str = ""


def _load_arrays(path: str) -> dict:
    """Variables of a .mat / .npz / .h5 file as a dict name -> numpy array."""
    ext = os.path.splitext(path)[1].lower()
    try:
        if ext == ".npz":
            with np.load(path, allow_pickle=False) as z:
                return {k: z[k] for k in z.files}
        if ext == ".mat":
            import scipy.io

            try:
                m = scipy.io.loadmat(path, squeeze_me=True)
                return {k: np.asarray(v) for k, v in m.items() if not k.startswith("__")}
            except NotImplementedError:  # MATLAB v7.3 files are HDF5
                pass
        import h5py

        out = {}
        with h5py.File(path, "r") as fh:
            fh.visititems(
                lambda name, obj: (
                    out.__setitem__(name, obj[()]) if isinstance(obj, h5py.Dataset) else None
                )
            )
        return {k: np.asarray(v) for k, v in out.items()}
    except (OSError, ValueError, KeyError) as exc:
        raise BayesUpdateError(f"{path}: not a readable {ext or 'data'} file ({exc})") from None


def _names_of_columns(arrays: dict) -> dict:
    """name -> (variable, column) from string variables naming the columns of a 2-D array."""
    out = {}
    for _var, a in arrays.items():
        if a.ndim != 1 or not (
            a.dtype.kind in "US"
            or (a.dtype.kind == "O" and all(isinstance(x, (str, bytes)) for x in a))
        ):
            continue
        names = [(x.decode() if isinstance(x, bytes) else str(x)).strip() for x in a]
        for other, b in arrays.items():
            if b.ndim == 2 and b.dtype.kind in "fiu" and len(names) in b.shape:
                for j, name in enumerate(names):
                    out.setdefault(name, (other, j))
    return out


def _column(arrays: dict, name: str, path: str) -> np.ndarray:
    named = _names_of_columns(arrays)
    if name in arrays and arrays[name].dtype.kind in "fiu":
        a = arrays[name]
        if a.ndim == 2 and 1 in a.shape:
            a = a.reshape(-1)
        if a.ndim == 1:
            return a.astype(float)
    var, _, col = name.rpartition(":")
    if var in arrays and col.isdigit():
        a, j = arrays[var], int(col)
    elif name in named:
        var, j = named[name]
        a = arrays[var]
    else:
        choices = sorted(set(k for k, v in arrays.items() if v.dtype.kind in "fiu") | set(named))
        raise BayesUpdateError(
            f"{path}: no channel {name!r}; channels there: {', '.join(choices)} "
            "(or VAR:j for column j of a 2-D variable)"
        )
    if a.ndim != 2:
        raise BayesUpdateError(f"{path}: {var!r} is not a 2-D array; name it without ':{col}'")
    # channels run along the shorter axis (many samples, few channels)
    a = a if a.shape[0] >= a.shape[1] else a.T
    if j >= a.shape[1]:
        raise BayesUpdateError(f"{path}: {var!r} has {a.shape[1]} columns; no column {j}")
    return a[:, j].astype(float)


def _sample_rate(arrays: dict, time_name: str | None, fs: float | None, path: str) -> float:
    """The sample rate [Hz]: the file's own (``_own_rate``), or ``--fs`` for a file that has
    none; an ``--fs`` that disagrees with the file's own rate is refused, not obeyed."""
    own = _own_rate(arrays, time_name, path)
    if fs is None:
        if own is None:
            raise BayesUpdateError(f"{path}: no uniform time variable found; give --fs or --time")
        return own[0]
    _check_fs(fs, own, path)
    return float(fs)


def _check_fs(fs: float, own: tuple[float, str] | None, path: str) -> None:
    """Refuse an ``--fs`` [Hz] that differs from the file's own rate (rate [Hz], its source)
    beyond the rounding of a stored time step (1e-6)."""
    if own is not None and abs(own[0] - fs) > 1e-6 * own[0]:
        raise BayesUpdateError(
            f"{path}: --fs {fs:g} Hz disagrees with the file's own sample rate, {own[0]:g} Hz "
            f"from {own[1]}; --fs is for a file that has none"
        )


def _own_rate(arrays: dict, time_name: str | None, path: str) -> tuple[float, str] | None:
    """The rate [Hz] a file states, with where from: the time variable ``time_name`` where given
    (it must be there and uniform, and agree with a stored rate), else a stored rate (an HDF5
    DAQ's ``sample_rate``), else the first uniform variable named ``t``, ``time...``; None if
    none."""
    base = {k: k.rsplit("/", 1)[-1].lower() for k in arrays}
    stored = next((k for k, b in base.items() if b in RATE_NAMES and arrays[k].size == 1), None)
    stored_rate = None if stored is None else (float(arrays[stored].reshape(-1)[0]), repr(stored))
    if stored_rate is not None and not 0 < stored_rate[0] < np.inf:
        raise BayesUpdateError(
            f"{path}: its sample rate {stored!r} is {stored_rate[0]:g}; give the file's rate in "
            "Hz (a finite number > 0)"
        )
    if time_name:
        if time_name not in arrays:
            raise BayesUpdateError(f"{path}: no time variable {time_name!r}")
        rate = _uniform_rate(arrays[time_name])
        if rate is None:
            raise BayesUpdateError(f"{path}: time variable {time_name!r} is not uniform")
        if stored_rate is not None and abs(stored_rate[0] - rate) > 1e-6 * rate:
            raise BayesUpdateError(
                f"{path}: time variable {time_name!r} gives {rate:g} Hz, {stored_rate[1]} "
                f"{stored_rate[0]:g} Hz; the file disagrees with itself"
            )
        return rate, f"time variable {time_name!r}"
    if stored_rate is not None:  # a stored rate wins over a time vector found by its name
        return stored_rate
    for name in (k for k, b in base.items() if b in ("t", "time") or b.startswith("time")):
        rate = _uniform_rate(arrays[name])
        if rate is not None:
            return rate, f"time variable {name!r}"
    return None


def _uniform_rate(values) -> float | None:
    """1 / the step [Hz] of a uniform, increasing time vector [s]; None if it is not one."""
    t = np.asarray(values, dtype=float).reshape(-1)
    step = np.diff(t)
    if t.size > 2 and np.all(step > 0) and np.ptp(step) <= 1e-6 * step.mean():
        return float(1.0 / step.mean())
    return None


def _read_uff_time(path: str) -> list[Channel]:
    from bayesupdate.ema.uff_io import _read_sets, make_label

    out = []
    for s in _read_sets(path):
        if s.get("type") != 58 or int(s.get("func_type", 0)) != 1:
            continue
        x = np.asarray(s["x"], dtype=float)
        step = float(s.get("abscissa_inc") or (x[1] - x[0] if x.size > 1 else 0.0))
        if not step > 0:
            raise BayesUpdateError(f"{path}: a time record has no valid time step")
        try:
            name = make_label(s["rsp_node"], s["rsp_dir"])
        except BayesUpdateError:
            name = str(s.get("id1", "")).strip()
        sign = np.sign(int(s["rsp_dir"])) or 1.0
        data = sign * np.real(np.asarray(s["data"])).astype(float)
        unit = str(s.get("ordinate_axis_units_lab", "")).strip()
        out.append(Channel(name, data, 1.0 / step, unit))
        if str(s.get("id1", "")).strip() not in ("", name):  # also reachable by its id line
            out.append(Channel(str(s["id1"]).strip(), data, 1.0 / step, unit))
    if not out:
        raise BayesUpdateError(f"{path}: holds no UFF 58 time record (function type 1)")
    return out


def read_channels(
    path: str, names: list[str], time_name: str | None = None, fs: float | None = None
) -> list[Channel]:
    """The named channels of one file, in the order of ``names`` (module docstring)."""
    path = str(path)
    if not os.path.isfile(path):
        raise BayesUpdateError(f"{path}: file not found")
    if fs is not None and not 0 < fs < np.inf:
        raise BayesUpdateError(f"--fs {fs}: must be a finite rate > 0 Hz")
    if path.lower().endswith((".uff", ".unv")):
        return _uff_channels(path, names, time_name, fs)
    arrays = _load_arrays(path)
    rate = _sample_rate(arrays, time_name, fs, path)
    return [Channel(n, _column(arrays, n, path), rate) for n in names]


def _uff_channels(path: str, names: list[str], time_name: str | None, fs: float | None):
    """The named time records of a UFF file; its records' abscissa step is their rate, so
    ``--time`` is refused and ``--fs`` must agree with it."""
    if time_name:
        raise BayesUpdateError(
            f"{path}: --time {time_name!r}: a UFF time record carries its own time step; "
            "--time is for .mat, .npz and HDF5 files"
        )
    by_name = {c.name: c for c in _read_uff_time(path)}
    missing = [n for n in names if n not in by_name]
    if missing:
        raise BayesUpdateError(
            f"{path}: no channel {missing[0]!r}; channels there: {', '.join(sorted(by_name))}"
        )
    chosen = [by_name[n] for n in names]
    if fs is not None:
        for channel in chosen:
            _check_fs(fs, (channel.sample_rate_hz, f"{channel.name}'s time step"), path)
    return chosen


def check_channels(channels: list[Channel], where: str) -> list[str]:
    """Refuse channels of unequal length or sample rate, or with NaN; return warnings (one line
    each) for clipped signals: ``FLAT_TOP_SAMPLES`` samples or more at the extreme value."""
    rates = {c.sample_rate_hz for c in channels}
    if max(rates) - min(rates) > 1e-9 * max(rates):
        text = ", ".join(f"{c.name} {c.sample_rate_hz:g} Hz" for c in channels)
        raise BayesUpdateError(f"{where}: sample rates differ ({text}); resample to one rate")
    sizes = {c.data.size for c in channels}
    if len(sizes) > 1:
        text = ", ".join(f"{c.name} {c.data.size}" for c in channels)
        raise BayesUpdateError(f"{where}: channels have unequal lengths ({text} samples)")
    if min(sizes) < 8:
        raise BayesUpdateError(f"{where}: the channels hold {min(sizes)} samples; at least 8")
    notes = []
    for c in channels:
        if not np.all(np.isfinite(c.data)):
            raise BayesUpdateError(f"{where}: channel {c.name!r} contains NaN or inf")
        if np.ptp(c.data) == 0:
            raise BayesUpdateError(f"{where}: channel {c.name!r} is constant (not connected?)")
        for peak in (np.max(c.data), np.min(c.data)):  # a clipper cuts either side
            count = int(np.sum(c.data == peak))  # a free signal meets its extreme once or twice
            if count >= FLAT_TOP_SAMPLES:
                notes.append(
                    f"{where}: channel {c.name!r} is clipped ({count} samples at {peak:g}); "
                    "FRFs near strong responses are biased: lower the gain or the excitation"
                )
                break
    return notes
