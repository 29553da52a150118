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
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.correlation import mac_matrix, pair_by_mac
from bayesupdate.errors import BayesUpdateError
from bayesupdate.model_protocol import Prediction

PAIRING_METHODS = ("auto", "order", "tracked", "mac")


@dataclass(frozen=True)
class ModePairing:
    """How test modes find their model modes.

    method : "order" | "tracked" | "mac".  n_test : number of test modes.  n_model : number of model
    modes computed (>= n_test; extra modes let a tracked mode be found past a swap).
    reference_shapes : (n_dof, n_test) model shapes at the reference design ("tracked"/"order").
    test_shapes : (n_dof, n_test) test shapes on ``dof_labels`` ("mac").
    """

    method: str
    n_test: int
    n_model: int
    dof_labels: tuple[str, ...] = ()
    reference_shapes: np.ndarray | None = None
    test_shapes: np.ndarray | None = None


@dataclass(frozen=True)
class PairedModes:
    """Result of pairing at one parameter point.

    model_index : (n_test,) 0-based model mode of each test mode.  mac : (n_test,) MAC of the pair
    (NaN when no shapes).  swapped : a test mode is not paired with the model mode of its order.
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
    n_avail = prediction.frequencies_hz.size
    if n_avail < n_test:
        raise BayesUpdateError(
            f"pairing: {n_test} test modes but the model computed only {n_avail}"
        )
    order = np.arange(n_test)
    if pairing.method == "order":
        mac = np.full(n_test, np.nan)
        if pairing.reference_shapes is not None and prediction.shapes is not None:
            current = shapes_at(prediction, pairing.dof_labels, "pairing")
            mac = np.diag(mac_matrix(pairing.reference_shapes, current[:, :n_test])).copy()
        return PairedModes(order, mac, False)
    reference = pairing.test_shapes if pairing.method == "mac" else pairing.reference_shapes
    current = shapes_at(prediction, pairing.dof_labels, "pairing")
    model_index, mac = pair_by_mac(reference, current)
    swapped = bool(np.any(model_index != order))
    return PairedModes(model_index, mac, swapped, current[:, model_index])


@dataclass(frozen=True)
class ResidualTable:
    """Per test mode: test and model frequency [Hz], error [%], MAC, paired model mode (1-based)."""

    test_hz: np.ndarray
    model_hz: np.ndarray
    error_pct: np.ndarray
    mac: np.ndarray
    model_mode: np.ndarray
    swapped: bool
    pairing_method: str

    def rows(self) -> list[dict]:
        return [
            {
                "mode": i + 1,
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
    test_hz: np.ndarray, model_hz_all: np.ndarray, paired: PairedModes, method: str
) -> ResidualTable:
    """Residual table from all model frequencies (n_model,) and a pairing."""
    model_hz = np.asarray(model_hz_all)[paired.model_index]
    return ResidualTable(
        test_hz=np.asarray(test_hz, dtype=float),
        model_hz=model_hz,
        error_pct=100.0 * (model_hz - test_hz) / test_hz,
        mac=np.asarray(paired.mac, dtype=float),
        model_mode=paired.model_index + 1,
        swapped=paired.swapped,
        pairing_method=method,
    )


def pair_batch(reference: np.ndarray, shapes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Batched MAC pairing: each reference mode takes a distinct current mode maximising the
    total MAC, for every point of a batch at once (same result as ``pair_by_mac`` per point).

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
    index = np.argmax(np.where(np.isfinite(mac), mac, -1.0), axis=2)
    ordered = np.sort(index, axis=1)
    contested = np.any(ordered[:, 1:] == ordered[:, :-1], axis=1) & ~bad
    for b in np.flatnonzero(contested):
        rows, cols = linear_sum_assignment(-mac[b])
        index[b, rows] = cols
    index[bad] = np.arange(n_test)
    paired_mac = np.take_along_axis(mac, index[:, :, None], axis=2)[:, :, 0]
    paired_mac[bad] = np.nan
    return index, paired_mac
