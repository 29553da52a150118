"""The certified reduced basis on a deck's line-element bindings (``nastran.lines.LineTerm``,
``fe.reduced.shell_terms``).  On the hand-edited variant of the MSC beam deck
(``test_nastran_lines._variant``: CBARs with a shear-rigid PBAR 1, a shear-flexible PBEAM 3,
two CRODs with PROD 2, MAT1 2 with G blank; here with coupled mass and a rotary inertia at
every GRID), PBAR A, I1, I2, J and
PROD A, J, NSM enter K and M linearly.  The affine sum must equal the deck's full assembly
(the bound elements re-built) to round-off at random points; the reduced frequencies must
match full solves within the certified tolerance, and bound them from above (Rayleigh-Ritz).
Fields that do not enter linearly (a PBARL dimension, a shear-flexible PBEAM's I1, E and A
together) are named, interpolated, and certified the same way.  Skipped without the shared
data.
"""

import warnings

import numpy as np
import pytest
from test_nastran_lines import BEAM, _deck, _load, _variant  # noqa: E402

from bayesupdate.fe.reduced import ReducedFEModel, ReducedSettings, reduced_model_for  # noqa: E402
from bayesupdate.fe.reduced.affine import decompose  # noqa: E402

LINEAR = {
    "a": {"binds": "PBAR 1 A"},
    "i1": {"binds": "PBAR 1 I1"},
    "i2": {"binds": "PBAR 1 I2"},
    "j": {"binds": "PBAR 1 J"},
    "ra": {"binds": "PROD 2 A"},
    "rj": {"binds": "PROD 2 J"},
    "nsm": {"binds": "PROD 2 NSM", "bounds": [1e-4, 5e-4]},
}


def _coupled(lines):
    """The variant with NSM 2e-4 on PROD 2 (PID MID A J C NSM), coupled mass and a rotary
    inertia of 1e-5 at every GRID (a massless CONM2): with the deck's lumped mass the
    rotations carry none, nor with a CBAR's coupled mass (translational, as MSC's), and the
    basis cannot hold their static response (``fe.reduced.basis.pod_basis``)."""
    out = [ln.replace("PROD,2,2,1.0,0.3", "PROD,2,2,1.0,0.3,,2e-4") for ln in _variant()(lines)]
    rotary = [f"CONM2,{900 + g},{g},,0.\n,1e-5,,1e-5,,,1e-5" for g in range(1, 13)]
    return ["PARAM,COUPMASS,1", *rotary, *out]


@pytest.fixture(scope="module")
def variant(tmp_path_factory):
    return _deck(tmp_path_factory.mktemp("variant"), _coupled)


def _points(fe, n, seed):
    rng = np.random.default_rng(seed)
    lo, hi = np.array([fe.default_bounds()[k] for k in fe.parameter_names]).T
    return lo + rng.random((n, lo.size)) * (hi - lo)


def test_affine_line_terms_equal_the_full_assembly(variant):
    fe = _load(variant, LINEAR)
    assert fe.default_parameters()["nsm"] == pytest.approx(2e-4)
    d = decompose(fe, fe.default_bounds(), 1e-9)
    eye = np.eye(fe.structure.n_dof)
    Kt, Mt = d.project(eye, d.k_stacks), d.project(eye, d.m_stacks)
    theta = _points(fe, 4, seed=1)
    cK, cM = d.coefficients(theta)
    for i, row in enumerate(theta):
        p = dict(zip(fe.parameter_names, row, strict=True))
        K, M = (X.toarray() for X in fe.matrices(p))  # the bound elements re-built at p
        K0, M0 = (X.toarray() for X in fe.matrices())
        assert np.abs(K - K0).max() > 1e-2 * np.abs(K).max()  # the point moves K and M
        assert np.abs(M - M0).max() > 1e-3 * np.abs(M).max()
        K_aff, M_aff = np.tensordot(cK[i], Kt, axes=1), np.tensordot(cM[i], Mt, axes=1)
        assert np.abs(K_aff - K).max() <= 1e-12 * np.abs(K).max()
        assert np.abs(M_aff - M).max() <= 1e-12 * np.abs(M).max()


def test_reduced_basis_on_line_fields_is_certified_against_full_solves(variant):
    fe = _load(variant, LINEAR)
    settings = ReducedSettings(n_modes=8, tol=1e-5, seed=0)
    rom = ReducedFEModel(fe, settings=settings).build()
    assert rom.certified and rom.max_rel_error <= 1e-5
    theta = _points(fe, 5, seed=2)
    rel = (
        rom.predict_frequencies_batch(theta)
        / fe.predict_frequencies_batch(theta, fe.parameter_names, 8)
        - 1.0
    )
    assert np.abs(rel).max() <= 1e-5
    assert rel.min() >= -1e-9  # Rayleigh-Ritz: the reduced frequencies bound the full ones
    # the reduced prediction's mass follows A and NSM (per-term masses, no assembly)
    p = dict(zip(fe.parameter_names, theta[0], strict=True))
    m = rom.predict(p, 8).mass_kg
    assert m == pytest.approx(fe.total_mass(p)[0], rel=1e-12)
    assert abs(m / fe.total_mass()[0] - 1.0) > 1e-3


@pytest.mark.parametrize(
    ("deck", "parameters", "named"),
    [
        ("msc", {"r1": {"binds": "PBARL 1 DIM1", "bounds": [0.7, 1.4]}}, "parameter r1 ("),
        ("variant", {"bi": {"binds": "PBEAM 3 I1"}}, "parameter bi ("),
        ("variant", {"e": {"binds": "MAT1 2 E scale"}, "a": {"binds": "PBAR 1 A"}},
         "parameters e, a together"),
    ],
)  # fmt: skip
def test_nonlinear_line_fields_get_an_interpolated_basis(variant, deck, parameters, named):
    """Fields that do not enter linearly are named (``line_nonlinear``) and interpolated in
    log(theta) (``lines.LineGroup``, to ``interp_tol`` 1e-9 of the entries they touch): the
    decomposition reproduces the full assembly at random points (1e-8 of the largest entry),
    and the reduced model built on it is certified and matches full solves (built on the
    variant's beams; the PBARL's interpolation alone is checked, its full solves are slow)."""
    fe = _load(BEAM / "beam_modes.dat" if deck == "msc" else variant, parameters)
    assert fe.line_terms() == ()
    assert named in fe.line_nonlinear and "\n" not in fe.line_nonlinear
    fe.affine_terms()  # no longer a reason for full solves
    d = decompose(fe, fe.default_bounds(), 1e-9)
    eye = np.eye(fe.structure.n_dof)
    Kt, Mt = d.project(eye, d.k_stacks), d.project(eye, d.m_stacks)
    theta = _points(fe, 3, seed=4)
    cK, cM = d.coefficients(theta)
    for i, row in enumerate(theta):
        K, M = (X.toarray() for X in fe.matrices(dict(zip(fe.parameter_names, row, strict=True))))
        assert np.abs(np.tensordot(cK[i], Kt, axes=1) - K).max() <= 1e-8 * np.abs(K).max()
        assert np.abs(np.tensordot(cM[i], Mt, axes=1) - M).max() <= 1e-8 * np.abs(M).max()
    if deck == "msc":  # a PBARL's records are not affine: every full solve re-reads its cards
        return
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no fallback to full solves
        rom = reduced_model_for(fe, n_modes=6, tol=1e-5)
    assert rom is not fe and rom.certified
    rel = (
        rom.predict_frequencies_batch(theta)
        / fe.predict_frequencies_batch(theta, fe.parameter_names, 6)
        - 1.0
    )
    assert np.abs(rel).max() <= 1e-5
    p = dict(zip(fe.parameter_names, theta[1], strict=True))
    assert rom.predict(p, 6).mass_kg == pytest.approx(fe.total_mass(p)[0], rel=1e-9)


def test_a_modulus_alone_on_shear_flexible_beams_is_linear(variant):
    # MAT1 E scale with G blank: G follows E, so the shear parameter 12 EI / (k G A L^2) is fixed
    # and K - K(deck) is (E / E0 - 1) x the same matrix, the PBEAM's shear flexibility included
    fe = _load(variant, {"e": {"binds": "MAT1 2 E scale"}})
    assert len(fe.line_terms()) == 1
    K0 = fe.matrices()[0]
    dK_13, dK_20 = ((fe.matrices({"e": e})[0] - K0).toarray() for e in (1.3, 2.0))
    assert np.abs(dK_20).max() > 0.1 * abs(K0).max()
    assert np.abs(dK_13 - 0.3 * dK_20).max() <= 1e-12 * abs(K0).max()


def test_sample_on_line_bindings_uses_the_certified_basis(variant, tmp_path, capsys):
    # the user's path: a study binding PBAR 1 A and PROD 2 A, frequencies of the deck at
    # a = 3.3, ra = 1.2; a short run (the basis is the point, not the chain's convergence)
    import json

    from bayesupdate.cli import main

    fe = _load(variant, {k: LINEAR[k] for k in ("a", "ra")})
    f = fe.solve({"a": 3.3, "ra": 1.2}, n_modes=6).frequencies_hz
    study = tmp_path / "study.toml"
    study.write_text(
        f'[model]\nsource = "{variant}"\n[data]\nfrequencies_hz = {[float(x) for x in f]}\n'
        '[parameters.a]\nbinds = "PBAR 1 A"\n[parameters.ra]\nbinds = "PROD 2 A"\n'
        "[likelihood]\nsigma = 0.01\n[sampler]\nwalkers = 8\nsteps = 40\ncheck_every = 20\n"
        "adapt_steps = 40\n"  # the claim is the basis, not the proposal's adaptation
    )
    assert main(["sample", str(study), "--json", "--out", str(tmp_path / "post.h5")]) == 0
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert out["rom"] is not None
    assert out["rom"]["max_rel_error"] <= 1e-4
    assert out["rom"]["error_at_posterior_mean"] <= 1e-4
    a = out["parameters"]["a"]
    assert abs(a["mean"] - 3.3) < 3 * a["sd"] < 0.1 * 3.3  # A is pinned by the data
    assert out["full_solves_reason"] is None


def test_sample_on_a_dimension_binding_uses_an_interpolated_basis(tmp_path, capsys):
    # the user's path on the MSC deck: a PBARL dimension does not enter K linearly (A and I are
    # powers of it); `sample` now runs on its interpolated, certified basis, not full solves
    import json

    from bayesupdate.cli import main

    deck = BEAM / "beam_modes.dat"
    fe = _load(deck, {"r1": {"binds": "PBARL 1 DIM1", "bounds": [0.7, 1.4]}})
    f = fe.solve(n_modes=3).frequencies_hz
    study = tmp_path / "study.toml"
    study.write_text(
        f'[model]\nsource = "{deck}"\n[data]\nfrequencies_hz = {[float(x) for x in f]}\n'
        '[parameters.r1]\nbinds = "PBARL 1 DIM1"\nbounds = [0.7, 1.4]\n'
        "[optimizer]\nstarts = 1\n[likelihood]\nsigma = 0.01\n"
        '[sampler]\nwalkers = 4\nsteps = 10\ncheck_every = 10\nmoves = "de"\n'
    )
    assert main(["sample", str(study), "--json"]) == 0
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert out["full_solves_reason"] is None
    rom = out["rom"]  # certified at the default tolerance 1e-4, and at the optimum
    assert rom["size"] > 6 and rom["max_rel_error"] <= 1e-4 and rom["error_at_optimum"] <= 1e-4
