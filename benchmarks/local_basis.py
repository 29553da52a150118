"""Would a posterior-local "basis of the basis" make ``sample --model exhaust --data paper:ema``
fast?  Measures what such a basis could save, from a chain the command itself wrote.

A local basis: the elastic reduced eigenvectors of the certified basis (size 74 on the exhaust)
at points of a region, compressed by POD in the energy norm and projected once more
(``ReducedBasis.restricted``, as ``ReducedFEModel.coarsened`` does on the whole box); its rank is
the smallest whose frequencies stay within a tolerance of the certified basis's at fresh points
of the region.  Printed, for the regions below and the tolerances 4e-5 (the exact stage: 1e-4
less the certified basis's own error), 1e-4, 5e-4, 1e-3 and 5e-3 (the screen's), the basis
size needed (rigid motions included); then the CPU time per point of the user's log-posterior
on each size in batches of 16 (five interleaved rounds: the least and the median); then how
well a Laplace approximation at the optimum, the one region known before sampling, covers the
chain.

Regions (theta: SI; z: the sampler's logit coordinates of the box):
  box       the whole parameter box (Sobol points)
  q-box     the chain's 0.5-99.5 % quantile box, widened by 25 % of its width on each side
  ellipsoid the chain's own 3.5-sd ellipsoid in z (its mean and covariance): points inside and
            on its surface

Run (the chain first; ~1 minute, then ~1 minute):
  PYTHONPATH=. python -m bayesupdate sample --model exhaust --data paper:ema --workers 1 \\
      --out /tmp/post.h5 --json > /tmp/post.json
  PYTHONPATH=. python benchmarks/local_basis.py --chain /tmp/post.h5
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402

import h5py  # noqa: E402
import numpy as np  # noqa: E402
from scipy.stats import norm, qmc  # noqa: E402

from bayesupdate.cli import build_parser  # noqa: E402
from bayesupdate.commands._shared import study_from_args  # noqa: E402
from bayesupdate.inference import LogPosterior, calibrate  # noqa: E402
from bayesupdate.pipelines.sample import walker_start_settings  # noqa: E402
from bayesupdate.pipelines.study import prepare  # noqa: E402
from bayesupdate.pipelines.surrogates import sampling_problem  # noqa: E402

TOLERANCES = (4e-5, 1e-4, 5e-4, 1e-3, 5e-3)
RADIUS = 3.5


def user_problem():
    """(prepared study, problem on the certified basis, the basis) of the user's command."""
    args = build_parser("sample").parse_args(
        ["sample", "--model", "exhaust", "--data", "paper:ema"]
    )
    prepared = prepare(study_from_args(args))
    problem, rom = sampling_problem(prepared.problem)
    return prepared, problem, rom


def logit(rom, theta):
    u = (theta - rom.low) / (rom.high - rom.low)
    return np.log(u) - np.log1p(-u)


def from_logit(rom, z):
    return rom.low + (rom.high - rom.low) / (1.0 + np.exp(-z))


def ellipsoid_points(rom, mean, chol, n, seed, surface):
    """(n, k) theta spread uniformly in (or on) the ``RADIUS`` ellipsoid of N(mean, L L^T) in z."""
    k = mean.size
    u = np.clip(qmc.Sobol(k + 1, seed=seed).random(n), 1e-12, 1 - 1e-12)
    g = norm.ppf(u[:, :k])
    g /= np.linalg.norm(g, axis=1, keepdims=True)
    r = RADIUS * (1.0 if surface else u[:, k:] ** (1.0 / k))
    return from_logit(rom, mean + (g * r) @ chol.T)


def regions(rom, theta):
    """{name: (training points, check points)} (module docstring)."""
    k = theta.shape[1]
    box = (rom.scale(qmc.Sobol(k, seed=1).random(128)), rom.scale(qmc.Sobol(k, seed=2).random(256)))
    lo, hi = np.quantile(theta, 0.005, axis=0), np.quantile(theta, 0.995, axis=0)
    lo, hi = np.maximum(lo - 0.25 * (hi - lo), rom.low), np.minimum(hi + 0.25 * (hi - lo), rom.high)
    corners = lo + (hi - lo) * np.array(np.meshgrid(*[[0, 1]] * k)).reshape(k, -1).T
    qbox = (
        np.vstack([lo + (hi - lo) * qmc.Sobol(k, seed=1).random(128), corners]),
        np.vstack([lo + (hi - lo) * qmc.Sobol(k, seed=2).random(256), corners]),
    )
    z = logit(rom, theta)
    mean, chol = z.mean(axis=0), np.linalg.cholesky(np.cov(z.T))
    ell = tuple(
        np.vstack([ellipsoid_points(rom, mean, chol, 128, s, False),
                   ellipsoid_points(rom, mean, chol, 128, s + 10, True)])
        for s in (1, 2)
    )  # fmt: skip
    return {"box": box, "q-box": qbox, "ellipsoid": ell}


def pod_directions(basis, train, n_modes):
    """(G, U): the energy-norm Cholesky factor at the training points' median and the POD
    directions of the elastic reduced eigenvectors there (``coarsening.coarsened``'s)."""
    nr, re = basis.n_rigid, basis.size - basis.n_rigid
    y = basis.eigen(train, n_modes, vectors=True)[1]
    Y = np.moveaxis(y[:, nr:, :], 1, 0).reshape(re, -1)
    Kc = basis.matrices(np.median(train, axis=0)[None, :])[0][0]
    G = np.linalg.cholesky(0.5 * (Kc + Kc.T))
    Z = G.T @ Y
    return G, np.linalg.svd(Z / np.linalg.norm(Z, axis=0), full_matrices=False)[0]


def sizes_needed(rom, train, check):
    """{tol: (size incl. rigid, error against the certified basis)} for ``TOLERANCES``."""
    basis, nm = rom.certification.basis, rom.n_modes
    G, U = pod_directions(basis, train, nm)
    lam = basis.eigen(check, nm)
    errors = {}
    for m in range(nm, basis.size - basis.n_rigid + 1, 2):
        Q = np.linalg.qr(np.linalg.solve(G.T, U[:, :m]))[0]
        local = basis.restricted(Q)
        errors[local.size] = float(np.max(np.abs(np.sqrt(local.eigen(check, nm) / lam) - 1)))
    out = {}
    for tol in TOLERANCES:
        fit = [(s, e) for s, e in errors.items() if e <= tol]
        out[tol] = fit[0] if fit else (rom.size, 0.0)
    return out, (G, U)


def restricted_model(rom, G, U, size):
    m = size - rom.n_rigid
    Q = np.linalg.qr(np.linalg.solve(G.T, U[:, :m]))[0]
    basis = rom.certification.basis.restricted(Q)
    return replace(rom, certification=replace(rom.certification, basis=basis))


def cost_per_point(prepared, problem, models, theta, rounds=5, batches=40):
    """{label: [least, median] CPU ms per point over ``rounds`` interleaved rounds} of the
    user's log-posterior on each model (the least is the one a busy machine disturbs least)."""
    rng = np.random.default_rng(0)
    x = theta[rng.choice(len(theta), 16 * batches)]
    posts = {
        k: LogPosterior(replace(problem, model=m), prepared.likelihood) for k, m in models.items()
    }
    times = {k: [] for k in models}
    for _ in range(rounds):
        for k, lp in posts.items():
            lp(x[:16])
            t = time.process_time()
            for i in range(batches):
                lp(x[16 * i : 16 * (i + 1)])
            times[k].append((time.process_time() - t) / (16 * batches) * 1e3)
    return {
        k: [round(float(np.min(v)), 3), round(float(np.median(v)), 3)] for k, v in times.items()
    }


def laplace_coverage(prepared, problem, rom, theta):
    """{step: share of the chain inside the 3.5-sd ellipsoid of the Laplace approximation at
    the optimum ``sample`` starts from} (central differences of log p in z, Jacobian included)."""
    lp = LogPosterior(problem, prepared.likelihood)
    opt = calibrate(problem, walker_start_settings(prepared.study.optimizer)).theta
    z0, k = logit(rom, opt), opt.size
    eye, out = np.eye(k), {}
    zc = logit(rom, theta)
    for h in (0.05, 0.5, 1.0):

        def f(dz):
            z = z0 + dz
            u = 1.0 / (1.0 + np.exp(-z))
            return lp(from_logit(rom, z)) + np.sum(np.log(u * (1 - u)), axis=1)

        H = np.empty((k, k))
        for i in range(k):
            for j in range(k):
                s = np.array([eye[i] + eye[j], eye[i] - eye[j], -eye[i] + eye[j], -eye[i] - eye[j]])
                v = f(h * s)
                H[i, j] = (v[0] - v[1] - v[2] + v[3]) / (4 * h * h)
        C = np.linalg.inv(-H)
        try:
            L = np.linalg.cholesky(0.5 * (C + C.T))
        except np.linalg.LinAlgError:
            out[h] = {"inside": None, "sd_z": None}
            continue
        d = np.linalg.norm(np.linalg.solve(L, (zc - z0).T), axis=0)
        out[h] = {
            "inside": float(np.mean(d <= RADIUS)),
            "sd_z": np.sqrt(np.diag(C)).round(3).tolist(),
        }
    out["chain_sd_z"] = zc.std(axis=0).round(3).tolist()
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--chain", required=True, help="the result file the sample command wrote")
    args = ap.parse_args()
    prepared, problem, rom = user_problem()
    with h5py.File(args.chain) as f:
        chain = f["posterior/chain"][:]
    theta = chain.reshape(-1, chain.shape[-1])[:, : len(problem.names)]
    if problem.names != rom.parameter_names:
        raise SystemExit("this benchmark expects the model's own parameters, in order")
    print(json.dumps({"certified": rom.summary(), "draws": len(theta)}))
    bases = {}
    for name, (train, check) in regions(rom, theta).items():
        needed, directions = sizes_needed(rom, train, check)
        bases[name] = (needed, directions)
        print(json.dumps({"region": name, **{f"{t:g}": v for t, v in needed.items()}}))
    screen = rom.coarsened()
    models = {f"certified {rom.size}": rom, f"screen (whole box) {screen.size}": screen}
    for region in ("box", "ellipsoid"):
        G, U = bases[region][1]
        for tol in TOLERANCES:
            size = bases[region][0][tol][0]
            models[f"{region} {size}"] = restricted_model(rom, G, U, size)
    print(json.dumps({"ms_per_point": cost_per_point(prepared, problem, models, theta)}))
    print(json.dumps({"laplace": laplace_coverage(prepared, problem, rom, theta)}))


if __name__ == "__main__":
    main()
