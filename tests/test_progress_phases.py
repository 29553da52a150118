"""Every long phase says what it is doing (``compute.progress``): the sampler's adaptation
stages and kept chain, TMCMC's tempering stages, discovery's score tests of the candidates and
its refits, identification's stabilization-diagram orders and FRF estimation's channels each
write their line in "lines" mode (a log, a pipe) with the count of what they did; and the
commands keep each phase's wall time in their result file and their --json output."""

import io
import json
import time
from dataclasses import replace

import h5py
import numpy as np
import pytest
from synthetic_models import free_beam_shapes
from test_discovery_workflow import FAST, frame_model, synthetic

from bayesupdate.cli import main
from bayesupdate.compute import progress
from bayesupdate.compute.progress import reporting
from bayesupdate.discovery.localization import CANDIDATES_PHASE
from bayesupdate.discovery.settings import LibraryScan
from bayesupdate.discovery.workflow import discover
from bayesupdate.ema.frf_estimation import FRF_PHASE, h1_h2_coherence
from bayesupdate.ema.identify import ORDERS_PHASE, IdentifySettings, identify
from bayesupdate.ema.uff_io import write_uff58
from bayesupdate.ema.virtual_test import virtual_impact_test
from bayesupdate.inference import (
    CalibrationSettings,
    LikelihoodSpec,
    LogPosterior,
    SamplerSettings,
    build_problem,
    calibrate,
    sample_posterior,
)
from bayesupdate.inference.tmcmc import TMCMCSettings, tmcmc
from bayesupdate.modal_data import ModalData
from bayesupdate.models import get_model
from bayesupdate.models.shear_building import shear_building_frequencies


@pytest.fixture
def lines(monkeypatch):
    """A "lines" reporting context that shows phases of any length: (stream, recorder)."""
    monkeypatch.setattr(progress, "SHOWN_FROM_S", 0.0)
    stream = io.StringIO()
    with reporting("lines", stream) as recorder:
        yield stream, recorder


def _shown(stream: io.StringIO, name: str) -> list[str]:
    """The lines of phase ``name``."""
    return [line for line in stream.getvalue().splitlines() if line.startswith(f"{name}: ")]


def test_silenced_phases_are_timed_but_not_shown(lines):
    stream, recorder = lines
    with progress.silenced():
        with progress.phase("hidden", 2) as p:
            p.advance(2)
    with progress.phase("shown", 1) as p:
        p.advance()
    assert stream.getvalue().startswith("shown: 1 it in ") and "hidden" not in stream.getvalue()
    assert [(t.name, t.count) for t in recorder.phases] == [("hidden", 2), ("shown", 1)]


def test_the_sampler_shows_its_adaptation_stages_and_its_kept_chain(lines):
    stream, recorder = lines
    data = ModalData(frequencies_hz=shear_building_frequencies(np.array([1.1, 0.9])) * 1.01)
    problem = build_problem(get_model("shear_building"), data, {"theta_1": {}}, pairing="order")
    optimum = calibrate(problem, CalibrationSettings(starts=2, seed=0))
    settings = SamplerSettings(walkers=8, steps=120, seed=3, check_every=60, adapt_steps=30)
    post = sample_posterior(LogPosterior(problem, LikelihoodSpec(sigma=0.05)), optimum, settings)
    kept = _shown(stream, "sampling: kept chain")
    assert kept == [kept[0]] and kept[0].startswith(
        f"sampling: kept chain: {len(post.chain)} steps"
    )
    stages = [p for p in recorder.phases if p.name == "sampling: adaptation stage"]
    # the mixture's two adaptation stages of adapt_steps each (``moves.staged``), one line each
    assert len(stages) >= 2 and all(p.count == 30 for p in stages)
    assert len(_shown(stream, "sampling: adaptation stage")) == len(stages)


def test_tmcmc_shows_one_step_per_tempering_stage(lines):
    stream, recorder = lines

    def log_likelihood(x):
        return -0.5 * np.sum(((x - 0.3) / 0.05) ** 2, axis=1)

    result = tmcmc(
        lambda rng, n: rng.uniform(-1, 1, (n, 2)),
        lambda x: np.where(np.all(np.abs(x) <= 1, axis=1), -np.log(4.0), -np.inf),
        log_likelihood,
        TMCMCSettings(particles=200, seed=1),
    )
    (line,) = _shown(stream, "TMCMC: tempering stages")
    assert line.startswith(f"TMCMC: tempering stages: {len(result.betas) - 1} stages in ")
    assert len(result.betas) - 1 >= 2  # a narrow likelihood needs several stages


def test_discovery_shows_every_candidate_and_its_refits(lines):
    stream, recorder = lines
    frame = frame_model()
    settings = replace(
        FAST,
        scan=LibraryScan(kinds=("added_mass",)),
        refit=replace(FAST.refit, quick_refits=2, max_refits=1),
        evidence=replace(FAST.evidence, loo_draws=100),
    )
    result = discover(frame, synthetic(frame, ["added_mass@5:m=0.3"]), settings)
    (line,) = _shown(stream, CANDIDATES_PHASE)
    assert line.startswith(f"{CANDIDATES_PHASE}: {len(result.localization.scores)} candidates")
    counts = {p.name: p.count for p in recorder.phases}
    # every compared fit was a quick fit first; the best max_refits of them were refitted
    assert counts["discovery: quick refits"] == len(result.fits) >= 1
    assert counts["discovery: full refits"] == 1
    assert counts["discovery: LOO"] == 1 + settings.evidence.loo_top


def _impact_frfs():
    """A seed-layout impact test of a free beam's first four bending modes (1 % noise)."""
    x = (np.arange(20) + 0.5) / 20
    phi = free_beam_shapes(x, 4)
    shapes = np.vstack([phi, 0.3 * phi[:, ::-1]]) / np.sqrt(10.0)
    labels = tuple(f"{k}V" for k in range(1, 21)) + tuple(f"{k}H" for k in range(1, 21))
    fn, zeta = np.array([30.0, 55.0, 70.0, 95.0]), np.array([0.01, 0.01, 0.01, 0.015])
    return virtual_impact_test(fn, zeta, shapes, labels, f_max_hz=120.0, noise=0.01, seed=5)


def test_identification_shows_every_band_s_model_orders(lines):
    stream, recorder = lines
    result = identify(_impact_frfs(), settings=IdentifySettings(max_order=20))
    n_bands = len(result.bands_hz)
    (line,) = _shown(stream, ORDERS_PHASE)
    # orders 2, 4, ..., 20 in each band
    assert line.startswith(f"{ORDERS_PHASE}: {10 * n_bands} orders in ")


def test_frf_estimation_shows_one_step_per_channel(lines):
    stream, _ = lines
    rng = np.random.default_rng(0)
    force = rng.standard_normal((2, 4096))
    response = np.stack([np.apply_along_axis(np.convolve, 1, force, [1.0, k], "same")
                         for k in (0.5, -0.3, 0.1)])  # fmt: skip
    f, h1, h2, coh = h1_h2_coherence(force, response, 1000.0, segment=256)
    (line,) = _shown(stream, FRF_PHASE)
    assert line.startswith(f"{FRF_PHASE}: 3 channels in ")
    # y[n] = x[n] + k x[n - 1] ('same' keeps the first lag): H1 = 1 + k exp(-j w dt)
    w_dt = 2 * np.pi * f / 1000.0
    for row, k in zip(h1, (0.5, -0.3, 0.1), strict=True):
        np.testing.assert_allclose(row, 1 + k * np.exp(-1j * w_dt), atol=0.05)


STUDY = """
[model]
source = "shear_building"
[data]
frequencies_hz = [4.30, 10.80]
[parameters.theta_1]
bounds = [0.2, 3.0]
[parameters.theta_2]
bounds = [0.2, 3.0]
[optimizer]
starts = 4
[sampler]
walkers = 8
steps = 60
check_every = 30
moves = "de"
min_autocorr_times = 1e9
predictive_draws = 10
seed = 5
"""


DISCOVER_STUDY = """
[model]
source = "exhaust"
[data]
source = "{data}"
[discovery]
kinds = ["added_mass"]
baseline_starts = 1
quick_refits = 2
per_kind = 2
max_refits = 1
max_nfev = 15
loo_top = 1
loo_draws = 100
"""


def _timings_kept(out, printed: str, wall_s: float) -> dict:
    """The result file's ``timings`` group against the --json "timings": the same phases and
    wall times, each within the command's own wall time ``wall_s``."""
    timings = json.loads(printed)["timings"]
    with h5py.File(out) as h5:
        stored = json.loads(h5.attrs["timings_json"])
    assert stored == timings and timings
    assert all(0.0 <= t <= wall_s for t in timings.values())
    return timings


@pytest.mark.parametrize("command", ["calibrate", "sample"])
def test_calibrate_and_sample_keep_their_phase_times(command, tmp_path, capsys):
    study, out = tmp_path / "study.toml", tmp_path / "run.h5"
    study.write_text(STUDY)
    t0 = time.perf_counter()
    assert main([command, str(study), "--out", str(out), "--json"]) == 0
    wall = time.perf_counter() - t0
    timings = _timings_kept(out, capsys.readouterr().out, wall)
    assert "calibration: starts" in timings
    if command == "sample":
        assert "sampling: kept chain" in timings


def test_identify_keeps_its_phase_times(tmp_path, capsys):
    uff, out = tmp_path / "test.uff", tmp_path / "modes.h5"
    write_uff58(uff, _impact_frfs())
    t0 = time.perf_counter()
    assert main(["identify", str(uff), "--out", str(out), "--max-order", "20", "--json"]) == 0
    timings = _timings_kept(out, capsys.readouterr().out, time.perf_counter() - t0)
    assert ORDERS_PHASE in timings


def test_discover_keeps_its_phase_times(tmp_path, capsys, monkeypatch):
    """The discover command on the small frame of test_discovery_workflow (the study's model
    replaced by it: the exhaust's scan takes minutes) with a hidden added mass."""
    frame = frame_model()
    monkeypatch.setattr("bayesupdate.pipelines.discover.study_model", lambda study, dofs: frame)
    data = tmp_path / "modes.csv"
    hz = synthetic(frame, ["added_mass@5:m=0.3"]).frequencies_hz
    data.write_text("frequency_hz\n" + "\n".join(f"{f:.6f}" for f in hz) + "\n")
    study, out = tmp_path / "study.toml", tmp_path / "found.h5"
    study.write_text(DISCOVER_STUDY.format(data=data))
    t0 = time.perf_counter()
    assert main(["discover", str(study), "--out", str(out), "--json"]) == 0
    timings = _timings_kept(out, capsys.readouterr().out, time.perf_counter() - t0)
    assert {CANDIDATES_PHASE, "discovery: quick refits", "discovery: LOO"} <= set(timings)
