"""The README's worked example: the NX FEMAP exhaust (``shared/data/nastran/
femap_exhaust``, 4,466 shells, inch-lbf-s), round-tripped through the commands a user types.

A study binds PSHELL 3 T and PSHELL 9 T and maps 20 test points (the three hanger GRIDs and 17
shell GRIDs spread by farthest-point sampling, ``studies/nastran_roundtrip.spread_points``).
``simulate`` makes a roving-hammer test with PSHELL 3 T +8 % and PSHELL 9 T -6 % (its defaults:
20 modes, 1 % noise, seed 0), ``identify`` finds its modes and their frequency sds, ``sample``
(default settings, with the noise level sigma sampled: ``sigma_prior`` halfnormal 0.01) gives
the posterior and writes its mean into the deck, and ``modes`` on the written deck gives the
model's frequencies there.

Checked: each identified frequency lies within 4 of its identification sds of a true one;
the posterior converged; each thickness's posterior mean lies within one posterior sd
of the truth (the issue's criterion); the re-read deck gives the frequencies of the deck solved
at the posterior mean to 1e-6 (``--write-bdf`` writes full precision; ``modes --json`` rounds to
1e-6 Hz).  About 200 s of CPU, most of it the reduced basis's 96 full solves of 26,832 DOFs, so
it runs with BAYESUPDATE_LONG_TESTS=1.  Skipped without the shared data.
"""

import json
import os
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.cli import main

DECK = Path(__file__).resolve().parents[2] / "shared/data/nastran/femap_exhaust/exhaust.bdf"
needs_deck = pytest.mark.skipif(not DECK.exists(), reason=f"shared data not found: {DECK}")
long_test = pytest.mark.skipif(
    not os.environ.get("BAYESUPDATE_LONG_TESTS"),
    reason="long: set BAYESUPDATE_LONG_TESTS=1 (the FEMAP round trip, ~200 s CPU)",
)
#: the hangers, then 17 shell GRIDs by farthest-point sampling from the first hanger
GRIDS = (15661, 17406, 20494, 20505, 20718, 16509, 20652, 17368, 21321, 21706, 22177, 16225,
         15676, 15546, 15414, 15611, 15492, 16745, 15944, 17232)  # fmt: skip
#: the deck's 0.0551181 in +8 % and 0.0629921 in -6 %
TRUTH = {"t_3": 0.0551181 * 1.08, "t_9": 0.0629921 * 0.94}


def _cli_json(capsys, argv) -> dict:
    code = main(argv)
    captured = capsys.readouterr()
    assert code == 0, captured.err
    return json.loads(captured.out.strip().splitlines()[-1])


def _study(folder: Path) -> Path:
    rows = "\n".join(f'"{k}" = {g}' for k, g in enumerate(GRIDS, start=1))
    study = folder / "study.toml"
    study.write_text(
        f'[model]\nsource = "{DECK}"\n[model.test_points]\n{rows}\n'
        f'[data]\nsource = "{folder / "modes.h5"}"\n'
        '[parameters.t_3]\nbinds = "PSHELL 3 T"\nbounds = [0.04, 0.08]\n'
        '[parameters.t_9]\nbinds = "PSHELL 9 T"\nbounds = [0.04, 0.09]\n'
        '[likelihood]\nsigma_prior = { kind = "halfnormal", scale = 0.01 }\n'
        # each full solve takes seconds: two starts, no Nelder-Mead polish
        "[optimizer]\nstarts = 2\npolish = false\n"
    )
    return study


def _simulate_and_identify(capsys, study, sets, uff, modes) -> None:
    test = _cli_json(capsys, ["simulate", "--study", str(study), *sets, "--out", str(uff),
                              "--json"])  # fmt: skip
    ident = _cli_json(capsys, ["identify", str(uff), "--out", str(modes), "--json"])
    # each identified frequency within 4 of its own sd of a true mode (before the end window
    # refined the pruned poles too: 138.1 and 143.5 Hz at -11 and -37 sd on this test)
    true = np.asarray(test["true_frequencies_hz"])
    for mode in ident["modes"]:
        error = np.min(np.abs(true - mode["frequency_hz"]))
        assert error < 4 * mode["identification_sd_hz"], (mode, true)
    # one pole cut at the band's top, at a true mode (149.2 Hz with Nastran's lumped shell
    # mass, 149.8 Hz with consistent mass)
    assert len(ident["cut"]) == 1, ident["cut"]
    assert np.min(np.abs(true - ident["cut"][0]["frequency_hz"])) < 0.5, (ident["cut"], true)
    assert 148 < ident["cut"][0]["frequency_hz"] < 151


@needs_deck
def test_femap_exhaust_virtual_test_is_identified_within_its_sds(tmp_path, capsys):
    """The worked example's first two steps (about 15 s): the 120.4 Hz mode (2.8 % damping) is
    pruned, and its pole must still take part in the top window's refinement."""
    sets = [f"--set={n}={v!r}" for n, v in TRUTH.items()]
    study = _study(tmp_path)
    _simulate_and_identify(capsys, study, sets, tmp_path / "t.uff", tmp_path / "m.h5")


@needs_deck
@long_test
def test_femap_exhaust_round_trip_through_the_cli(tmp_path, capsys):
    study = _study(tmp_path)
    sets = [f"--set={n}={v!r}" for n, v in TRUTH.items()]
    uff, modes, written = tmp_path / "test.uff", tmp_path / "modes.h5", tmp_path / "updated.bdf"
    _simulate_and_identify(capsys, study, sets, uff, modes)
    post = _cli_json(capsys, ["sample", str(study), "--json", "--out", str(tmp_path / "p.h5"),
                              "--write-bdf", str(written)])  # fmt: skip
    assert post["converged"], post["convergence"]
    assert post["rom"] is not None  # the certified reduced basis, not full solves
    for name, truth in TRUTH.items():
        p = post["parameters"][name]
        assert abs(p["mean"] - truth) < p["sd"], (name, p, truth)
    binds = {"t_3": "PSHELL 3 T", "t_9": "PSHELL 9 T"}
    mean = [f"--set={binds[n]}={post['parameters'][n]['mean']!r}" for n in TRUTH]
    at_mean = _cli_json(capsys, ["modes", "--model", str(DECK), *mean, "--modes", "10", "--json"])
    reread = _cli_json(capsys, ["modes", "--model", str(written), "--modes", "10", "--json"])
    np.testing.assert_allclose(reread["frequencies_hz"], at_mean["frequencies_hz"], rtol=1e-6)
