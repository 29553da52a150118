"""Convergence diagnostics (ArviZ 1.x's, ``inference.convergence``) and posterior predictive
frequencies.

Walkers as chains: after the warm-up, each emcee walker is passed to ArviZ as one chain, so the
rank-normalized split R-hat (Vehtari et al. 2021) compares the walkers with each other - a walker
stuck in one mode, or an ensemble not yet mixed, shows as R-hat > 1.01.  Walkers of an ensemble
sampler are not independent (each move uses the others), so ArviZ's ESS, which assumes independent
chains, can be optimistic; we therefore also report emcee's ESS = n_draws * n_walkers / tau, and the
``ess_bulk`` reported is the smaller of the two.
"""

import numpy as np

from bayesupdate.inference import convergence
from bayesupdate.inference.likelihood import LogPosterior
from bayesupdate.inference.sampling import PosteriorResult, rhat_and_ess


def summarize(result: PosteriorResult, hdi_prob: float = 0.9) -> dict:
    """Per parameter: mean, sd, hdi_low, hdi_high, r_hat, ess_bulk, ess_tail, ess_arviz_bulk,
    ess_autocorr.  Uses the post-burn-in chain, walkers as chains (module docstring)."""
    post = result.chain[result.burn :]  # (draws, walkers, d)
    rhat, ess_b, ess_tau = rhat_and_ess(post, result.autocorr_time)
    ess_t = convergence.tail_ess(post, (0.05, 0.95))
    flat = post.reshape(-1, post.shape[-1])
    out = {}
    for j, name in enumerate(result.names):
        low, high = convergence.hdi_nearest(flat[:, j], hdi_prob)
        out[name] = {
            "mean": float(np.mean(flat[:, j])),
            "sd": float(np.std(flat[:, j], ddof=1)),
            "hdi_low": float(low),
            "hdi_high": float(high),
            "r_hat": float(rhat[j]),
            "ess_bulk": float(np.nanmin([ess_b[j], ess_tau[j]])),
            "ess_tail": float(ess_t[j]),
            "ess_arviz_bulk": float(ess_b[j]),
            "ess_autocorr": float(ess_tau[j]),
        }
    return out


def posterior_predictive(
    log_posterior: LogPosterior,
    result: PosteriorResult,
    n_draws: int = 400,
    seed: int = 0,
    check_swaps: int = 50,
) -> dict:
    """Model frequencies per posterior draw, with and without measurement noise.

    Returns {"draw_index": (n,) rows of the flattened post-burn chain, "frequencies_hz": (n, m)
    model frequencies, "predictive_hz": (n, m) with the likelihood's noise added,
    "swap_fraction": share of draws whose shape pairing differs from the order pairing (all
    draws when the likelihood pairs by shape in batches; else ``check_swaps`` draws checked
    with the problem's pairing when the likelihood pairs by order; NaN when no shapes)}.
    """
    samples = result.samples()
    rng = np.random.default_rng([seed, 11])
    n = min(n_draws, samples.shape[0])
    index = np.sort(rng.choice(samples.shape[0], size=n, replace=False))
    theta = samples[index]
    d = len(log_posterior.problem.parameters)
    checked, differs = log_posterior.pair_checked, log_posterior.pair_differs
    freqs, _ = log_posterior.predict_frequencies(theta[:, :d])
    checked = log_posterior.pair_checked - checked
    differs = log_posterior.pair_differs - differs
    if log_posterior.spec.infer_sigma:
        sigma = theta[:, d]
    else:
        sigma = np.full(n, log_posterior.spec.sigma)
    w = log_posterior.problem.weights
    sd = log_posterior.problem.data.frequency_sd_hz
    f_test = log_posterior.problem.data.frequencies_hz
    with np.errstate(divide="ignore"):
        rel_sd = np.sqrt(
            sigma[:, None] ** 2 / np.where(w > 0, w, np.inf)
            + (0.0 if sd is None else (sd / f_test) ** 2)
        )
    predictive = freqs * (1.0 + rel_sd * rng.standard_normal(freqs.shape))
    # shape-paired batches: the share of draws whose modes are out of order
    swap_fraction = differs / checked if checked else float("nan")
    problem = log_posterior.problem
    if problem.pairing.method != "order" and log_posterior.spec.pairing == "order" and check_swaps:
        picks = theta[: min(check_swaps, n), :d]
        swaps = [problem.evaluate(p) for p in picks]
        ok = [e for e in swaps if e.ok]
        swap_fraction = float(np.mean([e.paired.swapped for e in ok])) if ok else float("nan")
    return {
        "draw_index": index,
        "frequencies_hz": freqs,
        "predictive_hz": predictive,
        "swap_fraction": swap_fraction,
    }


def convergence_report(
    result: PosteriorResult,
    summary: dict,
    target_rhat: float | None,
    target_ess: float | None,
    min_autocorr_times: float,
) -> dict:
    """Whether the run met its own targets, judged on what is reported (``summary``), and why not.

    A run that stops on its step budget is not converged, whatever its last check said; so is one
    whose final R-hat or bulk ESS (``summarize``) misses the target, or whose chain is shorter
    than ``min_autocorr_times`` autocorrelation times.  Returns {"converged": bool, "reason":
    str | None (the failed criteria, with the worst parameter), "max_r_hat", "min_ess_bulk",
    "target_rhat", "target_ess", "steps"}.
    """
    names = list(summary)
    rhat = np.array([summary[n]["r_hat"] for n in names], dtype=float)
    ess = np.array([summary[n]["ess_bulk"] for n in names], dtype=float)
    steps = int(result.chain.shape[0])
    reasons = []
    if target_rhat is not None and not np.all(rhat <= target_rhat):
        worst = int(np.nanargmax(np.where(np.isfinite(rhat), rhat, np.inf)))
        reasons.append(f"R-hat {rhat[worst]:.3f} > {target_rhat:g} ({names[worst]})")
    if target_ess and not np.all(ess >= target_ess):
        worst = int(np.nanargmin(np.where(np.isfinite(ess), ess, -np.inf)))
        reasons.append(f"bulk ESS {ess[worst]:.0f} < {target_ess:g} ({names[worst]})")
    tau = np.max(result.autocorr_time) if np.size(result.autocorr_time) else np.nan
    if np.isnan(tau) and np.size(result.autocorr_time):
        # emcee's estimate is 0 / 0 for a walker whose chain is constant (``_autocorr``)
        reasons.append("autocorrelation time undefined: a walker never moved")
    elif not (np.isfinite(tau) and steps >= min_autocorr_times * tau):
        reasons.append(f"{steps} steps < {min_autocorr_times:g} autocorrelation times ({tau:.0f})")
    if not result.converged and not reasons:
        reasons.append("stopped before its convergence check passed")
    if reasons:
        reasons.append(f"step budget reached after {steps} steps: raise sampler.steps")
    return {
        "converged": not reasons,
        "reason": "; ".join(reasons) if reasons else None,
        "max_r_hat": float(np.nanmax(rhat)),
        "min_ess_bulk": float(np.nanmin(ess)),
        "target_rhat": target_rhat,
        "target_ess": target_ess or None,
        "steps": steps,
    }
