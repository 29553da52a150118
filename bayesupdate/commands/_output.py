"""What a command that writes a result file and a report prints at its end (shared by
``correlate`` and ``sensitivity``): with ``--json`` one JSON object on stdout, else the text and
the paths written."""

import json


def emit(args, record: dict, text: str, report) -> int:
    """Print ``record`` (plus ``out`` and ``report``) as JSON with ``args.json``, else ``text``
    and a "wrote PATH" line per file written; 0."""
    if args.json:
        record.update(out=args.out, report=None if report is None else str(report))
        print(json.dumps(record))
        return 0
    print(text)
    for path in (args.out, report):
        if path:
            print(f"wrote {path}")
    return 0
