"""``correlate`` and ``sensitivity`` on a deck nobody here wrote: the NX FEMAP exhaust
(``../shared/data/nastran/femap_exhaust/exhaust.bdf``, 4,466 shells, inch-lbf-s), through the
commands a user types (``bayesupdate.cli.main``).

1. A study file maps the 20 test points of the worked example (``tests/
   test_nastran_femap_roundtrip.py``: the three hanger GRIDs and 17 shell GRIDs) in
   ``[model.test_points]`` and binds the two thicknesses it calibrates (PSHELL 3 and 9 T).
2. The virtual test: the deck's own first ``N_MODES`` modes at its values, V (z) and H (y) at the
   20 points, mass-normalized and noise-free, written as modal data (``ema.modal_h5``).
3. ``bayesupdate correlate study.toml --json``: the MAC diagonal of the unchanged deck against
   its own virtual test (1 to round-off), the pairs, the cross-orthogonality through the SEREP
   TAM (the identity).
4. ``bayesupdate sensitivity study.toml --candidates "PSHELL * T" "MAT1 * RHO" "MAT1 2 E"
   --json``: the four PSHELL thicknesses, the two MAT1 densities and the modulus of MAT1 2; which
   directions the 10 modes see, which candidates are confounded, and the suggested set.  E and
   RHO of MAT1 2 are not one direction here: the deck has a second material (MAT1 3, PSHELL 3
   and 5) and hanger springs, so scaling E and RHO of MAT1 2 together changes how stiffness and
   mass are shared; only E / RHO of everything moves nothing.
5. The same with the modulus of both materials as one candidate ("MAT1 2,3 E", their E is the
   same): E, RHO 2 and RHO 3 scaled together change only the hanger springs' share, a direction
   the modes hardly see.

Prints one JSON object.  About a minute (two reads of the deck, two modal solves of 26,832 DOFs;
the sensitivities are eigenvalue derivatives from assembled matrices).

    PYTHONPATH=. python studies/correlate_femap.py [--out DIR]
"""

import argparse
import contextlib
import io
import json
import tempfile
from pathlib import Path

import numpy as np

#: the shared data folder beside the checkout (a worktree sits one level deeper)
SHARED = next(
    (p / "shared" for p in Path(__file__).resolve().parents if (p / "shared" / "data").is_dir()),
    Path(__file__).resolve().parents[2] / "shared",
)
DECK = SHARED / "data/nastran/femap_exhaust/exhaust.bdf"
#: the worked example's test points: the hangers, then 17 shell GRIDs by farthest-point sampling
GRIDS = (15661, 17406, 20494, 20505, 20718, 16509, 20652, 17368, 21321, 21706, 22177, 16225,
         15676, 15546, 15414, 15611, 15492, 16745, 15944, 17232)  # fmt: skip
N_MODES = 10
CANDIDATES = ("PSHELL * T", "MAT1 * RHO", "MAT1 2 E")
#: the modulus of both materials as one candidate
CANDIDATES_ALL_E = ("PSHELL * T", "MAT1 * RHO", "MAT1 2,3 E")


def write_study(folder: Path) -> Path:
    """The study file (deck, test points, the two calibrated thicknesses, the virtual test)."""
    rows = "\n".join(f'"{k}" = {g}' for k, g in enumerate(GRIDS, start=1))
    study = folder / "study.toml"
    study.write_text(
        f'[model]\nsource = "{DECK}"\n[model.test_points]\n{rows}\n'
        f'[data]\nsource = "{folder / "virtual.h5"}"\n'
        '[parameters.t_3]\nbinds = "PSHELL 3 T"\n[parameters.t_9]\nbinds = "PSHELL 9 T"\n'
    )
    return study


def write_virtual_test(folder: Path) -> None:
    """The deck's own modes at its values, at the 20 points (V, H), as ``virtual.h5``."""
    from bayesupdate.ema.modal_h5 import write_modal_h5
    from bayesupdate.modal_data import ModalData
    from bayesupdate.nastran import load_nastran_model

    labels = tuple(f"{k}{d}" for k in range(1, len(GRIDS) + 1) for d in "VH")
    points = {str(k): g for k, g in enumerate(GRIDS, start=1)}
    model = load_nastran_model(str(DECK), None, labels, points)
    p = model.predict(None, N_MODES)
    data = ModalData(p.frequencies_hz, shapes=p.shapes, dof_labels=labels, source="virtual",
                     extra={"mass_normalized": np.ones(N_MODES, bool)})  # fmt: skip
    write_modal_h5(folder / "virtual.h5", data)


def _cli_json(argv) -> dict:
    from bayesupdate.cli import main

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(argv)
    if code != 0:
        raise SystemExit(f"bayesupdate {' '.join(argv)} exited {code}")
    return json.loads(out.getvalue().strip().splitlines()[-1])


def run(folder: Path, all_e: bool = True) -> dict:
    """The study's numbers (module docstring); ``all_e`` False leaves out step 5 (a third read
    and solve of the deck, which ``tests/test_correlate_femap.py`` does not check)."""
    study = write_study(folder)
    write_virtual_test(folder)
    corr = _cli_json(["correlate", str(study), "--json", "--out", str(folder / "corr.h5"),
                      "--report", str(folder / "corr"), "--force"])  # fmt: skip
    sens = _cli_json(["sensitivity", str(study), "--candidates", *CANDIDATES, "--json",
                      "--report", str(folder / "sens"), "--force"])  # fmt: skip
    all_e = (
        _cli_json(["sensitivity", str(study), "--candidates", *CANDIDATES_ALL_E, "--json"])
        if all_e
        else None
    )
    xor = np.asarray(corr["cross_orthogonality"])
    return {
        "frequencies_hz": [m["model_hz"] for m in corr["modes"]],
        "mac_diagonal": [m["mac"] for m in corr["modes"]],
        "pairs": [[m["test"], m["model"]] for m in corr["modes"]],
        "points": {p["dof"]: p["model_node"] for p in corr["points"]},
        "cross_orthogonality_diagonal_min": float(np.min(np.abs(np.diag(xor)))),
        "cross_orthogonality_off_max": float(np.max(np.abs(xor - np.diag(np.diag(xor))))),
        "candidates": [c["name"] for c in sens["candidates"]],
        "singular_values": sens["singular_values"],
        "rank": sens["rank"],
        "unseen": sens["unseen"],
        "groups": sens["groups"],
        "suggested": sens["suggested"],
        "sensitivity": sens["sensitivity"],
        "cosine_e2_rho2": _cosine(sens, "MAT1 2 E", "MAT1 2 RHO"),
        "all_e": _kept(all_e, ("singular_values", "rank", "unseen", "groups", "suggested")),
    }


def _kept(out: dict | None, keys: tuple[str, ...]) -> dict | None:
    """The given keys of a command's JSON (None when the command was not run)."""
    return None if out is None else {key: out[key] for key in keys}


def _cosine(out: dict, a: str, b: str) -> float:
    """Cosine between two candidates' sensitivity columns (1 or -1: one direction)."""
    names = [c["name"] for c in out["candidates"]]
    s = np.asarray(out["sensitivity"])
    x, y = s[:, names.index(a)], s[:, names.index(b)]
    return float(x @ y / np.linalg.norm(x) / np.linalg.norm(y))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", help="folder for the study, the test and the reports")
    args = parser.parse_args()
    if args.out:
        Path(args.out).mkdir(parents=True, exist_ok=True)
        print(json.dumps(run(Path(args.out))))
        return
    with tempfile.TemporaryDirectory() as tmp:
        print(json.dumps(run(Path(tmp))))


if __name__ == "__main__":
    main()
