"""The mAEWing1 aircraft case (``pipelines.aircraft``, ``demo --case aircraft``).

Fast checks of the comparison's arithmetic on hand-made inputs, of the packaged decks against
MSC Nastran's own ``.f06`` weights (v3.3 14.0589 lb, v4.2 13.7779 lb, README of
``../shared/data/gvt_maewing1``), and of the study file the case writes; one slow check runs
``demo --case aircraft --quick --json`` end to end on the packaged data and checks the numbers
that have references: the identified first mode against the authors' peak pick (7.797 Hz,
explog.txt), v3.3's and v4.2's paired frequencies against their ``.f06`` (5.3772, 8.0042 Hz),
which modes are held out, and that the calibrated modes moved onto the test.
"""

import contextlib
import io
import json

import numpy as np
import pytest

from bayesupdate.commands._demo_aircraft import AircraftSettings, Chain, run_aircraft
from bayesupdate.errors import BayesUpdateError
from bayesupdate.pipelines import aircraft as ac


def _corr(pairs):
    return {"modes": [{"test": t, "model": t, "model_hz": f, "mac": m} for t, f, m in pairs]}


def test_comparison_rows_and_metrics_by_hand():
    test_hz = [10.0, 20.0, 30.0, 40.0]
    corr = {
        "v33": _corr([(1, 8.0, 0.9), (3, 24.0, 0.7)]),
        "v42": _corr([(1, 10.5, 0.8), (2, 19.0, 0.6), (3, 31.5, 0.9), (4, 80.0, 0.7)]),
        "ours": _corr([(1, 10.0, 0.95), (3, 30.0, 0.85)]),
    }
    rows = ac.comparison_rows(test_hz, corr, calibrated=[1], predictive={3: (29.0, 28.0, 31.0)})
    assert [r.test for r in rows] == [1, 2, 3]  # mode 4: +100 %, outside the 60 % window
    assert [r.held_out for r in rows] == [False, True, True]
    assert rows[1].v33_hz is None and rows[1].v42_hz == 19.0 and rows[1].ours_hz is None
    assert rows[2].ours_band_hz == (28.0, 31.0) and rows[2].ours_mean_hz == 29.0
    m = ac.metrics(rows)
    assert m["v33"]["calibrated"]["rms_error_pct"] == pytest.approx(20.0)  # 8 Hz vs 10 Hz
    assert (m["v33"]["calibrated"]["mean_mac"], m["v33"]["calibrated"]["n"]) == (0.9, 1)
    # v4.2 held out: -5 % and +5 % -> RMS 5 %, MACs 0.6 and 0.9
    assert m["v42"]["held_out"]["rms_error_pct"] == pytest.approx(5.0)
    assert m["v42"]["held_out"]["mean_mac"] == pytest.approx(0.75)
    assert m["ours"]["held_out"] == {"rms_error_pct": 0.0, "mean_mac": 0.85, "n": 1,
                                     "unpaired": 1}  # fmt: skip


def test_calibration_modes_are_the_pre_update_pairs_below_20_hz():
    before = _corr([(1, 5.4, 0.83), (7, 9.5, 0.65), (10, 19.3, 0.69)])
    test_hz = [7.8, 9.2, 9.5, 15.7, 15.95, 18.9, 19.07, 19.15, 23.8, 30.7]
    assert ac.calibration_modes(test_hz, before) == [1, 7]


def test_predictive_band_pairs_each_draw_by_mac():
    rng = np.random.default_rng(3)
    test = np.eye(4)[:, :2]  # two test shapes on 4 DOFs
    freq, shapes = [], []
    for d in range(200):
        f = np.array([5.0 + 0.1 * rng.standard_normal(), 7.0 + 0.2 * rng.standard_normal(), 9.0])
        phi = np.eye(4)[:, [0, 1, 2]]
        if d % 2:  # the model's modes swap order in half the draws: pairing must follow shapes
            f, phi = f[[1, 0, 2]], phi[:, [1, 0, 2]]
        freq.append(f)
        shapes.append(phi)
    band = ac.predictive_band(np.array(freq), np.array(shapes), test, [1, 2])
    assert band[1][0] == pytest.approx(5.0, abs=0.03) and band[2][0] == pytest.approx(7.0, abs=0.05)
    # 5-95 % of a normal: +-1.645 sd
    assert band[2][2] - band[2][1] == pytest.approx(2 * 1.645 * 0.2, rel=0.25)


def test_packaged_decks_weigh_what_msc_printed_and_mass_rows_use_the_authors_ranges():
    from bayesupdate.commands._demo_aircraft import _mass

    folder = ac.data_folder()
    decks = {"v33": folder / ac.V33_DECK, "v42": folder / ac.V42_DECK}
    props = _mass(decks, folder / ac.V42_DECK)
    assert props["v33"]["mass"] == pytest.approx(14.0589, rel=1e-5)
    assert props["v42"]["mass"] == pytest.approx(13.7779, rel=1e-5)
    rows = {r["name"]: r for r in ac.mass_rows(props)}
    assert rows["mass"]["range"] == [13.4, 14.2] and rows["mass"]["v42_in_range"] is True
    assert rows["ixx"]["measured"] == 9560.0


def test_study_text_reads_as_a_study_with_the_parameters_and_measured_data(tmp_path):
    from bayesupdate.config import load_study

    path = tmp_path / "s.toml"
    path.write_text(ac.study_text(ac.data_folder() / ac.V33_DECK, tmp_path / "m.h5"))
    study = load_study(path)
    assert list(study.parameters) == list(ac.PARAMETERS)
    assert study.data.mass == "13.76 lb" and study.data.inertia["iyy"] == "1643.0 lb in^2"
    assert study.test.geometry.endswith("gvt_geometry.unv")
    # the case's own settings (``aircraft.STARTS``, ``WALKERS``): the sampler's least walkers
    # (2 per parameter), the reduced basis (its posterior is the full one: aircraft.REDUCED),
    # no polish
    assert study.sampler.walkers == 2 * len(study.parameters) and study.sampler.reduced
    assert study.optimizer.starts == 4 and not study.optimizer.polish
    assert not study.sampler.screen


def test_parameters_scale_the_outer_sections_and_the_foam_masses_alone():
    """``EI_outer`` scales the seven outer PBEAM I1 as the deck has them (0.00994078 in^4 on
    1003, from the cards), 1 at the default; ``m_foam`` acts on the 32 foam CONM2 M fields
    alone (3.4588688 lb summed from the cards: at 0.05 the weight falls by 0.95 of it) and
    ``rho_wing`` on the wing beams only (the foam's weight moved into them keeps the weight)."""
    from bayesupdate.nastran import load_nastran_model

    tables = {n: {"binds": b, "bounds": list(bd)} for n, (b, bd) in ac.PARAMETERS.items()}
    model = load_nastran_model(ac.data_folder() / ac.V33_DECK, tables)
    wtmass = model.structure.metadata["nastran"]["wtmass"]

    def props(**p):
        return ac.weight_units(model.mass_properties(p), wtmass)

    assert model.full_parameters(None)["EI_outer"] == 1.0
    outer = model.bindings["EI_outer"]
    assert outer.field.scale and outer.nominal[0] == pytest.approx(0.00994078256, rel=1e-9)
    assert np.ptp(outer.nominal) > 0.04  # v3.3's seven differ: 0.0099-0.0563 in^4
    base = props()
    assert base["mass"] == pytest.approx(14.0589, rel=1e-5)  # v3.3's f06
    assert props(m_foam=0.05)["mass"] == pytest.approx(base["mass"] - 0.95 * 3.4588688, rel=1e-7)
    beams = props(rho_wing=2.0)["mass"] - base["mass"]  # the MAT1 903 beams' own weight
    moved = props(m_foam=0.05, rho_wing=1.0 + 0.95 * 3.4588688 / beams)
    # rel 1e-8: the beams' records follow RHO through a map found from one step (``lines``)
    assert moved["mass"] == pytest.approx(base["mass"], rel=1e-8)


class _InProcessChain(Chain):
    """The demo's chain with each command run by ``cli.main`` in this process: the same
    commands, arguments and seeds, without seven interpreter start-ups (``Chain`` itself is
    checked on a child process below)."""

    def execute(self, argv):
        from bayesupdate.cli import main

        out, err = io.StringIO(), io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = main(argv)
        return code, out.getvalue(), err.getvalue()


def test_the_chain_runs_a_command_in_a_child_process_and_names_its_failure():
    said = []
    argv = ("modes", "--model", "exhaust", "--modes", "3")
    out = Chain(said.append)("modes", *argv)
    assert out == _InProcessChain(said.append)("modes", *argv)  # the child's numbers, to the bit
    assert len(out["frequencies_hz"]) == 3 and said[0] == "bayesupdate " + " ".join(argv)
    with pytest.raises(BayesUpdateError, match="demo aircraft: modes failed: .*'teleport'"):
        Chain(said.append)("bad", "modes", "--model", "teleport")


@pytest.mark.slow
def test_demo_aircraft_quick_end_to_end(tmp_path):
    """``demo --case aircraft --quick``'s chain (``run_aircraft``, as the command runs it)."""
    settings = AircraftSettings(tmp_path / "o", quick=True, seed=0)
    (tmp_path / "o").mkdir()
    said = []
    out = json.loads(json.dumps(run_aircraft(settings, said.append, _InProcessChain(said.append))))
    assert (tmp_path / "o" / "updated.bdf").is_file()
    assert (tmp_path / "o" / "report.md").read_text().startswith("# mAEWing1")
    rows = {r["test"]: r for r in out["comparison"]}
    keys = {"test_hz", "v33_hz", "v42_hz", "ours_hz", "mac_v33", "mac_v42", "mac_ours",
            "held_out"}  # fmt: skip
    assert all(keys <= set(r) for r in rows.values())
    assert rows[1]["test_hz"] == pytest.approx(7.797, rel=3e-3)  # the authors' peak pick
    assert rows[1]["v33_hz"] == pytest.approx(5.3772, rel=1e-4)  # v3.3's f06
    assert rows[1]["v42_hz"] == pytest.approx(8.0042, rel=1e-4)  # v4.2's f06
    # every compared mode that is not held out was calibrated; a calibrated mode without a row
    # (the 15.96 Hz mode 5, seen on one wing: v4.2 pairs it only by MAC at 66 Hz, outside the
    # comparison's 60 % window) is still calibrated
    assert {t for t, r in rows.items() if not r["held_out"]} <= set(out["calibrated_modes"])
    assert set(out["calibrated_modes"]) - set(rows) <= {5}
    assert rows[1]["held_out"] is False and any(r["held_out"] for r in rows.values())
    for t in (t for t, r in rows.items() if not r["held_out"]):  # -31 / -50 % to within 0.5 %
        assert abs(rows[t]["ours_hz"] / rows[t]["test_hz"] - 1) < 0.005
    m = out["metrics"]
    assert m["ours"]["calibrated"]["rms_error_pct"] < m["v42"]["calibrated"]["rms_error_pct"]
    assert m["ours"]["calibrated"]["mean_mac"] > m["v42"]["calibrated"]["mean_mac"]
    # the held-out 30.7 Hz mode: +27.7 % with one scale of v3.3's seven outer I1 and the
    # masses free (+53 % without rho_wing; +19.7 % with one absolute outer section, which
    # jumped at its default); v4.2 is within 3 % (the docs page says why we still lose)
    assert rows[10]["held_out"] and 0.2 < rows[10]["ours_hz"] / rows[10]["test_hz"] - 1 < 0.3
    assert all(r["ours_in_range"] for r in out["mass_properties"])


def test_an_evaluation_assembles_once_and_its_mass_properties_are_unchanged(monkeypatch):
    """A fit evaluation (eigen-solve, then the mass properties) assembles K and M once
    (``nastran.lines.LineAssembler`` keeps the last assembly); the mass properties it gives are
    those of a model that assembles afresh (the same bits), and a move of a line field
    (``EI_outer``) or of a property array alone (``m_foam``: CONM2 M) is not served stale."""
    from bayesupdate.fe.assembly import GeneralAssembler
    from bayesupdate.nastran import load_nastran_model

    tables = {n: {"binds": b, "bounds": list(bd)} for n, (b, bd) in ac.PARAMETERS.items()}
    cached = load_nastran_model(ac.data_folder() / ac.V33_DECK, tables)
    fresh = load_nastran_model(ac.data_folder() / ac.V33_DECK, tables)
    calls = []
    assemble = GeneralAssembler.assemble

    def counted(self, *args, **kwargs):
        calls.append(self)
        return assemble(self, *args, **kwargs)

    monkeypatch.setattr(GeneralAssembler, "assemble", counted)
    points = [
        {"EI_root": 1.05, "EI_outer": 3.929, "m_foam": 0.971, "rho_wing": 1.022},
        {"EI_root": 1.05, "EI_outer": 3.000, "m_foam": 0.971, "rho_wing": 1.022},
        {"EI_root": 1.05, "EI_outer": 3.000, "m_foam": 0.500, "rho_wing": 1.022},
    ]
    for p in points:
        calls.clear()
        cached.solve(p, n_modes=6)
        props = [cached.mass_properties(p) for _ in range(2)]  # the fit's and the likelihood's
        assert sum(c is cached.general for c in calls) == 1
        fresh.general._last = (None, None)  # forget: an assembly of its own
        expected = fresh.mass_properties(p)
        for got in props:
            assert got.mass == expected.mass
            np.testing.assert_array_equal(got.cg, expected.cg)
            np.testing.assert_array_equal(got.inertia, expected.inertia)
    # the three points differ: a stale assembly would repeat the first one's mass properties
    # (I1 moves the beams' rotary inertia rho (I1 + I2) only: IXX, not the mass)
    values = [fresh.mass_properties(p) for p in points]
    assert values[0].mass == values[1].mass and values[0].inertia[0, 0] != values[1].inertia[0, 0]
    assert values[2].mass < values[1].mass
