"""``FrfSet``: a set of measured or synthesized frequency response functions on one frequency axis.

Layout: ``frf`` is (n_frf, n_f) complex, one row per measured FRF, with per-row DOF labels
``response_labels[k]`` (where the accelerometer is) and ``reference_labels[k]`` (where the force
acts), e.g. ``("1V", "7V")`` for the hammer at point 7 vertical and the accelerometer at point 1
vertical.  A label is a sensor number followed by a direction letter (``V`` = z, ``H`` = y, ``L``
= x).  ``kind`` says what the FRF is: ``"accelerance"`` ((m/s^2)/N), ``"mobility"`` ((m/s)/N) or
``"receptance"`` (m/N).  The frequency axis is uniform and increasing [Hz].
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError

#: power of (j*omega) that turns receptance into each FRF kind
KIND_POWER = {"receptance": 0, "mobility": 1, "accelerance": 2}


def check_frequency_axis(frequencies_hz: np.ndarray, where: str = "FRF") -> np.ndarray:
    """Validate a uniform, strictly increasing, finite frequency axis; return it as float (n_f,)."""
    f = np.asarray(frequencies_hz, dtype=float).reshape(-1)
    if f.size < 4:
        raise BayesUpdateError(f"{where}: frequency axis has {f.size} lines; need at least 4")
    if not np.all(np.isfinite(f)):
        raise BayesUpdateError(f"{where}: frequency axis contains NaN or inf")
    step = np.diff(f)
    if np.any(step <= 0):
        raise BayesUpdateError(f"{where}: frequency axis is not strictly increasing")
    df = (f[-1] - f[0]) / (f.size - 1)
    if np.max(np.abs(step - df)) > 1e-6 * max(df, 1e-300) + 1e-9 * abs(f[-1]):
        raise BayesUpdateError(
            f"{where}: frequency axis is not uniform (steps {step.min():g}..{step.max():g} Hz); "
            "resample the FRFs to a constant step"
        )
    if f[0] < 0:
        raise BayesUpdateError(f"{where}: frequency axis starts below 0 Hz")
    return f


@dataclass(frozen=True)
class FrfSet:
    """FRFs on a uniform frequency axis.

    Attributes
    ----------
    frequencies_hz : (n_f,) float, uniform and increasing [Hz].
    frf : (n_frf, n_f) complex, FRF of each response/reference pair.
    response_labels : n_frf str, response DOF of each row (e.g. ``"1V"``).
    reference_labels : n_frf str, reference (force) DOF of each row (e.g. ``"7V"``).
    kind : ``"accelerance"``, ``"mobility"`` or ``"receptance"``.
    coherence : (n_frf, n_f) float or None, ordinary coherence of each estimate.
    source : str, where the FRFs came from.
    """

    frequencies_hz: np.ndarray
    frf: np.ndarray
    response_labels: tuple[str, ...]
    reference_labels: tuple[str, ...]
    kind: str = "accelerance"
    coherence: np.ndarray | None = None
    source: str = ""

    def __post_init__(self):
        where = f"FRF set {self.source!r}" if self.source else "FRF set"
        f = check_frequency_axis(self.frequencies_hz, where)
        h = np.asarray(self.frf)
        if h.ndim == 1:
            h = h[None, :]
        if h.ndim != 2 or h.shape[1] != f.size:
            raise BayesUpdateError(
                f"{where}: frf must be (n_frf, n_f={f.size}), got {np.shape(self.frf)}"
            )
        if not np.all(np.isfinite(h)):
            raise BayesUpdateError(f"{where}: FRFs contain NaN or inf; remove or repair them")
        resp = tuple(str(x) for x in self.response_labels)
        ref = tuple(str(x) for x in self.reference_labels)
        if len(resp) != h.shape[0] or len(ref) != h.shape[0]:
            raise BayesUpdateError(
                f"{where}: {h.shape[0]} FRFs but {len(resp)} response and {len(ref)} "
                "reference labels; give one of each per FRF"
            )
        if self.kind not in KIND_POWER:
            raise BayesUpdateError(
                f"{where}: kind {self.kind!r} unknown; use one of {sorted(KIND_POWER)}"
            )
        pairs = list(zip(resp, ref, strict=True))
        if len(set(pairs)) != len(pairs):
            raise BayesUpdateError(f"{where}: a response/reference pair appears twice")
        object.__setattr__(self, "frequencies_hz", f)
        object.__setattr__(self, "frf", h.astype(complex))
        object.__setattr__(self, "response_labels", resp)
        object.__setattr__(self, "reference_labels", ref)
        if self.coherence is not None:
            c = np.asarray(self.coherence, dtype=float)
            if c.shape != h.shape:
                raise BayesUpdateError(f"{where}: coherence shape {c.shape} != frf {h.shape}")
            object.__setattr__(self, "coherence", c)

    @property
    def n_frf(self) -> int:
        return int(self.frf.shape[0])

    @property
    def df_hz(self) -> float:
        f = self.frequencies_hz
        return float((f[-1] - f[0]) / (f.size - 1))

    def sets(self) -> list[dict]:
        """Group FRFs into test sets by their common (fixed) DOF.

        Roving hammer: the response DOF is fixed and the reference roves; roving accelerometer:
        the reference is fixed.  Each set is a dict with ``fixed`` (label), ``rows`` (indices),
        ``roving`` (labels of the roving DOF per row) and ``driving_row`` (row index where
        response == reference, or None).
        """
        resp, ref = self.response_labels, self.reference_labels
        # the fixed DOFs are the side with fewer distinct labels (roving hammer: the responses)
        by_ref = len(set(ref)) < len(set(resp))
        key = ref if by_ref else resp
        other = resp if by_ref else ref
        out = []
        for fixed in dict.fromkeys(key):
            rows = [k for k in range(self.n_frf) if key[k] == fixed]
            driving = [k for k in rows if resp[k] == ref[k]]
            out.append(
                {
                    "fixed": fixed,
                    "rows": np.array(rows),
                    "roving": tuple(other[k] for k in rows),
                    "driving_row": driving[0] if driving else None,
                }
            )
        return out


#: relative rounding of a UFF 58 abscissa start and step: written with 6 significant digits
#: (format E13.5), so each is within 5e-6 of itself
UFF_REL_ROUNDING = 5e-6


def line_offset_tolerance(f0_a: float, f0_b: float, df_hz: float, n_lines: float) -> float:
    """Largest deviation [lines] from a whole number of lines that two axes on one grid show
    after UFF's 6-digit rounding (:data:`UFF_REL_ROUNDING`), with a safety factor 2: the two
    starts' rounding, |f0_a| + |f0_b|, and the step's over the n_lines between them.

    mAEWing1 GVT runs 1 and 7 (starts 2.41665 and 1.73332 Hz, step 0.0166665 Hz): 0.0029
    lines; their offset reads 41.0002 lines.
    """
    bound = UFF_REL_ROUNDING * (abs(f0_a) + abs(f0_b) + abs(n_lines) * df_hz) / df_hz
    return 2.0 * bound + 1e-9


def _grid_offset(first: FrfSet, other: FrfSet) -> int | None:
    """Whole number of lines between the starts of two axes on one grid, or None."""
    df = first.df_hz
    if abs(other.df_hz - df) > 2 * UFF_REL_ROUNDING * df:
        return None
    offset = (other.frequencies_hz[0] - first.frequencies_hz[0]) / df
    n = round(offset)
    tol = line_offset_tolerance(first.frequencies_hz[0], other.frequencies_hz[0], df, n)
    return int(n) if abs(offset - n) <= tol else None


def merge_frf_sets(sets: list[FrfSet]) -> tuple[FrfSet, list[str]]:
    """One FrfSet from several files of one test (e.g. a roving accelerometer measured run by
    run), and notes.  The FRF kind and line spacing must agree; axes whose starts differ by a
    whole number of lines within UFF's 6-digit rounding (:func:`line_offset_tolerance`) are on
    one grid, and are cut to their common lines (noted) on the first file's axis; coherence is
    kept only if every set has it."""
    if len(sets) == 1:
        return sets[0], []
    first = sets[0]
    starts = [0]
    for other in sets[1:]:
        offset = _grid_offset(first, other)
        if offset is None:
            f1, f0, df = other.frequencies_hz, first.frequencies_hz, first.df_hz
            raise BayesUpdateError(
                f"{other.source}: frequency axis {f1[0]:g}..{f1[-1]:g} Hz step {other.df_hz:g} "
                f"does not share lines with {first.source}'s ({f0[0]:g}..{f0[-1]:g} Hz step "
                f"{df:g}): starts {abs(f1[0] - f0[0]) / df:.4f} lines apart, not a whole number; "
                "estimate all FRFs alike"
            )
        if other.kind != first.kind:
            raise BayesUpdateError(
                f"{other.source}: FRF kind {other.kind} differs from {first.source}'s "
                f"{first.kind}; convert them to one kind"
            )
        starts.append(offset)
    lo = max(starts)  # common lines, in lines of the first axis
    hi = min(k + s.frequencies_hz.size for k, s in zip(starts, sets, strict=True))
    if hi - lo < 4:
        raise BayesUpdateError(
            f"{first.source} and {sets[1].source}...: fewer than 4 common FRF lines; "
            "estimate all FRFs over one band"
        )
    cuts = [slice(lo - k, hi - k) for k in starts]
    notes = []
    if any(s.frequencies_hz.size != hi - lo for s in sets):
        f = first.frequencies_hz[0] + np.array([lo, hi - 1]) * first.df_hz
        notes.append(
            f"FRF files cover different ranges: their common lines {f[0]:g}..{f[1]:g} Hz are used"
        )
    coh = [s.coherence for s in sets]
    merged = FrfSet(
        frequencies_hz=first.frequencies_hz[0] + np.arange(lo, hi) * first.df_hz,
        frf=np.vstack([s.frf[:, c] for s, c in zip(sets, cuts, strict=True)]),
        response_labels=tuple(lab for s in sets for lab in s.response_labels),
        reference_labels=tuple(lab for s in sets for lab in s.reference_labels),
        kind=first.kind,
        coherence=None
        if any(c is None for c in coh)
        else np.vstack([c[:, k] for c, k in zip(coh, cuts, strict=True)]),
        source="+".join(s.source for s in sets)[:200],
    )
    return merged, notes
