"""Worked example (issue 19): calibrate a Nastran deck nobody here wrote and write it back.

The NX FEMAP exhaust (``../shared/data/nastran/femap_exhaust/exhaust.bdf``, 4,466 shells, inch-
lbf-s units): two PSHELL thicknesses are perturbed (PSHELL 3 +8 %, PSHELL 9 -6 %), a roving-
hammer test is simulated at the three hanger GRIDs and 17 shell GRIDs spread over the system
(``pipelines.simulate``, 1 % noise), identified (``bayesupdate identify``), calibrated back from
the deck's values (``bayesupdate calibrate study.toml --write-bdf``), and the written deck is read
again: its frequencies must be the calibrated ones.  Prints one JSON object; slow (full sparse
solves of 26,832 DOFs, several minutes; two starts without polish).

    PYTHONPATH=. python studies/nastran_roundtrip.py [--out DIR]
"""

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np

DECK = Path(__file__).resolve().parents[2] / "shared" / "data" / "nastran" / "femap_exhaust"
DECK = DECK / "exhaust.bdf"
HANGERS = (15661, 17406, 20494)
PARAMETERS = {
    "t_3": {"binds": "PSHELL 3 T", "bounds": [0.04, 0.08]},
    "t_9": {"binds": "PSHELL 9 T", "bounds": [0.04, 0.09]},
}
TRUTH = {"t_3": 0.0551181 * 1.08, "t_9": 0.0629921 * 0.94}


def spread_points(model, n: int) -> list[int]:
    """``n`` shell GRID ids by farthest-point sampling from the first hanger (deterministic)."""
    grid_ids = np.asarray(model.structure.metadata["nastran"]["grid_ids"])
    sh = model.structure.shells
    nodes = np.unique(np.concatenate([sh.quads.ravel(), sh.trias.ravel()]))
    xyz = model.structure.nodes[nodes]
    chosen = [int(np.flatnonzero(grid_ids[nodes] == HANGERS[0])[0])]
    dist = np.linalg.norm(xyz - xyz[chosen[0]], axis=1)
    while len(chosen) < n:
        chosen.append(int(np.argmax(dist)))
        dist = np.minimum(dist, np.linalg.norm(xyz - xyz[chosen[-1]], axis=1))
    return [int(g) for g in grid_ids[nodes[chosen]]]


def main(argv=None) -> dict:
    from bayesupdate.cli import main as cli
    from bayesupdate.ema.uff_io import write_uff58
    from bayesupdate.nastran import load_nastran_model
    from bayesupdate.pipelines.simulate import VirtualTestSettings, simulate_test

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", help="folder for the test, the study and the updated deck")
    args = parser.parse_args(argv)
    out = Path(args.out or tempfile.mkdtemp(prefix="nastran_roundtrip_"))
    out.mkdir(parents=True, exist_ok=True)

    plain = load_nastran_model(str(DECK), PARAMETERS)
    grids = list(HANGERS) + [g for g in spread_points(plain, 20) if g not in HANGERS][:17]
    table = {str(k): g for k, g in enumerate(grids, start=1)}
    labels = [f"{k}{d}" for d in "VH" for k in range(1, 21)]
    model = load_nastran_model(str(DECK), PARAMETERS, labels, table)
    test = simulate_test(model, VirtualTestSettings(TRUTH, noise=0.01, seed=0, n_modes=14))
    if not (out / "modes.h5").is_file():  # seeded: a second run reuses the identified test
        write_uff58(out / "test.uff", test.frfs)
        cli(["identify", str(out / "test.uff"), "--out", str(out / "modes.h5"), "--force"])

    rows = "\n".join(f'"{k}" = {g}' for k, g in table.items())
    params = "".join(
        f'[parameters.{n}]\nbinds = "{p["binds"]}"\nbounds = {p["bounds"]}\n'
        for n, p in PARAMETERS.items()
    )
    study = out / "study.toml"
    study.write_text(
        f'[model]\nsource = "{DECK}"\n[model.test_points]\n{rows}\n'
        f'[data]\nsource = "{out / "modes.h5"}"\n{params}'
        # each full solve takes seconds: two starts, no Nelder-Mead polish
        "[optimizer]\nstarts = 2\npolish = false\n"
    )
    updated = out / "updated.bdf"
    calibrated = _run_json(cli, ["calibrate", str(study), "--json", "--force",
                                 "--write-bdf", str(updated)])  # fmt: skip
    reread = load_nastran_model(str(updated)).solve(n_modes=10).frequencies_hz
    fitted = model.solve(calibrated["parameters"], n_modes=10).frequencies_hz
    result = {
        "truth": TRUTH,
        "deck": {n: float(v) for n, v in plain.default_parameters().items()},
        "calibrated": calibrated["parameters"],
        "error_pct": {n: 100 * (calibrated["parameters"][n] / TRUTH[n] - 1) for n in TRUTH},
        "true_hz": [round(float(f), 4) for f in test.frequencies_hz[:10]],
        "calibrated_hz": [round(float(f), 4) for f in fitted],
        "reread_max_rel_diff": float(np.max(np.abs(reread / fitted - 1))),
        "objective": calibrated["objective"],
        "out": str(out),
    }
    print(json.dumps(result))
    return result


def _run_json(cli, argv) -> dict:
    import contextlib
    import io

    buffer = io.StringIO()
    with contextlib.redirect_stdout(buffer):
        code = cli(argv)
    if code != 0:
        raise SystemExit(f"{' '.join(argv[:2])} failed (exit {code})")
    return json.loads(buffer.getvalue().strip().splitlines()[-1])


if __name__ == "__main__":
    main()
