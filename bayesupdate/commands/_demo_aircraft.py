"""``bayesupdate demo --case aircraft``: the mAEWing1's own model updated against its own GVT,
on the data packaged with bayesupdate, through the same commands a user types.

The chain (each step is ``bayesupdate <command>`` run in this process, its ``--json`` read):
``identify`` on the 10 packaged FRF files -> ``correlate`` of the authors' pre-update deck
v3.3 and of their updated v4.2 with the test geometry -> ``sensitivity`` of v3.3 to the
parameters (``pipelines.aircraft.PARAMETERS``) -> ``calibrate`` v3.3 on the GVT modes it pairs
below 20 Hz and the measured mass properties (``--write-bdf DIR/updated.bdf``) -> ``sample``
(``--write-bdf DIR/posterior_mean.bdf``) -> ``correlate`` of the updated deck -> the
posterior predictive band of every paired mode (the deck solved at posterior draws) -> (not
``--quick``) ``discover`` on v3.3 and on the updated deck.  Writes ``DIR/report.md`` and
``DIR/aircraft.json`` (the object ``--json`` prints).
"""

import json
import subprocess
import sys
import time
import warnings
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.pipelines import aircraft as ac

#: posterior draws solved for the predictive band (its 5 % quantile is the fifth lowest of them)
BAND_DRAWS = 100


@dataclass(frozen=True)
class AircraftSettings:
    """out : output folder.  quick : fewer starts, a short chain and no discovery (the test's
    and a first look's variant); otherwise ``calibrate`` and ``sample`` run with the study
    file's settings (``pipelines.aircraft.study_text``: 4 starts, 8 walkers, the reduced
    basis) and the sampler's own stop rule (R-hat, ESS).  seed : every random draw derives from it.
    discover : run ``discover`` (not with ``quick``)."""

    out: Path
    quick: bool = False
    seed: int = 0
    discover: bool = True

    def calibrate_flags(self) -> list:
        """Quick: 2 starts on full solves (``--full``: a few hundred evaluations cost less than
        building the reduced basis, about 90 s of CPU, that a first full run builds and caches
        for the chain)."""
        return ["--starts", 2, "--full"] if self.quick else []

    def sample_flags(self) -> list:
        """Quick: 2 starts and a 30-step chain of differential evolution alone (the mixture's
        three adaptation stages of 250 steps are 25 times a 30-step chain; a quick chain is not
        expected to converge), on full solves as ``calibrate_flags``."""
        return ["--starts", 2, "--steps", 30, "--moves", "de", "--full"] if self.quick else []


class Chain:
    """Runs ``bayesupdate`` commands as a user does (``python -m bayesupdate ...`` in a child
    process, the reduced bases shared through the on-disk cache), timing each and reading its
    JSON; each command's ``warning:`` lines are told to ``say``."""

    def __init__(self, say):
        self.say, self.times = say, {}

    def __call__(self, key: str, *argv) -> dict:
        self.say(f"bayesupdate {' '.join(map(str, argv))}")
        t0 = time.perf_counter()
        code, stdout, stderr = self.execute([*map(str, argv), "--json", "--quiet"])
        self.times[key] = round(time.perf_counter() - t0, 2)
        for line in dict.fromkeys(stderr.splitlines()):
            if line.startswith("warning:"):
                self.say(f"  {line}")
        if code != 0:
            last = (stderr.strip().splitlines() or ["no message"])[-1]
            raise BayesUpdateError(f"demo aircraft: {argv[0]} failed: {last}")
        return json.loads(stdout)

    def execute(self, argv: list[str]) -> tuple[int, str, str]:
        """(exit code, stdout, stderr) of ``bayesupdate argv`` in a child process."""
        command = [sys.executable, "-m", "bayesupdate", *argv]
        done = subprocess.run(command, capture_output=True, text=True, check=False)
        return done.returncode, done.stdout, done.stderr


def run_aircraft(settings: AircraftSettings, say, chain=None, runs=None) -> dict:
    """The chain of the module docstring; returns the ``--json`` object.  chain : runs one
    command (``Chain`` by default: a child process each); runs : the FRF files (default: the
    packaged ones)."""
    out, data = Path(settings.out), ac.data_folder()
    run = chain or Chain(say)
    modes = out / "modes.h5"
    runs = runs or [data / f"run{k}.uff" for k in range(1, ac.N_RUNS + 1)]
    identified = run("identify", "identify", *runs, "--out", modes, "--force")
    test_hz = [m["frequency_hz"] for m in identified["modes"]]
    decks = {"v33": data / ac.V33_DECK, "v42": data / ac.V42_DECK}
    corr = {k: run(f"correlate {k}", "correlate", _study(out, k, deck, modes, params=None))
            for k, deck in decks.items()}  # fmt: skip
    calibrated = ac.calibration_modes(test_hz, corr["v33"])
    if not calibrated:
        raise BayesUpdateError("demo aircraft: v3.3 pairs no GVT mode below 20 Hz")
    update = _study(out, "update", decks["v33"], modes, modes_list=calibrated, measured=True)
    sens = run("sensitivity", "sensitivity", _study(out, "v33_params", decks["v33"], modes))
    seed = ["--seed", settings.seed]
    cal = run("calibrate", "calibrate", update, "--out", out / "calibration.h5", "--force",
              "--write-bdf", out / "updated.bdf", *settings.calibrate_flags(), *seed)  # fmt: skip
    post = run("sample", "sample", update, "--out", out / "posterior.h5", "--force",
               "--write-bdf", out / "posterior_mean.bdf", *settings.sample_flags(),
               *seed)  # fmt: skip
    corr["ours"] = run("correlate ours", "correlate",
                       _study(out, "ours", out / "updated.bdf", modes, params=None))  # fmt: skip
    rows_tests = sorted({m["test"] for c in corr.values() for m in c["modes"]})
    band = _band(update, out / "posterior.h5", rows_tests, settings.seed, run.times)
    rows = ac.comparison_rows(test_hz, corr, calibrated, band)
    result = {
        "case": "aircraft",
        "calibrated_modes": calibrated,
        "comparison": [_row_json(r) for r in rows],
        "metrics": ac.metrics(rows),
        "mass_properties": ac.mass_rows(_mass(decks, out / "updated.bdf")),
        "parameters": {"optimum": cal["parameters"],
                       "posterior": post["parameters"], "converged": post.get("converged")},
        "sensitivity": {k: sens[k] for k in ("candidates", "modes", "sensitivity", "suggested")},
        "identified_hz": test_hz,
        "discover": None,
        "times_s": run.times,
        "files": {k: str(out / v) for k, v in (("updated_bdf", "updated.bdf"),
                  ("posterior_mean_bdf", "posterior_mean.bdf"), ("report", "report.md"))},
    }  # fmt: skip
    if settings.discover and not settings.quick:
        result.update(_discover_both(run, out, decks, modes, corr["v33"], seed))
    result["times_s"]["total"] = round(sum(v for k, v in run.times.items()), 2)
    (out / "aircraft.json").write_text(json.dumps(result, indent=1) + "\n")
    (out / "report.md").write_text(report_markdown(result))
    return result


def _discover_both(run, out: Path, decks: dict, modes: Path, corr_v33: dict, seed: list) -> dict:
    """``discover`` on v3.3 and on the updated deck, on the GVT modes v3.3 pairs:
    {"discover_modes", "discover": {key: summary or {"error"}}}."""
    paired = sorted(ac.pairs_of(corr_v33))
    found = {}
    for key, deck in (("v33", decks["v33"]), ("ours", out / "updated.bdf")):
        study = _study(out, f"discover_{key}", deck, modes, ac.DISCOVER_PARAMETERS, paired,
                       True)  # fmt: skip
        try:
            found[key] = _discover(run(f"discover {key}", "discover", study, *seed))
        except BayesUpdateError as exc:  # e.g. too few paired modes to decide: said
            found[key] = {"error": str(exc)}
    return {"discover_modes": paired, "discover": found}


def _study(out: Path, name, deck, modes, params=ac.PARAMETERS, modes_list=None,
           measured=False) -> Path:  # fmt: skip
    path = out / f"{name}.toml"
    path.write_text(ac.study_text(deck, modes, modes_list, params, measured))
    return path


def _row_json(row) -> dict:
    d = asdict(row)
    d["ours_band_hz"] = None if row.ours_band_hz is None else list(row.ours_band_hz)
    return d


def _discover(summary: dict) -> dict:
    keys = ("verdict", "flagged_modes", "named_effect", "gap_before", "gap_after")
    top = sorted(summary.get("candidates", []), key=lambda c: -c.get("log_evidence", -np.inf))
    return {**{k: summary.get(k) for k in keys},
            "top_candidates": [{k: c.get(k) for k in ("kind", "location", "log_evidence")}
                               for c in top[:3]]}  # fmt: skip


def _band(study_path: Path, posterior: Path, tests, seed: int, times: dict) -> dict:
    """The posterior predictive band of the test modes ``tests``: the study's deck solved at
    ``BAND_DRAWS`` draws of the chain (after burn-in), paired by MAC."""
    from bayesupdate.config import load_study
    from bayesupdate.inference.data import load_modal_data
    from bayesupdate.inference.results import read_result
    from bayesupdate.pipelines.model_source import paired_study_model

    t0 = time.perf_counter()
    study = load_study(study_path)
    data = load_modal_data(study.data.as_source())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # shared model points were named by calibrate already
        model = paired_study_model(study, data.dof_labels)[0]
    post = read_result(posterior)["posterior"]
    names = [str(n) for n in post["attrs"]["names"]]
    chain = post["chain"][int(post["attrs"]["burn"]) :].reshape(-1, len(names))
    rng = np.random.default_rng(seed)
    draws = chain[rng.choice(len(chain), min(BAND_DRAWS, len(chain)), replace=False)]
    n = max(tests) + 4
    freq, shapes = [], []
    for x in draws:
        r = model.solve(dict(zip(names, map(float, x), strict=True)), n_modes=n)
        freq.append(r.frequencies_hz)
        shapes.append(np.real(r.sensor_shapes))
    band = ac.predictive_band(np.array(freq), np.array(shapes), data.shapes, tests)
    times["predictive band"] = round(time.perf_counter() - t0, 2)
    return band


def _mass(decks: dict, updated: Path) -> dict:
    """{model: weight and inertias in the authors' units} of v3.3, v4.2 and the updated deck."""
    from bayesupdate.nastran import load_nastran_model

    out = {}
    for key, deck in {**decks, "ours": updated}.items():
        model = load_nastran_model(str(deck))
        wtmass = model.structure.metadata["nastran"]["wtmass"]
        out[key] = ac.weight_units(model.mass_properties(), wtmass)
    return out


def _f(x, fmt=".3f") -> str:
    return "-" if x is None else format(x, fmt)


def report_markdown(result: dict) -> str:
    """The demo's report: the comparison, the metrics, the mass properties, the parameters,
    discovery and the wall time of each command."""
    lines = ["# mAEWing1: v3.3 updated against its GVT, beside the authors' v4.2", "",
             f"Calibrated on GVT modes {result['calibrated_modes']} (paired with v3.3 below "
             f"{ac.CALIBRATE_BELOW_HZ:g} Hz); the other paired modes are held out.", "",
             "| GVT mode | test [Hz] | v3.3 [Hz] | MAC | v4.2 [Hz] | MAC | ours [Hz] | MAC "
             "| ours posterior mean [5-95 %] [Hz] | held out |",
             "|---|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for r in result["comparison"]:
        band = r["ours_band_hz"]
        post = "-" if band is None else (f"{r['ours_mean_hz']:.3f} [{band[0]:.3f}, "
                                         f"{band[1]:.3f}]")  # fmt: skip
        lines.append(
            f"| {r['test']} | {r['test_hz']:.3f} | {_f(r['v33_hz'])} | {_f(r['mac_v33'], '.2f')} "
            f"| {_f(r['v42_hz'])} | {_f(r['mac_v42'], '.2f')} | {_f(r['ours_hz'])} "
            f"| {_f(r['mac_ours'], '.2f')} | {post} | {'yes' if r['held_out'] else 'no'} |"
        )
    lines += ["", "| model | modes | RMS frequency error [%] | mean MAC | paired | unpaired |",
              "|---|---|---|---|---|---|"]  # fmt: skip
    names = {"v33": "v3.3", "v42": "v4.2", "ours": "ours"}
    for model, parts in result["metrics"].items():
        for part, m in parts.items():
            lines.append(f"| {names[model]} | {part.replace('_', ' ')} | "
                         f"{_f(m['rms_error_pct'], '.2f')} | {_f(m['mean_mac'], '.3f')} | "
                         f"{m['n']} | {m['unpaired']} |")  # fmt: skip
    lines += ["", "| quantity | measured [range] | v3.3 | v4.2 | ours |", "|---|---|---|---|---|"]
    for m in result["mass_properties"]:
        cells = [f"{_f(m[k], '.4g')}{'' if m[k + '_in_range'] else ' (out)'}"
                 for k in ("v33", "v42", "ours")]  # fmt: skip
        lines.append(f"| {m['name']} [{m['unit']}] | {m['measured']:g} [{m['range'][0]:g}, "
                     f"{m['range'][1]:g}] | " + " | ".join(cells) + " |")  # fmt: skip
    p = result["parameters"]
    lines += ["", "Parameters (scale factors on v3.3's fields): optimum " +
              ", ".join(f"{k} = {v:.4g}" for k, v in p["optimum"].items()) + "; posterior " +
              ", ".join(f"{k} = {v['mean']:.4g} (sd {v['sd']:.2g})"
                        for k, v in p["posterior"].items()) + "."]  # fmt: skip
    if result["discover"]:
        for key, d in result["discover"].items():
            if "error" in d:
                lines.append(f"\nDiscover on {names[key]}: not run: {d['error']}")
                continue
            lines.append(f"\nDiscover on {names[key]}: verdict {d['verdict']}; named "
                         f"{d['named_effect']}; top candidates {d['top_candidates']}.")  # fmt: skip
    lines += ["", "Wall time per step [s]: " +
              ", ".join(f"{k} {v:.1f}" for k, v in result["times_s"].items()), ""]  # fmt: skip
    return "\n".join(lines)


def run(args, out: Path, say) -> int:
    """``demo --case aircraft``: the chain into the checked folder ``out``, telling its steps
    to ``say`` (``commands.demo``'s), then the summary (or one JSON object)."""
    result = run_aircraft(AircraftSettings(out, args.quick, args.seed), say)
    if args.json:
        print(json.dumps(result))
        return 0
    print(report_markdown(result))
    return 0
