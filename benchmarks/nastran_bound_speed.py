"""Solve time of the mAEWing1 v3.3 deck with PBEAM fields bound, per parameter point: the
re-build through the deck (``nastran.lines.LineRebuild``: the bound cards converted again into a
fresh structure and assembler at every solve) against ``fe.line_update.LineUpdate`` (the bound
elements alone recomputed in the vectorised beam kernel and scattered at positions found once).

The deck is ``../shared/data/gvt_maewing1/fem/v3.3_hati`` copied to a temporary folder with the
edits the pyNastran-based reader needs (PARAM POST/PRTMAXIM/GRDPNT/VREF removed, NU 0.3 written
into MAT1 901-906 whose G is given, the CBUSH hinge grids' x moved from -0.01 to 0.01 so that
GA, GB coincide).  The structure's connectivity check is switched off while the rebuild path
converts the bound elements of both wings (two separate pieces, a known limitation of that
path).  Bound: ``PBEAM 1003 I1``, ``PBEAM 1004 I1``, ``PBEAM 1005 A``; the points are the deck's
values times 1.1, 0.9, 1.25.  Prints the median CPU time over ``--repeats`` solves of 20 modes
per point (and of the line update alone, and of the eigensolve alone at one point), the largest
relative difference between the two paths' frequencies, and the top of a profile of the new path.
``--before-only`` times the rebuild path alone, e.g. on a checkout from before
``fe.line_update`` existed (``PYTHONPATH=<that checkout>``).

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/nastran_bound_speed.py [--repeats 20]
        [--before-only] [--deck-dir DIR]
"""

import argparse
import cProfile
import os
import pstats
import re
import shutil
import tempfile
import time
from dataclasses import replace
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

import bayesupdate.fe.structure as fe_structure  # noqa: E402
from bayesupdate.fe.general_beam import end_frames  # noqa: E402
from bayesupdate.nastran import load_nastran_model  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
#: the shared data beside the checkout (a worktree one level deeper finds it too)
DECKS = [up / "shared/data/gvt_maewing1/fem/v3.3_hati" for up in (ROOT.parent, ROOT.parents[1])]
MAIN = "sol103_mAEWing1_Hati_FEMv3p3.bdf"
BINDS = {"i1_1003": "PBEAM 1003 I1", "i1_1004": "PBEAM 1004 I1", "a_1005": "PBEAM 1005 A"}
#: PBEAM field -> ``GeneralBeams`` field (``nastran.cards``: I1 is about element z)
FIELD = {"A": "area", "I1": "iz", "I2": "iy", "J": "torsion"}
N_MODES = 20


def edited_copy(source: Path, folder: Path) -> Path:
    """The v3.3 deck of ``source`` in ``folder`` with the reader's refusals edited out (module
    docstring)."""
    for f in source.iterdir():
        shutil.copy(f, folder / f.name)
    main = folder / MAIN
    text = main.read_text()
    text = re.sub(r"^PARAM(\s+|,)(POST|PRTMAXIM|GRDPNT|VREF).*\n", "", text, flags=re.M | re.I)
    main.write_text(text)
    mat = folder / "MAT1_mAEWing1.dat"
    lines = [
        ln[:32] + ".3      " + ln[40:] if ln.startswith("MAT1     90") and not ln[32:40].strip()
        else ln
        for ln in mat.read_text().splitlines()
    ]  # fmt: skip
    mat.write_text("\n".join(lines) + "\n")
    spring = folder / "Spring_mAEWing1.dat"
    spring.write_text(re.sub(r"^(GRID    [12]0[12]0[1-4]   [12]0[12]     )-0.01",
                             r"\g<1>0.01 ", spring.read_text(), flags=re.M))  # fmt: skip
    return main


class FieldUpdate:
    """What the Nastran side calls per solve: the bound PBEAM fields written into the
    ``GeneralBeams`` of their parts, the lumped end masses (COUPMASS < 1: half of
    (rho A + NSM) L and of the CBEAM twist inertia rho (I1 + I2) L at each end) recomputed,
    and ``LineUpdate.delta``.  Stands in for ``LineRebuild`` (same ``delta(values)``)."""

    def __init__(self, fe):
        s, g = fe.structure, fe.general
        self.fe = fe
        gb = s.general_beams
        self.parts = {n: s.part_index(f"PBEAM {b.field.ids[0]}") for n, b in fe.bindings.items()}
        beams = np.flatnonzero(np.isin(gb.part, list(self.parts.values())))
        masses = np.flatnonzero(np.isin(s.mass_part, list(self.parts.values())))
        from bayesupdate.fe.line_update import LineUpdate

        self.update = LineUpdate(g, beams=beams, masses=masses)
        b = self.update.beams
        R, self.length = end_frames(s.nodes, b)
        self.axis = R[:, 0]
        # the lumped end masses of each beam: two per element in the order they were added
        self.mass_beam = np.concatenate(
            [np.repeat(np.flatnonzero(b.part == p), 2) for p in np.unique(b.part)]
        )
        order = np.concatenate(
            [np.flatnonzero(s.mass_part[masses] == p) for p in np.unique(b.part)]
        )
        self.mass_slot = order

    def delta(self, values):
        b = self.update.beams
        fields = {k: getattr(b, k).copy() for k in ("area", "iy", "iz", "torsion")}
        for name, binding in self.fe.bindings.items():
            on = b.part == self.parts[name]
            fields[FIELD[binding.field.field]][on] = values[name] * binding.factor
        beams = replace(b, **fields)
        L = self.length
        m_end = 0.5 * (beams.rho * beams.area + beams.nsm) * L
        twist = 0.5 * beams.rho * (beams.iy + beams.iz) * L
        mass, inertia = np.zeros(self.mass_beam.size), np.zeros((self.mass_beam.size, 3, 3))
        e = self.mass_beam
        mass[self.mass_slot] = m_end[e]
        inertia[self.mass_slot] = twist[e, None, None] * np.einsum(
            "ei,ej->eij", self.axis[e], self.axis[e]
        )
        from bayesupdate.fe.line_update import PointMassValues

        return self.update.delta(beams=beams, masses=PointMassValues(mass, inertia))


def median_ms(fn, repeats: int) -> float:
    """Median CPU (process) time of ``fn`` [ms]: on a machine shared with other jobs the wall
    time also counts the waits for a core, the CPU time does not."""
    times = []
    for _ in range(repeats):
        t = time.process_time()
        fn()
        times.append(time.process_time() - t)
    return 1e3 * float(np.median(times))


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument(
        "--before-only",
        action="store_true",
        help="only the rebuild path (runs on a checkout without fe.line_update)",
    )
    parser.add_argument(
        "--deck-dir", type=Path, default=next((d for d in DECKS if d.is_dir()), DECKS[0])
    )
    args = parser.parse_args()
    fe_structure.check_connected = lambda structure: None  # the rebuild's two wings (docstring)
    with tempfile.TemporaryDirectory() as tmp:
        deck = edited_copy(args.deck_dir, Path(tmp))
        fe = load_nastran_model(str(deck), {n: {"binds": b} for n, b in BINDS.items()})
    print(f"deck: {fe.structure.n_dof} DOFs, bound {BINDS}")
    points = [{k: v * f for k, v in fe.default_parameters().items()} for f in (1.1, 0.9, 1.25)]
    g = fe.general
    rebuild = g.lines
    before = [fe.solve(p, N_MODES).frequencies_hz for p in points]
    t_before = [median_ms(lambda p=p: fe.solve(p, N_MODES), args.repeats) for p in points]
    t_rebuild = median_ms(lambda: rebuild.delta(fe.full_parameters(points[0])), args.repeats)
    K, M, _ = g.assemble(fe.element_properties(points[0]))
    t_eigen = median_ms(lambda: g.solve(K, M, N_MODES), args.repeats)
    print(f"solve per point, median of {args.repeats} CPU [ms]: rebuild {np.round(t_before, 1)}")
    print(f"line elements alone CPU [ms]: rebuild {t_rebuild:.1f}")
    print(f"eigensolve alone (GeneralAssembler.solve), CPU [ms]: {t_eigen:.1f}")
    if args.before_only:
        return
    from bayesupdate.fe.line_update import LineUpdate  # noqa: F401 - the new path

    g.lines = FieldUpdate(fe)
    after = [fe.solve(p, N_MODES).frequencies_hz for p in points]
    t_after = [median_ms(lambda p=p: fe.solve(p, N_MODES), args.repeats) for p in points]
    t_update = median_ms(lambda: g.lines.delta(fe.full_parameters(points[0])), args.repeats)
    miss = max(float(np.max(np.abs(a / b - 1))) for a, b in zip(after, before, strict=True))
    print(f"frequencies (20 modes) LineUpdate vs rebuild: largest relative difference {miss:.1e}")
    print(f"solve per point, median of {args.repeats} CPU [ms]: LineUpdate {np.round(t_after, 1)}")
    print(f"line elements alone CPU [ms]: LineUpdate {t_update:.2f}")
    prof = cProfile.Profile()
    prof.runcall(lambda: [fe.solve(points[0], N_MODES) for _ in range(args.repeats)])
    pstats.Stats(prof).sort_stats("tottime").print_stats(10)


if __name__ == "__main__":
    main()
