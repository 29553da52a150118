"""One snapshot of the shell exhaust's basis build (its modes and their design-sensitivity
vectors, ``fe.reduced.basis``), two ways side by side, at the same seeded points of the
``calibrate --data paper:ema`` box:

    separate   ``FEModel.solve`` then ``static_corrections`` with its own assembly and
               factorization of K - sigma M (the build before this change)
    shared     ``basis._snapshot``: one assembly and one factorization for both (the build now)

Printed: median wall and CPU seconds per snapshot over ``--repeats`` points, and the largest
difference of the frequencies and vectors between the two (round-off: the factorized matrix is
T^T K T - sigma T^T M T against T^T (K - sigma M) T).

    PYTHONPATH=. python benchmarks/snapshot_solve.py --repeats 3
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
from scipy.stats import qmc  # noqa: E402

from bayesupdate.fe.reduced import ReducedFEModel  # noqa: E402
from bayesupdate.fe.reduced.affine import decompose  # noqa: E402
from bayesupdate.fe.reduced.basis import _snapshot  # noqa: E402
from bayesupdate.fe.reduced.sensitivity import static_corrections  # noqa: E402
from bayesupdate.models import get_model  # noqa: E402

#: modes per snapshot: the 14 model modes of ``calibrate --data paper:ema`` + the 4 extra modes
#: a snapshot keeps (``ReducedSettings.extra_modes``); the box is the model's default bounds
N_MODES = 18


def separate(fe, dec, params):
    sol = fe.solve(params, N_MODES).modes
    extra = static_corrections(fe, dec, params, sol.eigenvalues, sol.shapes)
    return sol.frequencies_hz, np.concatenate([sol.shapes, extra], axis=1)


def timed(fn, *args):
    t, c = time.perf_counter(), time.process_time()
    out = fn(*args)
    return out, time.perf_counter() - t, time.process_time() - c


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3, help="snapshot points (3)")
    ap.add_argument("--mesh-density", type=int, default=32)
    args = ap.parse_args()
    fe = get_model("exhaust_shell", mesh_density=args.mesh_density)
    model = ReducedFEModel(fe)
    dec = decompose(fe, model.bounds, 1e-9)
    points = model.scale(qmc.Sobol(len(fe.parameter_names), seed=0).random(args.repeats))
    print(f"exhaust_shell density {args.mesh_density}: {fe.structure.n_dof} DOFs; "
          f"load before {os.getloadavg()[0]:.2f}")  # fmt: skip
    rows = {"separate": [], "shared": []}
    gap_f = gap_x = 0.0
    for row in points:
        params = model.mapping(row)
        (fa, xa), wa, ca = timed(separate, fe, dec, params)
        (fb, xb), wb, cb = timed(_snapshot, fe, dec, params, N_MODES)
        rows["separate"].append((wa, ca))
        rows["shared"].append((wb, cb))
        gap_f = max(gap_f, float(np.max(np.abs(fb / fa - 1))))
        gap_x = max(gap_x, float(np.max(np.abs(xb - xa)) / np.abs(xa).max()))
    for name, r in rows.items():
        w, c = np.median(np.array(r), axis=0)
        print(f"{name:9s} per snapshot: wall {w:6.2f} s  cpu {c:6.2f} s  ({len(r)} points)")
    print(f"largest difference: frequencies {gap_f:.1e} (relative), vectors {gap_x:.1e} "
          "(of the largest entry)")  # fmt: skip


if __name__ == "__main__":
    main()
