"""``bayesupdate correlate``: the model against the test before any parameter moves."""

from bayesupdate.commands._shared import add_correlate_arguments, correlate_study, emit

NAME = "correlate"
HELP = "frequency table, MAC matrix and mode pairs, COMAC, SEREP orthogonality: model vs test"
DESCRIPTION = """Correlate a model with test modes before updating: the frequency table of the
paired modes with % differences, the MAC matrix (test x model) and the test's AutoMAC, the pairs
chosen by MAC (Hungarian assignment) above --mac-threshold with swaps, refused and unpaired modes
named, COMAC per test DOF with the worst points named, and for an FE model a SEREP test-analysis
model at the test DOFs (O'Callahan et al. 1989): the model's pseudo-orthogonality, the
cross-orthogonality where the test's shapes are mass-normalised, and the test shapes expanded to
every model DOF (--out).  Test data without shapes (paper:ema, a frequency CSV) pair in order.

The test DOFs are mapped to the model as calibrate maps them: a built-in model's sensors, a
Nastran deck's [model.test_points] (or --test-points FILE; default: test node = GRID id).
The study's [data] modes = [...] chooses the test modes that are paired and reported (numbered
as in their source, as identify --json lists them).

  bayesupdate correlate --model exhaust --data paper:ema
  bayesupdate correlate --model exhaust --data modes.h5 --out corr.h5 --report corr --json
  bayesupdate correlate study.toml --mac-threshold 0.8

--json prints {"model", "data", "pairing", "transform" {"matrix", "rms_residual"}, "points" [{"dof",
"test_node", "model_node", "model_xyz", "direction", "distance"}], "modes" [{"test", "model",
"test_hz", "model_hz", "error_pct", "mac"}] (modes numbered from 1), "mac", "test_auto_mac",
"comac" [{"dof", "comac"}], "worst_points", "swapped", "refused", "unpaired_test",
"unpaired_model", "pseudo_orthogonality", "cross_orthogonality", "notes"}."""


def add_arguments(parser) -> None:
    add_correlate_arguments(parser)


def correlation_json(result) -> dict:
    """The ``correlate --json`` object of a ``pipelines.correlate.Correlation``."""
    from dataclasses import asdict

    pairs = result.pairs

    def matrix(a):
        return None if a is None else [[round(float(v), 6) for v in row] for row in a]

    return {
        "model": result.model,
        "data": result.data,
        "pairing": pairs.method,
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
        "refused": [
            {"test": result.number(t), "model": m + 1, "mac": v} for t, m, v in pairs.refused
        ],
        "unpaired_test": [result.number(t) for t in pairs.unpaired_test],
        "unpaired_model": [m + 1 for m in pairs.unpaired_model],
        "pseudo_orthogonality": matrix(result.pseudo_orthogonality),
        "cross_orthogonality": matrix(result.cross_orthogonality),
        "notes": list(result.notes),
    }


def run(args) -> int:
    from bayesupdate.atomic import check_output_path
    from bayesupdate.pipelines.correlate import (
        CorrelateSettings,
        correlate,
        study_correlation_model,
        write_correlation_h5,
    )
    from bayesupdate.report.correlate_report import write_correlate_report
    from bayesupdate.report.identify_report import check_report_folder

    settings = CorrelateSettings(
        **({} if args.mac_threshold is None else {"mac_threshold": args.mac_threshold}),
        extra_modes=args.extra_modes,
    )
    if args.out:
        check_output_path(args.out, args.force)
    study, data, numbers = correlate_study(args)
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
    lines = [
        f"{result.model} vs {result.data}: {result.test_hz.size} test modes, "
        f"{result.model_hz.size} model modes, paired by {pairs.method}",
        "test  model   test_Hz   model_Hz   diff_%    MAC",
    ]
    for t, m, e, v in zip(pairs.test, pairs.model, result.error_pct, pairs.mac, strict=True):
        mac = "  -  " if v != v else f"{v:.3f}"
        lines.append(
            f"{result.number(t):4d}  {m + 1:5d}  {result.test_hz[t]:8.3f}  "
            f"{result.model_hz[m]:9.3f}  {e:+7.2f}  {mac}"
        )
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
