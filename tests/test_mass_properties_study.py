"""Measured mass properties as data in a study (``[data] mass / cg / inertia`` with units):
a calibration whose mass and CG terms pull a density and a tip mass to their true values, the
likelihood's CG block, the JSON and result-file reports, and one-line errors (exit 2).

The model is a free-free bar of 10 CBARs (100 in, weight 5 lbf) with a 0.5 lbf CONM2 at its tip,
offset 2 in sideways, in inch-lbf-s with PARAM WTMASS: its frequencies depend on E / rho and the
tip's share of the mass, so the test frequencies alone cannot fix the density; the measured
mass and CG do.
"""

import json

import h5py
import numpy as np
import pytest
from scipy.stats import norm

from bayesupdate.cli import main

LB = 0.45359237  # kg
LBF_S2_IN = LB * 9.80665 / 0.0254  # kg: the deck's mass unit
PARAMETERS = {"rho": "MAT1 1 RHO scale", "E": "MAT1 1 E scale", "tip": "CONM2 100 M scale"}
TRUE = {"rho": 1.2, "E": 1.2, "tip": 1.6}


def write_bar(folder):
    lines = ["SOL 103", "CEND", "BEGIN BULK", "PARAM,WTMASS,0.00259", "EIGRL,1,,,6"]
    grids = [(i + 1 + 100 * j, 10.0 * i, 10.0 * j) for j in (0, 1) for i in range(11)]
    lines += [f"GRID,{n},,{x},{y},0." for n, x, y in grids]
    lines += [f"CQUAD4,{i + 1},1,{i + 1},{i + 2},{i + 102},{i + 101}" for i in range(10)]
    lines += ["PSHELL,1,1,0.1,1,,1", "MAT1,1,1.0e7,,0.3,0.1", "CONM2,100,111,,1.0,0.,0.,2."]
    path = folder / "bar.bdf"
    path.write_text("\n".join([*lines, "ENDDATA"]) + "\n")
    return path


@pytest.fixture(scope="module")
def bar(tmp_path_factory):
    """(deck path, true frequencies [Hz] (4,), true mass properties) at ``TRUE``."""
    from bayesupdate.nastran import load_nastran_model

    deck = write_bar(tmp_path_factory.mktemp("bar"))
    model = load_nastran_model(str(deck), {k: {"binds": v} for k, v in PARAMETERS.items()})
    freqs = model.solve(TRUE, n_modes=4).frequencies_hz
    return deck, freqs, model.mass_properties(TRUE)


def study_text(deck, freqs, data: str, extra: str = "") -> str:
    params = "".join(
        f'[parameters.{k}]\nbinds = "{v}"\nbounds = [0.5, 3.0]\n' for k, v in PARAMETERS.items()
    )
    return (
        f'[model]\nsource = "{deck}"\n[data]\nfrequencies_hz = {list(map(float, freqs))}\n'
        f'{data}\n{params}[pairing]\nmethod = "order"\n'
        f"[optimizer]\nstarts = 2\npolish = false\n{extra}"
    )


def test_the_measured_mass_fixes_the_density_the_frequencies_leave_free(bar, tmp_path, capsys):
    deck, freqs, true = bar
    mass_lb = float(true.mass * LBF_S2_IN / LB)  # the measured mass in pound-mass
    cg = [float(c) for c in true.cg]
    data = (
        f'mass = "{mass_lb!r} lb"\nmass_sd = "0.5 %"\n'
        f'cg = {{ x = "{cg[0]!r} in", y = {cg[1]!r}, sd = "0.05 in" }}'
    )
    study = tmp_path / "study.toml"
    study.write_text(study_text(deck, freqs, data))
    # without them (--no-mass drops every measured mass property) the frequencies fit exactly
    # anywhere on the ridge E / rho = 1, tip / rho = 4 / 3: the density is not fixed
    assert main(["calibrate", str(study), "--full", "--json", "--no-mass"]) == 0
    blind = json.loads(capsys.readouterr().out)
    p = blind["parameters"]
    assert blind["objective"] < 1e-12 and blind["mass_properties"] == []
    assert p["E"] / p["rho"] == pytest.approx(1.0, rel=1e-5)
    assert p["tip"] / p["rho"] == pytest.approx(4 / 3, rel=1e-5)
    assert abs(p["rho"] / TRUE["rho"] - 1) > 0.05
    out = tmp_path / "cal.h5"
    assert main(["calibrate", str(study), "--full", "--json", "--out", str(out)]) == 0
    result = json.loads(capsys.readouterr().out)
    for name, value in TRUE.items():
        assert result["parameters"][name] == pytest.approx(value, rel=1e-4), name
    rows = {r["name"]: r for r in result["mass_properties"]}
    assert set(rows) == {"mass", "cg_x", "cg_y"}
    # 1 lb of mass is 1 / (g in in/s^2) lbf s^2/in
    assert rows["mass"]["measured"] == pytest.approx(mass_lb / 386.08858, rel=1e-7)
    assert rows["mass"]["unit"] == "lbf s^2/in" and rows["cg_x"]["unit"] == "in"
    assert rows["mass"]["sd"] == pytest.approx(0.005 * rows["mass"]["measured"], rel=1e-12)
    assert rows["cg_x"]["predicted"] == pytest.approx(true.cg[0], abs=1e-4)
    with h5py.File(out) as h5:
        stored = json.loads(h5["optimum"].attrs["mass_properties_json"])
    assert stored == result["mass_properties"]


def test_the_likelihood_adds_the_cg_and_inertia_blocks_with_their_sds(bar, tmp_path):
    from bayesupdate.config import load_study
    from bayesupdate.inference.likelihood import LogPosterior
    from bayesupdate.pipelines.study import prepare

    deck, freqs, true = bar
    inertia = true.inertia_about([0.0, 0.0, 0.0])
    measured = {"cg": (float(true.cg[0]) + 0.3, 0.2), "izz": (float(inertia[2, 2]) * 1.01, 0.02)}
    with_props = (
        f"cg = {{ x = {measured['cg'][0]!r}, sd = {measured['cg'][1]} }}\n"
        f'inertia = {{ izz = {measured["izz"][0]!r}, sd = "2 %", about = [0, 0, "0 in"] }}'
    )
    posteriors = []
    for data in ("", with_props):
        path = tmp_path / f"s{len(posteriors)}.toml"
        path.write_text(study_text(deck, freqs, data + "\n[objective]\ncg_weight = 4.0"))
        prepared = prepare(load_study(path))
        posteriors.append(LogPosterior(prepared.problem, prepared.likelihood))
    theta = np.array([[TRUE["rho"], TRUE["E"], TRUE["tip"]]])
    # the objective: sqrt(w) (p - p_T) / S, S the largest radius of gyration at the reference
    # design (the deck's own values), and |p_T| for a moment of inertia
    problem = prepared.problem
    residuals = problem.residual_vector(problem.evaluate(theta[0]))
    reference = problem.model.mass_properties({})
    gyration = np.sqrt(np.diag(reference.inertia).max() / reference.mass)
    assert residuals[-2] == pytest.approx(2.0 * (true.cg[0] - measured["cg"][0]) / gyration)
    assert residuals[-1] == pytest.approx(
        np.sqrt(10.0) * (inertia[2, 2] / measured["izz"][0] - 1), rel=1e-9
    )
    expected = norm.logpdf(true.cg[0], *measured["cg"]) + norm.logpdf(
        inertia[2, 2], measured["izz"][0], measured["izz"][0] * measured["izz"][1]
    )
    assert posteriors[1](theta)[0] - posteriors[0](theta)[0] == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize(
    "data, words",
    [
        ('mass = "5.5 stone"', "data.mass: unknown unit 'stone'"),
        ('mass = "5.5 lbf"', "a weight; give the mass"),
        ('mass = "5.5 lb"\nmass_kg = 2.0', "data: give mass or mass_kg, not both"),
        ('cg = { x = "54 in" }', "data.cg.sd: give the sd of x"),
        ("cg = { x = [54, 0], sd = 1 }", "data.cg.x: give a number or a string"),
        ('inertia = { izz = "5 lb in", sd = 1 }', "is not a inertia unit"),
        ("inertia = { izz = 5, sd = 1, about = [0, 0] }", 'data.inertia.about: give "cg"'),
    ],
)
def test_bad_units_and_shapes_exit_2_with_one_line(bar, tmp_path, capsys, data, words):
    deck, freqs, _ = bar
    study = tmp_path / "bad.toml"
    study.write_text(study_text(deck, freqs, data))
    assert main(["calibrate", str(study), "--full", "--json"]) == 2
    err = capsys.readouterr().err.strip()
    assert words in err and "\n" not in err, err


def test_affine_mass_terms_are_exact_and_refused_where_the_mass_is_not_affine(bar, tmp_path):
    # densities, moduli and point masses: M_r(theta) is an exact affine sum (no assembly); so
    # is a shell thickness with Nastran's default lumped mass (t only); with consistent mass
    # (PARAM COUPMASS 1) it enters M as t and t^3 (rotary inertia): refused, the assembly is used
    from bayesupdate.fe.mass_properties import rigid_mass_terms
    from bayesupdate.nastran import load_nastran_model

    deck = str(bar[0])
    model = load_nastran_model(deck, {k: {"binds": v} for k, v in PARAMETERS.items()})
    terms = rigid_mass_terms(model)
    point = {"rho": 2.7, "E": 0.6, "tip": 0.3}
    exact = model.mass_properties(point).vector()
    np.testing.assert_allclose(terms(point).vector(), exact, rtol=0, atol=1e-12 * abs(exact).max())
    assert model.mass_properties_function() is not model.mass_properties
    thick = load_nastran_model(deck, {"t": {"binds": "PSHELL 1 T"}})
    at = {"t": 1.3 * thick.default_parameters()["t"]}
    exact = thick.mass_properties(at).vector()
    np.testing.assert_allclose(rigid_mass_terms(thick)(at).vector(), exact, rtol=0,
                               atol=1e-12 * abs(exact).max())  # fmt: skip
    coupled = tmp_path / "coupled.bdf"
    coupled.write_text(bar[0].read_text().replace("BEGIN BULK", "BEGIN BULK\nPARAM,COUPMASS,1"))
    thick = load_nastran_model(str(coupled), {"t": {"binds": "PSHELL 1 T"}})
    assert rigid_mass_terms(thick) is None
    assert thick.mass_properties_function() == thick.mass_properties


def test_sample_reports_the_mass_properties_at_the_posterior_mean(bar, tmp_path, capsys):
    deck, freqs, true = bar
    data = f"cg = {{ x = {float(true.cg[0])!r}, sd = 0.05 }}\nmass = {float(true.mass)!r}"
    sampler = "[sampler]\nwalkers = 8\nsteps = 12\ncheck_every = 6\npredictive_draws = 4\n"
    sampler += 'moves = "de"\n'
    study = tmp_path / "study.toml"
    study.write_text(study_text(deck, freqs, data, sampler))
    out = tmp_path / "post.h5"
    assert main(["sample", str(study), "--full", "--json", "--out", str(out)]) == 0
    result = json.loads(capsys.readouterr().out)
    rows = {r["name"]: r for r in result["mass_properties"]}
    means = {k: v["mean"] for k, v in result["parameters"].items()}
    from bayesupdate.nastran import load_nastran_model

    model = load_nastran_model(str(deck), {k: {"binds": v} for k, v in PARAMETERS.items()})
    at_mean = model.mass_properties(means)
    assert rows["cg_x"]["predicted"] == pytest.approx(at_mean.cg[0], rel=1e-12)
    assert rows["mass"]["predicted"] == pytest.approx(at_mean.mass, rel=1e-12)
    assert rows["mass"]["sd"] is None and rows["cg_x"]["sd"] == 0.05
    with h5py.File(out) as h5:
        assert [r["name"] for r in json.loads(h5["optimum"].attrs["mass_properties_json"])] == [
            "mass",
            "cg_x",
        ]
