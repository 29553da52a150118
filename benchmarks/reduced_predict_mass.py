"""One reduced ``predict`` of the shell exhaust with the mass from per-term masses
(``fe.reduced.mass``, now) against the mass from the assembled M (``FEModel.total_mass``,
before), on one small reduced model; prints the medians and the largest mass difference.

BLAS is pinned to one thread (set below, before numpy is imported).

Run (about 30 s at density 16, 2-3 min at 32 on the shared machine):
  .venv/bin/python benchmarks/reduced_predict_mass.py --mesh-density 16

The reduced model is built loosely (tol 0.05, 6 snapshots) to be quick: the mass's cost does not
depend on the basis, ``predict``'s eigen-solve and shape expansion do (a little).
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from bayesupdate.fe.reduced import ReducedFEModel, ReducedSettings  # noqa: E402
from bayesupdate.fe.reduced import mass as reduced_mass  # noqa: E402
from bayesupdate.models import get_model  # noqa: E402


def _timed(rom, points, label: str) -> np.ndarray:
    """Median wall and CPU time of ``rom.predict`` over ``points``; the masses it returned."""
    wall, cpu, masses = [], [], []
    rom.predict(points[0])  # warm: the per-term masses are computed once, here
    for p in points:
        w, c = time.perf_counter(), time.process_time()
        masses.append(rom.predict(p).mass_kg)
        wall.append(time.perf_counter() - w)
        cpu.append(time.process_time() - c)
    print(f"{label}: predict median wall {1e3 * np.median(wall):.1f} ms, "
          f"CPU {1e3 * np.median(cpu):.1f} ms", flush=True)  # fmt: skip
    return np.array(masses)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh-density", type=int, default=32)
    ap.add_argument("--points", type=int, default=7, help="random points timed (7)")
    args = ap.parse_args()
    fe = get_model("exhaust_shell", mesh_density=args.mesh_density)
    settings = ReducedSettings(n_modes=12, tol=0.05, seed=0, n_snapshots=6, n_validation=3)
    t0 = time.perf_counter()
    rom = ReducedFEModel(fe, settings=settings).build()
    print(f"density {args.mesh_density}: {fe.structure.n_dof} DOFs, basis size {rom.size}, "
          f"built in {time.perf_counter() - t0:.0f} s", flush=True)  # fmt: skip
    rng = np.random.default_rng(0)
    box = fe.default_bounds()
    names = fe.parameter_names
    points = [{k: float(rng.uniform(*box[k])) for k in names} for _ in range(args.points)]
    t0 = time.perf_counter()
    reduced_mass.total_mass(fe, points[0])
    print(f"per-term masses computed once: {time.perf_counter() - t0:.3f} s")
    after = _timed(rom, points, "after (per-term masses)")
    per_term = reduced_mass.total_mass
    reduced_mass.total_mass = lambda model, p: model.total_mass(p)[0]  # the previous path
    try:
        before = _timed(rom, points, "before (assembled K, M)")
    finally:
        reduced_mass.total_mass = per_term
    print(f"largest relative mass difference {np.max(np.abs(after - before) / before):.2e}")


if __name__ == "__main__":
    main()
