"""Warnings after a calibration or a posterior: what a user must look at before trusting it.

Each check returns plain one-line messages (the commands print them on stderr, list them in
``--json`` under ``warnings`` and store them in the result file):

* an optimum on a bound: a parameter within ``BOUND_TOLERANCE`` of its range from a bound (the
  data would move it further: the bounds, not the test, decide its value);
* a paired MAC below the pairing's threshold at the optimum, and a pair outside the frequency
  window there (``pairing.PairingRules``: the pairing is redone at every point and keeps a pair
  with no partner inside the window);
* fewer than half the starts reaching the best objective (``CalibrationResult.converged_starts``:
  within 1 %): the optimum may not be unique, or the search did not settle;
* a posterior piled at a bound: at least ``PILED_SHARE`` of the draws in the ``PILED_BAND`` of the
  range next to a bound (a posterior flat over the whole range puts ``PILED_BAND`` there; a
  posterior whose mode is inside the range and that the range does not cut puts almost none).
"""

import numpy as np

from bayesupdate.inference.optimize import CalibrationResult
from bayesupdate.inference.pairing import outside_window
from bayesupdate.inference.problem import CalibrationProblem

#: an optimum this close to a bound, as a share of the parameter's range, sits on it [-]
BOUND_TOLERANCE = 1e-3

#: band next to a bound (share of the range) and share of the draws in it that say "piled"
PILED_BAND = 0.02
PILED_SHARE = 0.10


def bound_warnings(problem: CalibrationProblem, theta: np.ndarray) -> list[str]:
    """One line per parameter of ``theta`` (d,) within ``BOUND_TOLERANCE`` of a bound."""
    out = []
    span = problem.upper - problem.lower
    for name, value, low, high, width in zip(
        problem.names, theta, problem.lower, problem.upper, span, strict=True
    ):
        for side, bound in (("lower", low), ("upper", high)):
            if abs(value - bound) <= BOUND_TOLERANCE * width:
                out.append(
                    f"{name} = {value:.6g} sits on its {side} bound {bound:.6g}: the bounds, "
                    "not the test, set it; widen the range or check the parameter"
                )
    return out


def pairing_warnings(problem: CalibrationProblem, result: CalibrationResult) -> list[str]:
    """One line per pair of the optimum's residual table with a MAC below the pairing's
    threshold, or outside its frequency window (MAC pairing with rules only)."""
    rules = problem.pairing.rules
    if rules is None or problem.pairing.method != "mac":
        return []
    table = result.table
    out = []
    far = outside_window(table.test_hz, table.model_hz, problem.pairing.window)
    for row, is_far in zip(table.rows(), far, strict=True):
        head = (
            f"test mode {row['mode']} ({row['test_hz']:.4g} Hz): paired with model mode "
            f"{row['model_mode']} at {row['model_hz']:.4g} Hz"
        )
        if row["mac"] is not None and row["mac"] < rules.mac_threshold:
            out.append(
                f"{head}, MAC {row['mac']:.2f} at the optimum, below {rules.mac_threshold:g}"
            )
        if is_far:
            out.append(
                f"{head} ({row['error_pct']:+.0f} %), outside the frequency window "
                f"+-{100 * rules.frequency_window:g} % at the optimum (the pair still counts)"
            )
    return out


def start_warnings(result: CalibrationResult) -> list[str]:
    """One line when fewer than half the starts reach the best objective."""
    if 2 * result.converged_starts >= result.starts:
        return []
    return [
        f"only {result.converged_starts} of {result.starts} starts reach the best objective "
        "(within 1 %): the optimum may not be unique; try more starts, fewer parameters or "
        "more test modes"
    ]


def calibration_warnings(problem: CalibrationProblem, result: CalibrationResult) -> list[str]:
    """All the checks of a calibration (module docstring), bounds first."""
    return [
        *bound_warnings(problem, result.theta),
        *pairing_warnings(problem, result),
        *start_warnings(result),
    ]


def piled_warnings(problem: CalibrationProblem, draws: np.ndarray) -> list[str]:
    """One line per parameter whose posterior draws (n, >= d; the first d columns in
    ``problem.names`` order) put at least ``PILED_SHARE`` in the ``PILED_BAND`` next to a
    bound."""
    out = []
    draws = np.asarray(draws, dtype=float)
    span = problem.upper - problem.lower
    for j, name in enumerate(problem.names):
        x = draws[:, j]
        for side, bound in (("lower", problem.lower[j]), ("upper", problem.upper[j])):
            share = float(np.mean(np.abs(x - bound) <= PILED_BAND * span[j]))
            if share >= PILED_SHARE:
                out.append(
                    f"{name}: {100 * share:.0f} % of the posterior lies within "
                    f"{100 * PILED_BAND:g} % of the range of its {side} bound {bound:.6g} "
                    "(the bounds cut the posterior); widen the range or check the parameter"
                )
    return out


def sampling_warnings(
    problem: CalibrationProblem, calibration: CalibrationResult, draws: np.ndarray
) -> list[str]:
    """The checks that apply to a posterior: the pairing at the optimum its walkers started
    from, and the draws (n, d) piled at a bound."""
    return [*pairing_warnings(problem, calibration), *piled_warnings(problem, draws)]
