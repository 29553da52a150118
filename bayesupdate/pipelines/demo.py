"""The demo pipeline: the seed's whole story on the embedded default, end to end.

(a) The seed's case on the shell exhaust ``exhaust_shell`` (the model that reproduces
    the paper better by the numbers, ``pipelines.exhaust_comparison.better_exhaust``): against
    seed Table 1, then calibrated against the measured frequencies of seed Table 2 with the mass
    kept (optimum and front on its certified reduced basis, then the posterior); beside it the
    beam exhaust ``exhaust`` (its optimum from its own calibration and its front), and
    discovery of what the beam exhaust is missing (full runs only; on the shell discovery takes
    about 4 minutes of CPU).
(b) A virtual test campaign on the beam exhaust: a "true" exhaust with known design values and
    a hidden effect -> simulated roving-hammer FRFs (UFF 58) -> automatic identification ->
    calibration against the identified modes (paired by MAC) -> posterior -> discovery, so the
    chain from FRFs to calibrated values with uncertainty is shown on data whose truth is known
    (not the paper's reproduction: the beam model keeps it fast).

``run_demo`` computes and writes the data files a user would keep (HDF5 results, the UFF file,
the identified modes) into ``settings.out`` and returns frozen records; the figures and the
report are made from them at the edge (``report.demo_report``).  The two parts are
independent: after the virtual test's FRFs and modes ("ema", a few seconds), they run as
tasks (``demo_tasks``) on the executor seam (``compute.executors``: two local processes on two
cores, the same bits as one after the other), each part's record handed back as it finishes.
"""

import json
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from importlib import resources
from pathlib import Path

import numpy as np

from bayesupdate.config import StudyConfig, parse_study
from bayesupdate.discovery.results_io import write_discovery
from bayesupdate.discovery.settings import DiscoverySettings
from bayesupdate.models import exhaust_paper as paper
from bayesupdate.pipelines.discover import DiscoveryRequest, DiscoveryRun, discover_study
from bayesupdate.pipelines.sample import SamplingOptions, SamplingRun, run_sampling
from bayesupdate.pipelines.simulate import VirtualTest, VirtualTestSettings, simulate_test
from bayesupdate.pipelines.study import PreparedStudy, prepare

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
#: the shell exhaust's mesh density in the demo: its certified basis builds in about a third of
#: the CPU of the default density 32's; the mesh error this costs is measured in every run
#: (``ShellCheck``; docs/guide/exhaust-shell.md, "The demo on the shell exhaust")
SHELL_MESH_DENSITY = 16
SHELL_MODEL = {"source": "exhaust_shell", "options": {"mesh_density": SHELL_MESH_DENSITY}}
BEAM_MODEL = {"source": "exhaust"}
#: the fronts of Expr against the mass error: these weights of the mass term, each fit on the
#: model's certified basis with this many starts (besides the reference start), not polished.
#: One start gives the 4 points of 2 starts on both exhausts (seed 0, quick demo's bases: Expr
#: equal to 8 digits, the mass errors to 5) for 3.2 s CPU against 4.2 (beam), 4.2 against 5.1
#: (shell) (``benchmarks/demo_steps.py``'s machine at load 5, 2026-11-29)
FRONT_WEIGHTS = (1e-3, 0.1, 10.0, 1e3)
FRONT_STARTS = 1


@dataclass(frozen=True)
class DemoSettings:
    """out : the output folder.  quick : a smaller run for a first look.  seed : every
    random draw derives from it.  progress : show the sampler's progress bars."""

    out: Path
    quick: bool = False
    seed: int = 0
    progress: bool = False

    @property
    def starts(self) -> int:
        """Starts of each optimum (besides the reference start).  A quick run's 3 are the fewest
        that reach the virtual test's optimum since smooth ends are not Nelder-Mead polished
        (``inference.optimize``): from 1 start its two ends stop at a local optimum, Expr
        0.010645 at seed 0, where one of 3 starts' ends reaches Expr 0.010142."""
        return 3 if self.quick else 12

    @property
    def walkers(self) -> int:
        return 16 if self.quick else 32

    @property
    def exact_polish(self) -> bool:
        """Whether the beam exhaust's optima (its seed optimum and the virtual test's) have their
        ends polished again on the full model (``bayesupdate calibrate``'s path) after the
        Nelder-Mead polish on the certified basis.  Not in a quick run: on the beam's seed
        optimum (the quick demo, seed 0) that second polish cost 8.6 of its 23.1 s CPU and
        left Expr on the basis at 0.06696 (0.06731 by a full solve at the basis's optimum)."""
        return not self.quick

    @property
    def steps(self) -> int:
        """Step budget; the sampler stops earlier once R-hat, ESS and 50 tau are met.  The
        shell seed case's mixture, fitted in the unit box (``moves.staged``), converges in
        1,000-3,500 kept steps on sampler seeds 1, 5, 9, 61-65 (24,000 on seed 1 while it was
        fitted in logit, 2026-11-24); the virtual test at 500-1,000.  A quick run is not
        expected to converge and says so."""
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
class OptimumPart:
    """An exhaust calibrated against seed Table 2 with the mass kept, on its certified basis.

    name : the model.  calibration : the optimum (``CalibrationResult``).  polished : its ends
    polished on the full model (the beam's ``run_calibration``) or not (the shell's, as
    ``run_sampling`` places its walkers; the beam's in a quick run, polished on its basis
    only, ``DemoSettings.exact_polish``).  front : ``inference.pareto_front_mass``'s points,
    one per ``FRONT_WEIGHTS``.  basis : the basis's ``summary()`` with its build "wall_s",
    "cpu_s" and "error_at_optimum" (a full solve there), or None without a basis.  search, rom:
    the problem on that basis and the basis (``surrogates.sampling_problem``), for
    ``run_sampling`` to reuse."""

    name: str
    calibration: object
    polished: bool
    front: tuple
    basis: dict | None
    search: object = field(default=None, repr=False, compare=False)
    rom: object = field(default=None, repr=False, compare=False)


@dataclass(frozen=True)
class ShellCheck:
    """The demo's shell mesh against the default density 32, by full solves: ``density``; the
    12 frequencies at the initial design (``initial_hz``, (12,)) and at the seed optimum
    (``optimum_hz``, (n_test,), paired as the problem pairs them); Expr and mass there; wall and
    CPU seconds of the check (its build and two solves)."""

    density: int
    initial_hz: np.ndarray
    optimum_hz: np.ndarray
    expr: float
    mass_kg: float
    wall_s: float
    cpu_s: float


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
    """Everything the demo computed; the discovery parts are None when not run.  fe, seed,
    seed_optimum, shell_check: the shell exhaust; beam_optimum, seed_discovery and the virtual
    test: the beam exhaust."""

    settings: DemoSettings
    fe: FePart
    seed: CalibrationPart
    seed_optimum: OptimumPart
    shell_check: ShellCheck | None
    beam_optimum: OptimumPart
    seed_discovery: DiscoveryPart | None
    virtual_test: VirtualTest
    uff: Path
    identified: IdentifiedPart
    virtual: CalibrationPart
    virtual_discovery: DiscoveryPart | None


def demo_reference(case: str) -> dict:
    """The stored importance-sampling reference of the demo's posterior ``case`` ("seed_shell":
    the seed case; "virtual": the virtual test at the default settings), package data made by
    ``studies/posterior_reference.py``; ``run_sampling`` judges the draws by it when the
    posterior is the one it was made for (``inference.reference_check``)."""
    name = f"data/posterior_reference_demo_{case}.json"
    return json.loads(resources.files("bayesupdate").joinpath(name).read_text())


#: the steps of each task of the demo (``run_demo``); "ema" (the virtual test's FRFs and their
#: identification) runs first in this process, as the virtual test's two tasks need its modes
TASK_STEPS = {
    "fe": ("shell exhaust vs seed Table 1",),
    "shell": (
        "seed case (shell): certified basis, optimum and front vs Table 2",
        "seed case (shell): posterior",
        "seed case (shell): the optimum at mesh density 32",
    ),
    "beam": ("beam exhaust: optimum and front vs Table 2",),
    "seed_discovery": ("beam exhaust vs Table 2: discovery",),
    "ema": ("virtual test (beam): simulate FRFs", "virtual test: identify"),
    "virtual_calibration": ("virtual test: calibrate + posterior",),
    "virtual_discovery": ("virtual test: discovery",),
}


def demo_tasks(settings: DemoSettings) -> tuple[str, ...]:
    """The independent tasks ``run_demo`` hands to its executor, in the order they start (a
    worker takes the next as it finishes one), chosen so that two workers end together
    (``benchmarks/demo_steps.py --workers 2``, CPU seconds per task with cached bases, at load
    5-9 on the 2 cores, 2026-11-29).  Quick: {FE part 1.2, virtual calibration 21, virtual
    discovery 39} against {shell seed case 54, beam optimum 15}: 61 against 69, the beam
    optimum taken by the first worker free; no split of these five ends closer.  This process
    draws the figures (27 s) as the parts arrive: the FE part first so that its figures are
    drawn early, the beam optimum last as it has no figures (the last task's are drawn after
    it, on one core).  With an empty cache the shell's basis adds 23 s to its task: 77 against
    76.  Full (``bayesupdate demo``'s own two workers, wall seconds of each task on a quiet
    machine, 2026-11-29): {FE part 1, shell seed case 78-80 (96-97 building its basis), seed
    discovery 41-46, virtual discovery 33-39} against {virtual calibration 77-88, beam optimum
    57-69}; the virtual discovery, whose figures are the fewest, ends last.  The whole command:
    164.7, 167.8, 173.1 s with cached bases (the order before, FE part, seed discovery, shell,
    virtual discovery, virtual calibration, beam: 171.6, 168.8), 176.1 and 176.2 s from an empty
    cache folder (before: 183.5, 182.8), its workers ending 10-13 s apart (before: 12-17).
    --quick keeps discovery where it has something to find (the virtual test's hidden
    effect)."""
    if settings.quick:
        return ("fe", "shell", "virtual_calibration", "virtual_discovery", "beam")
    return ("fe", "virtual_calibration", "shell", "seed_discovery", "beam", "virtual_discovery")


def demo_steps(settings: DemoSettings) -> tuple[str, ...]:
    """The steps ``run_demo`` announces, in the order a serial run takes them ("ema" first,
    then ``demo_tasks``)."""
    return tuple(name for task in ("ema", *demo_tasks(settings)) for name in TASK_STEPS[task])


def _silent(task: str, name: str | None) -> None:
    return None


def run_demo(
    settings: DemoSettings,
    step: Callable[[str, str | None], None] = _silent,
    executor=None,
    on_part: Callable[[str, object], None] | None = None,
) -> DemoResults:
    """Run both parts (module docstring): "ema" in this process, then ``demo_tasks`` on
    ``executor`` (``run_tasks``; None: serial, in this process).

    step(task, name) : announces each step of ``TASK_STEPS`` as it starts and, with name None,
    the task's end; called where the task runs (a worker process: it must pickle, e.g. a
    module-level class, and may print to stderr only).  on_part(task, record) : called in this
    process as each part's record arrives (in arrival order; "ema" with the first of the
    others), e.g. to draw that part's figures while the other tasks run.  Each worker pins
    BLAS to one thread (``compute.executors``) and reads the reduced bases from the one on-disk
    cache (``compute.cache``); the sampler's progress bars are shown by a serial run only."""
    from bayesupdate.compute.executors import executor_or_serial

    executor = executor_or_serial(executor)
    if executor.workers > 1:
        settings = replace(settings, progress=False)  # bars of two processes would interleave
    ema = {"ema": _run_task((settings, step), "ema")}
    parts = run_tasks(settings, demo_tasks(settings), step, executor, on_part, ema)
    return _assemble(settings, parts)


def run_tasks(
    settings: DemoSettings, tasks, step=_silent, executor=None, on_part=None, done=None
) -> dict:
    """{task: record} of ``tasks`` (names of ``TASK_STEPS``) run on ``executor`` (None:
    serial) through ``executor.map``: each task a pure function of ``settings`` and the files
    in ``settings.out``, so the records are the same bits on every executor.  ``step``,
    ``on_part``: as ``run_demo``; ``done``: records computed before, handed to ``on_part``
    with the first arrival and returned with the others."""
    from bayesupdate.compute.executors import executor_or_serial

    tasks = tuple(tasks)
    parts = dict(done or {})
    pending = list(parts)

    def arrived(index, record):
        parts[tasks[index]] = record
        pending.append(tasks[index])
        while pending and on_part is not None:
            name = pending.pop(0)
            on_part(name, parts[name])

    executor_or_serial(executor).map(_run_task, tasks, (settings, step), progress=arrived)
    return parts


def _run_task(shared, task: str):
    """One task of ``demo_tasks`` (or "ema"): its record; ``shared`` is (settings, step)."""
    settings, step = shared
    record = _TASKS[task](settings, iter(TASK_STEPS[task]), lambda name: step(task, name))
    step(task, None)
    return record


def _fe_task(settings, names, step) -> FePart:
    step(next(names))
    return fe_part(SHELL_MODEL)


@dataclass(frozen=True)
class ShellPart:
    """The shell seed case's task: the posterior, the optimum and the mesh check."""

    seed: CalibrationPart
    optimum: OptimumPart
    check: ShellCheck


def _shell_task(settings, names, step) -> ShellPart:
    step(next(names))
    prepared = prepare(seed_study(settings))
    optimum = optimum_part(prepared, polished=False, certify=False)
    step(next(names))
    path = settings.out / "seed_case.h5"
    options = SamplingOptions(
        out=path, progress=settings.progress, reference=demo_reference("seed_shell")
    )
    run = run_sampling(prepared, options, optimum.calibration, (optimum.search, optimum.rom))
    optimum = _with_error_at_optimum(optimum, run)
    step(next(names))
    check = check_at_density(prepared, optimum.calibration)
    return ShellPart(CalibrationPart(run, path, prepared.problem), _light(optimum), check)


def _with_error_at_optimum(optimum: OptimumPart, run: SamplingRun) -> OptimumPart:
    """``optimum`` (made with ``certify=False``) with its basis's "error_at_optimum" taken from
    ``run``: ``run_sampling`` full-solves the basis at the optimum it was given
    (``pipelines.sample._basis_at_optimum``, recorded in the posterior's ``diagnostics["rom"]``),
    so the demo does not solve the same point in full a second time (a shell solve at mesh
    density 16, about 0.7 s CPU).  Unchanged when the run has no basis record."""
    rom = run.posterior.diagnostics.get("rom") or {}
    if optimum.basis is None or "error_at_optimum" not in rom:
        return optimum
    return replace(optimum, basis={**optimum.basis, "error_at_optimum": rom["error_at_optimum"]})


def _light(optimum: OptimumPart) -> OptimumPart:
    """``optimum`` without its search problem and basis (used inside its task only; they would
    only add megabytes to the record a worker sends back)."""
    return replace(optimum, search=None, rom=None)


def _beam_task(settings, names, step) -> OptimumPart:
    step(next(names))
    beam = prepare(_study(settings, "paper:ema", BEAM_MODEL))
    return _light(optimum_part(beam, polished=True, exact=settings.exact_polish))


def _seed_discovery_task(settings, names, step) -> DiscoveryPart:
    step(next(names))
    return _discovery_part(settings, "paper:ema", settings.out / "seed_discovery.h5")


@dataclass(frozen=True)
class EmaPart:
    """The virtual test's FRFs (the truth and the UFF file) and their identification."""

    test: VirtualTest
    uff: Path
    identified: IdentifiedPart


def _ema_task(settings, names, step) -> EmaPart:
    step(next(names))
    test, uff = _virtual_test_part(settings)
    step(next(names))
    return EmaPart(test, uff, _identify_part(settings.out, uff))


def _virtual_modes(settings) -> str:
    """The identified modes' file (written by the "ema" task), the virtual test's data source."""
    return str(settings.out / "virtual_modes.h5")


def _virtual_calibration_task(settings, names, step) -> CalibrationPart:
    step(next(names))
    return _calibration_part(settings, _virtual_modes(settings), settings.out / "virtual_case.h5")


def _virtual_discovery_task(settings, names, step) -> DiscoveryPart:
    step(next(names))
    path = settings.out / "virtual_discovery.h5"
    return _discovery_part(settings, _virtual_modes(settings), path)


_TASKS = {
    "fe": _fe_task,
    "shell": _shell_task,
    "beam": _beam_task,
    "seed_discovery": _seed_discovery_task,
    "ema": _ema_task,
    "virtual_calibration": _virtual_calibration_task,
    "virtual_discovery": _virtual_discovery_task,
}


def _assemble(settings: DemoSettings, parts: dict) -> DemoResults:
    shell, ema = parts["shell"], parts["ema"]
    return DemoResults(
        settings, parts["fe"], shell.seed, shell.optimum, shell.check, parts["beam"],
        parts.get("seed_discovery"), ema.test, ema.uff, ema.identified,
        parts["virtual_calibration"], parts.get("virtual_discovery"),
    )  # fmt: skip


def _study(
    settings: DemoSettings, data_source, model: dict = BEAM_MODEL, starts: int | None = None
) -> StudyConfig:
    """The demo's study of ``model`` against ``data_source``; ``starts``: the optimizer's
    starts (None: ``settings.starts``)."""
    starts = settings.starts if starts is None else starts
    document = {
        "model": dict(model),
        "data": {"source": data_source},
        "pairing": {"method": "auto"},
        "objective": {"mass_kg": paper.MEASURED_MASS_KG, "mass_weight": 10.0},
        "optimizer": {"starts": starts, "seed": settings.seed},
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


def seed_study(settings: DemoSettings) -> StudyConfig:
    """The demo's seed case: the shell exhaust (``SHELL_MODEL``) against seed Table 2, the
    measured mass kept, the demo's optimizer and sampler settings."""
    return _study(settings, "paper:ema", SHELL_MODEL)


def fe_part(model: dict) -> FePart:
    """The built-in model ``model`` ({"source", "options"}) at its initial design: 12 modes
    with their energies and characters (plane and node count along the gas path)."""
    from bayesupdate.models import get_model
    from bayesupdate.models.exhaust import mode_character

    fe = get_model(model["source"], **model.get("options", {}))
    result = fe.solve(n_modes=12, energies=True)
    return FePart(fe, result, mode_character(fe.structure, result.modes.shapes))


def optimum_part(
    prepared: PreparedStudy,
    polished: bool,
    weights: tuple = FRONT_WEIGHTS,
    exact: bool = True,
    certify: bool = True,
) -> OptimumPart:
    """The optimum against the study's data and the front (one fit per mass-term weight in
    ``weights``), both on the certified basis that ``run_sampling`` builds for this study
    (``pipelines.surrogates.sampling_problem``).  ``polished``: as ``run_calibration`` (ends
    polished on the basis, then on the full model; with ``exact=False`` on the basis only),
    else as ``run_sampling`` places its walkers (no polish).  ``certify``: the basis checked at
    the optimum by a full solve ("error_at_optimum"); False where ``run_sampling`` is handed
    this optimum and solves there itself (``_with_error_at_optimum``; NaN until then)."""
    import time

    from bayesupdate.inference.optimize import (
        CalibrationSettings,
        calibrate,
        pareto_front_mass,
    )
    from bayesupdate.pipelines.surrogates import sampling_problem

    opt, cfg = prepared.study.optimizer, prepared.study.sampler
    t0, c0 = time.perf_counter(), time.process_time()
    search, rom = sampling_problem(prepared.problem, None, cfg.reduced, cfg.reduced_tol)
    build = {"wall_s": time.perf_counter() - t0, "cpu_s": time.process_time() - c0}
    fit = CalibrationSettings(
        starts=opt.starts, seed=opt.seed, method=opt.method, design=opt.design,
        polish=opt.polish if polished else False,
    )  # fmt: skip
    refine = prepared.problem if polished and exact and rom is not None else None
    calibration = calibrate(search, fit, refine=refine)
    basis = None
    if rom is not None:
        error = rom.certify_at(calibration.theta[None, :], search.names)[1] if certify else np.nan
        basis = {**rom.summary(), **build, "error_at_optimum": float(error)}
    front = pareto_front_mass(
        search, paper.MEASURED_MASS_KG, tuple(weights), starts=FRONT_STARTS, seed=opt.seed,
        polish=False,
    )  # fmt: skip
    name = prepared.study.model.source
    on_full = polished and (refine is not None or rom is None)
    return OptimumPart(name, calibration, on_full, tuple(front), basis, search, rom)


def check_at_density(prepared: PreparedStudy, calibration, density: int = 32) -> ShellCheck:
    """The shell model of ``prepared`` rebuilt at ``density`` (full solves): Table 1's design
    and the optimum ``calibration`` evaluated with the same pairing (``ShellCheck``)."""
    import time

    from bayesupdate.models import get_model

    t0, c0 = time.perf_counter(), time.process_time()
    options = {**prepared.study.model.options, "mesh_density": density}
    fe = get_model(prepared.study.model.source, **options)
    initial = fe.solve(n_modes=12).frequencies_hz
    problem = replace(prepared.problem, model=fe)
    evaluation = problem.evaluate(calibration.theta)
    return ShellCheck(
        density, np.asarray(initial), evaluation.frequencies_hz,
        float(problem.expr(evaluation.frequencies_hz)), float(evaluation.mass_kg),
        time.perf_counter() - t0, time.process_time() - c0,
    )  # fmt: skip


def _calibration_part(settings, data_source, path: Path) -> CalibrationPart:
    """The virtual test on the beam exhaust: its optimum (``run_calibration``; in a quick run
    polished on the certified basis only, ``DemoSettings.exact_polish``, which the sampler then
    reuses), then the posterior, written to ``path`` and judged by the stored reference of the
    default virtual test (it applies only when ``data_source`` holds that test's modes)."""
    from bayesupdate.pipelines.calibrate import run_calibration

    prepared = prepare(_study(settings, data_source))
    reference = demo_reference("virtual")
    options = SamplingOptions(out=path, progress=settings.progress, reference=reference)
    if settings.exact_polish:
        run = run_sampling(prepared, options, calibration=run_calibration(prepared))
    else:
        part = optimum_part(prepared, polished=True, weights=(), exact=False, certify=False)
        run = run_sampling(prepared, options, part.calibration, (part.search, part.rom))
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
    """Discovery of what the beam exhaust misses against ``data_source``, written to ``path``.
    A quick run refits fewer candidates and calibrates its baseline from one start (with the
    reference start): on the virtual test (seed 0) the default 4 starts' 5 ends all reach one
    optimum, the same design values to 8 digits as from 1 start, at 8.1 s CPU against 3.4 s."""
    options = {"seed": settings.seed}
    if settings.quick:
        options.update(
            baseline_starts=1, quick_refits=5, per_kind=1, max_refits=2, loo_top=1, loo_draws=100
        )
    study = parse_study({"model": {"source": "exhaust"}, "data": {"source": data_source}}, "demo")
    run = discover_study(study, DiscoveryRequest(DiscoverySettings.from_flat(**options)))
    write_discovery(path, run.result, command="demo")
    return DiscoveryPart(run, path)


def side_by_side(results: DemoResults, solves: int = 3) -> dict:
    """The two exhausts' records (``pipelines.exhaust_comparison.demo_comparison``): Table 1 and
    the speed measured here (the shell at the demo's mesh), each with the optimum and front this
    run computed."""
    from bayesupdate.pipelines.exhaust_comparison import calibrated_in_run, demo_comparison

    shell = f"this run: certified basis, {results.settings.starts} starts, not polished"
    where = "full solves" if results.beam_optimum.polished else "the certified basis"
    beam = f"this run: certified basis, {results.settings.starts} starts, polished on {where}"
    calibrated = {
        "exhaust": calibrated_in_run(results.beam_optimum, beam),
        "exhaust_shell": calibrated_in_run(results.seed_optimum, shell),
    }
    return demo_comparison(calibrated, {"exhaust_shell": SHELL_MODEL["options"]}, solves)
