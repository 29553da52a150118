"""Likelihood evaluation of the exhaust per walker, batch of 32: full FE solves vs the certified
reduced basis (bayesupdate.fe.reduced), and the reduced model's frequency error.

BLAS is pinned to one thread (set below, before numpy is imported): on this 2-core machine the
small dense and banded kernels only lose time to threading, and a sampler runs one process per core.

Run:  .venv/bin/python benchmarks/likelihood_speed.py [--repeats 30] [--validation 64]

Prints the median wall time per walker of the likelihood-relevant work (frequencies of 32 points
plus the Gaussian log-likelihood of seed Table 2 on relative errors) for:
  full     FEModel.predict_frequencies_batch (one shift-invert Krylov solve per point)
  rom      ReducedFEModel over the whole prior box (the default bounds)
  rom-post ReducedFEModel.localized on a box around the seed's Table 3 optimum (+-25 %), the box a
           posterior pilot would give; points outside it go to the whole-box model
and the largest relative frequency error against full solves on fresh uniform points of each box.
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from bayesupdate.fe.reduced import reduced_model_for  # noqa: E402
from bayesupdate.models import get_model  # noqa: E402
from bayesupdate.paper import TABLE2_EMA_HZ, TABLE3_OPTIMUM_SI  # noqa: E402

BATCH = 32
SIGMA = 0.05


def log_likelihood(freqs: np.ndarray) -> np.ndarray:
    """Gaussian on relative errors of the 12 Table 2 frequencies, sigma fixed (issue 4 item 5)."""
    e = (freqs - TABLE2_EMA_HZ) / TABLE2_EMA_HZ
    ll = -0.5 * np.sum(e * e, axis=1) / SIGMA**2
    return np.where(np.isfinite(ll), ll, -np.inf)


def per_walker_us(model, theta, names, repeats) -> tuple[float, float]:
    """Median wall and CPU (process) time per walker [us]; on a machine shared with other jobs
    the CPU time is the steadier of the two."""
    wall, cpu = [], []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        log_likelihood(model.predict_frequencies_batch(theta, names, 12))
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    n = theta.shape[0]
    return float(np.median(wall)) / n * 1e6, float(np.median(cpu)) / n * 1e6


def uniform(rng, low, high, n):
    return low + rng.random((n, low.size)) * (high - low)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=30)
    ap.add_argument("--validation", type=int, default=64)
    args = ap.parse_args()
    fe = get_model("exhaust")
    names = fe.parameter_names
    rng = np.random.default_rng(12345)

    t0 = time.perf_counter()
    rom = reduced_model_for(fe, tol=1e-4, seed=0)
    build_s = time.perf_counter() - t0
    opt = np.array([TABLE3_OPTIMUM_SI[n] for n in names])
    box = np.array([0.75 * opt, 1.25 * opt])
    t0 = time.perf_counter()
    local = rom.localized(box, names, widen=0.0)
    local_s = time.perf_counter() - t0
    print(f"whole box: {rom}  [built in {build_s:.1f} s]")
    print(f"posterior box: {local}  [built in {local_s:.1f} s]")

    theta_all = uniform(rng, rom.low, rom.high, BATCH)
    theta_post = uniform(rng, local.low, local.high, BATCH)
    full_us = per_walker_us(fe, theta_all, names, max(3, args.repeats // 10))
    rom_us = per_walker_us(rom, theta_all, names, args.repeats)
    local_us = per_walker_us(local, theta_post, names, args.repeats)

    errors = {}
    for label, model in (("rom", rom), ("rom-post", local)):
        theta = uniform(rng, model.low, model.high, args.validation)
        f_full = fe.predict_frequencies_batch(theta, names, 12)
        f_red = model.predict_frequencies_batch(theta, names, 12)
        rel = f_red / f_full - 1
        errors[label] = (float(np.nanmax(np.abs(rel))), float(np.nanmin(rel)))

    print(f"\nlikelihood per walker, batch of {BATCH}, median, BLAS threads = 1")
    print(
        f"{'model':<10}{'size':>6}{'wall us':>10}{'cpu us':>10}{'speed-up':>10}"
        f"{'max rel err':>14}{'min':>11}"
    )
    print(
        f"{'full':<10}{fe.structure.n_dof:>6}{full_us[0]:>10.0f}{full_us[1]:>10.0f}{1:>10.0f}"
        f"{'-':>14}{'-':>11}"
    )
    for label, model, us in (("rom", rom, rom_us), ("rom-post", local, local_us)):
        e_max, e_min = errors[label]
        print(
            f"{label:<10}{model.size:>6}{us[0]:>10.1f}{us[1]:>10.1f}{full_us[1] / us[1]:>10.0f}"
            f"{e_max:>14.2e}{e_min:>11.1e}"
        )
    print("(us per walker, wall and CPU; speed-up on CPU time)")
    print("(size: DOFs for full, basis vectors incl. 6 rigid for the reduced models; min rel err")
    print(" >= 0 up to round-off is the Rayleigh-Ritz upper bound; errors on fresh uniform points)")


if __name__ == "__main__":
    main()
