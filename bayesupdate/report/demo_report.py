"""The demo's figures, report and terminal summary, made from the records of
``pipelines.demo.run_demo`` (the side effects of the demo: PNG files, report.html/report.md)."""

from pathlib import Path

import numpy as np

from bayesupdate.discovery.results_io import discovery_summary
from bayesupdate.inference.reference_check import MEAN_TOLERANCE_SD, SD_TOLERANCE
from bayesupdate.models import exhaust_paper as paper
from bayesupdate.pipelines.demo import (
    IDENTIFIED_BELOW_HZ,
    CalibrationPart,
    DemoResults,
    DiscoveryPart,
    EmaPart,
    FePart,
    IdentifiedPart,
    OptimumPart,
    ShellCheck,
    ShellPart,
)
from bayesupdate.pipelines.simulate import VirtualTest
from bayesupdate.report.document import Alert, Document, Figure, Section, Table
from bayesupdate.report.render import write_report

_PLOT_CAPTIONS = {
    "residuals": "Per-mode residuals at the optimum (test vs model, swapped modes marked).",
    "trace": "Trace of the walkers (burn-in shaded) for each parameter.",
    "pair": "Posterior pair plot: marginals and pairwise correlations.",
    "predictive": "Posterior predictive frequencies (90 % bands) against the test.",
    "design_vs_reference": "Design variables: posterior beside the seed's Table 3 optimum.",
}


def _rel(path: Path, out: Path) -> str:
    return str(Path(path).relative_to(out))


def _figures(pairs, out) -> tuple:
    return tuple(Figure(_rel(p, out), caption) for p, caption in pairs)


def _fe_section(fe: FePart, figures, out) -> Section:
    r = fe.result
    rows = []
    for i, (f_paper, f_model) in enumerate(zip(paper.TABLE1_FEA_HZ, r.frequencies_hz, strict=True)):
        ch = fe.character[i]
        rows.append(
            (i + 1, f_paper, f_model, 100 * (f_model / f_paper - 1), ch["plane"], ch["nodes"])
        )
    rel = r.frequencies_hz / paper.TABLE1_FEA_HZ - 1
    first = enumerate(fe.character[:3], start=1)
    modes = ", ".join(f"mode {i} {c['plane']}{c['nodes']}" for i, c in first)
    text = (
        f"{_model_words(fe.model)} at the initial design (all walls 1.0 mm, shell densities "
        f"10,000 kg/m^3) weighs {r.mass_kg:.3f} kg (seed: 12.29 kg). Its first 12 elastic "
        f"modes match seed Table 1 with RMS {100 * np.sqrt(np.mean(rel**2)):.2f} % and max "
        f"{100 * np.abs(rel).max():.2f} %. Plane (H horizontal, V vertical) and node count "
        f"along the gas path: {modes}; the paper describes H2, V2, H3."
    )
    table = Table(
        ("mode", "seed Table 1 [Hz]", "model [Hz]", "error [%]", "plane", "nodes"),
        tuple(rows),
        caption="FE normal modes vs seed Table 1",
    )
    return Section("The FE model and seed Table 1", (text, table, *_figures(figures, out)))


def _model_words(model) -> str:
    """What the model is, in words, with its size."""
    n_dof = int(model.structure.n_dof)
    if model.name == "exhaust_shell":
        density = model.structure.metadata.get("mesh_density")
        mesh = "" if density is None else f"mesh density {density}, "
        return (
            f"The shell exhaust (`exhaust_shell`, {mesh}{n_dof:,} DOFs: the catalyst and both "
            "mufflers as closed shell bodies, the pipes as beams)"
        )
    return f"The beam exhaust (`{model.name}`, {n_dof:,} DOFs)"


def _swap_note(table) -> str:
    """Which model modes trade places at the optimum: a swap is reported, never hidden (the pairing
    rule, ``inference.pairing``: each test mode keeps the model mode whose shape matches its
    reference shape)."""
    moved = [f"test {i + 1} -> model {m}" for i, m in enumerate(table.model_mode) if m != i + 1]
    return (
        "; MODE SWAP: model modes trade order (" + ", ".join(moved) + "), each test mode paired "
        "with the model mode of its reference shape (MAC column)"
    )


def _calibration_sections(
    tag, title, part: CalibrationPart, plots, out, truth=None, how: str = ""
) -> list[Section]:
    """The optimum (design and residual tables) and the posterior (table and figures) of a case;
    ``tag`` "seed" adds the seed's Table 4 and Expr, ``truth`` a column of true values, ``how``
    a note on how the optimum was found (the design table's caption)."""
    c, p = part.run.calibration, part.run.posterior
    post_rows = tuple(
        (n, s["mean"], s["sd"], s["hdi_low"], s["hdi_high"], s["r_hat"], s["ess_bulk"])
        for n, s in part.run.summary.items()
    )
    post = Table(
        ("parameter", "mean", "sd", "HDI 90 % low", "HDI 90 % high", "R-hat", "bulk ESS"),
        post_rows,
        caption=f"Posterior: {p.chain.shape[1]} walkers x {p.chain.shape[0]} steps, "
        f"{p.evaluations} model evaluations, {p.wall_s:.0f} s",
    )
    figs = tuple(
        Figure(_rel(path, out), _PLOT_CAPTIONS.get(Path(path).stem, Path(path).stem))
        for path in plots
    )
    return [
        Section(f"{title}: optimum", (_design_table(c, truth, how), _residual_table(c, tag))),
        Section(
            f"{title}: posterior",
            (*_convergence_warning(p), *_reference_accuracy(p), post, *figs),
        ),
    ]


def _design_table(c, truth=None, how: str = "") -> Table:
    """The optimum's design values beside seed Table 3 (and the truth when known); ``how``
    ends the caption."""
    rows = []
    for i, name in enumerate(c.names):
        init = paper.TABLE3_INITIAL_SI.get(name)
        opt_paper = paper.TABLE3_OPTIMUM_SI.get(name)
        ours = float(c.theta[i])
        same_way = None
        if init is not None and opt_paper is not None:
            same_way = bool(np.sign(ours - init) == np.sign(opt_paper - init))
        row = [name, init, opt_paper, ours, same_way]
        if truth is not None:
            row.append(truth.get(name))
        rows.append(tuple(row))
    headers = [
        "parameter (SI)",
        "initial (Table 3)",
        "seed optimum (Table 3)",
        "ours",
        "moves the paper's way",
    ]
    if truth is not None:
        headers.append("true value")
    return Table(
        tuple(headers),
        tuple(rows),
        caption="Point optimum (bounded least squares, "
        f"{c.starts} starts, {c.converged_starts} reach the best{how})",
    )


def _residual_table(c, tag) -> Table:
    """Test vs model frequencies at the optimum (with seed Table 4 for the seed case)."""
    t = c.table
    freq_rows = []
    for i in range(t.test_hz.size):
        row = [
            i + 1,
            t.test_hz[i],
            t.model_hz[i],
            t.error_pct[i],
            None if np.isnan(t.mac[i]) else t.mac[i],
            int(t.model_mode[i]),
        ]
        if tag == "seed":
            row.insert(2, paper.TABLE4_FINAL_HZ[i])
        freq_rows.append(tuple(row))
    fheaders = ["mode", "test [Hz]", "model [Hz]", "error [%]", "MAC", "model mode"]
    if tag == "seed":
        fheaders.insert(2, "seed Table 4 [Hz]")
    return Table(
        tuple(fheaders),
        tuple(freq_rows),
        caption=f"Residuals at the optimum: Expr (seed eq. 19) = {c.expr:.4f}"
        + (f" (seed: {paper.EXPR_FINAL_REPORTED})" if tag == "seed" else "")
        + (f", mass {c.mass_kg:.3f} kg" if c.mass_kg is not None else "")
        + (_swap_note(c.table) if c.swapped else "; no mode swap"),
    )


def _convergence_warning(posterior) -> tuple:
    """A visible warning when the posterior missed its R-hat / ESS / tau targets."""
    report = posterior.diagnostics.get("convergence") or {}
    if posterior.converged:
        return ()
    reason = report.get("reason") or "it stopped before its convergence check passed"
    return (Alert(f"this posterior did not converge: {reason}. Read its numbers with care."),)


def _reference_accuracy(posterior) -> tuple:
    """The draws against the stored reference of this posterior (``inference.reference_check``):
    a line when they meet it, a warning when not; nothing when no reference applies."""
    ref = posterior.diagnostics.get("reference") or {}
    if not ref.get("applies"):
        return ()
    verdict = (
        f"Against the stored importance-sampling reference of this posterior: worst "
        f"{ref['worst']} (criterion: means within {MEAN_TOLERANCE_SD} sd, sds within "
        f"{100 * SD_TOLERANCE:.0f} %)"
    )
    if ref["accurate"]:
        return (f"{verdict}: met.",)
    return (
        Alert(
            f"{verdict}: NOT met, although R-hat and the ESS may pass: the chain under-visits "
            "part of the posterior. Sample longer (`bayesupdate sample` with more [sampler] "
            "steps or a higher target_ess) before relying on these sds."
        ),
    )


def _basis_section(optimum: OptimumPart, check: ShellCheck | None, fe: FePart) -> Section:
    """The seed case's certified basis (size, error, cost) and the demo's mesh against the
    default density (``ShellCheck``): what the shell's speed and its coarser mesh cost."""
    b, c = optimum.basis or {}, optimum.calibration
    blocks = []
    if b:
        blocks.append(
            f"The optimum, the front and the posterior run on the certified reduced basis that "
            f"`bayesupdate sample` builds for this study: {b['size']} vectors, largest relative "
            f"frequency error {b['max_rel_error']:.1e} on its validation points (tolerance "
            f"{b['tol']:g}, {b['n_modes']} modes), built in {b['wall_s']:.0f} s wall, "
            f"{b['cpu_s']:.0f} s CPU (built again by the posterior's `run_sampling`); at the "
            f"optimum a full solve differs by {b['error_at_optimum']:.1e}."
        )
    if check is not None:
        ours = fe.result.frequencies_hz
        d_init = 100 * (ours / check.initial_hz - 1)
        d_opt = 100 * (c.table.model_hz / check.optimum_hz - 1)
        rel = check.initial_hz / paper.TABLE1_FEA_HZ - 1
        blocks.append(
            f"The mesh: this run's shell model against the same model at mesh density "
            f"{check.density} (the default), by full solves ({check.wall_s:.0f} s wall, "
            f"{check.cpu_s:.0f} s CPU): at the initial design the 12 frequencies differ by "
            f"{d_init.min():+.2f} ... {d_init.max():+.2f} % (Table 1 at density "
            f"{check.density}: RMS {100 * np.sqrt(np.mean(rel**2)):.2f} %, max "
            f"{100 * np.abs(rel).max():.2f} %); at the optimum by {d_opt.min():+.2f} ... "
            f"{d_opt.max():+.2f} %, where Expr is {check.expr:.4f} at density {check.density} "
            f"against {c.expr:.4f} here (mass {check.mass_kg:.3f} kg)."
        )
    return Section("Seed case: the certified basis and the mesh", tuple(blocks))


def _beam_sections(optimum: OptimumPart) -> list[Section]:
    """The beam exhaust calibrated against Table 2 (mass kept): its optimum (design and
    residual tables); its front is drawn in the side-by-side section."""
    c, b = optimum.calibration, optimum.basis or {}
    how = "; polished on full solves" if optimum.polished else "; on the certified basis"
    polish = (
        "every end polished on the full model"
        if optimum.polished
        else "every end polished on the certified basis (a quick run: not again on full solves)"
    )
    text = (
        "The beam exhaust (`exhaust`) calibrated the same way, for the side by side: its "
        "optimum from its own multi-start calibration (`bayesupdate calibrate`'s path: the "
        f"search on its certified basis of {b.get('size', '-')} vectors, built in "
        f"{b.get('cpu_s', float('nan')):.1f} s CPU, {polish}). Its posterior is not sampled here."
    )
    tables = (_design_table(c, how=how), _residual_table(c, "seed"))
    return [Section("The beam exhaust against Table 2: optimum", (text, *tables))]


def _virtual_sections(
    truth: VirtualTest, identified: IdentifiedPart, figures, out
) -> list[Section]:
    modes = identified.modes
    f_true = truth.frequencies_hz
    z_true = truth.damping_ratio
    in_band = f_true < IDENTIFIED_BELOW_HZ
    rows = []
    for i, (f, z) in enumerate(zip(f_true[in_band], z_true[in_band], strict=True)):
        j = int(np.argmin(np.abs(modes.frequencies_hz - f)))
        rows.append(
            (
                i + 1,
                f,
                modes.frequencies_hz[j],
                100 * (modes.frequencies_hz[j] / f - 1),
                z,
                modes.damping_ratio[j],
                modes.mpc[j],
            )
        )
    text = (
        f"A 'true' beam exhaust (`exhaust`) with known design values and a hidden "
        f"{', '.join(truth.effects)}"
        f" is tested as in the seed: roving hammer over 20 points, accelerometers at points "
        f"{truth.reference_points[0]} (V) and {truth.reference_points[1]} (H), 40 FRFs "
        "with 1 % noise on the time signals, 0-150 Hz. LSCE with automatic bands, "
        "stabilization and pole clustering, then LSFD, identify the modes with no pole picked "
        "by hand."
    )
    table = Table(
        (
            "mode",
            "true [Hz]",
            "identified [Hz]",
            "error [%]",
            "true damping",
            "identified damping",
            "MPC",
        ),
        tuple(rows),
        caption="Virtual test: identified vs true modes below 140 Hz",
    )
    return [Section("Virtual test: from FRFs to modes", (text, table, *_figures(figures, out)))]


def discovery_headline(part: DiscoveryPart) -> str:
    """One paragraph: verdict, named effect, flagged modes, gap before -> after, scan size."""
    summary = discovery_summary(part.run.result)
    named = summary["named_effect"]
    name = "none" if named is None else f"{named['kind']}@{named['location']}"
    return (
        f"verdict: {summary['verdict']} (named effect: {name}); flagged modes "
        f"{summary['flagged_modes']}; gap (Expr, seed eq. 19) {summary['gap_before']:.4f}"
        f" -> {summary['gap_after']:.4f}; {summary['scanned']} candidate placements "
        f"scanned in {summary['wall_s']:.0f} s. {summary['reason']}"
    )


def _discovery_table(part: DiscoveryPart) -> Table:
    """The ten best candidates by evidence."""
    rows = tuple(
        (
            c["kind"],
            c["location"],
            c["log_evidence"],
            c["log_bayes_factor"],
            c["posterior_probability"],
            c["loo"],
            c["expr"],
        )
        for c in discovery_summary(part.run.result)["candidates"][:10]
    )
    return Table(
        (
            "kind",
            "location",
            "log evidence",
            "ln BF vs baseline",
            "posterior probability",
            "LOO elpd",
            "Expr after refit",
        ),
        rows,
        caption="Candidate ranking (best evidence first)",
    )


_DISCOVERY_CAPTIONS = {
    "residuals": "Per-mode residuals before and after adding the named effect.",
    "localization": "Localization map: where on the structure the misfit points.",
    "ranking": "Candidate ranking by evidence.",
}


def _discovery_section(title, part: DiscoveryPart, plots, out) -> Section:
    blocks = [discovery_headline(part), _discovery_table(part)]
    blocks += [
        Figure(_rel(p, out), _DISCOVERY_CAPTIONS.get(Path(p).stem, Path(p).stem)) for p in plots
    ]
    return Section(title, tuple(blocks))


#: the modes whose strain-energy density maps a report shows (the seed shows modes 1 and 2)
SED_MAP_MODES = 4


def _fe_figures(fe: FePart, folder: Path) -> list:
    from bayesupdate.report import energy_maps, fe_figures

    structure, result = fe.model.structure, fe.result
    maps = []
    if energy_maps.has_shells(structure):  # a shell model: the seed's Fig. 6 for the first modes
        maps = energy_maps.write_energy_density_maps(structure, result, folder, SED_MAP_MODES)
    return [
        (
            fe_figures.plot_layout(structure, folder / "fe_layout.png"),
            "The exhaust FE model (plan and elevation) with the 20 sensor points.",
        ),
        (
            fe_figures.plot_fe_mode_shapes(structure, result, folder / "fe_modes.png"),
            "First six FE mode shapes at the initial design.",
        ),
        (
            fe_figures.plot_strain_energy(result, folder / "fe_strain_energy.png"),
            "Modal strain energy per part (seed section 3.2).",
        ),
        *maps,
    ]


def _calibration_figures(part: CalibrationPart, folder: Path) -> list:
    from bayesupdate.inference import plots as inference_plots
    from bayesupdate.inference.results import read_result

    folder.mkdir(exist_ok=True)
    table3 = inference_plots.DesignReference(
        paper.TABLE3_INITIAL_SI, paper.TABLE3_OPTIMUM_SI, "seed Table 3 optimum"
    )
    return inference_plots.save_all(read_result(part.path), folder, table3)


def _identification_figures(truth: VirtualTest, identified: IdentifiedPart, folder: Path) -> list:
    from bayesupdate.ema import plots as ema_plots

    ident, frfs, modes = identified.identification, identified.frfs, identified.modes
    labels = list(truth.dof_labels)
    rows = [labels.index(lab) for lab in modes.dof_labels]
    in_band = truth.frequencies_hz < IDENTIFIED_BELOW_HZ
    folder.mkdir(exist_ok=True)
    return [
        (
            ema_plots.plot_stabilization(ident, frfs, folder / "stabilization.png"),
            "Stabilization diagram (LSCE orders) over the CMIF, selected poles marked.",
        ),
        (
            ema_plots.plot_frf_fit(ident, frfs, folder / "frf_fit.png"),
            "Measured vs synthesized FRFs (LSFD) at a few DOFs.",
        ),
        (
            ema_plots.plot_mac(
                modes.shapes,
                truth.shapes[rows][:, in_band],
                folder / "mac.png",
                title="MAC: identified vs true shapes",
            ),
            "MAC between identified and true (FE) mode shapes.",
        ),
        (
            ema_plots.plot_mode_shapes(modes, folder / "mode_shapes.png"),
            "Identified mode shapes at the 20 sensor points (V and H).",
        ),
    ]


def _discovery_figures(part: DiscoveryPart | None, folder: Path) -> list:
    from bayesupdate.discovery.plots import save_plots

    if part is None:
        return []
    folder.mkdir(exist_ok=True)
    return save_plots(part.run.result, folder, part.run.model.structure)


def part_figures(task: str, record, out: Path) -> dict:
    """The figures of one task of ``pipelines.demo.run_demo`` (its ``on_part(task, record)``:
    drawn as each part arrives, while the other tasks run), written under ``out/figures``;
    {part name: its figures} (the keys of ``demo_figures``)."""
    figures = out / "figures"
    figures.mkdir(parents=True, exist_ok=True)
    if task == "fe":
        return {"fe": _fe_figures(record, figures)}
    if task == "shell":
        return {"seed": _calibration_figures(record.seed, figures / "seed")}
    if task == "ema":
        ema = figures / "ema"
        return {"identified": _identification_figures(record.test, record.identified, ema)}
    if task == "virtual_calibration":
        return {"virtual": _calibration_figures(record, figures / "virtual")}
    if task in ("seed_discovery", "virtual_discovery"):
        return {task: _discovery_figures(record, figures / task)}
    return {}  # the beam optimum: its front is drawn with the side by side


def demo_figures(results: DemoResults) -> dict:
    """Write every figure into ``out/figures`` (``part_figures`` of every part); {part name:
    its figures}."""
    r, out = results, results.settings.out
    records = {
        "fe": r.fe,
        "shell": ShellPart(r.seed, r.seed_optimum, r.shell_check),
        "ema": EmaPart(r.virtual_test, r.uff, r.identified),
        "virtual_calibration": r.virtual,
        "seed_discovery": r.seed_discovery,
        "virtual_discovery": r.virtual_discovery,
    }
    figures = {}
    for task, record in records.items():
        figures.update(part_figures(task, record, out))
    return figures


def _seed_sections(results: DemoResults, plots, out) -> list[Section]:
    """The shell seed case (optimum, posterior, basis and mesh), then the beam's optimum."""
    error = (results.seed_optimum.basis or {}).get("error_at_optimum", float("nan"))
    how = (
        "; on the certified basis, not polished, as the sampler places its walkers; a full "
        f"solve there differs by {error:.1e}"
    )
    title = "Seed case (Table 2, shell exhaust)"
    sections = _calibration_sections("seed", title, results.seed, plots, out, how=how)
    sections.append(_basis_section(results.seed_optimum, results.shell_check, results.fe))
    return sections + _beam_sections(results.beam_optimum)


def write_demo_report(
    results: DemoResults, comparison: dict | None = None, figures: dict | None = None
) -> tuple[Path, Path]:
    """Figures, then report.html and report.md in ``results.settings.out``; returns the two.
    ``comparison``: the two exhausts' records (``pipelines.exhaust_comparison``), shown after the
    FE section when given.  ``figures``: {part name: its figures} already drawn (``part_figures``
    as each part of the run arrived); None: drawn here (``demo_figures``)."""
    figures = demo_figures(results) if figures is None else figures
    settings, out = results.settings, results.settings.out
    sections = [_fe_section(results.fe, figures["fe"], out)]
    if comparison is not None:
        from bayesupdate.report.exhaust_comparison import comparison_section

        sections.append(comparison_section(comparison, out, out / "figures"))
    sections += _seed_sections(results, figures["seed"], out)
    if results.seed_discovery is not None:
        sections.append(
            _discovery_section(
                "The beam exhaust against Table 2: what is missing",
                results.seed_discovery,
                figures["seed_discovery"],
                out,
            )
        )
    sections += _virtual_sections(
        results.virtual_test, results.identified, figures["identified"], out
    )
    truth = dict(results.virtual_test.parameters)
    sections += _calibration_sections(
        "virtual", "Virtual test", results.virtual, figures["virtual"], out, truth=truth
    )
    if results.virtual_discovery is not None:
        sections.append(
            _discovery_section(
                "Virtual test: the hidden effect",
                results.virtual_discovery,
                figures["virtual_discovery"],
                out,
            )
        )
    files = (
        "Files: seed_case.h5 (the shell exhaust's seed case), virtual_test.uff, "
        "virtual_modes.h5, virtual_case.h5 (the beam exhaust's virtual test; HDF5 schema "
        "bayesupdate-result/1, see the README), figures/*.png. Models: the seed case, its FE "
        "section and its posterior use the shell exhaust; the side by side both; the discovery "
        "of the seed case and the virtual test the beam exhaust."
    )
    sections.append(Section("Files", (files,)))
    mode = "quick" if settings.quick else "full"
    doc = Document(
        "bayesupdate demo: the seed's exhaust, end to end",
        f"Lupea (2013) reproduced and extended; {mode} run, seed {settings.seed}",
        tuple(sections),
    )
    return write_report(doc, out)


def summary_rows(results: DemoResults, wall_s: float) -> list[tuple[str, str]]:
    """(step, key numbers) rows of the terminal summary; ``wall_s``: the whole run."""
    rows = [fe_row(results.fe)]
    rows += _calibration_rows(results.seed, "seed case (shell)")
    rows += shell_rows(results.seed_optimum, results.shell_check)
    rows.append(optimum_row(results.beam_optimum.calibration, "beam exhaust"))
    rows += _calibration_rows(results.virtual, "virtual test (beam)")
    ident = results.identified.modes
    truth = results.virtual_test.frequencies_hz
    truth = truth[truth < IDENTIFIED_BELOW_HZ]
    if ident.n_modes == truth.size:
        err = np.abs(ident.frequencies_hz / truth - 1).max() * 100
        rows.append(
            ("virtual test: identify", f"{ident.n_modes} modes, max freq error {err:.3f} %")
        )
    else:
        rows.append(("virtual test: identify", f"{ident.n_modes} modes found of {truth.size}"))
    for label, part in (
        ("seed discovery", results.seed_discovery),
        ("virtual discovery", results.virtual_discovery),
    ):
        if part is not None:
            rows.append((label, discovery_headline(part)))
    rows.append(("whole run", f"{wall_s:.0f} s"))
    return rows


def fe_row(fe: FePart) -> tuple[str, str]:
    """The summary's line of the FE model against seed Table 1."""
    r = fe.result
    rel = r.frequencies_hz / paper.TABLE1_FEA_HZ - 1
    return (
        f"FE ({fe.model.name}) vs seed Table 1",
        f"RMS {100 * np.sqrt(np.mean(rel**2)):.2f} %, max {100 * np.abs(rel).max():.2f} %, "
        f"mass {r.mass_kg:.2f} kg",
    )


def optimum_row(c, label: str) -> tuple[str, str]:
    """The summary's line of an optimum (``CalibrationResult``)."""
    return (
        f"{label}: optimum",
        f"Expr {c.expr:.4f}, mass {c.mass_kg:.2f} kg, "
        f"{c.converged_starts}/{c.starts} starts agree, swap: {c.swapped}",
    )


def shell_rows(optimum: OptimumPart, check: ShellCheck | None) -> list[tuple[str, str]]:
    """The summary's lines of the seed case's basis, front and mesh check."""
    b = optimum.basis or {}
    rows = []
    if b:
        rows.append(
            (
                "seed case (shell): certified basis",
                f"{b['size']} vectors, error {b['max_rel_error']:.1e} (tol {b['tol']:g}), "
                f"{b['cpu_s']:.0f} s CPU; at the optimum {b['error_at_optimum']:.1e}",
            )
        )
    points = ", ".join(f"{p['expr']:.4f} at {p['mass_error_pct']:+.1f} %" for p in optimum.front)
    rows.append(("seed case (shell): front, Expr at mass error", points))
    if check is not None:
        rows.append(
            (
                f"seed case (shell): optimum at mesh {check.density}",
                f"Expr {check.expr:.4f}, mass {check.mass_kg:.2f} kg (full solve)",
            )
        )
    return rows


def _calibration_rows(part: CalibrationPart, label: str) -> list[tuple[str, str]]:
    c, p, summary = part.run.calibration, part.run.posterior, part.run.summary
    rhat = max(v["r_hat"] for v in summary.values())
    ess = min(v["ess_bulk"] for v in summary.values())
    report = p.diagnostics.get("convergence") or {}
    state = "converged" if p.converged else f"NOT CONVERGED: {report.get('reason')}"
    ref = p.diagnostics.get("reference") or {}
    if ref.get("applies"):
        state += f"; reference {'met' if ref['accurate'] else 'NOT met'} ({ref['worst']})"
    return [
        optimum_row(c, label),
        (
            f"{label}: posterior",
            f"{p.chain.shape[0]} steps x {p.chain.shape[1]} "
            f"walkers, max R-hat {rhat:.3f}, min ESS {ess:.0f}, {p.wall_s:.0f} s; {state}",
        ),
    ]
