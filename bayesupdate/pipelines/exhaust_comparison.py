"""The two exhausts side by side: the beam model ``exhaust`` and the shell model
``exhaust_shell`` on seed Table 1 (each solved here), their solve time (measured here), and
the calibrated optimum against Table 2 and the front of Expr against the mass error, either
read from a file (``compare_exhausts``: a calibration at the default mesh takes minutes to
hours) or computed in the run (``demo_comparison``: the demo's own optima and fronts).

``better_exhaust`` applies one rule, "whichever reproduces the paper better, by the
numbers", to these records (the model a demo should use); ``report.exhaust_comparison`` draws
them.
"""

import json
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.models import exhaust_paper as paper

MODELS = ("exhaust", "exhaust_shell")


@dataclass(frozen=True)
class Calibrated:
    """A calibrated optimum against Table 2 (mass kept) and, from a front file, the front.

    expr : seed eq. 19 at the optimum; mass_kg : its mass; swapped : a mode swap in the pairing;
    front : ((mass error [%], Expr), ...) from the lightest mass weight to the heaviest (empty
    for a calibration result file); source : the file read, or how the run computed it."""

    expr: float
    mass_kg: float
    swapped: bool
    front: tuple[tuple[float, float], ...]
    source: str


@dataclass(frozen=True)
class ExhaustRecord:
    """One exhaust on seed Table 1 and its speed.

    name, n_dof; frequencies_hz (12,) at the initial design; mass_kg; build_s : model build
    (``get_model``) [s]; solve_s : median wall time of ``solve(n_modes=12)`` [s] over
    ``solves`` calls; calibrated : None without a file."""

    name: str
    n_dof: int
    frequencies_hz: np.ndarray
    mass_kg: float
    build_s: float
    solve_s: float
    solves: int
    calibrated: Calibrated | None = None

    @property
    def table1_error_pct(self) -> np.ndarray:
        return 100.0 * (self.frequencies_hz / paper.TABLE1_FEA_HZ - 1.0)

    @property
    def table1_rms_pct(self) -> float:
        return float(np.sqrt(np.mean(self.table1_error_pct**2)))

    @property
    def table1_max_pct(self) -> float:
        return float(np.abs(self.table1_error_pct).max())


def measure(name: str, options: dict | None = None, solves: int = 3) -> ExhaustRecord:
    """Build ``name`` (``get_model(name, **options)``) and solve it ``solves`` times at the
    initial design (the median wall time is the speed; the machine's load is not controlled)."""
    from bayesupdate.models import get_model

    t0 = time.perf_counter()
    model = get_model(name, **(options or {}))
    build = time.perf_counter() - t0
    times, result = [], None
    for _ in range(max(int(solves), 1)):
        t0 = time.perf_counter()
        result = model.solve(n_modes=12)
        times.append(time.perf_counter() - t0)
    return ExhaustRecord(
        name, int(model.structure.n_dof), np.asarray(result.frequencies_hz),
        float(result.mass_kg), build, float(np.median(times)), len(times),
    )  # fmt: skip


def read_calibrated(path) -> Calibrated:
    """A calibrated optimum from a ``bayesupdate calibrate --out`` HDF5 file (no front) or from
    a front file of ``studies/exhaust_shell_front.py`` (JSON: "optimum" and "front")."""
    path = Path(path)
    if not path.is_file():
        raise BayesUpdateError(f"comparison file {path}: not found; give a calibration result")
    if path.suffix.lower() == ".json":
        try:
            doc = json.loads(path.read_text())
            opt, front = doc["optimum"], doc["front"]
            points = tuple((float(p["mass_error_pct"]), float(p["expr"])) for p in front)
            return Calibrated(
                float(opt["expr"]), float(opt["mass_kg"]), bool(opt["swapped"]), points, str(path)
            )
        except (ValueError, KeyError, TypeError) as exc:
            raise BayesUpdateError(
                f"comparison file {path}: not a front file ({exc!r} missing or malformed); "
                "write one with studies/exhaust_shell_front.py"
            ) from None
    from bayesupdate.inference.results import read_result

    attrs = read_result(path)["optimum"]["attrs"]
    return Calibrated(
        float(attrs["expr"]), float(attrs["mass_kg"]), bool(attrs["swapped"]), (), str(path)
    )


def better_exhaust(records: dict[str, ExhaustRecord]) -> tuple[str, str]:
    """Which exhaust reproduces the paper better, by the numbers: each model scores one point for
    each of the paper's numbers it reproduces better than the other (Table 1 RMS error, Table 1
    largest error and, when both were calibrated, Expr against Table 2 at the mass-kept
    optimum); more points wins, a tie goes to the smaller Table 1 RMS.  Returns (the model's
    name, the reason in words)."""
    a, b = (records[m] for m in MODELS)
    numbers = [
        ("Table 1 RMS error [%]", a.table1_rms_pct, b.table1_rms_pct),
        ("Table 1 largest error [%]", a.table1_max_pct, b.table1_max_pct),
    ]
    if a.calibrated is not None and b.calibrated is not None:
        numbers.append(("Expr vs Table 2, mass kept", a.calibrated.expr, b.calibrated.expr))
    score_a = sum(x < y for _, x, y in numbers)
    score_b = sum(y < x for _, x, y in numbers)
    if score_a != score_b:
        winner = a.name if score_a > score_b else b.name
    else:
        winner = a.name if a.table1_rms_pct <= b.table1_rms_pct else b.name
    detail = "; ".join(f"{label}: {a.name} {x:.4g}, {b.name} {y:.4g}" for label, x, y in numbers)
    reason = (
        f"{winner} reproduces the paper better on {max(score_a, score_b)} of {len(numbers)} "
        f"numbers ({detail})"
    )
    return winner, reason


def compare_exhausts(
    files: dict | None = None, options: dict | None = None, solves: int = 3
) -> dict[str, ExhaustRecord]:
    """Both exhausts measured (``measure``), each with its calibration file when ``files``
    {model name: path} gives one.  ``options`` {model name: ``get_model`` options}."""
    files = dict(files or {})
    _check_names(files, "comparison files")
    return _measured({k: read_calibrated(v) for k, v in files.items()}, options, solves)


def _check_names(mapping: dict, where: str) -> None:
    unknown = sorted(set(mapping) - set(MODELS))
    if unknown:
        raise BayesUpdateError(f"{where}: unknown model {unknown[0]!r}; use {MODELS}")


def _measured(calibrated: dict, options: dict | None, solves: int) -> dict[str, ExhaustRecord]:
    from dataclasses import replace

    records = {}
    for name in MODELS:
        record = measure(name, (options or {}).get(name), solves)
        if name in calibrated:
            record = replace(record, calibrated=calibrated[name])
        records[name] = record
    return records


def calibrated_in_run(optimum, what: str) -> Calibrated:
    """A ``Calibrated`` record of an optimum and front computed in this run (the demo's
    ``pipelines.demo.OptimumPart``: .calibration, .front); ``what`` says how, for the report."""
    c = optimum.calibration
    front = tuple((float(p["mass_error_pct"]), float(p["expr"])) for p in optimum.front)
    return Calibrated(float(c.expr), float(c.mass_kg), bool(c.swapped), front, what)


def demo_comparison(
    calibrated: dict[str, Calibrated], options: dict | None = None, solves: int = 3
) -> dict[str, ExhaustRecord]:
    """The demo's side by side: both exhausts measured here (``options``:
    {model name: ``get_model`` options}, the demo's shell mesh), each with its optimum and
    front against Table 2 with the mass kept as the demo computed them (``calibrated``: {model
    name: ``calibrated_in_run``}); ``solves``: as ``measure``."""
    _check_names(calibrated, "comparison")
    return _measured(calibrated, options, solves)
