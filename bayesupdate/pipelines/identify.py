"""The identify pipeline: FRF files (UFF 58) -> modes (seed eqs 7-17: LSCE or pLSCF poles,
stabilization, automatic selection, LSFD shapes), as ``bayesupdate identify`` runs it.

Several files are one test (the runs of a roving accelerometer); ``IdentifyRequest`` is
validated once; the result is the frozen ``IdentifyRun`` (the merged FRFs, the
identification and the notes a user must read with the modes).  With several files the runs
are grouped where poles shift between them (:mod:`bayesupdate.ema.run_groups`): each group's
poles and residues are estimated apart, and the modes reported are the groups' combined
(frequency, damping, sd with the spread) with the shapes assembled over the groups.
``identify_summary`` is the record ``identify --json`` prints, with the rule of when a mode's
MPC means something (``mpc_reasons``).
"""

from dataclasses import dataclass, replace

import numpy as np

from bayesupdate.ema.frf_set import FrfSet, merge_frf_sets
from bayesupdate.ema.identify import MAX_SHAPE_SD, Identification, IdentifySettings, identify
from bayesupdate.ema.uff_io import read_uff58
from bayesupdate.errors import BayesUpdateError


@dataclass(frozen=True)
class IdentifyRequest:
    """files : UFF 58 FRF files (one test); band_hz : (lo, hi) [Hz] to analyse or None (all
    lines); max_order : highest polynomial order per band (None: the default); method :
    ``"lsce"`` or ``"plscf"``; groups : file indices (from 0) per run group, or None to find
    them (:func:`~bayesupdate.ema.run_groups.group_poles`)."""

    files: tuple[str, ...]
    band_hz: tuple[float, float] | None = None
    max_order: int | None = None
    method: str = "lsce"
    groups: tuple[tuple[int, ...], ...] | None = None

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
    """The modes of the merged FRFs with the request's band, order and estimator; with
    several files, per run group (:func:`_grouped`)."""
    settings = IdentifySettings(max_order=request.max_order, method=request.method)
    result = identify(data.frfs, band_hz=request.band_hz, settings=settings)
    if len(data.files) > 1 or request.groups is not None:
        result = _grouped(data, result, request.groups)
    return IdentifyRun(data, result)


def _grouped(data: FrfFiles, result: Identification, groups=None) -> Identification:
    """The identification with its modes re-estimated per run group
    (:func:`~bayesupdate.ema.run_groups.group_poles`) when there is more than one group;
    ``extra["run_groups"]`` holds the groups either way, and the modes' ``extra`` the
    per-group values (``group_*`` arrays (m, G), ``frequency_spread_hz``, ``pole_shift``,
    ``mpc_one_pole``: the MPC with one pole per mode over all runs)."""
    from bayesupdate.ema.run_groups import group_poles

    f = data.frfs.frequencies_hz
    lines = tuple(int(np.argmin(np.abs(f - x))) for x in result.fit_range_hz)
    rg = group_poles(
        data.frfs, data.file_sets, result.poles, result.extra["basis_poles"], lines, groups
    )
    extra = {**result.extra, "run_groups": rg}
    if len(rg.groups) == 1:
        return replace(result, extra=extra)
    return replace(result, modes=_grouped_modes(result.modes, rg, len(data.files)), extra=extra)


def _grouped_modes(modes, rg, n_files: int):
    """ModalData of the combined groups (:class:`~bayesupdate.ema.run_groups.RunGroups`)."""
    power = np.sum(np.abs(rg.shapes) ** 2, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        sd_rel = np.sqrt(np.sum(rg.shape_error_var, axis=0) / power)
    fallback = ~np.isfinite(sd_rel) | (sd_rel <= 0) | (sd_rel > MAX_SHAPE_SD)
    group_of_file = np.zeros(n_files, int)
    for k, g in enumerate(rg.groups):
        group_of_file[list(g.files)] = k
    extra = {
        **modes.extra,
        "mass_normalized": rg.mass_normalized,
        "shape_sd_fallback": fallback,
        "mpc_one_pole": modes.mpc,
        "frequency_one_pole_hz": modes.frequencies_hz,
        "frequency_spread_hz": rg.spread_hz,
        "pole_shift": rg.shifted,
        "group_poles_used": rg.own_poles,
        "group_frequencies_hz": np.array([g.frequencies_hz for g in rg.groups]).T,
        "group_damping_ratio": np.array([g.damping_ratio for g in rg.groups]).T,
        "group_sd_hz": np.array([g.sd_hz for g in rg.groups]).T,
        "group_mpc": np.array([g.mpc for g in rg.groups]).T,
        "group_sees": np.array([g.seen for g in rg.groups]).T,
        "group_of_file": group_of_file,
    }
    return replace(
        modes,
        frequencies_hz=rg.frequencies_hz,
        damping_ratio=rg.damping_ratio,
        shapes=rg.shapes,
        dof_labels=rg.labels,
        mpc=rg.mpc,
        shape_sd_rel=np.where(fallback, MAX_SHAPE_SD, sd_rel),
        identification_sd_hz=rg.sd_hz,
        extra=extra,
    )


def identification_notes(result: Identification, merge_notes=()) -> tuple[str, ...]:
    """What a user must know to read the modes (the same lines on the terminal and in the
    report): merged ranges, MPC not defined, unscaled shapes, capped shape errors, dropped
    poles, resonances cut by the range's ends."""
    modes = result.modes
    notes = list(merge_notes)
    notes += _group_notes(result)
    if len(modes.dof_labels) < 2:
        notes.append("MPC not reported: shapes have one DOF, so phase collinearity is undefined")
    if not np.all(modes.extra.get("mass_normalized", result.mass_normalized)):
        notes.append(
            "shapes without a driving point are unscaled (largest component 1), "
            "not mass-normalized; measure a driving point to scale them"
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


def _files_text(files) -> str:
    """Run positions (from 1) as ranges: (0, 1, 2, 5) -> "1-3, 6"."""
    runs, out = [j + 1 for j in files], []
    start = prev = runs[0]
    for j in [*runs[1:], None]:
        if j is not None and j == prev + 1:
            prev = j
            continue
        out.append(f"{start}" if start == prev else f"{start}-{prev}")
        if j is not None:
            start = prev = j
    return ", ".join(out)


def _group_notes(result: Identification) -> list[str]:
    """The note naming the run groups and the modes whose poles shift between them."""
    rg = result.extra.get("run_groups")
    if rg is None or len(rg.groups) == 1:
        return []
    how = "found from the poles' shifts" if rg.automatic else "as given"
    names = "; ".join(f"files {_files_text(g.files)}" for g in rg.groups)
    text = f"{len(rg.groups)} run groups ({how}): {names}"
    extra = result.modes.extra
    shifted = np.flatnonzero(extra["group_poles_used"])
    small = np.flatnonzero(extra["pole_shift"] & ~extra["group_poles_used"])
    if shifted.size:
        parts = []
        for r in shifted:
            fg = extra["group_frequencies_hz"][r]
            parts.append(
                f"mode {r + 1} " + " / ".join(f"{x:.3f}" for x in fg) + " Hz "
                f"(MPC {extra['mpc_one_pole'][r]:.2f} with one pole, "
                f"{result.modes.mpc[r]:.2f} assembled from the groups)"
            )
        text += "; poles shift between them (roving sensors' mass, shaker attachment or "
        text += "drift between runs), residues fitted at each group's pole: " + "; ".join(parts)
    if small.size:
        text += "; shifted by less than a half-power half-width, one pole kept: mode " + ", ".join(
            str(r + 1) for r in small
        )
    return [text]


def mpc_reasons(modes) -> list[str | None]:
    """Per mode: None when its MPC is meaningful, else why it is not reported (the phase
    scatter of a shape over one DOF says nothing; an MPC not computed or not finite)."""
    if len(modes.dof_labels) < 2:
        return ["one DOF"] * modes.n_modes
    if modes.mpc is None:
        return ["not computed"] * modes.n_modes
    return [None if np.isfinite(v) else "not finite" for v in modes.mpc]


_CUT_KEYS = ("cut_hz", "cut_damping", "cut_end")


def identify_summary(result: Identification, out, notes, report=None) -> dict:
    """What ``identify --json`` prints: per mode its frequency [Hz], identification sd [Hz],
    damping ratio, MPC (None where ``mpc_reasons`` says it means nothing), shape sd, scaling,
    stable orders and the run-group values; the run groups, the dropped poles [Hz], the
    resonances an end of the range cuts, the notes and the files written (``out``, ``report``
    or None)."""
    modes = result.modes
    no_mpc = mpc_reasons(modes)  # e.g. the phase scatter of one value says nothing
    summary = {
        "modes": [
            {
                "frequency_hz": float(modes.frequencies_hz[r]),
                "identification_sd_hz": float(modes.identification_sd_hz[r]),
                "damping_ratio": float(modes.damping_ratio[r]),
                "mpc": None if no_mpc[r] else float(modes.mpc[r]),
                "shape_sd_rel": float(modes.shape_sd_rel[r]),
                "mass_normalized": bool(modes.extra["mass_normalized"][r]),
                "stable_orders": int(modes.extra["stable_orders"][r]),
                **_group_keys(modes.extra, r),
            }
            for r in range(modes.n_modes)
        ],
        "groups": _groups(result),
        "dropped_hz": [float(x) for x in result.extra["dropped_hz"]],
        # resonances an end of the range cuts: fitted, not reported as modes (ema.identify)
        "cut": [
            {"frequency_hz": float(f), "damping_ratio": float(z), "end": e}
            for f, z, e in zip(*(result.extra[k] for k in _CUT_KEYS), strict=True)
        ],
        "out": str(out),
        "notes": list(notes),
    }
    if report is not None:
        summary["report"] = str(report)
    return summary


def _group_keys(extra: dict, r: int) -> dict:
    """Per-mode run-group values (absent with one group): the frequency spread [Hz], whether
    the pole shifts, the MPC and frequency with one pole over all runs, and per group the
    frequency [Hz], damping, sd [Hz], MPC and whether the group sees the mode."""
    if "group_frequencies_hz" not in extra:
        return {}
    return {
        "frequency_spread_hz": float(extra["frequency_spread_hz"][r]),
        "pole_shift": bool(extra["pole_shift"][r]),
        "group_poles_used": bool(extra["group_poles_used"][r]),
        "mpc_one_pole": float(extra["mpc_one_pole"][r]),
        "frequency_one_pole_hz": float(extra["frequency_one_pole_hz"][r]),
        "per_group": [
            {
                "frequency_hz": float(f),
                "damping_ratio": float(z),
                "sd_hz": float(s),
                "mpc": float(m),
                "sees": bool(k),
            }
            for f, z, s, m, k in zip(
                *(
                    extra[key][r]
                    for key in (
                        "group_frequencies_hz",
                        "group_damping_ratio",
                        "group_sd_hz",
                        "group_mpc",
                        "group_sees",
                    )
                ),
                strict=True,
            )
        ],
    }


def _groups(result) -> list[dict]:
    """Run groups: file positions (from 1) and whether they were found automatically."""
    rg = result.extra.get("run_groups")
    if rg is None:
        return []
    return [{"files": [j + 1 for j in g.files], "automatic": rg.automatic} for g in rg.groups]
