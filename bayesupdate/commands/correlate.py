"""``bayesupdate correlate``: the model against the test before any parameter moves."""

from bayesupdate.commands._shared import (
    add_correlate_arguments,
    check_outputs,
    correlate_settings,
    correlate_study,
    emit,
)

NAME = "correlate"
HELP = "frequency table, MAC matrix and mode pairs, COMAC, SEREP orthogonality: model vs test"
DESCRIPTION = """Correlate a model with test modes before updating: a row per test mode, paired
(model mode, % difference, MAC) or refused with the rule that refused it, the MAC matrix (test x
model) and the test's AutoMAC, swaps and unpaired modes named, COMAC per test DOF with the worst
points named, and for an FE model a SEREP test-analysis model at the test DOFs (O'Callahan et
al. 1989): the model's pseudo-orthogonality, the cross-orthogonality where the test's shapes are
mass-normalized, and the test shapes expanded to
every model DOF (--out).  Test data without shapes (paper:ema, a frequency CSV) pair in order.

Pairs follow the one rule calibrate, sample and discover keep pairs by (the study's [pairing]
table, or the flags): a pair is admissible when its MAC reaches --mac-threshold (0.6) and
|f_model / f_test - 1| <= --frequency-window (0.5); the pairs are the assignment of distinct
model modes maximizing the total MAC of the admissible pairs (Hungarian method).  Any other
test mode is refused, named with its best MAC partner and the rule: mac (below the threshold),
window (that partner outside the window) or taken (that partner paired with another test
mode).  The model is solved for --extra-modes (2) modes beyond the test's highest, and for
more where those all lie below the test's highest frequency (a test that missed lower modes).

The test DOFs are mapped to the model as calibrate maps them: a built-in model's sensors, a
Nastran deck's [model.test_points] (or --test-points FILE; default: test node = GRID id).
The study's [data] modes = [...] chooses the test modes that are paired and reported (numbered
as in their source, as identify --json lists them).

  bayesupdate correlate --model exhaust --data paper:ema
  bayesupdate correlate --model exhaust --data modes.h5 --out corr.h5 --report corr --json
  bayesupdate correlate study.toml --mac-threshold 0.8 --frequency-window 0.3

--json prints {"model", "data", "pairing", "rules" {"mac_threshold", "frequency_window"},
"transform" {"matrix", "rms_residual"}, "points" [{"dof", "test_node", "model_node",
"model_xyz", "direction", "distance"}], "modes" [{"test", "model", "test_hz", "model_hz",
"error_pct", "mac"}] (the pairs; modes numbered from 1), "tests" [{"test", "test_hz", "status"
(paired | refused | unpaired), "model", "model_hz", "error_pct", "mac", "reason" (mac | window
| taken)}] (every test mode), "mac", "test_auto_mac", "comac" [{"dof", "comac"}],
"worst_points", "swapped", "refused" [{"test", "model", "test_hz", "model_hz", "error_pct",
"mac", "reason", "other", "message"}], "unpaired_test", "unpaired_model",
"pseudo_orthogonality", "cross_orthogonality", "notes"}."""


def add_arguments(parser) -> None:
    add_correlate_arguments(parser)


def correlation_json(result) -> dict:
    """The ``correlate --json`` object of a ``pipelines.correlate.Correlation``."""
    from dataclasses import asdict

    pairs = result.pairs

    def matrix(a):
        return None if a is None else [[round(float(v), 6) for v in row] for row in a]

    rules = result.rules
    return {
        "model": result.model,
        "data": result.data,
        "pairing": pairs.method,
        "rules": None
        if rules is None
        else {
            "mac_threshold": rules.mac_threshold,
            "frequency_window": _finite(rules.frequency_window),
        },
        "transform": {
            "matrix": matrix(result.mapping.transform),
            "rms_residual": result.mapping.rms_residual,
            "source": result.mapping.source,
        },
        "points": [asdict(p) for p in result.mapping.points],
        "modes": [
            {
                "test": result.number(t),
                "model": int(m) + 1,
                "test_hz": float(result.test_hz[t]),
                "model_hz": float(result.model_hz[m]),
                "error_pct": float(e),
                "mac": None if v != v else float(v),
            }
            for t, m, e, v in zip(pairs.test, pairs.model, result.error_pct, pairs.mac, strict=True)
        ],
        "tests": test_mode_rows(result),
        "mac": matrix(result.mac),
        "test_auto_mac": matrix(result.test_auto_mac),
        "comac": None
        if result.comac is None
        else [
            {"dof": d, "comac": float(c)}
            for d, c in zip(result.dof_labels, result.comac, strict=True)
        ],  # fmt: skip
        "worst_points": [{"dof": d, "comac": c} for d, c in result.worst_points(3)],
        "swapped": [{"test": result.number(t), "model": m + 1} for t, m in pairs.swapped],
        "refused": [_refused_json(r, rules) for r in result.refused],
        "unpaired_test": [result.number(t) for t in pairs.unpaired_test],
        "unpaired_model": [m + 1 for m in pairs.unpaired_model],
        "pseudo_orthogonality": matrix(result.pseudo_orthogonality),
        "cross_orthogonality": matrix(result.cross_orthogonality),
        "notes": list(result.notes),
    }


def _finite(value: float) -> float | None:
    """``value``, or None for an infinite one (JSON has no infinity)."""
    return None if value == float("inf") else value


def _refused_json(refused, rules) -> dict:
    return {
        "test": refused.number,
        "model": refused.model_mode,
        "test_hz": refused.test_hz,
        "model_hz": refused.model_hz,
        "error_pct": refused.error_pct,
        "mac": refused.mac,
        "reason": refused.reason,
        "other": refused.other or None,
        "message": refused.message(rules),
    }


def test_mode_rows(result) -> list[dict]:
    """Every test mode of a ``Correlation``, in test order: {"test", "test_hz", "status"
    (paired | refused | unpaired), "model", "model_hz", "error_pct", "mac" (a refused mode:
    its best MAC partner; unpaired: null), "reason" (refused: mac | window | taken; else
    null)}."""
    pairs = result.pairs
    paired = {int(t): k for k, t in enumerate(pairs.test)}
    refused = {r.number: r for r in result.refused}
    rows = []
    for t, f in enumerate(result.test_hz):
        row = {"test": result.number(t), "test_hz": float(f), "status": "unpaired"}
        row.update(dict.fromkeys(("model", "model_hz", "error_pct", "mac", "reason")))
        if t in paired:
            k = paired[t]
            m, v = int(pairs.model[k]), float(pairs.mac[k])
            row.update(status="paired", model=m + 1, model_hz=float(result.model_hz[m]),
                       error_pct=float(result.error_pct[k]), mac=None if v != v else v)  # fmt: skip
        elif row["test"] in refused:
            r = refused[row["test"]]
            row.update(status="refused", model=r.model_mode, model_hz=r.model_hz,
                       error_pct=r.error_pct, mac=r.mac, reason=r.reason)  # fmt: skip
        rows.append(row)
    return rows


def run(args) -> int:
    check_outputs(args)  # before the imports below
    from bayesupdate.pipelines.correlate import (
        correlate,
        study_correlation_model,
        write_correlation_h5,
    )
    from bayesupdate.report.correlate_report import write_correlate_report
    from bayesupdate.report.identify_report import check_report_folder

    study, data, numbers = correlate_study(args)
    settings = correlate_settings(args, study)
    labels = data.dof_labels if data.shapes is not None else ()
    model, mapping = study_correlation_model(study, labels)
    result = correlate(model, data, settings, str(study.model.source), mapping, numbers)
    if args.report:  # made only once the inputs have passed (no folder left by bad input)
        check_report_folder(args.report, args.force)
    if args.out:
        write_correlation_h5(args.out, result)
    report = write_correlate_report(args.report, result)[0] if args.report else None
    text = "" if args.json else format_correlation(result)
    return emit(args, correlation_json(result) if args.json else {}, text, report)


def format_correlation(result) -> str:
    """The terminal text: frequency table, MAC matrix, pairs, COMAC, orthogonality, notes."""
    import numpy as np

    pairs = result.pairs
    rules = result.rules
    head = f"{result.model} vs {result.data}: {result.test_hz.size} test modes, "
    head += f"{result.model_hz.size} model modes, paired by {pairs.method}"
    if rules is not None:
        head += f" (MAC >= {rules.mac_threshold:g} within +-{100 * rules.frequency_window:g} %)"
    lines = [head, "test  model   test_Hz   model_Hz   diff_%    MAC  pair"]
    refused = {r.number: r for r in result.refused}
    for row in test_mode_rows(result):
        lines.append(_table_line(row, refused.get(row["test"]), rules))
    if result.mac is not None:
        lines.append("MAC (rows: test modes, columns: model modes)")
        lines += [" ".join(f"{v:4.2f}" for v in row) for row in result.mac]
        off = result.test_auto_mac - np.eye(result.test_hz.size)
        lines.append(f"test AutoMAC: largest off-diagonal {off.max():.3f}")
    unpaired = (
        ("test", [result.number(t) for t in pairs.unpaired_test]),
        ("model", [m + 1 for m in pairs.unpaired_model]),
    )
    for label, numbers in unpaired:
        if numbers:
            lines.append(f"unpaired {label} modes: " + ", ".join(map(str, numbers)))
    if result.comac is not None:
        worst = ", ".join(f"{d} {c:.3f}" for d, c in result.worst_points(3))
        lines.append(f"COMAC: lowest at {worst}")
    lines += _orthogonality_lines(result)
    lines += [f"note: {n}" for n in result.notes]
    return "\n".join(lines)


def _table_line(row: dict, refused, rules) -> str:
    """One test mode's line of the table: its pair, or its best partner and why refused."""
    start = f"{row['test']:4d}  "
    if row["model"] is None:
        return start + f"{'-':>5}  {row['test_hz']:8.3f}  {'-':>9}  {'-':>7}  {'-':>5}  unpaired"
    mac = "  -  " if row["mac"] is None else f"{row['mac']:.3f}"
    status = "paired" if refused is None else f"refused: {refused.why(rules)}"
    return start + (
        f"{row['model']:5d}  {row['test_hz']:8.3f}  {row['model_hz']:9.3f}  "
        f"{row['error_pct']:+7.2f}  {mac}  {status}"
    )


def _orthogonality_lines(result) -> list[str]:
    import numpy as np

    out = []
    for name, x in (
        ("pseudo-orthogonality (model, SEREP TAM)", result.pseudo_orthogonality),
        ("cross-orthogonality (test vs model)", result.cross_orthogonality),
    ):
        if x is not None:
            off = np.abs(x - np.diag(np.diag(x)))
            out.append(
                f"{name}: diagonal {np.abs(np.diag(x)).min():.3f}..{np.abs(np.diag(x)).max():.3f}"
                f", largest off-diagonal {off.max():.3f}"
            )
    return out
