"""Discovery on the shell exhaust, the user's round: a virtual test of a "true" ``exhaust_shell``
with a hidden connection flexibility (or none), ``bayesupdate identify`` on its FRFs, then
``bayesupdate discover`` on a study file whose model is ``exhaust_shell``.

    PYTHONPATH=. OPENBLAS_NUM_THREADS=1 python studies/exhaust_shell_discovery.py \\
        --out shell_disc \\
        --effect connection_flexibility@cold_pipe/main_muffler:k_rot=1e4 --seed 7
    PYTHONPATH=. OPENBLAS_NUM_THREADS=1 python studies/exhaust_shell_discovery.py \\
        --out shell_null --seed 24

The virtual test is made at the same mesh density as the model discovery runs on (the
``simulate`` command takes no model options, so the test is made with
``pipelines.simulate.simulate_test``, as the command does, and written as UFF); identification
and discovery are the CLI with default settings.  Prints the verdict, the named effect, the
best candidates, the wall and CPU time of each step and the peak memory, and how discovery's
reduced models did (``discovery.reduced_candidates``: the design basis, the candidates on
enriched bases, the largest error of a compared fit against its full solve); writes the files
into ``--out``.  ``--count-solves`` also counts the full solves (``FEModel.solve``) by the
discovery step on the call stack and by candidate (a ``boundary_spring`` or not), with their CPU.
"""

import argparse
import contextlib
import io
import json
import resource
import time
import traceback
from collections import Counter
from pathlib import Path

from bayesupdate.cli import main as cli
from bayesupdate.discovery.effects import parse_effect_spec
from bayesupdate.ema.uff_io import write_uff58
from bayesupdate.fe.model import FEModel
from bayesupdate.models import get_model
from bayesupdate.pipelines.simulate import VirtualTestSettings, simulate_test


def _cli(argv: list) -> str:
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = cli([str(a) for a in argv])
    if code != 0:
        raise SystemExit(f"bayesupdate {argv[0]} failed ({code}): {buf.getvalue()[-2000:]}")
    return buf.getvalue()


#: discovery steps (``discovery.workflow`` functions) a full solve is attributed to, innermost last
STEPS = ("_prepare", "_baseline_fit", "_localize", "energy_excess", "_quick_refits")
STEPS += ("_full_refits", "_verdict")


def count_solves() -> tuple[Counter, Counter]:
    """Wrap ``FEModel.solve`` to count calls and their CPU [s] by (step, candidate kind)."""
    counts, cpu = Counter(), Counter()
    solve = FEModel.solve

    def counted(self, *args, **kwargs):
        names = [frame.name for frame in traceback.extract_stack()]
        step = next((s for s in STEPS[::-1] if s in names), "other")
        key = (step, "boundary_spring" if "boundary_spring" in self.name else "other")
        c = time.process_time()
        out = solve(self, *args, **kwargs)
        cpu[key] += time.process_time() - c
        counts[key] += 1
        return out

    FEModel.solve = counted
    return counts, cpu


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="folder for the test, modes and result")
    ap.add_argument("--effect", action="append", default=[], help="hidden effect spec(s)")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--noise", type=float, default=0.01)
    ap.add_argument("--mesh-density", type=int, default=16)
    ap.add_argument("--count-solves", action="store_true", help="count full solves by step")
    args = ap.parse_args()
    counts, cpu = count_solves() if args.count_solves else (None, None)
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
    c2 = time.process_time()
    found = _cli(["discover", study, "--out", out / "discovery.h5", "--force", "--json"])
    t3, c3 = time.perf_counter(), time.process_time()
    (out / "discovery.json").write_text(found)
    doc = json.loads(found)
    print(f"discover: {t3 - t2:.0f} s wall, {c3 - c2:.0f} s CPU; verdict {doc['verdict']}")
    print(f"named {doc['named_effect']}")
    print(f"reduced models: {doc.get('reduced')}")
    print(f"flagged modes {doc['flagged_modes']}; gap {doc['gap_before']} -> {doc['gap_after']}")
    for c in doc["candidates"][:6]:
        print(f"  {c['kind']}@{c['location']}: ln BF {c.get('log_bayes_factor')}")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20  # KiB -> GiB
    print(f"whole script: {time.process_time():.0f} s CPU, peak RSS {peak:.2f} GiB")
    if counts is not None:
        for key in sorted(counts):
            print(f"  full solves in {key[0]} ({key[1]}): {counts[key]}, {cpu[key]:.1f} s CPU")


if __name__ == "__main__":
    main()
