"""Pairing of test modes with model modes, and the residual table reported with every result.

Three methods (``PAIRING_METHODS``):

* ``mac``: the test has shapes; each test mode takes the distinct model mode of highest MAC on the
  common sensor DOFs (Hungarian assignment, ``correlation.pair_by_mac``).
* ``tracked``: frequencies only (seed Table 2).  Test mode i belongs to the model's i-th mode
  *at the reference design*; at any other parameter point that reference shape is found again by
  MAC, so a mode that moves past its neighbour keeps its pairing and the swap is reported (the check
  the seed made by eye: "the modal shapes for the first and the last iteration are similar").
* ``order``: the i-th test mode with the i-th model mode; MAC against the reference shapes is still
  reported when the model gives shapes, so a swap is visible.

Rules of a MAC pairing (``PairingRules``), as a test engineer correlates before updating (paired
modes by MAC and frequency: Ewins, *Modal Testing: Theory, Practice and Application*, 2nd ed.
2000; Friswell & Mottershead, *Finite Element Model Updating in Structural Dynamics*, 1995): at
the reference design a test mode is paired only with a model mode whose frequency lies within a
relative window of its own (|f_model / f_test - 1| <= ``frequency_window``) and whose MAC
reaches ``mac_threshold``; a test mode with no such partner is refused (``screen_pairs``),
named with its best MAC partner and the rule that refused it, and left out of the objective.
``correlate`` and ``sensitivity`` pair by the same function with the same rules (the study's
``[pairing]`` table), so the pairs a user sees before updating are those ``calibrate``,
``sample`` and ``discover`` keep.  At other parameter points the
pairing is redone with the same window preferred (``window_scores``): a model mode inside it
always wins over one outside, but a pair with no partner inside the window still counts, and is
reported at the optimum.
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.correlation import DEFAULT_MAC_THRESHOLD, mac_matrix, pair_by_mac
from bayesupdate.errors import BayesUpdateError
from bayesupdate.model_protocol import Prediction

PAIRING_METHODS = ("auto", "order", "tracked", "mac")

#: default relative frequency window of a MAC pair, |f_model / f_test - 1| <= 0.5: a model
#: before updating is usually within a few tens of percent of its test, so 50 % keeps every
#: plausible partner, while a shape match at half or twice the test's frequency (or beyond) is
#: another mode of similar shape seen on too few sensors, not the same mode (the mAEWing1's
#: pre-update model, paired with any MAC pair, reached -75 % / +130 % at MACs of 0.07-0.72)
DEFAULT_FREQUENCY_WINDOW = 0.5

#: the most model modes a MAC pairing computes to reach the test's highest frequency
#: (``reach_modes``)
MAX_REACH_MODES = 100

#: score subtracted from the MAC of a pair outside the frequency window when the pairing is
#: redone: larger than any MAC difference, so a partner inside the window always wins
_OUTSIDE_WINDOW_PENALTY = 2.0


@dataclass(frozen=True)
class PairingRules:
    """What a MAC pair must meet (module docstring).

    mac_threshold : lowest MAC of a kept pair at the reference design [-], in [0, 1].
    frequency_window : largest |f_model / f_test - 1| of a pair [-], > 0 (``inf``: none).
    """

    mac_threshold: float = DEFAULT_MAC_THRESHOLD
    frequency_window: float = DEFAULT_FREQUENCY_WINDOW

    def __post_init__(self):
        check_rules(self.mac_threshold, self.frequency_window)


def check_rules(
    mac_threshold: float,
    frequency_window: float,
    names: tuple[str, str] = ("pairing.mac_threshold", "pairing.frequency_window"),
) -> None:
    """One line naming the bad value of a ``PairingRules`` field, as ``names`` call them (the
    study's keys, or a command's flags)."""
    if not 0.0 <= mac_threshold <= 1.0:
        raise BayesUpdateError(
            f"{names[0]}: {mac_threshold}; give a MAC in [0, 1] (default {DEFAULT_MAC_THRESHOLD})"
        )
    if not frequency_window > 0:
        raise BayesUpdateError(
            f"{names[1]}: {frequency_window}; give a relative window > 0, e.g. "
            f"{DEFAULT_FREQUENCY_WINDOW} (model within +-50 % of the test; inf: none)"
        )


@dataclass(frozen=True)
class RefusedMode:
    """A test mode left out at the reference design (``screen_pairs``).

    number : its 1-based number in the data source.  test_hz : its frequency [Hz].
    model_mode : 1-based model mode of its highest MAC.  model_hz : that mode's frequency [Hz].
    mac : that MAC [-].  reason : "mac" (below the threshold), "window" (outside the frequency
    window) or "taken" (its best partner is paired with another test mode and no other
    admissible partner is free for it).  other : for "taken", the 1-based number of that other
    test mode.
    """

    number: int
    test_hz: float
    model_mode: int
    model_hz: float
    mac: float
    reason: str
    other: int = 0

    def message(self, rules: PairingRules) -> str:
        """One line: "test mode 3 (15.95 Hz): best model mode 12 at 66.4 Hz, MAC 0.31: refused
        (below 0.6)"."""
        head = (
            f"test mode {self.number} ({self.test_hz:.4g} Hz): best model mode "
            f"{self.model_mode} at {self.model_hz:.4g} Hz, MAC {self.mac:.2f}: refused"
        )
        if self.reason == "mac":
            return f"{head} (below {rules.mac_threshold:g})"
        if self.reason == "window":
            return (
                f"{head} ({self.error_pct:+.1f} % off, outside the frequency window "
                f"+-{100 * rules.frequency_window:g} %)"
            )
        return (
            f"{head} (that mode is paired with test mode {self.other}; no other model mode "
            f"within +-{100 * rules.frequency_window:g} % at MAC >= {rules.mac_threshold:g} is "
            "free for it)"
        )

    @property
    def error_pct(self) -> float:
        """The best partner's frequency less the test's, in % of the test's."""
        return 100.0 * (self.model_hz / self.test_hz - 1.0)

    def why(self, rules: PairingRules) -> str:
        """The rule that refused it, short: "MAC < 0.6", "+140 % outside +-50 %", "model
        mode 2 taken by test mode 1"."""
        if self.reason == "mac":
            return f"MAC < {rules.mac_threshold:g}"
        if self.reason == "window":
            return f"{self.error_pct:+.1f} % outside +-{100 * rules.frequency_window:g} %"
        return f"model mode {self.model_mode} taken by test mode {self.other}"

    def to_dict(self, rules: PairingRules) -> dict:
        return {
            "test_mode": self.number,
            "test_hz": self.test_hz,
            "model_mode": self.model_mode,
            "model_hz": self.model_hz,
            "error_pct": self.error_pct,
            "mac": self.mac,
            "reason": self.reason,
            "other": self.other or None,
            "message": self.message(rules),
        }


def reach_modes(solve, first, n_first: int, f_reach: float):
    """(result, n): the model's first ``n_first`` modes (``first``, ``solve(n_first)``'s
    result, with ``frequencies_hz``) or, where they all lie below ``f_reach`` [Hz] (the test's
    highest mode with shapes: a test that missed some of the model's lower modes, as a GVT
    under its band or a sparse sensor set does, pairs beyond them), ``solve(n)`` with n
    doubled until its modes reach f_reach, the model has no more modes, or n reaches
    ``MAX_REACH_MODES``.  A test mode number says where a mode sits in the test's own list,
    not in the model's."""
    result, n = first, n_first
    cap = max(n_first, MAX_REACH_MODES)
    while np.max(result.frequencies_hz, initial=0.0) < f_reach and n < cap:
        try:
            result, n = solve(min(2 * n, cap)), min(2 * n, cap)
        except BayesUpdateError:  # the model has no more modes
            break
    return result, n


def window_scores(mac: np.ndarray, test_hz: np.ndarray, model_hz: np.ndarray, window) -> np.ndarray:
    """Pairing scores: the MAC (..., n_test, n_model), less ``_OUTSIDE_WINDOW_PENALTY`` where
    |f_model / f_test - 1| > ``window`` (test_hz (n_test,), model_hz (..., n_model) [Hz]);
    ``window`` None: the MAC itself."""
    if window is None:
        return mac
    return mac - _OUTSIDE_WINDOW_PENALTY * ~inside_window(test_hz, model_hz, window)


def inside_window(test_hz: np.ndarray, model_hz: np.ndarray, window: float) -> np.ndarray:
    """(..., n_test, n_model) bool: |f_model / f_test - 1| <= ``window`` for every test mode
    (test_hz (n_test,)) and model mode (model_hz (..., n_model)) [Hz]; NaN: outside."""
    ratio = np.asarray(model_hz, dtype=float)[..., None, :] / np.asarray(test_hz)[:, None]
    with np.errstate(invalid="ignore"):
        return np.abs(ratio - 1.0) <= window


@dataclass(frozen=True)
class ScreenedPairs:
    """The verdict of the pairing rules on every test mode at one design (``screen_pairs``).

    test, model : (k,) 0-based indices of the kept pairs (test ascending).  mac : (k,) their
    MAC [-].  refused : the other test modes, each with its reason (``RefusedMode``).
    """

    test: np.ndarray
    model: np.ndarray
    mac: np.ndarray
    refused: tuple[RefusedMode, ...]


def screen_pairs(
    mac: np.ndarray,
    test_hz: np.ndarray,
    model_hz: np.ndarray,
    rules: PairingRules,
    numbers: tuple[int, ...],
) -> ScreenedPairs:
    """The one pairing rule of ``correlate``, ``sensitivity``, ``calibrate``, ``sample`` and
    ``discover`` (module docstring): which test modes a MAC pairing keeps, and why the others
    are refused.

    mac : (n_test, n_model) MAC matrix (``correlation.mac_matrix(test, model)``); test_hz :
    (n_test,) [Hz]; model_hz : (n_model,) [Hz]; numbers : (n_test,) 1-based numbers of the test
    modes in their source.  A pair is admissible when it lies inside the frequency window and
    its MAC reaches the threshold; the pairs kept are the assignment of distinct model modes
    maximizing the total MAC of the admissible pairs (Hungarian method, Kuhn 1955), so a pair
    that will be refused never takes the partner of one that is kept.  Returns
    ``ScreenedPairs``.
    """
    from scipy.optimize import linear_sum_assignment

    mac = np.asarray(mac, dtype=float)
    model_hz = np.asarray(model_hz, dtype=float)
    inside = inside_window(test_hz, model_hz, rules.frequency_window)
    admissible = inside & (mac >= rules.mac_threshold)
    rows, cols = linear_sum_assignment(-np.where(admissible, mac, 0.0))
    partner = np.full(mac.shape[0], -1)
    partner[rows] = cols
    owner = {int(c): int(r) for r, c in zip(rows, cols, strict=True)}
    kept, refused = [], []
    for i, j in enumerate(partner):
        if j >= 0 and admissible[i, j]:
            kept.append(i)
            continue
        best = int(np.argmax(mac[i]))
        if mac[i, best] < rules.mac_threshold:
            reason, other = "mac", 0
        elif not inside[i, best]:
            reason, other = "window", 0
        else:  # the best partner, admissible, went to a test mode it suits better
            reason, other = "taken", numbers[owner[best]] if best in owner else 0
        pair = (best + 1, float(model_hz[best]), float(mac[i, best]))
        refused.append(RefusedMode(int(numbers[i]), float(test_hz[i]), *pair, reason, int(other)))
    test = np.array(kept, dtype=int)
    model = partner[test]
    return ScreenedPairs(test, model, mac[test, model], tuple(refused))


def screen_test_modes(
    test_hz: np.ndarray,
    test_shapes: np.ndarray,
    model_hz: np.ndarray,
    model_shapes: np.ndarray,
    rules: PairingRules,
    numbers: tuple[int, ...],
) -> tuple[np.ndarray, tuple[RefusedMode, ...]]:
    """The test modes a MAC pairing keeps at the reference design (``screen_pairs`` on the MAC
    of test_shapes (n_dof, n_test) and model_shapes (n_dof, n_model) on the same DOFs).
    Returns (kept (k,) 0-based indices of the test modes, refused modes)."""
    screened = screen_pairs(
        mac_matrix(test_shapes, model_shapes), test_hz, model_hz, rules, numbers
    )
    return screened.test, screened.refused


@dataclass(frozen=True)
class ModePairing:
    """How test modes find their model modes.

    method : "order" | "tracked" | "mac".  n_test : number of test modes.  n_model : number of model
    modes computed (>= n_test; extra modes let a tracked mode be found past a swap).
    reference_shapes : (n_dof, n_test) model shapes at the reference design ("tracked"/"order").
    test_shapes : (n_dof, n_test) test shapes on ``dof_labels`` ("mac").
    rules : the MAC pair's threshold and frequency window ("mac"; None: any pair).
    test_hz : (n_test,) the test frequencies [Hz] the window is taken around ("mac" with rules).
    refused : the test modes left out at the reference design (``screen_test_modes``).
    order : 0-based model mode of each test mode by order (``expected``), for a selection of a
    source's modes ("order", "tracked"; () : 0..n_test-1).
    """

    method: str
    n_test: int
    n_model: int
    dof_labels: tuple[str, ...] = ()
    reference_shapes: np.ndarray | None = None
    test_shapes: np.ndarray | None = None
    rules: PairingRules | None = None
    test_hz: np.ndarray | None = None
    refused: tuple[RefusedMode, ...] = ()
    order: tuple[int, ...] = ()

    @property
    def expected(self) -> np.ndarray:
        """(n_test,) 0-based model mode each test mode is by its order ("order", "tracked": the
        source's number of a selected test mode less one; () : 0..n_test-1)."""
        return np.asarray(self.order, dtype=int) if self.order else np.arange(self.n_test)

    @property
    def window(self) -> float | None:
        """The frequency window the pairing is redone with (None: none)."""
        if self.method != "mac" or self.rules is None or self.test_hz is None:
            return None
        return self.rules.frequency_window

    def to_dict(self) -> dict:
        """JSON-able record: method, rules and the refused test modes."""
        rules = self.rules
        return {
            "method": self.method,
            "mac_threshold": None if rules is None else rules.mac_threshold,
            "frequency_window": None if rules is None else rules.frequency_window,
            "refused": [r.to_dict(rules) for r in self.refused],
        }


@dataclass(frozen=True)
class PairedModes:
    """Result of pairing at one parameter point.

    model_index : (n_test,) 0-based model mode of each test mode.  mac : (n_test,) MAC of the pair
    (NaN when no shapes).  swapped : a test mode is not paired with the model mode of its order
    ("mac": the paired model modes are not in the test modes' ascending order).
    shapes : (n_labels, n_test) the paired model shapes at the pairing's ``dof_labels`` (the test
    DOFs for "mac"), or None for "order".
    """

    model_index: np.ndarray
    mac: np.ndarray
    swapped: bool
    shapes: np.ndarray | None = None


def label_rows(available, labels, where: str, fix: str = "rename the test DOFs") -> np.ndarray:
    """(n_labels,) row of each of ``labels`` among the model's DOF labels ``available``; one
    line naming the missing ones (and ``fix``) when a label is not there."""
    index = {label: i for i, label in enumerate(available)}
    missing = [label for label in labels if label not in index]
    if missing:
        raise BayesUpdateError(
            f"{where}: sensor labels {missing[:5]} are not model DOFs "
            f"(model has {list(available)[:6]}...); {fix}"
        )
    return np.array([index[label] for label in labels], dtype=int)


def shapes_at(prediction: Prediction, labels: tuple[str, ...], where: str) -> np.ndarray:
    """Rows of ``prediction.shapes`` at ``labels`` (n_labels, n_modes)."""
    if prediction.shapes is None:
        raise BayesUpdateError(f"{where}: the model gives no mode shapes; use pairing 'order'")
    rows = label_rows(prediction.dof_labels, labels, where)
    return np.asarray(prediction.shapes)[rows, :]


def pair_modes(prediction: Prediction, pairing: ModePairing) -> PairedModes:
    """Pair test modes with the modes of ``prediction`` (see module docstring)."""
    n_test = pairing.n_test
    order = pairing.expected
    n_avail = prediction.frequencies_hz.size
    if n_avail < max(n_test, int(order.max()) + 1):
        raise BayesUpdateError(
            f"pairing: {n_test} test modes (up to mode {int(order.max()) + 1}) but the model "
            f"computed only {n_avail}"
        )
    if pairing.method == "order":
        mac = np.full(n_test, np.nan)
        if pairing.reference_shapes is not None and prediction.shapes is not None:
            current = shapes_at(prediction, pairing.dof_labels, "pairing")
            mac = np.diag(mac_matrix(pairing.reference_shapes, current[:, order])).copy()
        return PairedModes(order, mac, False)
    reference = pairing.test_shapes if pairing.method == "mac" else pairing.reference_shapes
    current = shapes_at(prediction, pairing.dof_labels, "pairing")
    if pairing.window is None:
        model_index, mac = pair_by_mac(reference, current)
    else:
        model_index, mac = _pair_in_window(reference, current, prediction, pairing)
    if pairing.method == "mac":
        # the test modes (a selection of a source, perhaps) in ascending order: a swap is a
        # pair out of that order, not a model mode the test did not see
        swapped = bool(np.any(np.diff(model_index) < 0))
    else:
        swapped = bool(np.any(model_index != order))
    return PairedModes(model_index, mac, swapped, current[:, model_index])


def _pair_in_window(reference, current, prediction: Prediction, pairing: ModePairing):
    """(model_index (n_test,), mac (n_test,)): the assignment maximizing the total
    ``window_scores`` (a partner inside the frequency window first)."""
    from scipy.optimize import linear_sum_assignment

    mac = mac_matrix(reference, current)
    freqs = np.asarray(prediction.frequencies_hz, dtype=float)[: current.shape[1]]
    rows, cols = linear_sum_assignment(-window_scores(mac, pairing.test_hz, freqs, pairing.window))
    order = np.argsort(rows)
    return cols[order], mac[rows[order], cols[order]]


def outside_window(test_hz, model_hz, window) -> np.ndarray:
    """(n,) bool: the pairs (test_hz (n,), paired model_hz (n,) [Hz]) outside the window."""
    if window is None:
        return np.zeros(np.size(test_hz), dtype=bool)
    with np.errstate(invalid="ignore"):
        return ~(np.abs(np.asarray(model_hz) / np.asarray(test_hz) - 1.0) <= window)


@dataclass(frozen=True)
class ResidualTable:
    """Per test mode: test and model frequency [Hz], error [%], MAC, paired model mode (1-based).

    test_mode : (n_test,) each test mode's 1-based number in its data source (None: 1..n_test).
    """

    test_hz: np.ndarray
    model_hz: np.ndarray
    error_pct: np.ndarray
    mac: np.ndarray
    model_mode: np.ndarray
    swapped: bool
    pairing_method: str
    test_mode: np.ndarray | None = None

    def rows(self) -> list[dict]:
        numbers = np.arange(1, self.test_hz.size + 1) if self.test_mode is None else self.test_mode
        return [
            {
                "mode": int(numbers[i]),
                "test_hz": float(self.test_hz[i]),
                "model_hz": float(self.model_hz[i]),
                "error_pct": float(self.error_pct[i]),
                "mac": None if np.isnan(self.mac[i]) else float(self.mac[i]),
                "model_mode": int(self.model_mode[i]),
            }
            for i in range(self.test_hz.size)
        ]

    def format(self) -> str:
        """A plain-text table, one line per mode, with a swap warning when there is one."""
        lines = ["mode  test_Hz   model_Hz  error_%   MAC    model_mode"]
        for row in self.rows():
            mac = "  -  " if row["mac"] is None else f"{row['mac']:.3f}"
            lines.append(
                f"{row['mode']:4d}  {row['test_hz']:8.3f}  {row['model_hz']:8.3f}  "
                f"{row['error_pct']:+7.2f}  {mac}  {row['model_mode']:5d}"
            )
        if self.swapped:
            lines.append(
                "WARNING: model modes are swapped relative to their order (see model_mode)"
            )
        return "\n".join(lines)


def residual_table(
    test_hz: np.ndarray,
    model_hz_all: np.ndarray,
    paired: PairedModes,
    method: str,
    test_mode: np.ndarray | None = None,
) -> ResidualTable:
    """Residual table from all model frequencies (n_model,) and a pairing; ``test_mode``: the
    test modes' 1-based numbers in their source (None: 1..n_test)."""
    model_hz = np.asarray(model_hz_all)[paired.model_index]
    return ResidualTable(
        test_hz=np.asarray(test_hz, dtype=float),
        model_hz=model_hz,
        error_pct=100.0 * (model_hz - test_hz) / test_hz,
        mac=np.asarray(paired.mac, dtype=float),
        model_mode=paired.model_index + 1,
        swapped=paired.swapped,
        pairing_method=method,
        test_mode=None if test_mode is None else np.asarray(test_mode, dtype=int),
    )


def pair_batch(
    reference: np.ndarray, shapes: np.ndarray, window: tuple | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Batched MAC pairing: each reference mode takes a distinct current mode maximizing the
    total MAC, for every point of a batch at once (same result as ``pair_by_mac`` per point;
    with ``window`` = (test_hz (n_test,), freqs (B, n_model) [Hz], relative window) the total
    ``window_scores``, as ``pair_modes`` with a ``ModePairing.window``).

    reference : (n_dof, n_test) shapes to find (reference design or test); shapes : (B, n_dof,
    n_model) current shapes, n_model >= n_test, on the same DOFs.  Returns (model_index (B,
    n_test), mac (B, n_test)); rows of NaN shapes give index = order and MAC NaN.
    When every reference mode's best MAC falls on a different model mode, that argmax
    assignment is optimal (each row at its maximum), so only the rare points with a contested
    mode go through the Hungarian method.
    """
    from scipy.optimize import linear_sum_assignment

    ref = np.asarray(reference)  # identified test shapes are complex
    cur = np.asarray(shapes, dtype=float)
    n_test = ref.shape[1]
    cross = np.abs(ref.conj().T @ cur) ** 2  # (t, d) @ (B, d, m): BLAS, unlike einsum
    denom = np.sum(np.abs(ref) ** 2, axis=0)[None, :, None] * np.sum(cur * cur, axis=1)[:, None, :]
    with np.errstate(invalid="ignore", divide="ignore"):
        mac = np.clip(np.where(denom > 0, cross / np.where(denom > 0, denom, 1.0), 0.0), 0, 1)
    bad = ~np.all(np.isfinite(mac), axis=(1, 2))
    score = mac if window is None else window_scores(mac, window[0], window[1], window[2])
    score = np.where(np.isfinite(score), score, -1.0 - _OUTSIDE_WINDOW_PENALTY)
    index = np.argmax(score, axis=2)
    ordered = np.sort(index, axis=1)
    contested = np.any(ordered[:, 1:] == ordered[:, :-1], axis=1) & ~bad
    for b in np.flatnonzero(contested):
        rows, cols = linear_sum_assignment(-score[b])
        index[b, rows] = cols
    index[bad] = np.arange(n_test)
    paired_mac = np.take_along_axis(mac, index[:, :, None], axis=2)[:, :, 0]
    paired_mac[bad] = np.nan
    return index, paired_mac
