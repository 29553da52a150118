"""The demo pipeline: the seed's whole story on the embedded default, end to end.

(a) The seed's case: the built-in exhaust at the initial design against seed Table 1, then
    calibrated against the measured frequencies of seed Table 2 (optimum and posterior), and
    discovery of what it is missing (full runs only).
(b) A virtual test campaign: a "true" exhaust with known design values and a hidden effect ->
    simulated roving-hammer FRFs (UFF 58) -> automatic identification -> calibration against the
    identified modes (paired by MAC) -> posterior -> discovery, so the chain from FRFs to
    calibrated values with uncertainty is shown on data whose truth is known.

``run_demo`` computes and writes the data files a user would keep (HDF5 results, the UFF file,
the identified modes) into ``settings.out`` and returns frozen records; the figures and the
report are made from them at the edge (``report.demo_report``).
"""

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from bayesupdate import paper
from bayesupdate.config import StudyConfig, parse_study
from bayesupdate.discovery.results_io import write_discovery
from bayesupdate.discovery.settings import DiscoverySettings
from bayesupdate.pipelines.calibrate import run_calibration
from bayesupdate.pipelines.discover import DiscoveryRequest, DiscoveryRun, discover_study
from bayesupdate.pipelines.sample import SamplingOptions, SamplingRun, run_sampling
from bayesupdate.pipelines.simulate import VirtualTest, VirtualTestSettings, simulate_test
from bayesupdate.pipelines.study import prepare

#: the hidden truth of the virtual campaign: design values (SI) and one hidden effect
VIRTUAL_TRUTH = {
    "t_hot_pipe": 1.6e-3,
    "t_cold_pipe": 1.25e-3,
    "t_main_muffler": 0.8e-3,
    "rho_catalyst": 9.0e3,
    "rho_intermediate_muffler": 14.0e3,
}
VIRTUAL_EFFECT = "added_mass@14:m=0.4"
#: the identified modes kept for calibration: below this [Hz] (the test band ends at 150 Hz)
IDENTIFIED_BELOW_HZ = 140.0


@dataclass(frozen=True)
class DemoSettings:
    """out : the output folder.  quick : a smaller run for a first look (<= 60 s).  seed : every
    random draw derives from it.  progress : show the sampler's progress bars."""

    out: Path
    quick: bool = False
    seed: int = 0
    progress: bool = False

    @property
    def starts(self) -> int:
        return 3 if self.quick else 12

    @property
    def walkers(self) -> int:
        return 16 if self.quick else 32

    @property
    def steps(self) -> int:
        """Step budget; the sampler stops earlier once R-hat, ESS and 50 tau are met.  2,500
        left the demo's posteriors at R-hat 1.02-1.03; with the weighed mass in the likelihood the
        seed case's mixture proposal is repaired after its coverage check and converges at
        4,000-6,000 kept steps (17,500 on one of sampler seeds 1, 5-7, 2026-11-24; the virtual
        test converges at 500-1,000); a quick run is not expected to converge and says so."""
        return 300 if self.quick else 25000


@dataclass(frozen=True)
class FePart:
    """The FE model at the initial design: model, its 12-mode ``FEResult`` (with energies), and
    each mode's character (``models.exhaust.mode_character``)."""

    model: object
    result: object
    character: list


@dataclass(frozen=True)
class CalibrationPart:
    """A calibrated case: the sampling run (optimum, posterior, summary, predictions), the result
    file and the calibration problem."""

    run: SamplingRun
    path: Path
    problem: object


@dataclass(frozen=True)
class IdentifiedPart:
    """The identification of the virtual test: the FRFs read back from the UFF file, the
    ``ema.identify`` result and the modes kept (below ``IDENTIFIED_BELOW_HZ``)."""

    frfs: object
    identification: object
    modes: object


@dataclass(frozen=True)
class DiscoveryPart:
    """A discovery run and its result file."""

    run: DiscoveryRun
    path: Path


@dataclass(frozen=True)
class DemoResults:
    """Everything the demo computed; the discovery parts are None when not run."""

    settings: DemoSettings
    fe: FePart
    seed: CalibrationPart
    seed_discovery: DiscoveryPart | None
    virtual_test: VirtualTest
    uff: Path
    identified: IdentifiedPart
    virtual: CalibrationPart
    virtual_discovery: DiscoveryPart | None


def demo_steps(settings: DemoSettings) -> tuple[str, ...]:
    """The steps ``run_demo`` announces, in order."""
    steps = [
        "FE model vs seed Table 1",
        "seed case: calibration vs Table 2",
        "seed case: posterior",
    ]
    # --quick keeps discovery where it has something to find (the virtual test's hidden effect)
    if not settings.quick:
        steps.append("seed case: discovery")
    steps += [
        "virtual test: simulate FRFs",
        "virtual test: identify",
        "virtual test: calibrate + posterior",
        "virtual test: discovery",
    ]
    return tuple(steps)


def run_demo(
    settings: DemoSettings, step: Callable[[str], None] = lambda name: None
) -> DemoResults:
    """Run both parts (module docstring); ``step(name)`` announces each of ``demo_steps``."""
    out = settings.out
    step("FE model vs seed Table 1")
    fe = _fe_part()
    step("seed case: calibration vs Table 2")
    seed = _calibration_part(settings, "paper:ema", out / "seed_case.h5", step)
    seed_discovery = None
    if not settings.quick:
        step("seed case: discovery")
        seed_discovery = _discovery_part(settings, "paper:ema", out / "seed_discovery.h5")
    step("virtual test: simulate FRFs")
    virtual_test, uff = _virtual_test_part(settings)
    step("virtual test: identify")
    identified = _identify_part(out, uff)
    step("virtual test: calibrate + posterior")
    modes = str(out / "virtual_modes.h5")
    virtual = _calibration_part(settings, modes, out / "virtual_case.h5")
    step("virtual test: discovery")
    virtual_discovery = _discovery_part(settings, modes, out / "virtual_discovery.h5")
    return DemoResults(
        settings,
        fe,
        seed,
        seed_discovery,
        virtual_test,
        uff,
        identified,
        virtual,
        virtual_discovery,
    )


def _study(settings: DemoSettings, data_source) -> StudyConfig:
    document = {
        "model": {"source": "exhaust"},
        "data": {"source": data_source},
        "pairing": {"method": "auto"},
        "objective": {"mass_kg": paper.MEASURED_MASS_KG, "mass_weight": 10.0},
        "optimizer": {"starts": settings.starts, "seed": settings.seed},
        "likelihood": {"sigma_prior": {"kind": "halfnormal", "scale": 0.1}},
        "sampler": {
            "walkers": settings.walkers,
            "steps": settings.steps,
            "seed": settings.seed + 1,
            "check_every": 100 if settings.quick else 500,
            "predictive_draws": 100 if settings.quick else 400,
        },
    }
    return parse_study(document, where="demo")


def _fe_part() -> FePart:
    from bayesupdate.models import get_model
    from bayesupdate.models.exhaust import mode_character

    model = get_model("exhaust")
    result = model.solve(n_modes=12, energies=True)
    return FePart(model, result, mode_character(model.structure, result.modes.shapes))


def _calibration_part(settings, data_source, path: Path, step=None) -> CalibrationPart:
    """Optimum, then (announced by ``step`` when given) the posterior, written to ``path``."""
    prepared = prepare(_study(settings, data_source))
    calibration = run_calibration(prepared)
    if step is not None:
        step("seed case: posterior")
    options = SamplingOptions(out=path, progress=settings.progress)
    run = run_sampling(prepared, options, calibration=calibration)
    return CalibrationPart(run, path, prepared.problem)


def _virtual_test_part(settings) -> tuple[VirtualTest, Path]:
    from bayesupdate.discovery.effects import parse_effect_spec
    from bayesupdate.ema.uff_io import write_uff58
    from bayesupdate.models import get_model

    truth = VirtualTestSettings(
        parameters=VIRTUAL_TRUTH,
        effects=(parse_effect_spec(VIRTUAL_EFFECT),),
        noise=0.01,
        seed=settings.seed,
    )
    test = simulate_test(get_model("exhaust"), truth)
    uff = settings.out / "virtual_test.uff"
    write_uff58(uff, test.frfs)
    return test, uff


def _identify_part(out: Path, uff: Path) -> IdentifiedPart:
    from bayesupdate.ema.modal_h5 import write_modal_h5
    from bayesupdate.pipelines.identify import IdentifyRequest, identify_frfs, read_frf_files

    data = read_frf_files([uff])  # the round trip through the file a user would bring
    frfs = data.frfs
    ident = identify_frfs(data, IdentifyRequest((str(uff),))).identification
    modes = ident.modes.subset(np.flatnonzero(ident.modes.frequencies_hz < IDENTIFIED_BELOW_HZ))
    write_modal_h5(out / "virtual_modes.h5", modes)
    return IdentifiedPart(frfs, ident, modes)


def _discovery_part(settings, data_source, path: Path) -> DiscoveryPart:
    options = {"seed": settings.seed}
    if settings.quick:
        options.update(quick_refits=5, per_kind=1, max_refits=2, loo_top=1, loo_draws=100)
    study = parse_study({"model": {"source": "exhaust"}, "data": {"source": data_source}}, "demo")
    run = discover_study(study, DiscoveryRequest(DiscoverySettings.from_flat(**options)))
    write_discovery(path, run.result, command="demo")
    return DiscoveryPart(run, path)
