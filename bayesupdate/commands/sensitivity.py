"""``bayesupdate sensitivity``: which parameters the measured modes can inform, before updating."""

from dataclasses import replace

import numpy as np

from bayesupdate.commands._shared import (
    add_correlate_arguments,
    check_outputs,
    correlate_settings,
    correlate_study,
    emit,
)
from bayesupdate.errors import BayesUpdateError

NAME = "sensitivity"
HELP = "normalized sensitivities of the paired frequencies, what the test sees, a parameter set"
DESCRIPTION = """Normalized sensitivities (d f / f) / (d p / p) of the model modes paired with the
test (as 'correlate' and 'calibrate' pair them: the study's [pairing] rules) to every candidate
parameter, at the model's defaults: by the eigenvalue derivative phi^T (dK - lambda dM) phi for
FE models and decks (one modal solve), or by central differences in log-parameter (--method
fd; with test shapes also d MAC / d ln p).  Then the singular values of the sensitivity matrix
and their directions (those below --rank-tol x the largest are directions the test cannot see),
groups of confounded parameters (columns parallel within --group-cos: they move the frequencies
as one direction), and a suggested parameter set by QR with column pivoting (a rank-revealing
choice: a suggestion, not a verdict).

Candidates are the study's parameters, or for a Nastran deck --candidates: deck fields, with *
for every card of that type ("PSHELL * T" is one candidate per PSHELL of the deck):

  bayesupdate sensitivity --model exhaust --data paper:ema
  bayesupdate sensitivity study.toml --candidates "PSHELL * T" "MAT1 * RHO" --json
  bayesupdate sensitivity study.toml --candidates "MAT1 2 E" "MAT1 2 RHO" --report sens

--json prints {"model", "method", "candidates" [{"name", "value"}], "modes" [{"test", "model",
"frequency_hz"}] (numbered from 1), "sensitivity" (modes x candidates), "mac_sensitivity" (fd
with shapes, else null), "singular_values", "rank", "directions" [{"singular_value", "relative",
"seen", "terms" {name: weight}}], "unseen", "groups", "suggested", "notes"}."""


def add_arguments(parser) -> None:
    add_correlate_arguments(parser)  # the same inputs and outputs as correlate
    parser.add_argument(
        "--candidates",
        nargs="+",
        metavar="SPEC",
        help='Nastran deck: candidate deck fields, e.g. "PSHELL * T" "MAT1 * RHO" "MAT1 2 E"',
    )
    parser.add_argument(
        "--method",
        default="auto",
        choices=("auto", "analytic", "fd"),
        help="auto: analytic for FE models and decks, else fd",
    )
    parser.add_argument("--step", type=float, default=1e-3, help="log-parameter step (1e-3)")
    parser.add_argument(
        "--rank-tol",
        type=float,
        default=0.02,
        help="relative singular value below which a direction is not seen (0.02)",
    )
    parser.add_argument(
        "--group-cos",
        type=float,
        default=0.99,
        help="|cosine| of two candidates' sensitivities above which they are confounded (0.99)",
    )


def _deck_card_ids(bdf, card: str) -> list[int]:
    """Ids of the deck's cards of type ``card`` (the tables ``nastran.bindings`` reads)."""
    tables = (bdf.properties, bdf.materials, bdf.masses, bdf.elements)
    return sorted({int(i) for table in tables for i, c in table.items() if c.type == card})


def candidate_model(args, study, data):
    """(model, candidate base values {name: value}): the study's model with its parameters,
    or a deck re-read with the --candidates bound (``pipelines.model_source``)."""
    from bayesupdate.pipelines.correlate import study_correlation_model
    from bayesupdate.pipelines.model_source import is_deck, resolve_model
    from bayesupdate.pipelines.sensitivity import expand_candidates

    labels = data.dof_labels if data.shapes is not None else ()
    source = study.model.source
    if args.candidates and not is_deck(source):
        raise BayesUpdateError(
            f"--candidates: only for a Nastran deck; {source!r} has parameters "
            "(list them in the study's [parameters] tables)"
        )
    if args.candidates:
        deck = resolve_model(source, units=study.model.units, needs_parameters=False)
        tables = expand_candidates(args.candidates, lambda c: _deck_card_ids(deck.bdf, c))
        study = replace(study, parameters=tables)
    model = study_correlation_model(study, labels)[0]
    names = tuple(study.parameters) if study.parameters and not args.candidates else ()
    base = model.default_parameters()
    if names:
        base = {n: base[n] for n in names if n in base}
    if not base:
        raise BayesUpdateError(
            f"sensitivity: {source} has no candidate parameters; bind deck fields in the study "
            'or give --candidates "PSHELL * T"'
        )
    return model, base


def run(args) -> int:
    check_outputs(args)  # before the imports below
    from bayesupdate.pipelines.correlate import correlate
    from bayesupdate.pipelines.sensitivity import (
        SensitivityInput,
        SensitivitySettings,
        run_sensitivity,
        write_sensitivity_h5,
    )
    from bayesupdate.report.correlate_report import write_sensitivity_report
    from bayesupdate.report.identify_report import check_report_folder

    settings = SensitivitySettings(args.method, args.step, args.rank_tol, args.group_cos)
    study, data, numbers = correlate_study(args)
    pairing = correlate_settings(args, study)  # the pairs correlate and calibrate keep
    model, base = candidate_model(args, study, data)
    corr = correlate(model, data, pairing, str(study.model.source), numbers=numbers)
    if not corr.pairs.test.size:
        raise BayesUpdateError("sensitivity: no test mode pairs with a model mode (see correlate)")
    if args.report:  # made only once the inputs have passed (no folder left by bad input)
        check_report_folder(args.report, args.force)
    test_shapes = None if data.shapes is None else data.shapes[:, corr.pairs.test]
    in_source = np.array([corr.number(t) - 1 for t in corr.pairs.test], dtype=int)
    inp = SensitivityInput(model, str(study.model.source), base, corr.pairs.model,
                           in_source, test_shapes, data.dof_labels, corr.notes)  # fmt: skip
    result = run_sensitivity(inp, settings)
    if args.out:
        write_sensitivity_h5(args.out, result)
    report = write_sensitivity_report(args.report, result)[0] if args.report else None
    text = "" if args.json else format_sensitivity(result)
    return emit(args, sensitivity_json(result) if args.json else {}, text, report)


def sensitivity_json(result) -> dict:
    """The ``sensitivity --json`` object of a ``pipelines.sensitivity.Sensitivity``."""

    def rows(a):
        return None if a is None else [[round(float(v), 6) for v in row] for row in a]

    top = result.singular_values[0] if result.singular_values[0] > 0 else 1.0
    return {
        "model": result.model,
        "method": result.method,
        "candidates": [
            {"name": n, "value": float(v)} for n, v in zip(result.names, result.values, strict=True)
        ],  # fmt: skip
        "modes": [
            {"test": int(t) + 1, "model": int(m) + 1, "frequency_hz": float(f)}
            for t, m, f in zip(result.test_modes, result.modes, result.frequencies_hz, strict=True)
        ],  # fmt: skip
        "sensitivity": rows(result.matrix),
        "mac_sensitivity": rows(result.mac_matrix),
        "singular_values": [float(s) for s in result.singular_values],
        "rank": result.rank,
        "directions": [
            {
                "singular_value": float(s),
                "relative": float(s / top),
                "seen": k < result.rank,
                "terms": dict(result.direction_terms(k)),
            }
            for k, s in enumerate(result.singular_values)
        ],  # fmt: skip
        "unseen": [dict(result.direction_terms(k)) for k in result.unseen],
        "groups": [list(g) for g in result.groups],
        "suggested": list(result.suggested),
        "notes": list(result.notes),
    }


def format_sensitivity(result) -> str:
    """The terminal text: the matrix, singular values and directions, groups, suggestion."""
    width = max(10, *(len(n) for n in result.names))
    lines = [f"{result.model}: d ln f / d ln p ({result.method}), rows: paired modes"]
    lines.append(" mode  model_Hz  " + " ".join(f"{n:>{width}}" for n in result.names))
    for i, row in enumerate(result.matrix):
        lines.append(
            f"{result.test_modes[i] + 1:5d}  {result.frequencies_hz[i]:8.3f}  "
            + " ".join(f"{v:>+{width}.4f}" for v in row)
        )
    top = result.singular_values[0] if result.singular_values[0] > 0 else 1.0
    for k, s in enumerate(result.singular_values):
        seen = "seen" if k < result.rank else "NOT SEEN"
        terms = ", ".join(f"{w:+.2f} {n}" for n, w in result.direction_terms(k))
        lines.append(f"direction {k + 1}: sigma {s:.4g} ({s / top:.3g}) {seen}: {terms}")
    for group in result.groups:
        lines.append("confounded (one direction): " + " + ".join(group))
    lines.append("suggested parameters (QR with column pivoting): " + ", ".join(result.suggested))
    lines += [f"note: {n}" for n in result.notes]
    return "\n".join(lines)
