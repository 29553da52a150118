"""Discovery on the shell exhaust, the user's round: a virtual test of a "true" ``exhaust_shell``
with a hidden connection flexibility (or none), ``bayesupdate identify`` on its FRFs, then
``bayesupdate discover`` on a study file whose model is ``exhaust_shell`` (issue 20, item 3).

    PYTHONPATH=. OPENBLAS_NUM_THREADS=1 python studies/exhaust_shell_discovery.py \\
        --out shell_disc \\
        --effect connection_flexibility@cold_pipe/main_muffler:k_rot=1e4 --seed 7
    PYTHONPATH=. OPENBLAS_NUM_THREADS=1 python studies/exhaust_shell_discovery.py \\
        --out shell_null --seed 24

The virtual test is made at the same mesh density as the model discovery runs on (the
``simulate`` command takes no model options, so the test is made with
``pipelines.simulate.simulate_test``, as the command does, and written as UFF); identification
and discovery are the CLI with default settings.  Prints the verdict, the named effect, the
best candidates and the wall time of each step; writes the files into ``--out``.
"""

import argparse
import contextlib
import io
import json
import time
from pathlib import Path

from bayesupdate.cli import main as cli
from bayesupdate.discovery.effects import parse_effect_spec
from bayesupdate.ema.uff_io import write_uff58
from bayesupdate.models import get_model
from bayesupdate.pipelines.simulate import VirtualTestSettings, simulate_test


def _cli(argv: list) -> str:
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = cli([str(a) for a in argv])
    if code != 0:
        raise SystemExit(f"bayesupdate {argv[0]} failed ({code}): {buf.getvalue()[-2000:]}")
    return buf.getvalue()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="folder for the test, modes and result")
    ap.add_argument("--effect", action="append", default=[], help="hidden effect spec(s)")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--noise", type=float, default=0.01)
    ap.add_argument("--mesh-density", type=int, default=16)
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    model = get_model("exhaust_shell", mesh_density=args.mesh_density)
    effects = tuple(parse_effect_spec(spec) for spec in args.effect)
    test = simulate_test(model, VirtualTestSettings({}, effects, args.noise, args.seed))
    write_uff58(out / "test.uff", test.frfs)
    t1 = time.perf_counter()
    print(f"virtual test: {t1 - t0:.0f} s; true frequencies {test.frequencies_hz[:12].round(2)}")
    _cli(["identify", out / "test.uff", "--out", out / "modes.h5", "--force"])
    t2 = time.perf_counter()
    print(f"identify: {t2 - t1:.0f} s", flush=True)
    study = out / "study.toml"
    study.write_text(
        f'[model]\nsource = "exhaust_shell"\noptions = {{ mesh_density = {args.mesh_density} }}\n'
        f'\n[data]\nsource = "{(out / "modes.h5").resolve()}"\n'
    )
    found = _cli(["discover", study, "--out", out / "discovery.h5", "--force", "--json"])
    t3 = time.perf_counter()
    (out / "discovery.json").write_text(found)
    doc = json.loads(found)
    print(f"discover: {t3 - t2:.0f} s; verdict {doc['verdict']}; named {doc['named_effect']}")
    print(f"flagged modes {doc['flagged_modes']}; gap {doc['gap_before']} -> {doc['gap_after']}")
    for c in doc["candidates"][:6]:
        print(f"  {c['kind']}@{c['location']}: ln BF {c.get('log_bayes_factor')}")


if __name__ == "__main__":
    main()
