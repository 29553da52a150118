"""The identify pipeline: FRF files (UFF 58) -> modes (seed eqs 7-17: LSCE or pLSCF poles,
stabilization, automatic selection, LSFD shapes), as ``bayesupdate identify`` runs it.

Several files are one test (the runs of a roving accelerometer); ``IdentifyRequest`` is
validated once; the result is the frozen ``IdentifyRun`` (the merged FRFs, the
identification and the notes a user must read with the modes).
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.ema.frf_set import FrfSet, merge_frf_sets
from bayesupdate.ema.identify import MAX_SHAPE_SD, Identification, IdentifySettings, identify
from bayesupdate.ema.uff_io import read_uff58
from bayesupdate.errors import BayesUpdateError


@dataclass(frozen=True)
class IdentifyRequest:
    """files : UFF 58 FRF files (one test); band_hz : (lo, hi) [Hz] to analyse or None (all
    lines); max_order : highest polynomial order per band (None: the default); method :
    ``"lsce"`` or ``"plscf"``."""

    files: tuple[str, ...]
    band_hz: tuple[float, float] | None = None
    max_order: int | None = None
    method: str = "lsce"

    def __post_init__(self):
        if not self.files:
            raise BayesUpdateError("identify: give at least one FRF file")
        if self.max_order is not None and self.max_order < 2:
            raise BayesUpdateError(f"--max-order {self.max_order}: must be at least 2")


@dataclass(frozen=True)
class FrfFiles:
    """The FRFs read from each file (``file_sets``), their merged set and the merge notes."""

    files: tuple[str, ...]
    file_sets: tuple[FrfSet, ...]
    frfs: FrfSet
    merge_notes: tuple[str, ...]


@dataclass(frozen=True)
class IdentifyRun:
    """The data identified and the identification (``ema.identify.Identification``)."""

    data: FrfFiles
    identification: Identification

    @property
    def notes(self) -> tuple[str, ...]:
        return identification_notes(self.identification, self.data.merge_notes)


def read_frf_files(files) -> FrfFiles:
    """Read and merge the FRF files of one test."""
    file_sets = tuple(read_uff58(path) for path in files)
    frfs, merge_notes = merge_frf_sets(list(file_sets))
    return FrfFiles(tuple(str(p) for p in files), file_sets, frfs, tuple(merge_notes))


def identify_frfs(data: FrfFiles, request: IdentifyRequest) -> IdentifyRun:
    """The modes of the merged FRFs with the request's band, order and estimator."""
    settings = IdentifySettings(max_order=request.max_order, method=request.method)
    return IdentifyRun(data, identify(data.frfs, band_hz=request.band_hz, settings=settings))


def identification_notes(result: Identification, merge_notes=()) -> tuple[str, ...]:
    """What a user must know to read the modes (the same lines on the terminal and in the
    report): merged ranges, MPC not defined, unscaled shapes, capped shape errors, dropped
    poles, resonances cut by the range's ends."""
    modes = result.modes
    notes = list(merge_notes)
    if len(modes.dof_labels) < 2:
        notes.append("MPC not reported: shapes have one DOF, so phase collinearity is undefined")
    if not np.all(modes.extra.get("mass_normalised", result.mass_normalised)):
        notes.append(
            "shapes without a driving point are unscaled (largest component 1), "
            "not mass-normalised; measure a driving point to scale them"
        )
    if np.any(modes.extra.get("shape_sd_fallback", False)):
        notes.append(f"shape_sd_rel not estimable for some modes: set to {MAX_SHAPE_SD}")
    dropped = np.asarray(result.extra.get("dropped_hz", ()), dtype=float)
    if dropped.size:
        notes.append(
            "stable poles dropped as not physical (explain little of the FRF, peak near the "
            "fit residual): " + ", ".join(f"{x:.2f}" for x in dropped) + " Hz"
        )
    cut = np.asarray(result.extra.get("cut_hz", ()), dtype=float)
    if cut.size:
        notes.append(
            "resonances cut by an end of the analysed range, fitted but not reported as modes: "
            + ", ".join(f"{x:.2f}" for x in cut)
            + " Hz; widen the band to identify them"
        )
    return tuple(notes)
