"""``bayesupdate correlate``: the model against the test before any parameter moves."""

from bayesupdate.commands._output import emit
from bayesupdate.errors import BayesUpdateError

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

  bayesupdate correlate --model exhaust --data paper:ema
  bayesupdate correlate --model exhaust --data modes.h5 --out corr.h5 --report corr --json
  bayesupdate correlate study.toml --mac-threshold 0.8

--json prints {"model", "data", "pairing", "transform" {"matrix", "rms_residual"}, "points" [{"dof",
"test_node", "model_node", "model_xyz", "direction", "distance"}], "modes" [{"test", "model",
"test_hz", "model_hz", "error_pct", "mac"}] (modes numbered from 1), "mac", "test_auto_mac",
"comac" [{"dof", "comac"}], "worst_points", "swapped", "refused", "unpaired_test",
"unpaired_model", "pseudo_orthogonality", "cross_orthogonality", "notes"}."""


def add_arguments(parser) -> None:
    parser.add_argument("study", nargs="?", help="TOML study file ([model], [data]); optional")
    parser.add_argument("--model", help="built-in model, Nastran deck or package.module:function")
    parser.add_argument("--data", help="test modes: .h5 or .uff (shapes), a CSV table, paper:ema")
    parser.add_argument(
        "--test-points",
        metavar="FILE",
        help="Nastran deck: test node -> GRID table (CSV 'point,grid[,frame]' or TOML)",
    )
    parser.add_argument(
        "--geometry",
        metavar="FILE",
        help="test geometry (UFF 15/2411/2420/82 .unv/.uff or CSV): aligned (auto) and paired "
        "with the model instead of the study's [test] table",
    )
    parser.add_argument(
        "--length-unit",
        metavar="UNIT",
        help="--geometry's length unit where the file has no UFF 164 record (mm, m, in, ft)",
    )
    parser.add_argument(
        "--pair-tolerance",
        metavar="LENGTH",
        help="--geometry: farthest a test point may lie from the model (e.g. '5 mm'; 0.01 m)",
    )
    parser.add_argument(
        "--mac-threshold",
        type=float,
        default=None,
        metavar="X",
        help="refuse pairs below this MAC (default 0.6)",
    )
    parser.add_argument(
        "--extra-modes",
        type=int,
        default=4,
        metavar="N",
        help="model modes computed beyond the test's (default 4)",
    )
    parser.add_argument("--out", help="result file (HDF5)")
    parser.add_argument("--report", metavar="DIR", help="write DIR/report.html and DIR/report.md")
    parser.add_argument("--force", action="store_true", help="overwrite --out / --report files")
    parser.add_argument("--json", action="store_true", help="print one JSON object on stdout")


def study_inputs(args, with_model: bool = True):
    """(study, model, data) of a study file and/or --model/--data/--test-points (flags win);
    (study, data) without the model."""
    from dataclasses import replace

    from bayesupdate.config import StudyConfig, load_study, with_overrides
    from bayesupdate.inference.data import load_modal_data

    if args.study is None and args.model is None:
        raise BayesUpdateError(f"{args.command}: give a STUDY.toml or --model (and --data)")
    study = load_study(args.study) if args.study else StudyConfig()
    study = with_overrides(study, model__source=args.model, data__source=args.data)
    if args.data is not None and study.data.frequencies_hz is not None:
        study = replace(study, data=replace(study.data, frequencies_hz=None))
    study = _with_geometry(study, args)
    if args.test_points:
        from bayesupdate.nastran.test_points import read_test_points

        points = read_test_points(args.test_points)
        study = replace(study, model=replace(study.model, test_points=points))
    data = load_modal_data(study.data.as_source())
    if not with_model:
        return study, data
    labels = data.dof_labels if data.shapes is not None else ()
    return study, *study_model_any(study, labels), data


def _with_geometry(study, args):
    """The study with ``--geometry`` (and its unit and tolerance) as its ``[test]`` table."""
    from dataclasses import replace

    from bayesupdate.config import parse_test_table

    geometry = getattr(args, "geometry", None)
    unit, tol = getattr(args, "length_unit", None), getattr(args, "pair_tolerance", None)
    if not geometry:
        if unit or tol:
            raise BayesUpdateError(f"{args.command}: --length-unit and --pair-tolerance need "
                                   "--geometry")  # fmt: skip
        return study
    table = {"geometry": geometry, "length_unit": unit, "pair_tolerance": tol}
    table = {k: v for k, v in table.items() if v is not None}
    return replace(study, test=parse_test_table(table, "--geometry"))


def study_model_any(study, labels):
    """(model, mapping): the study's model, a Nastran deck also without bound parameters
    (correlation needs none; ``nastran.load_nastran_model``); with a ``[test]`` geometry the
    model's sensors are the test DOFs paired by it and mapping says how (else None)."""
    from bayesupdate.nastran import is_nastran_path, load_nastran_model
    from bayesupdate.pipelines.model_source import study_model

    if study.test is not None:
        return _paired(study, labels)
    if is_nastran_path(study.model.source):
        model = load_nastran_model(
            study.model.source, study.parameters, tuple(labels), dict(study.model.test_points)
        )
        return model, None
    return study_model(study, labels), None


def _paired(study, labels):
    """The ``[test]`` table's pairing of the test DOFs ``labels`` with the study's model."""
    from bayesupdate.nastran import is_nastran_path, load_nastran_model
    from bayesupdate.pipelines.correlate import geometry_mapping
    from bayesupdate.pipelines.model_source import paired_study_model
    from bayesupdate.testgeom import pair_structure, read_geometry, with_pairing

    if not is_nastran_path(study.model.source):
        model, pairing = paired_study_model(study, labels)
        return model, None if pairing is None else geometry_mapping(pairing)
    cfg = study.test
    model = load_nastran_model(study.model.source, study.parameters)
    geometry = read_geometry(cfg.geometry, cfg.length_unit)
    if not labels:
        return model, None
    pairing = pair_structure(
        model.structure, geometry, tuple(labels), cfg.settings(), cfg.model_length_unit
    )
    return model.with_structure(with_pairing(model.structure, pairing)), geometry_mapping(pairing)


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
                "test": int(t) + 1,
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
        "swapped": [{"test": t + 1, "model": m + 1} for t, m in pairs.swapped],
        "refused": [{"test": t + 1, "model": m + 1, "mac": v} for t, m, v in pairs.refused],
        "unpaired_test": [t + 1 for t in pairs.unpaired_test],
        "unpaired_model": [m + 1 for m in pairs.unpaired_model],
        "pseudo_orthogonality": matrix(result.pseudo_orthogonality),
        "cross_orthogonality": matrix(result.cross_orthogonality),
        "notes": list(result.notes),
    }


def run(args) -> int:
    from bayesupdate.atomic import check_output_path
    from bayesupdate.pipelines.correlate import CorrelateSettings, correlate, write_correlation_h5
    from bayesupdate.report.correlate_report import write_correlate_report
    from bayesupdate.report.identify_report import check_report_folder

    settings = CorrelateSettings(
        **({} if args.mac_threshold is None else {"mac_threshold": args.mac_threshold}),
        extra_modes=args.extra_modes,
    )
    if args.out:
        check_output_path(args.out, args.force)
    study, model, mapping, data = study_inputs(args)
    result = correlate(model, data, settings, name=str(study.model.source), mapping=mapping)
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
            f"{t + 1:4d}  {m + 1:5d}  {result.test_hz[t]:8.3f}  {result.model_hz[m]:9.3f}  "
            f"{e:+7.2f}  {mac}"
        )
    if result.mac is not None:
        lines.append("MAC (rows: test modes, columns: model modes)")
        lines += [" ".join(f"{v:4.2f}" for v in row) for row in result.mac]
        off = result.test_auto_mac - np.eye(result.test_hz.size)
        lines.append(f"test AutoMAC: largest off-diagonal {off.max():.3f}")
    unpaired = (("test", pairs.unpaired_test), ("model", pairs.unpaired_model))
    for label, modes in unpaired:
        if modes:
            lines.append(f"unpaired {label} modes: " + ", ".join(str(i + 1) for i in modes))
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
