"""``bayesupdate sample`` on a Nastran deck: the issue-19 round trip through the CLI on the
free-free steel plate deck of ``test_nastran_params`` (two PSHELLs, one CONM2), made thinner so
that four modes fall in the simulated test's 0-150 Hz band (1.25 and 1.875 mm: 41.6-136.2 Hz,
the fifth at 158 Hz, with Nastran's default lumped shell mass).  Simulate a test at perturbed
thicknesses, identify it, sample the thicknesses, write the posterior mean back.

The thicknesses must be sampled on the certified reduced basis (``fe.reduced``, the path of the
built-in FE models), and the posterior must be the right one.  Plate bending frequencies are
proportional to the thickness, so with a relative sd of 0.005 the posterior is Gaussian to
within the sampler's error, with the Gauss-Newton sd sigma (J^T J)^-1/2 of full solves at its
mean.
"""

import json

import numpy as np
import pytest
from test_nastran_params import _model, _plate

from bayesupdate.cli import main

DECK_T = (0.00125, 0.001875)
TRUTH = {"t1": 0.00125 * 1.08, "t2": 0.001875 * 0.94}
#: corners, edge middles and two inner GRIDs (GRID id = 1 + i + 9 j on the 9 x 5 grid)
POINTS = (1, 5, 9, 19, 23, 27, 37, 41, 45)
PARAMETERS = {"t1": "PSHELL 1 T", "t2": "PSHELL 2 T"}


def _cli_json(capsys, argv) -> dict:
    code = main(argv)
    captured = capsys.readouterr()
    assert code == 0, captured.err
    return json.loads(captured.out.strip().splitlines()[-1])


def _study(tmp_path, deck):
    rows = "\n".join(f'"{k}" = {g}' for k, g in enumerate(POINTS, start=1))
    params = "".join(
        f'[parameters.{n}]\nbinds = "{b}"\nbounds = [0.0006, 0.0025]\n'
        for n, b in PARAMETERS.items()
    )
    study = tmp_path / "study.toml"
    study.write_text(
        f'[model]\nsource = "{deck}"\n[model.test_points]\n{rows}\n'
        f'[data]\nsource = "{tmp_path / "modes.h5"}"\n{params}'
        # 10 x the identification's error: a posterior narrow enough to be Gaussian
        "[likelihood]\nsigma = 0.005\n"
        # the suite's time budget: half the default walkers, the run checked every 200 steps
        "[sampler]\nwalkers = 16\ncheck_every = 200\n"
    )
    return study


def test_sample_a_deck_on_the_reduced_basis_and_write_the_posterior_mean(tmp_path, capsys):
    deck = _plate(tmp_path / "plate.bdf", *DECK_T)
    study = _study(tmp_path, deck)
    sets = [f"--set={n}={v!r}" for n, v in TRUTH.items()]
    uff, modes = tmp_path / "test.uff", tmp_path / "modes.h5"
    test = _cli_json(capsys, ["simulate", "--study", str(study), *sets, "--noise", "0.01",
                              "--seed", "0", "--out", str(uff), "--json"])  # fmt: skip
    assert len(test["true_frequencies_hz"]) == 4
    identified = _cli_json(capsys, ["identify", str(uff), "--out", str(modes), "--json"])
    assert len(identified["modes"]) == 4
    updated = tmp_path / "updated.bdf"
    post = _cli_json(capsys, ["sample", str(study), "--json", "--write-bdf", str(updated)])

    # the certified reduced basis was used, and holds at the posterior mean
    assert post["rom"] is not None
    assert post["rom"]["max_rel_error"] <= 1e-4
    assert post["rom"]["error_at_posterior_mean"] <= 1e-4
    assert post["converged"]
    mean = {n: post["parameters"][n]["mean"] for n in PARAMETERS}
    sd = {n: post["parameters"][n]["sd"] for n in PARAMETERS}
    for n in PARAMETERS:
        assert abs(mean[n] - TRUTH[n]) < sd[n]

    # the posterior sd is the Gauss-Newton sd of full solves of the deck at the posterior mean
    names = list(PARAMETERS)
    model = _model(deck, {n: {"binds": b} for n, b in PARAMETERS.items()})
    targets = np.array([m["frequency_hz"] for m in identified["modes"]])
    jac = []
    for n in names:
        h = 1e-4 * mean[n]
        hi = model.solve({**mean, n: mean[n] + h}, n_modes=4).frequencies_hz
        lo = model.solve({**mean, n: mean[n] - h}, n_modes=4).frequencies_hz
        jac.append((hi - lo) / (2 * h) / targets)
    jac = np.array(jac).T  # (4 modes, 2 parameters) relative frequency per m
    laplace = np.sqrt(np.diag(np.linalg.inv(jac.T @ jac))) * post["sigma"]["fixed"]
    np.testing.assert_allclose([sd[n] for n in names], laplace, rtol=0.1)

    # the written deck is the deck at the posterior mean: its T fields hold the means to the
    # large field's 13 digits, and its frequencies are the model's at the mean to the eigen
    # solver's own repeatability (a 1e-14 change of T moves them by up to 1.6e-9, measured)
    from bayesupdate.nastran.deck import read_deck

    pshell = read_deck(updated).table("PSHELL")
    for pid, n in ((1, "t1"), (2, "t2")):
        assert pshell[pid]["T"] == pytest.approx(mean[n], rel=1e-12)
    written = _model(updated, {}).solve(n_modes=4).frequencies_hz
    np.testing.assert_allclose(written, model.solve(mean, n_modes=4).frequencies_hz, rtol=1e-8)
