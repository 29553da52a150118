"""Discover pairs what calibrate and correlate pair, on the real mAEWing1 pair (packaged GVT
and decks); the deck's line records are reused by the candidates; candidates that are one
model (two test points on one node) are computed once and reported under both names.

The study files are the demo's discover studies (``pipelines.aircraft.study_text`` with
``DISCOVER_PARAMETERS``).  The pairs asserted are those ``correlate`` prints for the same
study file: GVT modes 1, 7, 10 with v3.3's modes 1, 2, 5 (5.38, 9.47, 19.35 Hz), GVT modes 1
and 10 with v4.2's modes 1 and 5 (8.00, 31.49 Hz; ``docs/guide/aircraft.md``, section 4).
Before, discover set up its problem as if the selected modes were the source's first ones
and computed that many model modes plus 2: for GVT modes 1 and 10, model modes 1-4, so the
30.7 Hz mode's partner was never solved for and GVT mode 10 was refused, named "test mode
2" (on the updated deck GVT modes 1, 7, 10 pair with model modes 1, 4, 7, and discover
stopped: "2 modes with weight > 0").
The GVT is identified from the packaged FRFs once (``identify``, about 10 s): slow.
"""

import dataclasses
import json

import numpy as np
import pytest

from bayesupdate.pipelines import aircraft as ac

MODES = [1, 7, 10]


@pytest.fixture(scope="module")
def modes_h5(tmp_path_factory):
    """The GVT identified from the 10 packaged FRF files (``identify``, defaults)."""
    from bayesupdate.cli import main

    out = tmp_path_factory.mktemp("gvt") / "modes.h5"
    runs = [str(ac.data_folder() / f"run{k}.uff") for k in range(1, ac.N_RUNS + 1)]
    assert main(["identify", *runs, "--out", str(out), "--quiet"]) == 0
    return out


def _study(tmp_path, deck: str, modes_h5, modes=MODES):
    path = tmp_path / "discover.toml"
    path.write_text(
        ac.study_text(ac.data_folder() / deck, modes_h5, modes, ac.DISCOVER_PARAMETERS, False)
    )
    return path


def _correlate_pairs(path, capsys) -> dict[int, int]:
    from bayesupdate.cli import main

    capsys.readouterr()
    assert main(["correlate", str(path), "--json", "--quiet"]) == 0
    out = json.loads(capsys.readouterr().out)
    return {int(m["test"]): int(m["model"]) for m in out["modes"]}


def _discover_problem(path):
    """(problem, record) as ``discover`` sets them up from the study file."""
    from bayesupdate.config import load_study
    from bayesupdate.discovery.workflow import discovery_problem
    from bayesupdate.pipelines.discover import study_pairing
    from bayesupdate.pipelines.model_source import problem_parameters, study_model
    from bayesupdate.pipelines.study import study_data

    study = load_study(path)
    data, numbers = study_data(study)
    model = study_model(study, data.dof_labels)
    choice = study_pairing(study, numbers)
    problem, record = discovery_problem(
        model, data, problem_parameters(study.parameters), choice.method, choice.rules,
        extra_modes=choice.extra_modes, test_modes=choice.test_modes,
    )  # fmt: skip
    return problem, record


@pytest.mark.slow
@pytest.mark.parametrize(
    ("deck", "modes", "pairs"),
    [(ac.V33_DECK, [1, 7, 10], {1: 1, 7: 2, 10: 5}), (ac.V42_DECK, [1, 10], {1: 1, 10: 5})],
)
def test_discover_pairs_the_modes_correlate_pairs_on_the_packaged_decks(
    tmp_path, modes_h5, capsys, deck, modes, pairs
):
    path = _study(tmp_path, deck, modes_h5, modes)
    assert _correlate_pairs(path, capsys) == pairs
    problem, record = _discover_problem(path)
    assert record["refused"] == [] and record["frequency_window"] == ac.FREQUENCY_WINDOW
    assert problem.mode_numbers.tolist() == modes
    at_reference = problem.evaluate(problem.start)
    assert at_reference.ok
    got = dict(zip(modes, (at_reference.paired.model_index + 1).tolist(), strict=True))
    assert got == pairs
    if deck == ac.V33_DECK:  # v3.3's f06: 5.3772 Hz for its first flexible mode
        assert at_reference.frequencies_hz[0] == pytest.approx(5.3772, rel=1e-4)


@pytest.mark.slow
def test_a_candidate_takes_over_the_decks_line_records_and_solves_as_if_found_again(
    tmp_path, modes_h5
):
    from bayesupdate.config import load_study
    from bayesupdate.discovery.candidates import make_candidate
    from bayesupdate.discovery.effects import Effect
    from bayesupdate.pipelines.model_source import study_model
    from bayesupdate.pipelines.study import study_data

    study = load_study(_study(tmp_path, ac.V33_DECK, modes_h5))
    model = study_model(study, study_data(study)[0].dof_labels)
    model.solve({"EI_wing": 2.0}, n_modes=3)  # the deck's records found once
    candidate = make_candidate(model, Effect("added_mass", "17"))
    point = {"EI_wing": 2.4, "added_mass@17:m": 0.002}
    reused = candidate.model.solve(point, n_modes=8).frequencies_hz
    fields = candidate.model._general.fields  # noqa: SLF001
    assert fields.fit is model._general.fields.fit  # noqa: SLF001 - taken over
    assert fields.update.structure is candidate.model.structure  # on the extended pattern
    fresh = make_candidate(model, Effect("added_mass", "17")).model
    fresh._general._known = None  # noqa: SLF001 - found again from the cards
    again = fresh.solve(point, n_modes=8).frequencies_hz
    assert fresh._general.fields.fit is not fields.fit  # noqa: SLF001
    np.testing.assert_allclose(reused, again, rtol=1e-13)
    # and the extended model moved: 2 g at the tip node lowers the first bending mode
    assert reused[0] < model.solve({"EI_wing": 2.4}, n_modes=3).frequencies_hz[0]


@pytest.mark.slow
def test_two_test_points_on_one_node_are_one_candidate_for_the_deck(tmp_path, modes_h5):
    """On v3.3 the GVT's accelerometers 17 and 18 read on one beam node
    (``effects.effect_site``): one extended model; 17 and 15 do not."""
    from bayesupdate.config import load_study
    from bayesupdate.discovery.effects import Effect, effect_site
    from bayesupdate.pipelines.model_source import study_model
    from bayesupdate.pipelines.study import study_data

    study = load_study(_study(tmp_path, ac.V33_DECK, modes_h5))
    model = study_model(study, study_data(study)[0].dof_labels)
    sites = {k: effect_site(model, Effect("added_mass", k)) for k in ("15", "17", "18")}
    assert sites["17"] == sites["18"] != sites["15"]
    assert effect_site(model, Effect("boundary_spring", "17"))[0] == "boundary_spring"


@pytest.mark.slow
def test_shared_candidates_give_what_each_computed_alone(monkeypatch):
    """A small frame with a seventh test point on the node of the fifth: discover with the
    twins computed once equals discover with every candidate computed (fits, evidence, verdict),
    and makes fewer score tests."""
    from test_discovery_workflow import FAST, frame_model, synthetic

    from bayesupdate.discovery import localization, twins
    from bayesupdate.discovery.settings import LibraryScan
    from bayesupdate.discovery.workflow import discover

    frame = frame_model()
    s = frame.structure
    node5 = int(s.sensor_node[list(s.sensor_labels).index("5V")])
    frame = frame.with_structure(_with_sensor(s, "7", node5))
    data = synthetic(frame, ["added_mass@5:m=0.3"])
    scan = LibraryScan(kinds=("added_mass",), locations={"added_mass": ["3", "5", "7"]})
    settings = dataclasses.replace(FAST, scan=scan)
    calls = []
    original = localization.score_candidate

    def counted(*args):
        calls.append(args[-1].label)
        return original(*args)

    monkeypatch.setattr(localization, "score_candidate", counted)
    shared = discover(frame, data, settings)
    n_shared = len(calls)
    monkeypatch.setattr(twins, "site", lambda c: ("label", c.label))
    alone = discover(frame, data, settings)
    assert n_shared == 2 and len(calls) - n_shared == 3  # 3 names, 2 models
    assert [f.label for f in shared.fits] == [f.label for f in alone.fits]
    for a, b in zip(shared.fits, alone.fits, strict=True):
        assert a.log_evidence == b.log_evidence and np.array_equal(a.theta, b.theta)
        assert a.names == b.names and a.space.axes[-1].name == b.space.axes[-1].name
    assert (shared.verdict, shared.reason) == (alone.verdict, alone.reason)
    labels = {f.label: f for f in shared.fits}
    assert labels["added_mass@7"].log_evidence == labels["added_mass@5"].log_evidence
    assert labels["added_mass@7"].effect_parameters == labels["added_mass@5"].effect_parameters


def _with_sensor(structure, point: str, node: int):
    """``structure`` with test point ``point`` (V and H) read at ``node`` too."""
    labels = (*structure.sensor_labels, f"{point}V", f"{point}H")
    nodes = np.concatenate([structure.sensor_node, [node, node]])
    dirs = np.concatenate([structure.sensor_direction, structure.sensor_direction[-2:]])
    return dataclasses.replace(
        structure, sensor_labels=labels, sensor_node=nodes, sensor_direction=dirs
    )


def test_flagged_modes_are_named_by_their_number_in_the_source():
    """A study's selection of GVT modes 1, 7, 10 with the last two flagged: "7" and "10" (the
    problem's 2 and 3 before), in the summary and the verdict's reason alike."""
    from types import SimpleNamespace

    from bayesupdate.discovery.flagging import ModeFlags
    from bayesupdate.discovery.workflow import source_modes

    flagged = np.array([False, True, True])
    flags = ModeFlags(*(np.zeros(3),) * 4, flagged, 0.05, 9.0, 3, 0.03)
    problem = SimpleNamespace(mode_numbers=np.array([1, 7, 10]))
    fit = SimpleNamespace(space=SimpleNamespace(problem=problem))
    assert flags.flagged_modes == [2, 3]
    assert source_modes(flags, fit) == [7, 10]


@pytest.mark.slow
def test_discover_takes_the_measured_mass_properties_as_calibrate_does(tmp_path, modes_h5):
    """The demo's discover study with the authors' measured weight and inertias: discover's
    objective and mass sd are calibrate's (``pipelines.study.prepare``), in the deck's units:
    13.76 lb is 13.76 / 386.088 = 0.035640 lbf s^2/in, its sd 0.4 / 13.76 = 2.907 %."""
    from bayesupdate.config import load_study
    from bayesupdate.discovery.mass_block import MassBlock
    from bayesupdate.inference.data import load_modal_data, select_modes
    from bayesupdate.pipelines.discover import study_mass_properties
    from bayesupdate.pipelines.model_source import study_model
    from bayesupdate.pipelines.study import prepare

    path = tmp_path / "discover.toml"
    path.write_text(
        ac.study_text(ac.data_folder() / ac.V33_DECK, modes_h5, MODES, ac.DISCOVER_PARAMETERS)
    )
    study = load_study(path)
    data, _ = select_modes(load_modal_data(study.data.as_source()), study.data.selection(), "")
    model = study_model(study, data.dof_labels)
    data, objective = study_mass_properties(study, data, model)
    prepared = prepare(study)
    theirs = prepared.problem.objective
    assert objective.mass_target_kg == pytest.approx(13.76 / 386.088, rel=1e-4)
    assert objective.mass_target_kg == theirs.mass_target_kg
    assert objective.mass_weight == theirs.mass_weight > 0
    assert objective.mass_properties.names == theirs.mass_properties.names == ("ixx", "iyy")
    np.testing.assert_array_equal(objective.mass_properties.values, theirs.mass_properties.values)
    np.testing.assert_array_equal(objective.mass_properties.sd, theirs.mass_properties.sd)
    assert data.mass_sd_rel == prepared.likelihood.mass_sd_rel == pytest.approx(0.4 / 13.76)
    block = MassBlock.of(dataclasses.replace(prepared.problem, data=data))
    assert block.names == ("mass", "ixx", "iyy")
    # IXX 9560 lb in^2 in the deck's lbf s^2 in: / 386.088, its sd half the authors' range
    assert block.targets.values[0] == pytest.approx(9560.0 / 386.088, rel=1e-4)
    assert block.scale[1] == pytest.approx(239.0 / 386.088, rel=1e-4)
