"""Likelihood evaluation of the exhaust per walker, batch of 32: full FE solves vs the certified
reduced basis (bayesupdate.fe.reduced), and the reduced model's frequency error.

BLAS is pinned to one thread (set below, before numpy is imported): on this 2-core machine the
small dense and banded kernels only lose time to threading, and a sampler runs one process per core.

Run:  .venv/bin/python benchmarks/likelihood_speed.py [--repeats 30] [--validation 64]
      .venv/bin/python benchmarks/likelihood_speed.py --mass   # the screen's mass polynomial

Prints the median wall time per walker of the likelihood-relevant work (frequencies of 32 points
plus the Gaussian log-likelihood of seed Table 2 on relative errors) for:
  full     FEModel.predict_frequencies_batch (one shift-invert Krylov solve per point)
  rom      ReducedFEModel over the whole prior box (the default bounds)
  rom-post ReducedFEModel.localized on a box around the seed's Table 3 optimum (+-25 %), the box a
           posterior pilot would give; points outside it go to the whole-box model
and the largest relative frequency error against full solves on fresh uniform points of each box.
The reduced rows are timed three ways in the same run: the batched solve (``fe.batched_eigen``)
split over 2 threads (or ``BAYESUPDATE_SOLVER_THREADS`` if more), the same on one thread (the
default), and the independent per-point LAPACK dsygvd path
(``sygvd_elastic_eigenvalues`` in tests/reference_eigen.py, the tests' reference).
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from bayesupdate.fe.batched_eigen import THREADS_VARIABLE, solver_threads  # noqa: E402
from bayesupdate.fe.reduced import reduced_model_for  # noqa: E402
from bayesupdate.models import get_model  # noqa: E402
from bayesupdate.models.exhaust_paper import TABLE2_EMA_HZ, TABLE3_OPTIMUM_SI  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from reference_eigen import sygvd_elastic_eigenvalues  # noqa: E402

BATCH = 32
SIGMA = 0.05


def log_likelihood(freqs: np.ndarray) -> np.ndarray:
    """Gaussian on relative errors of the 12 Table 2 frequencies, sigma fixed."""
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


class SygvdPath:
    """The reduced model's frequencies through the per-point dsygvd reference path."""

    def __init__(self, rom):
        self.rom = rom

    def predict_frequencies_batch(self, theta, names, n_modes):
        K, M = self.rom.reduced_matrices(theta)  # theta holds all parameters in order
        lam = sygvd_elastic_eigenvalues(K, M, self.rom.n_rigid, n_modes)
        return np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)


def with_threads(n: int, fn, *args):
    previous = os.environ.get(THREADS_VARIABLE)
    os.environ[THREADS_VARIABLE] = str(n)
    try:
        return fn(*args)
    finally:
        if previous is None:
            del os.environ[THREADS_VARIABLE]
        else:
            os.environ[THREADS_VARIABLE] = previous


def uniform(rng, low, high, n):
    return low + rng.random((n, low.size)) * (high - low)


def mass_rows(repeats: int) -> None:
    """``--mass``: the posterior ``bayesupdate sample --model exhaust --data paper:ema`` samples
    (the weighed mass in the likelihood), its exact and screening log-posteriors on a batch of
    32 points: CPU ms per batch and of that the masses, with the model's per-point masses and
    with the screen's verified polynomial (``LogPosterior.with_fitted_mass``), the fit's cost
    and its largest relative error at its check points."""
    from bayesupdate.config import StudyConfig, with_overrides
    from bayesupdate.inference.likelihood import LogPosterior
    from bayesupdate.pipelines.study import prepare
    from bayesupdate.pipelines.surrogates import sampling_problem, screening_posterior

    study = with_overrides(StudyConfig(), model__source="exhaust", data__source="paper:ema")
    prepared = prepare(study)
    cfg = prepared.study.sampler
    problem, rom = sampling_problem(prepared.problem, None, cfg.reduced, cfg.reduced_tol)
    exact = LogPosterior(problem, prepared.likelihood)
    screen = screening_posterior(problem, rom, prepared.likelihood, cfg.reduced_tol)
    c0 = time.process_time()
    fitted = screen.with_fitted_mass()
    fit_s = time.process_time() - c0
    theta = uniform(np.random.default_rng(3), problem.lower, problem.upper, BATCH)
    full = np.hstack([theta, np.tile(exact.fixed_values, (BATCH, 1))])
    names = problem.names + exact.fixed_names

    def cpu_ms(fn) -> float:
        times = []
        for _ in range(repeats):
            c = time.process_time()
            fn()
            times.append(time.process_time() - c)
        return 1e3 * float(np.median(times))

    print(f"mass polynomial: fitted in {fit_s:.2f} s CPU, max relative error at its check "
          f"points {fitted._mass_fit.max_rel_error:.1e}")  # fmt: skip
    print(f"{'posterior, batch of 32':<34}{'call ms':>10}{'masses ms':>11}  (CPU, median)")
    for label, post in ((f"exact (size {rom.size})", exact),
                        ("screen, per-point masses", screen),
                        ("screen, mass polynomial", fitted)):  # fmt: skip
        call, mass = cpu_ms(lambda p=post: p(theta)), cpu_ms(lambda p=post: p._masses(full, names))
        print(f"{label:<34}{call:>10.2f}{mass:>11.2f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=30)
    ap.add_argument("--validation", type=int, default=64)
    ap.add_argument("--mass", action="store_true", help="the screen's mass polynomial only")
    args = ap.parse_args()
    if args.mass:
        mass_rows(args.repeats)
        return
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
    threads = max(2, solver_threads())
    rom_us = with_threads(threads, per_walker_us, rom, theta_all, names, args.repeats)
    rom1_us = with_threads(1, per_walker_us, rom, theta_all, names, args.repeats)
    sygvd_us = per_walker_us(SygvdPath(rom), theta_all, names, args.repeats)
    local_us = with_threads(threads, per_walker_us, local, theta_post, names, args.repeats)
    local1_us = with_threads(1, per_walker_us, local, theta_post, names, args.repeats)

    errors = {}
    for label, model in (("rom", rom), ("rom-post", local)):
        theta = uniform(rng, model.low, model.high, args.validation)
        f_full = fe.predict_frequencies_batch(theta, names, 12)
        f_red = model.predict_frequencies_batch(theta, names, 12)
        rel = f_red / f_full - 1
        errors[label] = (float(np.nanmax(np.abs(rel))), float(np.nanmin(rel)))

    print(
        f"\nlikelihood per walker, batch of {BATCH}, median, BLAS threads = 1, "
        f"solver threads = {threads}"
    )
    print(
        f"{'model':<10}{'size':>6}{'wall us':>10}{'cpu us':>10}{'speed-up':>10}"
        f"{'max rel err':>14}{'min':>11}"
    )
    print(
        f"{'full':<10}{fe.structure.n_dof:>6}{full_us[0]:>10.0f}{full_us[1]:>10.0f}{1:>10.0f}"
        f"{'-':>14}{'-':>11}"
    )
    rows = (
        (f"rom {threads}thr", rom, rom_us, "rom"),
        ("rom 1thr", rom, rom1_us, "rom"),
        ("rom sygvd", rom, sygvd_us, "rom"),
        (f"post {threads}thr", local, local_us, "rom-post"),
        ("post 1thr", local, local1_us, "rom-post"),
    )
    for label, model, us, box_label in rows:
        e_max, e_min = errors[box_label]
        print(
            f"{label:<10}{model.size:>6}{us[0]:>10.1f}{us[1]:>10.1f}{full_us[1] / us[1]:>10.0f}"
            f"{e_max:>14.2e}{e_min:>11.1e}"
        )
    print("(us per walker, wall and CPU; speed-up on CPU time)")
    print("(size: DOFs for full, basis vectors incl. 6 rigid for the reduced models; min rel err")
    print(" >= 0 up to round-off is the Rayleigh-Ritz upper bound; errors on fresh uniform points)")


if __name__ == "__main__":
    main()
