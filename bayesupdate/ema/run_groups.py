"""Poles per run group: a roving-sensor test whose poles shift between runs.

A roving accelerometer test is measured run by run; the structure between runs is not quite
one structure (the roving sensors' mass moves, the shaker is re-attached, the temperature
drifts).  One global pole per mode then sits between the runs' own poles, and the residues of
the runs away from it are fitted at the wrong pole: their phase turns and the assembled shape
is complex (mAEWing1 GVT, mode 1 at 7.796 Hz in runs 1-5 and 7.817 Hz in runs 6-10, 1.6
half-power half-widths apart: MPC 0.61 with one pole).  Test engineers identify each group of
runs apart and assemble the shapes, checking the consistency of the parts (Ewins 2000,
*Modal Testing: Theory, Practice and Application*, on data from several test set-ups).  Here:

1. Each file's poles are refined on its own FRFs (:func:`local_poles`: per mode, variable
   projection on the lines within ``WINDOW_WIDTHS`` half-widths of the global pole, its
   neighbours fixed), with each frequency's sd (:func:`~bayesupdate.ema.frequency_sd.
   frequency_sd`) and whether the file sees the mode (:func:`sees`).
2. Groups: the files in the order given (runs in time), split by binary segmentation over
   the modes every file sees, where weighted-mean frequencies differ by ``Z_SPLIT`` or more
   combined sds and ``MIN_SHIFT_WIDTHS`` half-power half-widths (:func:`split_files`); or
   the user's groups.
3. Each group's poles are refined on the group's FRFs in the same way; the residues of each
   group are fitted by LSFD at its own poles for the modes whose group frequencies spread by
   ``MIN_SHIFT_WIDTHS`` half-widths or more (and shift by more than their sds), at the
   global pole for the others (there one pole turns no residue by more than 45 degrees, and
   separate poles only add their scatter: GVT, the 2 %-damped 30.9 Hz mode, groups at 30.93,
   30.66 and 30.49 Hz, 0.7 half-widths: MPC 0.90 with one pole, 0.75 with its groups'), and
   the shapes assembled over all groups
   (:func:`~bayesupdate.ema.lsfd.shapes_from_residues`).  Consistency: the MPC of each
   group's part and of the assembly.
4. Per mode the frequency and damping are the means over the groups that see it, weighted by
   1/(sd^2 + tau^2) (random effects, :func:`random_effects`); the frequency sd is
   sqrt(var(mean) + tau^2), so a shift between groups counts as test uncertainty.
"""

from dataclasses import dataclass, replace

import numpy as np

from bayesupdate.ema.frequency_sd import frequency_sd, mode_window
from bayesupdate.ema.frf_set import FrfSet
from bayesupdate.ema.lsfd import lsfd, mpc, shapes_from_residues
from bayesupdate.ema.pole_refinement import refine_poles
from bayesupdate.ema.synthesis import modal_from_poles, poles_from_modal
from bayesupdate.errors import BayesUpdateError

#: a group boundary is placed where a mode's weighted-mean frequencies on its two sides are
#: this many combined sds apart (noise alone: two-sided probability 6e-5; the GVT's cuts, at
#: runs 5|6 and 8|9, have z 78 and 35)
Z_SPLIT = 4.0
#: ... and by at least this many half-power half-widths |Re s| / 2 pi: the offset at which one
#: pole shared by both sides turns a side's residues by 45 degrees, so a shift matters for the
#: shapes (GVT mode 1, runs 1-5 | 6-10: 1.6; runs 6-7 | 8-10: 0.7, no boundary)
MIN_SHIFT_WIDTHS = 1.0
#: floor of a frequency sd, relative to the frequency (a window without noise gives ~0)
SD_FLOOR = 1e-6
#: a group's pole may move this many half-power half-widths from the global pole (the window
#: of :func:`~bayesupdate.ema.frequency_sd.mode_window` is 5 wide): a shift of a few widths
#: is what a group estimate exists for (GVT mode 1: 1.6)
MAX_GROUP_MOVE = 4.0


@dataclass(frozen=True)
class GroupPoles:
    """One run group: files (indices into the files given), rows (FRF rows of the merged
    set), poles (m,) [rad/s], sd_hz (m,) frequency sd, seen (m,) bool, residues and
    residue_var (n_rows, m) of its LSFD fit at its own poles."""

    files: tuple[int, ...]
    rows: np.ndarray
    poles: np.ndarray
    sd_hz: np.ndarray
    seen: np.ndarray
    residues: np.ndarray
    residue_var: np.ndarray

    @property
    def frequencies_hz(self) -> np.ndarray:
        return modal_from_poles(self.poles)[0]

    @property
    def damping_ratio(self) -> np.ndarray:
        return modal_from_poles(self.poles)[1]

    @property
    def mpc(self) -> np.ndarray:
        """MPC (m,) of the group's residues (scale-free, so that of its part of the shape)."""
        return mpc(self.residues)


@dataclass(frozen=True)
class RunGroups:
    """Result of :func:`group_poles`: the groups, whether they were found automatically, the
    split statistic of each boundary (max over modes of the z of :func:`split_files`), and
    per mode (m,): frequency [Hz], damping, sd [Hz] (mean and spread), spread [Hz] (max - min
    over the groups that see it), shifted (bool: its highest and lowest group frequencies
    differ by more than ``Z_SPLIT`` combined sds), own_poles (bool: its residues fitted at
    each group's own pole, module docstring point 3), the assembled shapes (n_dof, m) with
    labels, their MPC and error variance."""

    groups: tuple[GroupPoles, ...]
    automatic: bool
    split_z: tuple[float, ...]
    frequencies_hz: np.ndarray
    damping_ratio: np.ndarray
    sd_hz: np.ndarray
    spread_hz: np.ndarray
    shifted: np.ndarray
    own_poles: np.ndarray
    labels: tuple[str, ...]
    shapes: np.ndarray
    shape_error_var: np.ndarray
    mass_normalized: np.ndarray

    @property
    def mpc(self) -> np.ndarray:
        return mpc(self.shapes)


def file_rows(file_sets) -> list[np.ndarray]:
    """FRF row indices of each file in the merged set (rows are stacked file by file)."""
    sizes = np.cumsum([0, *(s.n_frf for s in file_sets)])
    return [np.arange(a, b) for a, b in zip(sizes[:-1], sizes[1:], strict=True)]


def local_poles(frfs: FrfSet, rows, poles, others, lines) -> tuple[np.ndarray, np.ndarray]:
    """Poles (m,) [rad/s] refined on the FRF rows ``rows`` and their frequency sds (m,) [Hz].

    Per mode, variable projection (:func:`~bayesupdate.ema.pole_refinement.refine_poles`) on
    the lines of its window (:func:`~bayesupdate.ema.frequency_sd.mode_window`) within
    ``lines`` (first, last), the other poles there fixed; a refinement moving it more than
    ``MAX_GROUP_MOVE`` half-widths or half-way to another pole (onto a neighbour of a
    cluster), or unstable, keeps the global pole.  others (k,): the
    basis' other poles (residual poles, cut resonances), fixed."""
    f, h = frfs.frequencies_hz, frfs.frf[rows]
    everything = np.concatenate([poles, others])
    out = np.array(poles, dtype=complex)
    for r in range(poles.size):
        idx, free, fixed = mode_window(f, everything, r, *lines)
        if idx.size < 4:
            continue
        basis = np.concatenate([free[1:], fixed])
        ref = refine_poles(
            f[idx], h[:, idx], free[:1], np.zeros(0, complex), basis, frfs.kind,
            max_move=MAX_GROUP_MOVE,
        )  # fmt: skip
        gap = np.min(np.abs(np.delete(everything, r) - poles[r]), initial=np.inf)
        if ref.accepted and abs(ref.poles[0] - poles[r]) < 0.5 * gap:
            out[r] = ref.poles[0]
    sd = frequency_sd(f, h, out, others, frfs.kind, lines)
    return out, np.where(np.isfinite(sd), sd, np.abs(out.real) / (2 * np.pi))


def _fit_group(frfs: FrfSet, rows, poles, others, lines):
    """LSFD residues and their variances (n_rows, m) of the rows at their poles over lines
    (first, last)."""
    a, b = lines
    basis = np.concatenate([poles, others])
    fit = lsfd(frfs.frequencies_hz[a : b + 1], frfs.frf[rows, a : b + 1], basis, frfs.kind)
    m = poles.size
    return fit.residues[:, :m], fit.residue_var[:, :m]


def estimate_group(frfs: FrfSet, files, rows, poles, others, lines) -> GroupPoles:
    """:class:`GroupPoles` of the FRF rows ``rows`` (the files ``files``): a mode the rows do
    not see (:func:`sees`) keeps the global pole, as its refinement there fits noise."""
    own, sd = local_poles(frfs, rows, poles, others, lines)
    seen = sees(own, sd)
    own = np.where(seen, own, poles)
    res, var = _fit_group(frfs, rows, own, others, lines)
    return GroupPoles(tuple(files), np.asarray(rows), own, sd, seen, res, var)


def sees(poles: np.ndarray, sd_hz: np.ndarray) -> np.ndarray:
    """Whether FRFs see each mode (m,) bool: its frequency sd below its half-power half-width
    |Re s| / 2 pi.  (GVT, one run of 2 FRFs: mode 1 sd 0.0002-0.001 Hz against a 0.013 Hz
    half-width; the 9.47 Hz mode on the other wing 0.1-0.5 Hz against 0.084 Hz.)"""
    return np.asarray(sd_hz) < np.abs(np.asarray(poles).real) / (2 * np.pi)


def _side(f, sd, seen, part):
    """Weighted mean frequency (m,) and its variance (m,) over the units ``part`` that see
    each mode (NaN where none does)."""
    w = np.where(seen[part], 1.0 / sd[part] ** 2, 0.0)
    total = w.sum(axis=0)
    with np.errstate(invalid="ignore", divide="ignore"):
        return (w * f[part]).sum(axis=0) / total, 1.0 / total


def split_files(f, sd, seen, width, z_split: float = Z_SPLIT):
    """Contiguous groups of units (files in run order) by binary segmentation.

    f, sd (n, m) [Hz], seen (n, m) bool per unit and mode; width (m,) [Hz]: each mode's
    half-power half-width.  For every cut of a segment, mode r's z is |mean_left -
    mean_right| / sqrt(var_left + var_right) over the units that see it on each side
    (:func:`_side`), and its shift the means' difference in widths.  Over the modes with
    z >= ``z_split``, a cut qualifies when one shifts by ``MIN_SHIFT_WIDTHS`` or more; the
    segment is cut where the sum of their squared shifts is largest (the cut that explains
    the shifts of all modes together; the sds of a run's lightly damped modes are tiny, so
    z alone would cut at any drift), and both parts are cut again.  Returns (groups as lists of unit
    indices, z of the deciding mode at each cut made)."""
    groups, cuts = [], []
    sd = np.maximum(sd, SD_FLOOR * np.abs(f))

    def cut(units: list[int]) -> None:
        best, where = (0.0, 0.0), None
        for c in range(1, len(units)):
            m1, v1 = _side(f, sd, seen, units[:c])
            m2, v2 = _side(f, sd, seen, units[c:])
            with np.errstate(invalid="ignore"):
                z = np.abs(m1 - m2) / np.sqrt(v1 + v2)
                shift = np.abs(m1 - m2) / width
            ok = np.isfinite(z) & (z >= z_split)
            score = float(np.sum(shift[ok] ** 2))
            if np.any(shift[ok] >= MIN_SHIFT_WIDTHS) and score > best[0]:
                best, where = (score, float(np.max(z[ok]))), c
        if where is None:
            groups.append(units)
            return
        cuts.append(best[1])
        cut(units[:where])
        cut(units[where:])

    cut(list(range(f.shape[0])))
    return groups, cuts


def random_effects(f: np.ndarray, sd: np.ndarray, seen: np.ndarray) -> tuple:
    """Per mode over the groups that see it (all, where none does): the random-effects mean
    (DerSimonian & Laird 1986, Control. Clin. Trials 7, 177-188), the between-group variance
    tau^2 and the weights.  f, sd, seen (G, m).  With w = 1/sd^2, Q = sum w (f - mean_w)^2,
    tau^2 = max(0, (Q - (k - 1)) / (sum w - sum w^2 / sum w)); the mean is weighted by
    1 / (sd^2 + tau^2), so groups that disagree by more than their sds count alike."""
    seen = np.where(seen.any(axis=0), seen, True)
    sd = np.maximum(sd, SD_FLOOR * np.abs(f))
    w = np.where(seen, 1.0 / sd**2, 0.0)
    mean_w = (w * f).sum(0) / w.sum(0)
    q = (w * (f - mean_w) ** 2).sum(0)
    k = seen.sum(0)
    denom = w.sum(0) - (w**2).sum(0) / w.sum(0)
    with np.errstate(invalid="ignore", divide="ignore"):
        tau2 = np.where((k > 1) & (denom > 0), np.maximum(0.0, (q - (k - 1)) / denom), 0.0)
    w_star = np.where(seen, 1.0 / (sd**2 + tau2), 0.0)
    return (w_star * f).sum(0) / w_star.sum(0), tau2, w_star


def _combine(groups: tuple[GroupPoles, ...]) -> tuple:
    """Per mode: frequency, damping, sd, spread [Hz], shifted (module docstring, point 4)."""
    f = np.array([g.frequencies_hz for g in groups])  # (G, m)
    sd = np.array([g.sd_hz for g in groups])
    seen = np.array([g.seen for g in groups])
    mean, tau2, w = random_effects(f, sd, seen)
    on = w > 0
    damping = (w * np.array([g.damping_ratio for g in groups])).sum(0) / w.sum(0)
    sd_total = np.sqrt(1.0 / w.sum(0) + tau2)
    spread = np.where(on.sum(0) > 1, np.ptp(np.where(on, f, mean), axis=0), 0.0)
    cols = np.arange(f.shape[1])
    lo = np.argmin(np.where(on, f, np.inf), axis=0)
    hi = np.argmax(np.where(on, f, -np.inf), axis=0)
    gap = np.hypot(sd[lo, cols], sd[hi, cols])
    shifted = (on.sum(0) > 1) & (f[hi, cols] - f[lo, cols] > Z_SPLIT * gap)
    return mean, damping, sd_total, spread, shifted


def group_poles(
    frfs: FrfSet,
    file_sets,
    poles: np.ndarray,
    others: np.ndarray,
    lines: tuple[int, int],
    groups: tuple[tuple[int, ...], ...] | None = None,
) -> RunGroups:
    """Run groups of a multi-file test and the modes estimated per group (module docstring).

    frfs : the merged set (files stacked in order, :func:`~bayesupdate.ema.frf_set.
    merge_frf_sets`); file_sets : the FrfSet of each file; poles (m,) [rad/s]: the global
    modes' poles; others (k,): the basis' other poles; lines (first, last): the LSFD fit's
    line indices; groups : file indices (from 0) per group, or None to find them
    (:func:`split_files`).
    """
    rows = file_rows(file_sets)
    automatic = groups is None
    cuts: list[float] = []
    if automatic:
        units = [estimate_group(frfs, (j,), r, poles, others, lines) for j, r in enumerate(rows)]
        f = np.array([u.frequencies_hz for u in units])
        sd = np.array([u.sd_hz for u in units])
        seen = np.array([u.seen for u in units])
        seen &= seen.all(axis=0)  # modes every file sees: others' estimates jump between modes
        found, cuts = split_files(f, sd, seen, np.abs(poles.real) / (2 * np.pi))
        groups = tuple(tuple(g) for g in found)
    _check_groups(groups, len(file_sets))
    est = tuple(
        estimate_group(frfs, g, np.concatenate([rows[j] for j in g]), poles, others, lines)
        for g in groups
    )
    mean, damping, sd, spread, shifted = _combine(est)
    own = shifted & (spread >= MIN_SHIFT_WIDTHS * np.abs(poles.real) / (2 * np.pi))
    residues = np.zeros((frfs.n_frf, poles.size), complex)
    var = np.zeros((frfs.n_frf, poles.size))
    for k, g in enumerate(est):
        if not np.all(own):  # a mode shifted by less than a half-width keeps the global pole
            at = np.where(own, g.poles, poles)
            res, rvar = _fit_group(frfs, g.rows, at, others, lines)
            est = (*est[:k], replace(g, residues=res, residue_var=rvar), *est[k + 1 :])
            g = est[k]
        residues[g.rows], var[g.rows] = g.residues, g.residue_var
    scaled = shapes_from_residues(residues, poles_from_modal(mean, damping), frfs.sets(), var)
    per_mode = (mean, damping, sd, spread, shifted, own)
    shapes = (scaled.labels, scaled.shapes, scaled.error_var, scaled.mass_normalized)
    return RunGroups(est, automatic, tuple(cuts), *per_mode, *shapes)


def _check_groups(groups, n_files: int) -> None:
    flat = sorted(j for g in groups for j in g)
    if flat != list(range(n_files)) or any(len(g) == 0 for g in groups):
        raise BayesUpdateError(
            f"--groups: each of the {n_files} files must be in exactly one group "
            "(e.g. --groups 1-5,6-10)"
        )


def parse_groups(text: str | None, n_files: int) -> tuple[tuple[int, ...], ...] | None:
    """File groups from ``"1-5,6-10"`` or ``"1 2 3,4 5"`` (file positions from 1) as indices
    from 0; None for None."""
    if text is None:
        return None
    out = []
    try:
        for part in text.split(","):
            members: list[int] = []
            for item in part.split():
                a, _, b = item.partition("-")
                members += list(range(int(a) - 1, int(b or a)))
            out.append(tuple(members))
    except ValueError:
        raise BayesUpdateError(
            f"--groups {text!r}: give file positions from 1, groups split by commas (e.g. 1-5,6-10)"
        ) from None
    groups = tuple(out)
    _check_groups(groups, n_files)
    return groups
