"""Certified reduced basis (bayesupdate.fe.reduced) and the process pool
(bayesupdate.inference.evaluators), checked against full FE solves on a small free frame with
every kind of parameter: a wall thickness and a bend factor on the same elbow (tensor-product
interpolation), a density of an oval shell, a point-mass factor and a joint-spring factor."""

import warnings

import numpy as np
import pytest
import scipy.linalg as sl

from bayesupdate.fe import STEEL, Binding, FEModel, StructureBuilder, circular_tube, oval_tube
from bayesupdate.fe.elements.beam import bend_flexibility_factor
from bayesupdate.fe.reduced import (
    ReducedFEModel,
    ReducedSettings,
    barycentric_weights,
    chebyshev_nodes,
    reduced_model_for,
)
from bayesupdate.fe.reduced.affine import b31_kinks
from bayesupdate.inference.evaluators import PoolEvaluator

N_MODES = 8


def frame_model() -> FEModel:
    """Pipe with two bends -> joint spring -> oval shell with an end mass -> tail pipe."""
    b = StructureBuilder()
    pipe = circular_tube(0.045, 1.5e-3)
    a = b.add_pipe_run(
        [(0, 0, 0), (0.8, 0, 0), (1.2, 0.5, 0.0), (1.8, 0.5, 0.2)],
        pipe,
        STEEL,
        "pipe",
        bend_radii=[0.12, 0.1],
        bend_names=["elbow", "bend2"],
        element_length=0.15,
    )
    j = b.add_node(b.node_xyz(a[-1]))
    b.add_spring(a[-1], j, [1e8, 1e8, 1e8, 1e5, 3e4, 3e4], "pipe/shell")
    end = b.node_xyz(j) + np.array([0.4, 0.0, 0.0])
    s = b.add_pipe_run([b.node_xyz(j), end], oval_tube(0.25, 0.15, 1.0e-3), STEEL, "shell",
                       start_node=j, element_length=0.1)  # fmt: skip
    b.add_point_mass(s[-1], 1.5, "shell_mass", inertia=[0.01, 0.01, 0.01], offset=(0.05, 0, 0))
    b.add_pipe_run([end, end + np.array([0.5, 0.0, -0.1])], pipe, STEEL, "tail",
                   start_node=s[-1], element_length=0.15)  # fmt: skip
    b.add_point_mass(a[0], 0.3, "flange")
    for k, node in enumerate([a[0], a[4], s[2], s[-1]], start=1):
        b.add_sensor(f"{k}V", node, "V")
        b.add_sensor(f"{k}H", node, "H")
    bindings = {
        "t_pipe": Binding("pipe", "thickness"),
        "f_elbow": Binding("elbow", "bend_factor"),
        "rho_shell": Binding("shell", "density"),
        "m_shell": Binding("shell_mass", "mass_factor"),
        "k_joint": Binding("pipe/shell", "stiffness_factor"),
    }
    defaults = dict(t_pipe=1.5e-3, f_elbow=1.0, rho_shell=9000.0, m_shell=1.0, k_joint=1.0)
    bounds = dict(
        t_pipe=(0.6e-3, 6.5e-3),  # includes the B31.3 kinks of both bends (5.3, 6.1 mm)
        f_elbow=(0.5, 2.0),
        rho_shell=(3000.0, 25000.0),
        m_shell=(0.5, 2.0),
        k_joint=(0.3, 3.0),
    )
    return FEModel(b.build(), bindings, defaults, bounds, name="frame")


@pytest.fixture(scope="module")
def fe():
    return frame_model()


def settings(**changes) -> ReducedSettings:
    return ReducedSettings(**{"n_modes": N_MODES, "tol": 1e-4, "seed": 0, **changes})


@pytest.fixture(scope="module")
def rom(fe):
    return ReducedFEModel(fe, settings=settings()).build()


@pytest.fixture(scope="module")
def fresh(fe, rom):
    """12 fresh uniform points in the box (not the Sobol sets of the build) and their full
    frequencies."""
    rng = np.random.default_rng(2024)
    theta = rom.low + rng.random((12, len(rom.parameter_names))) * (rom.high - rom.low)
    return theta, fe.predict_frequencies_batch(theta, fe.parameter_names, N_MODES)


def test_certified_error_holds_on_fresh_points(rom, fresh):
    theta, f_full = fresh
    f_rom = rom.predict_frequencies_batch(theta, rom.parameter_names, N_MODES)
    assert rom.certified and 6 < rom.size <= rom.settings.max_size
    assert rom.max_rel_error <= 1e-4
    assert np.max(np.abs(f_rom / f_full - 1)) <= 1e-4
    assert "certified" in str(rom) and f"size {rom.size}" in str(rom)
    assert rom.summary()["size"] == rom.size


def test_reduced_frequencies_bound_the_full_ones_from_above(rom, fresh):
    # Rayleigh-Ritz (Courant-Fischer): lambda_i(V^T K V, V^T M V) >= lambda_i(K, M); the slack
    # covers the full solver's own error (~1e-8 relative) and the 1e-10 interpolation
    theta, f_full = fresh
    f_rom = rom.predict_frequencies_batch(theta, rom.parameter_names, N_MODES)
    assert np.all(f_rom >= f_full * (1 - 1e-7))
    assert np.min(f_rom / f_full - 1) < 1e-4  # and they are close, not trivially above


def test_rigid_modes_removed(fe, rom):
    # dense LAPACK on the full matrices: 6 zero eigenvalues, then the elastic ones
    p = fe.default_parameters()
    K, M, _ = fe.assembler.assemble(fe.element_properties(p))
    lam = sl.eigh(K.toarray(), M.toarray(), eigvals_only=True, subset_by_index=[0, 5 + N_MODES])
    f_dense = np.sqrt(np.abs(lam)) / (2 * np.pi)
    assert np.all(f_dense[:6] < 1e-2)
    f_rom = rom.predict_frequencies_batch(np.array([[p[n] for n in rom.parameter_names]]))[0]
    assert f_rom[0] > 1.0
    np.testing.assert_allclose(f_rom, f_dense[6:], rtol=1e-4)


def test_batch_equals_one_by_one_and_predict(rom, fresh):
    theta = fresh[0][:5]
    batch = rom.predict_frequencies_batch(theta, rom.parameter_names, N_MODES)
    for row, f in zip(theta, batch, strict=True):
        single = rom.predict_frequencies_batch(row[None, :], rom.parameter_names, N_MODES)[0]
        # same maths, other BLAS blocking: eigvalsh round-off eps ||C|| ~ 1e-16 x 1e5 lambda_1
        np.testing.assert_allclose(single, f, rtol=1e-9)
        pred = rom.predict(dict(zip(rom.parameter_names, row, strict=True)), N_MODES)
        np.testing.assert_allclose(pred.frequencies_hz, f, rtol=1e-10)
        assert pred.shapes.shape == (8, N_MODES) and pred.mass_kg > 0


def test_predict_shapes_and_mass_match_full(fe, rom):
    p = {"t_pipe": 2.2e-3, "rho_shell": 15000.0}
    full, red = fe.predict(p, N_MODES), rom.predict(p, N_MODES)
    assert red.mass_kg == pytest.approx(full.mass_kg, rel=1e-12)
    mac = (np.sum(full.shapes * red.shapes, 0) ** 2) / (
        np.sum(full.shapes**2, 0) * np.sum(red.shapes**2, 0)
    )
    assert np.all(mac > 0.999)


def test_subset_of_names_and_outside_box(fe, rom):
    names = ("rho_shell", "t_pipe")
    theta = np.array([[12000.0, 1.8e-3], [40000.0, 1.8e-3]])  # second row outside the box
    out = rom.predict_frequencies_batch(theta, names, N_MODES)
    full = fe.predict_frequencies_batch(theta, names, N_MODES)
    np.testing.assert_array_equal(out[1], full[1])  # outside: a full solve, not extrapolation
    assert np.max(np.abs(out[0] / full[0] - 1)) <= 1e-4
    assert np.all(np.isnan(rom.predict_frequencies_batch(np.array([[-1.0]]), ("t_pipe",), 4)))


def test_fallback_when_size_limit_too_small(fe):
    with pytest.warns(RuntimeWarning, match="falling back to full solves"):
        small = ReducedFEModel(fe, settings=settings(tol=1e-6, max_size=14, max_rounds=2)).build()
    assert not small.certified and small.max_rel_error > 1e-6
    theta = np.array([[1.2e-3, 1.1, 8000.0, 1.0, 1.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        out = small.predict_frequencies_batch(theta, small.parameter_names, N_MODES)
    np.testing.assert_array_equal(out, fe.predict_frequencies_batch(theta, fe.parameter_names, 8))


def test_seeded_build_is_deterministic(fe, rom, fresh):
    unbuilt = ReducedFEModel(fe, settings=settings())
    again = unbuilt.build()
    assert unbuilt.size == 0 and not unbuilt.certified  # build returns a new model
    assert again.size == rom.size and again.max_rel_error == rom.max_rel_error
    theta = fresh[0]
    np.testing.assert_array_equal(
        again.predict_frequencies_batch(theta), rom.predict_frequencies_batch(theta)
    )


def test_certify_at_a_point_and_localized_model(fe, rom):
    centre = 0.5 * (rom.low + rom.high)
    n_before = rom.certificate.n_points
    checked, err = rom.certify_at(centre[None, :])
    assert 0 <= err <= 1e-4 and checked.max_rel_error <= 1e-4
    # certify_at returns a new model with the point recorded; the model itself is unchanged
    assert checked.certificate.n_points == n_before + 1 and rom.certificate.n_points == n_before
    assert checked.max_rel_error == max(rom.max_rel_error, err)
    rng = np.random.default_rng(3)
    pilot = centre + 0.05 * (rom.high - rom.low) * rng.standard_normal((50, 5))
    local = rom.localized(pilot)
    assert local.certified and local.size <= rom.size and local.outer is rom
    inside = pilot[:4]
    full = fe.predict_frequencies_batch(inside, fe.parameter_names, N_MODES)
    assert np.max(np.abs(local.predict_frequencies_batch(inside) / full - 1)) <= 1e-4


def test_certify_at_enriches_below_the_tolerance_when_asked(fe, rom):
    # the sampler asks for this at the optimum when the basis's error (within tol) could still
    # bias a posterior whose data sds are smaller than it (pipelines.surrogates)
    point = rom.low + np.array([0.3, 0.7, 0.2, 0.6, 0.4]) * (rom.high - rom.low)
    kept, err = rom.certify_at(point[None, :])
    assert 1e-9 < err <= 1e-4 and kept.size == rom.size  # within tol: no enrichment by default
    enriched, err_after = rom.certify_at(point[None, :], enrich_above=0.1 * err)
    assert enriched.certified and enriched.size > rom.size
    # certify_at solves the point once, with the modes the enrichment needs (n_modes +
    # extra_modes); its lowest frequencies differ from an n_modes solve's by round-off (3e-12)
    n_solve = N_MODES + rom.settings.extra_modes
    full = fe.predict_frequencies_batch(point[None, :], fe.parameter_names, n_solve)[:, :N_MODES]
    exact = np.max(np.abs(enriched.predict_frequencies_batch(point) / full - 1))
    assert exact == pytest.approx(err_after) and exact < 1e-9  # its own shapes: exact there


def test_factory_returns_full_model_for_non_fe_models(fe):
    sentinel = object()
    assert reduced_model_for(sentinel) is sentinel


def test_barycentric_chebyshev_interpolation_is_exact_for_polynomials():
    pieces = np.array([0.5, 1.2, 3.0])
    x = np.linspace(0.5, 3.0, 37)
    w = barycentric_weights(x, pieces, 6)
    nodes = np.concatenate([chebyshev_nodes(0.5, 1.2, 6), chebyshev_nodes(1.2, 3.0, 6)])
    poly = lambda t: 3 * t**6 - 2 * t**3 + t - 7  # noqa: E731
    np.testing.assert_allclose(w @ poly(nodes), poly(x), rtol=1e-12)
    np.testing.assert_allclose(w.sum(axis=1), 1.0, rtol=1e-14)


def test_b31_kink_is_where_the_flexibility_factor_leaves_one(fe):
    s = fe.structure
    elements = np.flatnonzero(s.beam_elbow & (s.beam_bend_radius > 0))
    kinks = b31_kinks(s, elements, 1e-4, 0.02)
    assert kinks, "the elbows of the frame have a B31.3 kink below t = 20 mm"
    for t in kinks:
        D = s.beam_width[elements[0]]
        R = s.beam_bend_radius[elements]
        k = bend_flexibility_factor(np.full(R.size, t), R, np.full(R.size, D))
        assert np.any(np.isclose(k, 1.0, rtol=1e-9))


def test_affine_terms_reproduce_the_linear_parameters(fe):
    # FEModel.affine_terms: a linear parameter's element matrices assembled from ``unit``, times
    # value x scale, are the element matrices at that value
    terms = fe.affine_terms()
    a = fe.assembler
    values = {"rho_shell": 12000.0, "m_shell": 1.7, "k_joint": 0.6}
    props = fe.element_properties(values)
    kinds = {t.name: t.enters for t in terms.parameters}
    assert kinds == dict(t_pipe="nonlinear", f_elbow="nonlinear", rho_shell="M", m_shell="M",
                         k_joint="K")  # fmt: skip
    for t in terms.parameters:
        if t.family == "beam" and t.enters == "M":
            exact, unit = (
                a.matrices("beam", props, t.elements)[1],
                a.matrices("beam", terms.unit, t.elements)[1],
            )
        elif t.family == "mass":
            exact, unit = (
                a.matrices("mass", props)[1][t.elements],
                a.matrices("mass", terms.unit)[1][t.elements],
            )
        elif t.family == "spring":
            exact, unit = (
                a.matrices("spring", props)[0][t.elements],
                a.matrices("spring", terms.unit)[0][t.elements],
            )
        else:
            continue
        assert t.elements.size > 0
        value = values[t.name] * t.scale
        np.testing.assert_allclose(
            value * unit, exact, rtol=1e-13, atol=1e-13 * np.abs(exact).max()
        )


def test_pool_evaluator_matches_serial(fe):
    theta = np.array([[1.0e-3, 1.0, 6000.0, 1.2, 0.8], [2.5e-3, 1.5, 20000.0, 0.7, 2.0]])
    serial = fe.predict_frequencies_batch(theta, fe.parameter_names, 6)
    with PoolEvaluator(fe, n_workers=2) as pool:
        out = pool.predict_frequencies_batch(theta, fe.parameter_names, 6)
        bad = pool.predict_frequencies_batch(np.array([[-1.0]]), ("t_pipe",), 6)
    np.testing.assert_allclose(out, serial, rtol=1e-12)
    assert np.all(np.isnan(bad))
