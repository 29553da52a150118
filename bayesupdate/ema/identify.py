"""End-to-end modal identification: FRFs -> LSCE per band -> stabilization -> automatic poles ->
LSFD shapes -> :class:`~bayesupdate.modal_data.ModalData` plus diagnostics.

The range (the whole axis, or the band given) is split into consecutive narrow bands
(:mod:`bayesupdate.ema.bands`); the modes of all bands are merged, a duplicate pair (frequency
within 1 %, pole-vector MAC >= 0.9) keeping the estimate farther from its band's edges; the poles
at the ends of the analysed range are then refined on the FRFs by variable projection with an
extra pole beyond the end (:func:`_refine_ends`).  A resonance that an end of the range cuts
(its half-power band reaching past the end: :func:`_refine_window`, :func:`_move_cut_modes`)
stays in the fit but is not reported as a mode; ``extra["cut_hz"]`` names it.  Poles are
estimated globally over all FRFs of all test sets; the residues of all FRFs are then fitted at
once by LSFD over the analysed range, and the shapes of the sets are scaled by their driving
points and aligned on shared DOFs (:func:`~bayesupdate.ema.lsfd.shapes_from_residues`).
"""

from dataclasses import dataclass, field, replace

import numpy as np

from bayesupdate.compute.progress import phase
from bayesupdate.correlation import mac_matrix
from bayesupdate.ema.bands import automatic_bands, default_band_lines
from bayesupdate.ema.frequency_sd import frequency_sd
from bayesupdate.ema.frf_set import KIND_POWER, FrfSet
from bayesupdate.ema.indicators import frf_correlation
from bayesupdate.ema.lsce import band_indices, lsce
from bayesupdate.ema.lsfd import LsfdFit, ScaledShapes, lsfd, mpc, shapes_from_residues
from bayesupdate.ema.plscf import plscf
from bayesupdate.ema.pole_refinement import refine_poles
from bayesupdate.ema.stabilization import (
    SelectedPole,
    StabilizationDiagram,
    select_poles,
    stabilization_diagram,
)
from bayesupdate.ema.synthesis import modal_from_poles, synthesize_frf
from bayesupdate.errors import BayesUpdateError
from bayesupdate.modal_data import ModalData


@dataclass(frozen=True)
class Identification:
    """Result of :func:`identify`: the modes and everything needed to judge them."""

    modes: ModalData
    poles: np.ndarray  # (m,) complex [rad/s]
    residues: np.ndarray  # (n_frf, m) complex
    lower_residual: np.ndarray  # (n_frf,)
    upper_residual: np.ndarray  # (n_frf,)
    selected: tuple  # SelectedPole per mode
    diagrams: tuple  # StabilizationDiagram per band
    bands_hz: tuple  # ((lo, hi), ...) analysed bands
    fit_range_hz: tuple  # (lo, hi) of the LSFD fit
    synthesized: np.ndarray  # (n_frf, n_f) synthesized FRFs on the fit range lines
    frf_correlation: np.ndarray  # (n_frf,) FRAC of synthesized vs measured
    mass_normalized: np.ndarray  # (m,) bool
    # dropped_hz (pruned poles); cut_hz, cut_damping, cut_end (:func:`_cut_summary`)
    extra: dict = field(default_factory=dict)


def _merge(candidates: list[tuple[SelectedPole, float]]) -> list[SelectedPole]:
    """Resolve duplicates: keep, of a pair within 1 % and MAC >= 0.9, the more central one."""
    candidates = sorted(candidates, key=lambda c: c[0].frequency_hz)
    kept: list[tuple[SelectedPole, float]] = []
    for pole, centrality in candidates:
        dup = None
        for i, (other, _) in enumerate(kept):
            close = abs(pole.frequency_hz - other.frequency_hz) < 0.01 * pole.frequency_hz
            if close and mac_matrix(pole.vector, other.vector)[0, 0] >= 0.9:
                dup = i
        if dup is None:
            kept.append((pole, centrality))
        elif centrality > kept[dup][1]:
            kept[dup] = (pole, centrality)
    return [p for p, _ in kept]


#: a mode is dropped when it explains less than this fraction of the FRF at its resonance ...
MIN_SIGNIFICANCE = 0.3
#: ... and its peak is less than this many times the local fit residual (a weak real mode
#: beside strong ones explains little of the FRF but stands far above the noise)
MIN_PEAK_TO_RESIDUAL = 10.0
#: ... or, whatever its share, when its peak does not rise above the local fit residual: the
#: share of a pole at an antiresonance is large, as the measured level there is tiny (beam,
#: pLSCF: a pole at 3666 Hz, |H| 1/50 of the median, share 1.3, peak 0.3 x the residual),
#: unless the measured FRFs peak there (:func:`measured_peak`): then the residual is large
#: because a neighbour is missing from the basis, not because the pole fits nothing (mAEWing1
#: GVT, pLSCF: the broad 30.9 Hz hump not stable, the 31.72 Hz mode beside it at 0.9 x)
MIN_PEAK_ABOVE_RESIDUAL = 1.0


def measured_peak(frfs: FrfSet, poles: np.ndarray) -> np.ndarray:
    """Whether the measured sum-FRF (:func:`~bayesupdate.ema.bands.sum_frf`) peaks at each
    pole (m,) bool: its largest value within 3 half-power half-widths |Re s| (at least 3
    lines) of the damped frequency lies within one half-width (at least 1 line) of it, away
    from the window's ends.  An antiresonance, where spurious high-share poles sit, fails."""
    from bayesupdate.ema.bands import sum_frf

    f, s = frfs.frequencies_hz, sum_frf(frfs.frf)
    out = np.zeros(poles.size, bool)
    for r, p in enumerate(poles):
        fd, hw = p.imag / (2 * np.pi), max(abs(p.real) / (2 * np.pi), frfs.df_hz)
        idx = np.flatnonzero(np.abs(f - fd) <= 3 * hw)
        if idx.size < 3:
            continue
        k = idx[np.argmax(s[idx])]
        out[r] = k not in (idx[0], idx[-1]) and abs(f[k] - fd) <= hw
    return out


#: shape_sd_rel is capped here: a shape cannot be less known than its own size
MAX_SHAPE_SD = 1.0


def modal_significance(frfs: FrfSet, poles: np.ndarray, fit: LsfdFit) -> tuple:
    """Share of the measured FRFs each mode explains at its resonance, and its peak over the
    local fit residual; each (m,).

    P_kr = |A_kr (j w_dr)^p / Re s_r| is the mode's own peak height in row k (its term of seed
    eq. 4 at w = w_dr), M_kr the measured level there (RMS over the 3 lines nearest f_dr).
    share_r = sum_k P_kr^2 / sum_k P_kr M_kr (P/M averaged with weights P M, so rows where the
    mode is absent do not dilute it); peak_r = ||P_r|| / ||s_r|| with s_kr the local residual
    sd (:class:`LsfdFit`).  A physical mode makes its own peak (share ~1) or, when weak beside
    strong ones, still stands far above the residual; a pole fitted to noise or ripple does
    neither (beam: share 0.06-0.18 and peak 2-8 for the four such poles above 5 kHz).
    """
    f = frfs.frequencies_hz
    m = poles.size
    wd = poles.imag
    res = fit.residues[:, :m]
    peak = np.abs(res * (1j * wd)[None, :] ** KIND_POWER[frfs.kind] / -poles.real[None, :])
    k = np.clip(np.searchsorted(f, wd / (2 * np.pi)), 1, f.size - 2)
    near = np.abs(frfs.frf[:, np.stack([k - 1, k, k + 1])])  # (n_frf, 3, m)
    meas = np.sqrt(np.mean(near**2, axis=1))  # (n_frf, m)
    tiny = np.finfo(float).tiny
    share = np.sum(peak**2, axis=0) / np.maximum(np.sum(peak * meas, axis=0), tiny)
    local = np.linalg.norm(fit.local_sd[:, :m], axis=0)
    return share, np.linalg.norm(peak, axis=0) / np.maximum(local, tiny)


def shape_sd_rel(scaled: ScaledShapes) -> tuple[np.ndarray, np.ndarray]:
    """Relative shape standard deviation (m,) and a fallback mask (m,) bool.

    sd_rel_r^2 = sum_i E|psi_ir - psi_ir_true|^2 / sum_i |psi_ir|^2 with the errors of
    :func:`~bayesupdate.ema.lsfd.shapes_from_residues` (residue noise, each set's scale
    relative to the anchor, the parts of sets too weak to be scaled), so E[1 - MAC] ~
    sd_rel^2.  Modes where it is not finite, not > 0 or above ``MAX_SHAPE_SD`` get
    MAX_SHAPE_SD and are flagged in the mask.
    """
    power = np.sum(np.abs(scaled.shapes) ** 2, axis=0)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        sd = np.sqrt(np.sum(scaled.error_var, axis=0) / power)
    bad = ~np.isfinite(sd) | (sd <= 0) | (sd > MAX_SHAPE_SD)
    return np.where(bad, MAX_SHAPE_SD, sd), bad


#: the progress phase of the pole estimators: every band's model orders (``compute.progress``)
ORDERS_PHASE = "identify: stabilization diagram orders"
#: pole estimators by name: each returns an LsceResult (poles and pole vectors per order)
ESTIMATORS = {"lsce": lsce, "plscf": plscf}


def _edge_margin(f: np.ndarray, band, df_hz: float) -> float:
    """Width [Hz] at each end of a band where a pole is a truncation artefact, not a mode."""
    return max(2 * df_hz, 0.01 * (f[band.hi] - f[band.lo]))


def _owned_range(f: np.ndarray, bands: list, i: int, df_hz: float) -> tuple[float, float]:
    """(lo, hi) [Hz] of the poles band i keeps: its own range (:class:`Band`) with the edge
    zone at its start handed to the band before, where it is interior, and the next band's
    edge zone taken over.  Else a mode just above a boundary, where a weak mode's own
    antiresonance can make the deepest sum-FRF minimum, is at the edge of the band that owns
    it and outside the range of the band that sees it whole (mAEWing1 GVT, 23.81 Hz, with a
    boundary at 23.77 Hz for --band 5:35)."""
    band = bands[i]
    lo = f[band.own_lo] + (_edge_margin(f, band, df_hz) if i > 0 else 0.0)
    hi = f[band.own_hi] + 0.5 * df_hz
    if i + 1 < len(bands):
        hi += _edge_margin(f, bands[i + 1], df_hz)
    return lo, hi


@dataclass(frozen=True)
class IdentifySettings:
    """Knobs of :func:`identify`, validated once here.

    max_order : highest polynomial order per band (None: 40; at least 2).  band_lines : lines
    per band minus one (None: :func:`~bayesupdate.ema.bands.automatic_bands`; at least the
    range's lines for one band).  min_count : stable orders a pole needs (None: the
    selection's default, :func:`~bayesupdate.ema.stabilization.select_poles`).
    tol_frequency, tol_damping [-], min_mac : stabilization tolerances between orders.
    tol_damping 0.2 (not 0.05): on the real plate, damping of clear modes scatters 5-15 %
    between orders, so 0.05 lost 3 of its 5 peaks depending on the band; spurious poles that
    pass are removed by :func:`modal_significance`.  method : a key of ``ESTIMATORS``.
    refine : refine the poles at the ends of the range on the FRFs (:func:`_refine_ends`).
    """

    max_order: int | None = None
    band_lines: int | None = None
    min_count: int | None = None
    tol_frequency: float = 0.01
    tol_damping: float = 0.2
    min_mac: float = 0.98
    method: str = "lsce"
    refine: bool = True

    def __post_init__(self):
        order = 40 if self.max_order is None else int(self.max_order)
        if order < 2:
            raise BayesUpdateError(f"--max-order {order}: must be at least 2")
        if self.method not in ESTIMATORS:
            raise BayesUpdateError(f"--method {self.method!r}: use one of {', '.join(ESTIMATORS)}")
        object.__setattr__(self, "max_order", order)


def _poles_by_band(frfs, bands, settings: IdentifySettings):
    """Selected poles owned by each band, all diagrams, and stable poles at the data's top;
    BayesUpdateError when no band has a stable mode."""
    f = frfs.frequencies_hz
    candidates, diagrams, edge = [], [], []
    # orders 2, 4, ..., max_order rounded up to even (``lsce``, ``plscf``)
    n_orders = (settings.max_order + 1) // 2
    with phase(ORDERS_PHASE, len(bands) * n_orders, "orders") as shown:
        for i, band in enumerate(bands):
            res = ESTIMATORS[settings.method](
                f, frfs.frf, (f[band.lo], f[band.hi]), max_order=settings.max_order
            )
            shown.advance(len(res.orders))
            _band_candidates(frfs, bands, i, res, settings, (candidates, diagrams, edge))
    if not candidates:
        raise BayesUpdateError(
            f"{frfs.source or 'FRF set'}: no stable mode found; check the band and the data, "
            "or raise --max-order"
        )
    return _merge(candidates), diagrams, edge


def _band_candidates(frfs, bands, i: int, res, settings: IdentifySettings, into: tuple) -> None:
    """Band ``i``'s stabilization diagram from its estimator result ``res`` and the poles it
    owns, appended to ``into`` = (candidates [(pole, centrality)], diagrams, edge poles)."""
    candidates, diagrams, edge = into
    f, band = frfs.frequencies_hz, bands[i]
    diagram = stabilization_diagram(
        res,
        settings.tol_frequency,
        settings.tol_damping,
        settings.min_mac,
        resolution_hz=frfs.df_hz,
    )
    diagrams.append(diagram)
    f_own_lo, f_own_hi = _owned_range(f, bands, i, frfs.df_hz)
    width = f[band.hi] - f[band.lo]
    margin = _edge_margin(f, band, frfs.df_hz)
    selected = select_poles(diagram, min_count=settings.min_count, resolution_hz=frfs.df_hz)
    for pole in selected:
        # damped frequency decides ownership: it is what sits between the band's lines
        fd = pole.pole.imag / (2 * np.pi)
        at_edge = fd < f[band.lo] + margin or fd > f[band.hi] - margin
        if f_own_lo <= fd <= f_own_hi and not at_edge:
            centrality = min(fd - f[band.lo], f[band.hi] - fd) / width
            candidates.append((pole, centrality))
        elif band is bands[-1] and fd > f[band.hi] - margin:
            edge.append(pole.pole)


def _fit_and_prune(frfs, selected, residual_poles, fit_lo, fit_hi):
    """LSFD over lines fit_lo..fit_hi; drop, one at a time, the least significant mode that is
    weak by the measures of :func:`modal_significance` (both low, or a peak below the local
    residual), and refit.  Returns (kept poles, fit, (2, m) share and peak-to-residual,
    dropped poles)."""
    f, h = frfs.frequencies_hz, frfs.frf
    f_fit = f[fit_lo : fit_hi + 1]
    kept, dropped = list(selected), []
    while True:
        poles = np.array([p.pole for p in kept])
        fit = lsfd(
            f_fit, h[:, fit_lo : fit_hi + 1], np.concatenate([poles, residual_poles]), frfs.kind
        )
        share, peak = modal_significance(frfs, poles, fit)
        weak = (share < MIN_SIGNIFICANCE) & (peak < MIN_PEAK_TO_RESIDUAL)
        weak |= (peak < MIN_PEAK_ABOVE_RESIDUAL) & ~measured_peak(frfs, poles)
        if not np.any(weak) or len(kept) == 1:
            return kept, fit, np.stack([share, peak]), dropped
        worst = int(np.flatnonzero(weak)[np.argmin(share[weak])])
        dropped.append(kept.pop(worst))


def _residual_poles(selected: list, edge: list) -> np.ndarray:
    """Out-of-band poles (0 or 1,) [rad/s] for the LSFD basis: the first stable pole hugging
    the top of the data more than 1 % above the highest selected mode.

    Such a pole is a mode just above the data: not reported, but kept in the basis, whose
    flank the constant upper residual cannot follow (on the FE exhaust a mode at 150.5 Hz
    otherwise biases mode 11's weak H part: MAC 0.978 -> 0.99+).  Its residues are dropped.
    """
    f_top = max(p.frequency_hz for p in selected)
    return np.array([p for p in edge if p.imag / (2 * np.pi) > f_top * 1.01])[:1]


#: starting guess of an extra pole beyond an end of the analysed range: frequency ratio to
#: that end and damping ratio (the fit moves it onto the neighbour's flank)
EXTRA_POLE_START = (1.15, 0.03)


def _extra_pole(f_hz: float, above: bool) -> np.ndarray:
    """Starting extra pole (1,) [rad/s] beyond f_hz [Hz], above or below it."""
    ratio, zeta = EXTRA_POLE_START
    w = 2 * np.pi * f_hz * (ratio if above else 1 / ratio)
    return np.array([complex(-zeta * w, w * np.sqrt(1 - zeta**2))])


def _has_bottom_end(frfs: FrfSet, lo_i: int) -> bool:
    """Whether the analysed range starting at line lo_i has a bottom end to refine and cut at:
    it starts more than 10 lines above 0 Hz (below that the range holds the data's start)."""
    return bool(frfs.frequencies_hz[lo_i] > 10 * frfs.df_hz)


def _end_windows(frfs: FrfSet, lo_i: int, hi_i: int, residual_poles) -> list:
    """(first line, last line, extra poles, top?) of each end of the analysed range lines
    lo_i..hi_i whose poles :func:`_refine_ends` refines: the top end, and the bottom end when
    the range starts more than 10 lines above 0 Hz; each one automatic band wide
    (:func:`~bayesupdate.ema.bands.default_band_lines`).  The extra pole is free: at the top
    it starts at the residual pole (:func:`_residual_poles`) if there is one, else beyond the
    end.  Free, not fixed: a residual pole hugging the data's last line can be an artefact of
    the edge (FEMAP deck, 0-150 Hz: a pole at 150.00 Hz, damping 0.2 %, while the mode there
    is at 149.78 Hz); held fixed in the window it moved the refined 120.4 Hz mode by -2e-3.
    A free extra pole that converges on the lines is a resonance the end cuts
    (:func:`_refine_window`)."""
    f, width = frfs.frequencies_hz, default_band_lines(hi_i - lo_i + 1)
    first = max(lo_i, int(np.searchsorted(f, 0.0, side="right")))
    top_extra = _extra_pole(f[hi_i], above=True) if residual_poles.size == 0 else residual_poles
    windows = [(max(first, hi_i - width), hi_i, top_extra, True)]
    if _has_bottom_end(frfs, lo_i):
        windows.append((first, min(hi_i, first + width), _extra_pole(f[first], above=False), False))
    return windows


def _is_cut(pole: complex, f_lo: float, f_hi: float, top: bool) -> bool:
    """Whether a stable pole [rad/s] is a resonance that the end (top or bottom) of lines
    f_lo..f_hi [Hz] cuts: its damped frequency on the lines and its half-power band,
    w_d +- |Re s|, past that end.  A peak beyond the lines is a mode beyond the range, which
    an extra pole stands for (:func:`_end_windows`), even when its flank reaches the lines."""
    w_lo, w_hi = 2 * np.pi * f_lo, 2 * np.pi * f_hi
    on_lines = pole.real < 0 and w_lo <= pole.imag <= w_hi
    past = pole.imag - pole.real > w_hi if top else pole.imag + pole.real < w_lo
    return bool(np.isfinite(pole) and on_lines and past)


def _refine_window(frfs: FrfSet, window, poles, fixed) -> tuple[np.ndarray, np.ndarray]:
    """Refined poles (q,) of one end window (:func:`_end_windows`) and the resonance the end
    cuts, (0 or 1,) [rad/s].

    First the window's poles with one free extra pole (:func:`~bayesupdate.ema.pole_refinement.
    refine_poles`).  When that extra pole converges on the lines with its half-power band past
    the end (:func:`_is_cut`; the refinement is then rejected), it found a resonance the end
    cuts, and one pole cannot stand for it and for the modes beyond: the window is refined
    again with that resonance as a free pole, allowed on the lines, and a new extra pole
    beyond the end, free, or, when the free one is rejected, fixed at its start.

    FEMAP deck, 0-150 Hz, a mode at 149.78 Hz (2.8 Hz half-width), the next at 171.6 Hz: the
    cut mode's flank biased the 120.4 Hz mode by -4.9e-4 (1 % noise); the one extra pole,
    moved onto it, left the modes above unmodelled (-1.6e-4 without noise; 2e-7 with the
    pole beyond).  With noise the window holds too little of the flank beyond to place that
    pole: free, it went unstable (-6 % damping) in 2 of 4 draws.  When these are rejected,
    the first refinement's result stands (the starting poles if it was rejected too)."""
    a, b, extra, top = window
    f = frfs.frequencies_hz
    lines, h = f[a : b + 1], frfs.frf[:, a : b + 1]
    first = refine_poles(lines, h, poles, extra.astype(complex), fixed, frfs.kind)
    found = first.converged_extra[0]
    if not _is_cut(found, f[a], f[b], top):
        return first.poles, np.zeros(0, complex)
    beyond = _extra_pole(f[b] if top else f[a], above=top)
    free_beyond = (np.concatenate([[found], beyond]), fixed)
    for start, held in (free_beyond, (np.array([found]), np.concatenate([fixed, beyond]))):
        ref = refine_poles(lines, h, poles, start, held, frfs.kind, cut=1)
        if ref.accepted and _is_cut(ref.extra[0], f[a], f[b], top):
            return ref.poles, ref.extra[:1]
    return first.poles, np.zeros(0, complex)


def _refine_ends(frfs: FrfSet, lo_i: int, hi_i: int, selected: list, residual_poles) -> tuple:
    """The selected poles, those at the ends of the analysed range refined by variable
    projection (:func:`_refine_window`) on the lines of each end's window
    (:func:`_end_windows`), and the resonances the ends cut, ((top, bottom) each (0 or 1,)
    [rad/s]).  The rule: a pole is refined when it lies in such a window, as there no
    identified pole models the flank of a mode beyond the range (the poles of the inner bands
    have their neighbours on both sides); the poles within one window's width of it enter the
    basis fixed."""
    f = frfs.frequencies_hz
    poles = np.array([p.pole for p in selected])
    cut = [np.zeros(0, complex), np.zeros(0, complex)]
    for window in _end_windows(frfs, lo_i, hi_i, residual_poles):
        a, b = window[:2]
        fd = poles.imag / (2 * np.pi)
        free = (fd >= f[a]) & (fd <= f[b])
        span = f[b] - f[a]
        near = ~free & (fd > f[a] - span) & (fd < f[b] + span)
        if free.any():
            poles[free], cut[0 if window[3] else 1] = _refine_window(
                frfs, window, poles[free], poles[near]
            )
    fn, zeta = modal_from_poles(poles)
    refined = [
        p if p.pole == s else replace(p, pole=s, frequency_hz=float(n), damping_ratio=float(z))
        for p, s, n, z in zip(selected, poles, fn, zeta, strict=True)
    ]
    return refined, tuple(cut)


def _fit_end(frfs: FrfSet, f_top: float, fit_hi: int) -> int:
    """Last line index of the LSFD fit: the sum-FRF minimum between the highest selected mode
    f_top [Hz] and line fit_hi (fit_hi itself with under 3 lines there).  A resonance just
    beyond the analysed range is not among the poles, and its rising flank is not the smooth
    upper residual the fit assumes (seed sec. 4.1: band limits at local minima)."""
    f = frfs.frequencies_hz
    above = np.flatnonzero((f > f_top) & (np.arange(f.size) <= fit_hi))
    if above.size > 2:
        fit_hi = int(above[np.argmin(np.sum(np.abs(frfs.frf[:, above]), axis=0))])
    return fit_hi


def identification_sd(frfs: FrfSet, poles: np.ndarray, others: np.ndarray, lines) -> tuple:
    """Each mode's frequency sd [Hz] (m,) from the FRFs (:func:`~bayesupdate.ema.frequency_sd.
    frequency_sd` on the fit's lines (first, last)) and a fallback mask (m,) bool: where its
    window holds too few lines, the sd is the half-power half-width |Re s| / 2 pi, as wide
    as the resonance itself.  poles (m,), others (k,): the modes' and the basis' other poles."""
    sd = frequency_sd(frfs.frequencies_hz, frfs.frf, poles, others, frfs.kind, lines)
    bad = ~np.isfinite(sd)
    return np.where(bad, np.abs(poles.real) / (2 * np.pi), sd), bad


def _modal_data(frfs: FrfSet, selected: list, fit: LsfdFit, significance, basis) -> ModalData:
    """The identified modes: the selected poles (m) with the LSFD residues of ``fit`` scaled
    to shapes over all test sets, their errors and the diagnostics in ``extra``;
    significance (2, m): share and peak-to-residual (:func:`modal_significance`); basis: the
    fit's other poles and its lines (first, last), for the frequency sds
    (:func:`identification_sd`)."""
    poles = np.array([p.pole for p in selected])
    sd = identification_sd(frfs, poles, *basis)
    residues = fit.residues[:, : poles.size]
    scaled = shapes_from_residues(residues, poles, frfs.sets(), fit.residue_var[:, : poles.size])
    sd_rel, sd_fallback = shape_sd_rel(scaled)
    return ModalData(
        frequencies_hz=np.array([p.frequency_hz for p in selected]),
        damping_ratio=np.array([p.damping_ratio for p in selected]),
        shapes=scaled.shapes,
        dof_labels=scaled.labels,
        mpc=mpc(scaled.shapes),
        shape_sd_rel=sd_rel,
        identification_sd_hz=sd[0],
        source=frfs.source or "identify",
        extra={
            "frequency_sd_fallback": sd[1],
            "stable_orders": np.array([p.stable_orders for p in selected]),
            "cluster_spread_hz": np.array([p.spread_hz for p in selected]),
            "mass_normalized": scaled.mass_normalized,
            "fit_share": significance[0],
            "peak_to_residual": significance[1],
            "shape_sd_fallback": sd_fallback,
            "shape_weak_part": scaled.weak_part,
        },
    )


def _synthesis(frfs: FrfSet, fit: LsfdFit, fit_poles: np.ndarray, lines: slice) -> tuple:
    """FRFs (n_frf, n_fit) synthesized from ``fit`` with its poles fit_poles [rad/s] on the fit
    lines ``lines``, and their correlation (FRAC, (n_frf,)) with the measured FRFs there."""
    f_fit = frfs.frequencies_hz[lines]
    synth = synthesize_frf(f_fit, fit_poles, fit.residues, frfs.kind, fit.lower, fit.upper)
    return synth, frf_correlation(frfs.frf[:, lines], synth)


def _move_cut_modes(frfs: FrfSet, selected: list, cut: tuple, lo_i: int, hi_i: int) -> tuple:
    """The selected modes without those whose half-power band an end of the analysed range
    (lines lo_i..hi_i) cuts (:func:`_is_cut`; the bottom end only where the range starts more
    than 10 lines above 0 Hz), and those added to the cut resonances ``cut`` (top, bottom).
    Their estimates rest on one flank, so they are not reported; they stay in the LSFD basis.
    BayesUpdateError when no mode is left."""
    f = frfs.frequencies_hz
    bottom = _has_bottom_end(frfs, lo_i)
    top_cut = [_is_cut(p.pole, f[lo_i], f[hi_i], True) for p in selected]
    low_cut = [bottom and _is_cut(p.pole, f[lo_i], f[hi_i], False) for p in selected]
    kept = [p for p, t, b in zip(selected, top_cut, low_cut, strict=True) if not (t or b)]
    if not kept:
        raise BayesUpdateError(
            f"{frfs.source or 'FRF set'}: every mode found has its half-power band cut by the "
            f"end of the range {f[lo_i]:g}-{f[hi_i]:g} Hz; widen the band"
        )
    top = [p.pole for p, t in zip(selected, top_cut, strict=True) if t]
    low = [p.pole for p, b in zip(selected, low_cut, strict=True) if b]
    return kept, (np.concatenate([top, cut[0]]), np.concatenate([cut[1], low]))


def _cut_summary(cut: tuple) -> dict:
    """``extra`` entries of the resonances the ends of the range cut (:func:`_refine_window`):
    natural frequencies [Hz] and damping ratios, (c,) each, bottom end first, and "top" or
    "bottom" per resonance.  They are in the LSFD basis but not among the modes: with part of
    the half-power band beyond the range, their estimates rest on one flank."""
    poles = np.concatenate([cut[1], cut[0]])  # bottom first, as the labels
    fn, zeta = modal_from_poles(poles) if poles.size else (np.zeros(0), np.zeros(0))
    return {
        "cut_hz": np.asarray(fn, float),
        "cut_damping": np.asarray(zeta, float),
        "cut_end": tuple(["bottom"] * cut[1].size + ["top"] * cut[0].size),
    }


def _refined_and_cut(frfs, settings, selected, residual_poles, ends, pruned=()) -> tuple:
    """(refined poles, cut (top, bottom) poles, the residual poles of the refit, the pruned
    poles revived): the ends' refinement (``settings.refine``) and the resonances an end of the
    lines ``ends`` (lo, hi) cuts, which join the fit as poles but are not modes.

    ``pruned``: stable poles the first fit dropped as weak (:func:`_fit_and_prune`).  They take
    part in the ends' refinement like the selected poles; those it moves (the ones inside an
    end window) join the refined poles, for the refit to judge again.  Left out, a heavily
    damped true mode's flank is absorbed by its neighbours: FEMAP deck, ``simulate`` seed 0,
    the 120.4 Hz mode (2.8 % damping) pruned, the end window's refinement moved the 138.1 and
    143.5 Hz modes by 11 and 37 of their sds (with it in the window: 0.1 and 0.1)."""
    refined, cut, revived = list(selected), (np.zeros(0, complex),) * 2, []
    if settings.refine:
        both, cut = _refine_ends(frfs, *ends, [*selected, *pruned], residual_poles)
        n = len(selected)
        pairs = [(new, old) for new, old in zip(both[n:], pruned, strict=True) if new is not old]
        revived = [old for _, old in pairs]
        refined = both[:n]
        if pairs:  # only then can the order change
            refined = sorted([*refined, *(new for new, _ in pairs)], key=lambda p: p.frequency_hz)
    if cut[0].size:  # the resonance at the top replaces the edge pole that stood for it
        residual_poles = np.zeros(0, complex)
    refined, cut = _move_cut_modes(frfs, refined, cut, *ends)
    return refined, cut, np.concatenate([cut[1], residual_poles, cut[0]]), revived


def _refit(frfs, settings, first, residual_poles, ranges):
    """The first fit's poles refined and cut (``_refined_and_cut``) and, where that changed
    them, fitted and pruned again: ((selected, fit, significance, dropped), cut, the residual
    poles).  first : ``_fit_and_prune``'s result plus the dropped poles; ranges : (the band's,
    the fit's) (lo, hi) line indices."""
    selected, fit, significance, dropped = first
    refined, cut, residual_poles, revived = _refined_and_cut(
        frfs, settings, selected, residual_poles, ranges[0], dropped
    )
    changed = [id(p) for p in refined] != [id(p) for p in selected]
    if changed or cut[0].size or cut[1].size:
        selected, fit, significance, more = _fit_and_prune(
            frfs, refined, residual_poles, *ranges[1]
        )
        dropped = [p for p in dropped if all(p is not r for r in revived)] + more
    return (selected, fit, significance, dropped), cut, residual_poles


def identify(
    frfs: FrfSet,
    band_hz: tuple[float, float] | None = None,
    settings: IdentifySettings | None = None,
    **options,
) -> Identification:
    """Identify the modes of an FRF set without user pole picking.

    band_hz : (lo, hi) [Hz] to analyse, or None for the whole axis; either range is split
    into consecutive narrow bands (:func:`~bayesupdate.ema.bands.automatic_bands`), so a
    mode's estimate does not depend on the range typed around it (one band of order 60 over
    the mAEWing1 GVT's 3-35 Hz, 1920 lines, left its weak 31.7 Hz mode drifting with the
    order, 31.48-31.68 Hz, and pLSCF lost it).  settings : :class:`IdentifySettings`
    (default: its defaults); options : fields of it to set or override, for calls without
    a record (``identify(frfs, max_order=60)``).  Returns an :class:`Identification`;
    raises BayesUpdateError for bad settings, a bad band, too few lines for the order, or
    when no stable mode is found.
    """
    settings = IdentifySettings(**options) if settings is None else replace(settings, **options)
    f = frfs.frequencies_hz
    lo_i, hi_i = (0, f.size - 1) if band_hz is None else band_indices(f, band_hz)
    bands = automatic_bands(frfs.frf, lo_i, hi_i, settings.band_lines, settings.max_order)
    selected, diagrams, edge = _poles_by_band(frfs, bands, settings)
    residual_poles = _residual_poles(selected, edge)
    fit_lo = bands[0].lo
    fit_hi = _fit_end(frfs, max(p.frequency_hz for p in selected), bands[-1].hi)
    selected, fit, significance, dropped = _fit_and_prune(
        frfs, selected, residual_poles, fit_lo, fit_hi
    )
    (selected, fit, significance, dropped), cut, residual_poles = _refit(
        frfs, settings, (selected, fit, significance, dropped), residual_poles,
        ((lo_i, hi_i), (fit_lo, fit_hi)),
    )  # fmt: skip
    poles = np.array([p.pole for p in selected])
    lines = slice(fit_lo, fit_hi + 1)
    synth, frac = _synthesis(frfs, fit, np.concatenate([poles, residual_poles]), lines)
    modes = _modal_data(frfs, selected, fit, significance, (residual_poles, (fit_lo, fit_hi)))
    return Identification(
        modes=modes,
        poles=poles,
        residues=fit.residues[:, : poles.size],
        lower_residual=fit.lower,
        upper_residual=fit.upper,
        selected=tuple(selected),
        diagrams=tuple(diagrams),
        bands_hz=tuple((float(f[b.lo]), float(f[b.hi])) for b in bands),
        fit_range_hz=(float(f[fit_lo]), float(f[fit_hi])),
        synthesized=synth,
        frf_correlation=frac,
        mass_normalized=modes.extra["mass_normalized"],
        extra={
            "dropped_hz": np.array([p.frequency_hz for p in dropped]),
            # the fit's other poles (residual poles, cut resonances) [rad/s]: a re-fit of the
            # residues on part of the FRFs (ema.run_groups) needs the same basis
            "basis_poles": residual_poles,
            **_cut_summary(cut),
        },
    )


__all__ = ["Identification", "IdentifySettings", "identify", "StabilizationDiagram"]
