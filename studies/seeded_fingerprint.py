"""Bit-identity of the seeded runs a user makes, before and after a refactor.

Runs, through the CLI with default settings and fixed seeds:
- ``bayesupdate demo --quick --seed 0`` (seed case and virtual test: optimum, posterior, modes);
- ``bayesupdate calibrate --model exhaust --data paper:ema --json`` (the default calibration);
- ``bayesupdate simulate --effect added_mass@8:m=0.5 --noise 0.01 --seed 7`` ->
  ``identify`` -> ``discover --json`` (a hidden effect) and the null case (no effect, seed 24).

Every HDF5 dataset and attribute and every ``--json`` field is reduced to a digest: the SHA-256
of its bytes for arrays, the value itself for scalars and strings.  Wall times, creation
stamps, library versions and the temporary folder's path are left out.  ``--write F`` stores
the fingerprint, ``--compare F`` prints every entry that differs and exits 1 if any does.

Run: .venv/bin/python studies/seeded_fingerprint.py --write before.json
     (refactor)
     .venv/bin/python studies/seeded_fingerprint.py --compare before.json
"""

import argparse
import contextlib
import hashlib
import io
import json
import re
import sys
import tempfile
from pathlib import Path

import h5py
import numpy as np

from bayesupdate.cli import main as cli

#: run-to-run clocks and versions, never results (timings_json: the sampler's stage clocks)
VOLATILE = {"wall_s", "created_utc", "versions", "elapsed_s", "timings", "timings_json"}


def run(argv: list) -> str:
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(io.StringIO()):
        code = cli([str(a) for a in argv])
    if code != 0:
        raise SystemExit(f"bayesupdate {' '.join(map(str, argv))} failed ({code})")
    return buf.getvalue()


def digest(value, tmp: str):
    """A comparable stand-in: arrays by SHA-256 of their bytes, strings without the temp path."""
    if isinstance(value, bytes):
        value = value.decode()
    if isinstance(value, str):
        return value.replace(tmp, "<tmp>")
    if isinstance(value, np.generic):
        value = value.item()
    if value is None or isinstance(value, bool | int | float):
        return value
    array = np.asarray(value)
    if array.dtype.kind in "OSU":
        return [digest(v, tmp) for v in array.ravel().tolist()]
    if array.size == 1:
        return array.item()
    return f"{array.dtype}{array.shape}:" + hashlib.sha256(array.tobytes()).hexdigest()[:16]


def from_json(prefix: str, obj, out: dict, tmp: str) -> None:
    """Flatten a parsed ``--json`` output; lists of numbers become one digest."""
    if isinstance(obj, dict):
        for key, value in obj.items():
            if key not in VOLATILE:
                from_json(f"{prefix}.{key}", value, out, tmp)
    elif isinstance(obj, list) and obj and all(isinstance(v, int | float) for v in obj):
        out[prefix] = digest(np.array(obj, dtype=float), tmp)
    elif isinstance(obj, list):
        for k, value in enumerate(obj):
            from_json(f"{prefix}[{k}]", value, out, tmp)
    else:
        out[prefix] = digest(obj, tmp)


def from_attrs(prefix: str, attrs, out: dict, tmp: str) -> None:
    """HDF5 attributes; JSON text (``*_json``) compared field by field, wall times left out."""
    for key, value in attrs.items():
        if key in VOLATILE:
            continue
        if key.endswith("_json"):
            from_json(f"{prefix}@{key}", json.loads(value), out, tmp)
        else:
            out[f"{prefix}@{key}"] = digest(value, tmp)


def from_h5(path: Path, out: dict, tmp: str) -> None:
    def visit(name, node):
        if any(part in VOLATILE for part in name.split("/")):
            return
        if isinstance(node, h5py.Dataset):
            out[f"{path.name}:{name}"] = digest(node[()], tmp)
        from_attrs(f"{path.name}:{name}", node.attrs, out, tmp)

    with h5py.File(path, "r") as h5:
        from_attrs(f"{path.name}:", h5.attrs, out, tmp)
        h5.visititems(visit)


def fingerprint() -> dict:
    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        run(["demo", "--quick", "--seed", "0", "--out", tmp / "demo"])
        for h5 in sorted((tmp / "demo").glob("*.h5")):
            from_h5(h5, out, tmp_name)
        calibration = run(["calibrate", "--model", "exhaust", "--data", "paper:ema", "--json",
                           "--out", tmp / "cal.h5"])  # fmt: skip
        from_json("calibrate", json.loads(calibration), out, tmp_name)
        cases = {"effect": ["--effect", "added_mass@8:m=0.5", "--seed", "7"],
                 "null": ["--seed", "24"]}  # fmt: skip
        for name, args in cases.items():
            uff, modes = tmp / f"{name}.uff", tmp / f"{name}.h5"
            run(["simulate", "--noise", "0.01", *args, "--out", uff])
            run(["identify", uff, "--out", modes])
            from_h5(modes, out, tmp_name)
            found = run(["discover", "--model", "exhaust", "--data", modes, "--json",
                         "--out", tmp / f"{name}_discover.h5"])  # fmt: skip
            from_json(f"discover_{name}", json.loads(found), out, tmp_name)
    return out


def _text(fingerprint: dict, key: str) -> str:
    return json.dumps(fingerprint.get(key, "<missing>"))


def _volatile(key: str) -> bool:
    """A key under a volatile name (a baseline written before that name was listed)."""
    return any(part in VOLATILE for part in re.split(r"[@./:\[]", key))


def compare(now: dict, before: dict) -> int:
    keys = sorted(k for k in set(now) | set(before) if not _volatile(k))
    # through JSON text, so that NaN equals NaN
    differ = [k for k in keys if _text(now, k) != _text(before, k)]
    for key in differ:
        was, now_value = before.get(key, "<missing>"), now.get(key, "<missing>")
        print(f"DIFFERS {key}: before {was!r} now {now_value!r}")
    print(f"{len(keys)} entries, {len(differ)} differ")
    return 1 if differ else 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    group = parser.add_mutually_exclusive_group(required=True)
    group.add_argument("--write", type=Path, help="store the fingerprint here")
    group.add_argument("--compare", type=Path, help="compare with a stored fingerprint")
    args = parser.parse_args()
    now = fingerprint()
    if args.write:
        args.write.write_text(json.dumps(now, indent=1, sort_keys=True))
        print(f"{len(now)} entries written to {args.write}")
        return 0
    return compare(now, json.loads(args.compare.read_text()))


if __name__ == "__main__":
    sys.exit(main())
