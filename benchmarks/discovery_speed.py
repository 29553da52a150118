"""Speed of one whole discovery run on the exhaust (target <= 2 min with >= 5 kinds x >= 6
locations).  Data: the true first 12 frequencies of the exhaust at the seed's Table 3 design with
a hidden joint flexibility and 0.3 % noise, and its shapes at the 40 sensor DOFs with
``--shape-noise`` (default 3 % of each shape's RMS amplitude; 0: frequencies only).  Every effect
kind of the library at every admissible location is scanned (58 candidates: 20 points x 2 kinds,
6 joints, 4 bends, 8 parts); the default settings refit the promising ones.  Prints wall times
per run, their median, and the split into baseline / localization / refits / LOO.

    OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/discovery_speed.py [--repeats 3]
        [--shape-noise 0.03]
"""

import argparse
import os
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from bayesupdate.discovery.effects import EFFECT_KINDS, effect_locations  # noqa: E402
from bayesupdate.discovery.results_io import extend_with_specs  # noqa: E402
from bayesupdate.discovery.workflow import discover  # noqa: E402
from bayesupdate.modal_data import noisy_modes  # noqa: E402
from bayesupdate.models import get_model  # noqa: E402
from bayesupdate.models.exhaust_paper import TABLE3_OPTIMUM_SI  # noqa: E402

HIDDEN = "joint_flexibility@cold_pipe/main_muffler:k_rot=1e3"
NOISE = 0.003


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--shape-noise", type=float, default=0.03)
    args = parser.parse_args()
    model = get_model("exhaust")
    counts = {k: len(effect_locations(model, k)) for k in EFFECT_KINDS}
    print(f"library: {counts} -> {sum(counts.values())} candidates")
    truth = extend_with_specs(model, [HIDDEN]).predict(TABLE3_OPTIMUM_SI, 12)
    print(
        f"data: 12 frequencies (noise {NOISE})"
        + (
            f" + shapes at {len(truth.dof_labels)} DOFs (noise {args.shape_noise})"
            if args.shape_noise > 0
            else ""
        )
    )
    walls, cpus = [], []
    for k in range(args.repeats):
        data = noisy_modes(truth, NOISE, args.shape_noise, np.random.default_rng(k), "benchmark")
        t0, c0 = time.perf_counter(), time.process_time()
        result = discover(model, data)
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
        split = ", ".join(f"{key} {value:.1f}" for key, value in result.timings.items())
        print(
            f"run {k}: {walls[-1]:.1f} s wall, {cpus[-1]:.1f} s CPU  verdict {result.verdict}, "
            f"named "
            f"{result.named.label if result.named else None}; scanned "
            f"{len(result.localization.scores)}, refitted {len(result.fits)}; {split}"
        )
    print(
        f"median wall {np.median(walls):.1f} s (CPU {np.median(cpus):.1f} s), "
        f"min {min(walls):.1f} s, max {max(walls):.1f} s"
    )


if __name__ == "__main__":
    main()
