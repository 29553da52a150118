"""Study file: parsing, defaults, unknown keys and wrong types named in the error."""

import dataclasses
import textwrap

import pytest

from bayesupdate.config import load_study, parse_study, with_overrides
from bayesupdate.discovery.settings import (
    FLAT_NAMES,
    DiscoverySettings,
    EvidenceSettings,
    LibraryScan,
    RefitBudget,
    VerdictThresholds,
)
from bayesupdate.errors import BayesUpdateError
from bayesupdate.pipelines.study import prepare

FULL = """
[model]
source = "shear_building"
[data]
frequencies_hz = [4.2, 10.96]
weights = [1.0, 2.0]
[parameters.theta_1]
bounds = [0.2, 3.0]
prior = { kind = "lognormal", mu = 0.0, sigma = 0.5 }
[parameters.theta_2]
bounds = [0.2, 3]
prior = { kind = "normal", mean = 1.0, sd = 0.3 }
start = 1.1
[likelihood]
sigma_prior = { kind = "halfnormal", scale = 0.1 }
[sampler]
walkers = 16
steps = 200
seed = 4
"""


def _write(tmp_path, text, name="study.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def test_full_study_parses_and_prepares(tmp_path):
    study = load_study(_write(tmp_path, FULL))
    assert study.sampler.walkers == 16 and study.sampler.seed == 4
    assert study.likelihood.sigma is None  # sigma_prior given: sigma inferred
    assert study.data.as_source() == {"frequencies_hz": (4.2, 10.96), "weights": (1.0, 2.0)}
    prepared = prepare(study)
    assert prepared.problem.names == ("theta_1", "theta_2")
    assert prepared.problem.start.tolist() == [1.0, 1.1]
    assert prepared.problem.parameters[0].prior.kind == "lognormal"
    assert prepared.likelihood.infer_sigma
    assert prepared.problem.weights.tolist() == [1.0, 2.0]


def test_parameters_default_from_the_model():
    study = parse_study(
        {"model": {"source": "shear_building"}, "data": {"frequencies_hz": [4, 11]}}
    )
    prepared = prepare(study)
    assert prepared.problem.names == ("theta_1", "theta_2")
    assert prepared.problem.lower.tolist() == [0.1, 0.1]
    assert prepared.problem.upper.tolist() == [4.0, 4.0]
    assert prepared.likelihood.sigma == 0.05


@pytest.mark.parametrize(
    "document, match",
    [
        ({"sampler": {"walker": 3}}, r"sampler\.walker: unknown key"),
        ({"samplr": {}}, r"unknown table \[samplr\]"),
        ({"sampler": {"walkers": "many"}}, r"sampler\.walkers: must be an integer"),
        ({"sampler": {"walkers": 3.5}}, r"sampler\.walkers: must be an integer"),
        ({"likelihood": {"sigma": "small"}}, r"likelihood\.sigma: must be a number"),
        ({"parameters": {"t": {"bound": [1, 2]}}}, r"parameters\.t\.bound: unknown key"),
        ({"parameters": {"t": {"bounds": [2, 1]}}}, r"parameters\.t\.bounds: low must be < high"),
        ({"parameters": {"t": {"bounds": [1]}}}, r"parameters\.t\.bounds: must be \[low, high\]"),
        ({"data": {"weights": [1.0]}}, r"data: give source"),
        ({"data": {"source": "paper:ema", "frequencies_hz": [1.0]}}, r"not both"),
        ({"model": {"source": 3}}, r"model\.source: must be a string"),
        ({"optimizer": {"polish": 1}}, r"optimizer\.polish: must be"),
        # a negative seed, which numpy's generators refuse (was an internal ValueError)
        ({"sampler": {"seed": -1}}, r"sampler\.seed: must be an integer >= 0, got -1"),
        ({"discovery": {"seed": -2}}, r"discovery\.seed: must be an integer >= 0, got -2"),
        ({"sampler": {"min_autocorr_times": -1.0}}, r"sampler\.min_autocorr_times: must be > 0"),
        # a percentage sd that is no number (was an internal ValueError when the run began)
        ({"data": {"source": "paper:ema", "mass": "12.29 kg", "mass_sd": "%"}},
         r'data\.mass_sd: give a number before "%"'),
        ({"data": {"source": "paper:ema", "mass": "12.29 kg", "mass_sd": "nan %"}},
         r"data\.mass_sd: must be > 0, got 'nan %'"),
    ],
)  # fmt: skip
def test_bad_study_documents_name_the_key(document, match):
    with pytest.raises(BayesUpdateError, match=match):
        parse_study(document, "s.toml")


def test_errors_found_when_preparing(tmp_path):
    cases = [
        (
            '[model]\nsource = "shear_building"\n[data]\nfrequencies_hz = [4, 11]\n'
            "[parameters.theta_1]\nbounds = [0.2, 0.5]\n",
            "outside bounds",
        ),
        (
            '[model]\nsource = "shear_building"\n[data]\nfrequencies_hz = [4, 11]\n'
            '[parameters.theta_1]\nprior = { kind = "normal", mean = 40.0, sd = 0.1 }\n',
            "no support",
        ),
        (
            '[model]\nsource = "no_such_mod:fn"\n[parameters.a]\nbounds = [0, 1]\n',
            "does not import",
        ),
        ('[model]\nsource = "beam"\n', "unknown"),
        ('[data]\nsource = "missing.csv"\n[model]\nsource = "shear_building"\n', "not found"),
        (
            '[model]\nsource = "shear_building"\n[data]\nfrequencies_hz = [4, 11]\n'
            "[sampler]\ntarget_rhat = 0.9\n",
            "target_rhat: must be >= 1",
        ),
        (
            '[model]\nsource = "shear_building"\n[data]\nfrequencies_hz = [4, 11]\n'
            "[sampler]\ntarget_ess = -5.0\n",
            "target_ess: must be >= 0",
        ),
    ]
    for text, match in cases:
        with pytest.raises(BayesUpdateError, match=match):
            prepare(load_study(_write(tmp_path, text)))


def test_invalid_toml_and_missing_file(tmp_path):
    with pytest.raises(BayesUpdateError, match="not valid TOML"):
        load_study(_write(tmp_path, "[model\n"))
    with pytest.raises(BayesUpdateError, match="not found"):
        load_study(tmp_path / "nope.toml")


def test_discovery_tables_are_part_of_the_schema():
    # [effects] and [discovery] parse without importing anything else first (no registration)
    study = parse_study(
        {"effects": {"add": ["added_mass@14:m=0.2"]}, "discovery": {"max_refits": 2, "sigma": 1}}
    )
    assert study.extensions == {
        "effects": ("added_mass@14:m=0.2",),
        "discovery": DiscoverySettings(
            refit=RefitBudget(max_refits=2), evidence=EvidenceSettings(sigma=1.0)
        ),
    }
    assert isinstance(study.extensions["discovery"].evidence.sigma, float)
    with pytest.raises(BayesUpdateError, match=r"valid tables are \[.*'discovery', 'effects'"):
        parse_study({"effect": {}}, "s.toml")
    with pytest.raises(BayesUpdateError, match=r"s.toml: discovery.max_refits: must be an integer"):
        parse_study({"discovery": {"max_refits": 2.5}}, "s.toml")


def test_prepare_extends_the_model_by_the_study_effects_then_the_extra_ones():
    base = prepare(parse_study({"model": {"source": "exhaust"}}))
    study = parse_study(
        {"model": {"source": "exhaust"}, "effects": {"add": ["added_mass@14:m=0.2"]}}
    )
    one = prepare(study)
    two = prepare(study, effects=("added_mass@8:m=0.3",))
    masses = [p.problem.model.predict({}, 12).mass_kg for p in (base, one, two)]
    assert masses[1] - masses[0] == pytest.approx(0.2, rel=1e-9)
    assert masses[2] - masses[0] == pytest.approx(0.5, rel=1e-9)
    # a bad spec is named before the model is even looked up
    unknown_model = parse_study({"model": {"source": "no_such_model"}})
    with pytest.raises(BayesUpdateError, match="bogus"):
        prepare(unknown_model, effects=("bogus@1",))


def test_overrides():
    study = with_overrides(parse_study({}), sampler__seed=9, sampler__steps=None)
    assert study.sampler.seed == 9 and study.sampler.steps == 5000


def test_discovery_settings_group_the_flat_knobs_of_the_study_file():
    """Every flat [discovery] key belongs to exactly one record field; flat <-> records round
    trip; a result file stores the knobs flat; each record validates its own fields."""
    records = {
        "scan": LibraryScan,
        "refit": RefitBudget,
        "evidence": EvidenceSettings,
        "verdict": VerdictThresholds,
    }
    grouped = {(g, f.name) for g, r in records.items() for f in dataclasses.fields(r)}
    assert {(g, n) for n, g in FLAT_NAMES if g} == grouped
    assert len(FLAT_NAMES) == len(grouped) + 1  # + the seed
    table = {"max_refits": 2, "sigma": 0.01, "alpha": 0.1, "seed": 3, "kinds": ["added_mass"]}
    s = parse_study({"discovery": table}, "s.toml").extensions["discovery"]
    assert (s.refit.max_refits, s.evidence.sigma, s.scan.alpha, s.seed) == (2, 0.01, 0.1, 3)
    assert s.scan.kinds == ("added_mass",) and s.refit.max_nfev == RefitBudget().max_nfev
    assert DiscoverySettings.from_flat(**s.flat()) == s
    assert list(s.flat()) == [n for n, _ in FLAT_NAMES]
    assert s.replaced(max_nfev=7).refit == RefitBudget(max_refits=2, max_nfev=7)
    stored = parse_study({"discovery": table}).to_dict()["extensions"]["discovery"]
    assert stored == s.flat() and "refit" not in stored
    for key, value, message in [
        ("max_nfev", 0, "discovery.max_nfev: must be >= 1"),
        ("loo_draws", 0, "discovery.loo_draws: must be >= 25"),
        ("loo_draws", 24, r"discovery.loo_draws: must be >= 25 \(PSIS-LOO.*got 24"),
        ("loo_top", -1, "discovery.loo_top: must be >= 0"),
        ("per_kind", -1, "discovery.per_kind: must be >= 0"),
        ("alpha", 2.0, r"discovery.alpha: must lie in \(0, 1\)"),
        ("adequacy_p", float("nan"), r"adequacy_p must lie in \(0, 1\)"),
        ("bound_tolerance", 0.7, r"bound_tolerance in \[0, 0.5\)"),
        ("max_noise_rel", -1.0, "discovery.max_noise_rel: must be a finite number > 0"),
        ("sigma", float("nan"), "discovery.sigma: must be > 0"),
        ("margin_ln_bf", -1.0, "thresholds on log odds"),
        ("effect_prior", 1.0, "strictly between 0 and 1"),
        ("bound_tolerance", "x", "s.toml: discovery.bound_tolerance: must be a number"),
    ]:
        with pytest.raises(BayesUpdateError, match=message):
            parse_study({"discovery": {key: value}}, "s.toml")
    with pytest.raises(BayesUpdateError, match=r"discovery.quick: unknown key; valid keys are"):
        parse_study({"discovery": {"quick": 1}}, "s.toml")


def test_an_empty_sampler_table_gives_the_documented_sampler_settings():
    """What ``bayesupdate sample`` runs with no ``[sampler]`` table (the settings
    studies/posterior_reference.py --user-sampler checks against the reference)."""
    from bayesupdate.pipelines.sample import sampler_settings

    study = parse_study({"model": {"source": "exhaust"}, "data": {"source": "paper:ema"}})
    settings = sampler_settings(study.sampler)
    assert (settings.walkers, settings.steps, settings.seed, settings.check_every) == (
        32, 5000, 1, 500,
    )  # fmt: skip
    assert (settings.target_rhat, settings.target_ess, settings.min_autocorr_times) == (
        1.01, 400.0, 50.0,
    )  # fmt: skip
    assert (settings.moves, settings.transform, settings.progress) == ("mixture", "logit", False)
    no_ess = parse_study({"model": {"source": "exhaust"}, "sampler": {"target_ess": 0}})
    assert sampler_settings(no_ess.sampler).target_ess is None
    assert settings.adapt_steps == 250  # the documented default of [sampler] adapt_steps
    short = parse_study({"model": {"source": "exhaust"}, "sampler": {"adapt_steps": 60}})
    assert sampler_settings(short.sampler).adapt_steps == 60
    with pytest.raises(BayesUpdateError, match=r"sampler.adapt_steps: 19; use at least 20"):
        parse_study({"model": {"source": "exhaust"}, "sampler": {"adapt_steps": 19}})


def test_the_default_walkers_follow_the_sampled_dimensions():
    """No ``[sampler] walkers``: 32, or two per sampled dimension above 16 (the ensemble's
    moves need two per dimension); a given number is kept, and refused where it is too few."""
    from bayesupdate.pipelines.study import _check_sampler

    study = parse_study({"model": {"source": "exhaust"}})
    assert study.sampler.walkers is None
    assert [study.sampler.walkers_for(n) for n in (5, 16, 17, 34)] == [32, 32, 34, 68]
    assert _check_sampler(study, 35).sampler.walkers == 70
    given = parse_study({"model": {"source": "exhaust"}, "sampler": {"walkers": 8}})
    assert _check_sampler(given, 4).sampler.walkers == 8
    with pytest.raises(BayesUpdateError, match="8 is too few for 34 sampled parameters; use at "
                       "least 68"):  # fmt: skip
        _check_sampler(given, 34)
