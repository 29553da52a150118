"""Test data in: frequency tables (CSV or inline), the seed's Table 2, and (hook) EMA files.

``load_modal_data(source)`` is the one entry point.  ``source`` is

* a ``ModalData`` (returned as is),
* ``"paper:ema"``: seed Table 2 (12 EMA frequencies, unit weights) and the measured mass,
* a mapping with ``frequencies_hz`` and optional ``weights``, ``sd_hz``, ``mass_kg``,
  ``mass_sd_kg`` (inline in a study file),
* a path: ``.csv`` (columns ``frequency_hz``, optional ``weight``, ``sd_hz``, ``mode``; a measured
  mass as comment lines ``# mass_kg = 12.29`` and ``# mass_sd_kg = 0.12``), or any suffix
  registered with ``register_loader`` (the EMA layer registers ``.h5`` / ``.uff``).

A measured mass is test data: calibration and the likelihood use it by default
(``pipelines.study.prepare``).

``select_modes(data, ModeSelection(...))`` keeps the modes a study names (``[data] modes``, 1-based
in the source's order: the order ``identify --json`` lists them) and gives them the study's
``weights`` / ``sd_hz``, whatever the source.
"""

import csv
import importlib
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.modal_data import ModalData

#: suffix (lower case, with dot) -> loader(path) -> ModalData
_LOADERS: dict[str, Callable[[Path], ModalData]] = {}

#: lazily imported loaders of other layers: suffix -> "module:function"
_LAZY_LOADERS = {
    ".h5": "bayesupdate.ema.modal_h5:read_modal_h5",
    ".hdf5": "bayesupdate.ema.modal_h5:read_modal_h5",
    ".uff": "bayesupdate.ema.uff_io:read_uff55",
    ".unv": "bayesupdate.ema.uff_io:read_uff55",
}

#: named data sets of a layer above (the seed paper's tables live beside the exhaust model):
#: name -> "module:function" returning ``ModalData``, imported when the name is asked for
_NAMED_SOURCES = {"paper:ema": "bayesupdate.models.exhaust_paper:paper_ema"}

CSV_COLUMNS = ("frequency_hz", "weight", "sd_hz", "mode")
INLINE_KEYS = ("frequencies_hz", "weights", "sd_hz", "mass_kg", "mass_sd_kg")
#: scalar keys a CSV file may carry in comment lines ``# key = value``
CSV_SCALARS = ("mass_kg", "mass_sd_kg")


def register_loader(suffix: str, loader: Callable[[Path], ModalData]) -> None:
    """Make ``load_modal_data`` read files ending in ``suffix`` with ``loader(path)``."""
    _LOADERS[suffix.lower()] = loader


def modal_data_from_mapping(table: Mapping, where: str = "data") -> ModalData:
    """Inline data such as ``{frequencies_hz = [...], weights = [...], sd_hz = [...],
    mass_kg = 12.29, mass_sd_kg = 0.12}``."""
    unknown = sorted(set(table) - set(INLINE_KEYS))
    if unknown:
        raise BayesUpdateError(f"{where}: unknown key(s) {unknown}; valid: {list(INLINE_KEYS)}")
    if "frequencies_hz" not in table:
        raise BayesUpdateError(f"{where}: give frequencies_hz = [...] or source = ...")
    arrays = {}
    for key in INLINE_KEYS[:3]:
        if key in table:
            try:
                arrays[key] = np.asarray(table[key], dtype=float).reshape(-1)
            except (TypeError, ValueError) as exc:
                raise BayesUpdateError(f"{where}.{key}: must be a list of numbers") from exc
    return ModalData(
        frequencies_hz=arrays["frequencies_hz"],
        weights=arrays.get("weights"),
        frequency_sd_hz=arrays.get("sd_hz"),
        mass_kg=table.get("mass_kg"),
        mass_sd_kg=table.get("mass_sd_kg"),
        source=f"inline:{where}",
    )


def _csv_scalars(text: str, path: Path) -> dict:
    """``# key = value`` comment lines of a CSV table, for the keys of ``CSV_SCALARS``."""
    found = {}
    for line in text.splitlines():
        body = line.strip().lstrip("#").strip()
        if not line.lstrip().startswith("#") or "=" not in body:
            continue
        key, value = (part.strip() for part in body.split("=", 1))
        if key in CSV_SCALARS:
            try:
                found[key] = float(value)
            except ValueError as exc:
                raise BayesUpdateError(f"{path}: {key} = {value!r} is not a number") from exc
    return found


def read_frequency_csv(path: str | os.PathLike) -> ModalData:
    """A CSV frequency table with a header row; ``#`` lines are comments.

    Columns: ``frequency_hz`` (required), ``weight``, ``sd_hz`` [Hz], ``mode`` (label, ignored).
    """
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise BayesUpdateError(f"{path}: cannot read ({exc.strerror}); check the path") from exc
    except UnicodeDecodeError as exc:  # a binary file (e.g. a spreadsheet) named .csv
        raise BayesUpdateError(
            f"{path}: not a text CSV file ({exc.reason}); export the table as UTF-8 CSV"
        ) from exc
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise BayesUpdateError(f"{path}: empty; give a header frequency_hz[,weight,sd_hz]")
    rows = list(csv.reader(lines))
    header = [h.strip() for h in rows[0]]
    unknown = sorted(set(header) - set(CSV_COLUMNS))
    if unknown or "frequency_hz" not in header:
        raise BayesUpdateError(
            f"{path}: header must name frequency_hz and optionally weight, sd_hz, mode; "
            f"got {header}"
        )
    columns: dict[str, list[float]] = {h: [] for h in header}
    for number, row in enumerate(rows[1:], start=2):
        if len(row) != len(header):
            raise BayesUpdateError(
                f"{path}: row {number} has {len(row)} fields, header {len(header)}"
            )
        for name, value in zip(header, row, strict=True):
            if name == "mode":
                continue
            try:
                columns[name].append(float(value))
            except ValueError as exc:
                raise BayesUpdateError(
                    f"{path}: row {number}, {name}: {value!r} is not a number"
                ) from exc
    if not columns["frequency_hz"]:
        raise BayesUpdateError(f"{path}: no data rows")
    return ModalData(
        frequencies_hz=np.array(columns["frequency_hz"]),
        weights=np.array(columns["weight"]) if "weight" in columns else None,
        frequency_sd_hz=np.array(columns["sd_hz"]) if "sd_hz" in columns else None,
        source=str(path),
        **_csv_scalars(text, path),
    )


register_loader(".csv", read_frequency_csv)


def load_modal_data(source) -> ModalData:
    """Test modal data from any supported ``source`` (see module docstring)."""
    if isinstance(source, ModalData):
        return source
    if isinstance(source, Mapping):
        return modal_data_from_mapping(source)
    if not isinstance(source, str | os.PathLike):
        raise BayesUpdateError(f"data: cannot read test data from {type(source).__name__}")
    text = str(source)
    if text.startswith("paper:"):
        if text in _NAMED_SOURCES:
            module_name, func = _NAMED_SOURCES[text].split(":")
            return getattr(importlib.import_module(module_name), func)()
        raise BayesUpdateError(f"data {text!r}: unknown paper data; use 'paper:ema' (seed Table 2)")
    path = Path(text)
    suffix = path.suffix.lower()
    if not path.exists():
        raise BayesUpdateError(f"{path}: file not found; give a CSV table, .h5/.uff or paper:ema")
    if suffix in _LOADERS:
        return _LOADERS[suffix](path)
    if suffix in _LAZY_LOADERS:
        module_name, func = _LAZY_LOADERS[suffix].split(":")
        try:
            loader = getattr(importlib.import_module(module_name), func)
        except (ImportError, AttributeError) as exc:
            raise BayesUpdateError(
                f"{path}: reading {suffix} modal data needs {_LAZY_LOADERS[suffix]}, "
                "not available in this installation; export a CSV frequency table instead"
            ) from exc
        data = loader(path)
        if not isinstance(data, ModalData):
            raise BayesUpdateError(f"{path}: loader did not return ModalData")
        return data
    raise BayesUpdateError(
        f"{path}: unknown data format {suffix!r}; use .csv, .h5, .uff or paper:ema"
    )


@dataclass(frozen=True)
class ModeSelection:
    """The study's choice among a source's modes (``[data]``).

    modes : 1-based numbers of the source's modes that enter (None: all, in order).
    weights : (k,) eq. 19 weights of the modes that enter, in the order of ``modes`` (None: the
    source's own, else unit).  sd_hz : (k,) their frequency sd [Hz] (None: the source's own).
    """

    modes: tuple[int, ...] | None = None
    weights: tuple[float, ...] | None = None
    sd_hz: tuple[float, ...] | None = None


def _checked_numbers(modes, n_source: int, source: str) -> list[int]:
    """The 1-based ``modes`` after checking each against the ``n_source`` modes of ``source``."""
    numbers = [int(m) for m in modes]
    if not numbers:
        raise BayesUpdateError("data.modes: empty; list the test modes that enter, e.g. [1, 2]")
    for number in numbers:
        if not 1 <= number <= n_source:
            raise BayesUpdateError(
                f"data.modes: test mode {number} is not in {source!r}, which has {n_source} "
                f"modes (numbered 1 to {n_source}, as identify --json lists them)"
            )
    repeated = sorted({m for m in numbers if numbers.count(m) > 1})
    if repeated:
        raise BayesUpdateError(f"data.modes: test mode(s) {repeated} listed twice")
    return numbers


def _per_mode(values, name: str, numbers: list[int], chosen: bool) -> np.ndarray | None:
    """``values`` (one per selected mode) as an array; one line naming both lengths if not
    (``chosen``: the modes were listed by ``[data] modes``)."""
    if values is None:
        return None
    try:
        array = np.asarray(values, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise BayesUpdateError(f"data.{name}: must be a list of numbers") from exc
    if array.size != len(numbers):
        modes = (
            f"{len(numbers)} selected test modes {numbers}; give one per selected mode, in the "
            "order of [data] modes"
            if chosen
            else f"the source's {len(numbers)} test modes; give one per mode, or choose the "
            "modes with [data] modes = [...]"
        )
        raise BayesUpdateError(f"data.{name}: {array.size} values for {modes}")
    return array


def select_modes(
    data: ModalData, selection: ModeSelection, name: str = ""
) -> tuple[ModalData, tuple[int, ...]]:
    """The modes of ``data`` that ``selection`` names, with its weights and sd; ``name``: the
    source as the user gave it, for messages (default: ``data.source``).

    Returns (data with the selected modes in ascending source order, their 1-based numbers in
    the source).  A number the source does not have, a repeated number, or weights / sd_hz of
    another length than the selection: ``BayesUpdateError`` in one line.
    """
    modes = selection.modes
    numbers = (
        list(range(1, data.n_modes + 1))
        if modes is None
        else _checked_numbers(modes, data.n_modes, name or data.source)
    )
    weights = _per_mode(selection.weights, "weights", numbers, modes is not None)
    sd_hz = _per_mode(selection.sd_hz, "sd_hz", numbers, modes is not None)
    order = np.argsort(numbers, kind="stable")
    chosen = data if modes is None else data.subset(np.asarray(numbers)[order] - 1)
    changes = {}
    if weights is not None:
        changes["weights"] = weights[order]
    if sd_hz is not None:
        changes["frequency_sd_hz"] = sd_hz[order]
    if changes:
        chosen = replace(chosen, **changes)  # re-validated (signs, finiteness)
    return chosen, tuple(int(numbers[i]) for i in order)
