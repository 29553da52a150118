"""Property-based tests (hypothesis): exact invariances of the FE model, LSCE/LSFD round trips on
random modal models, and study-file parsing of random junk (only BayesUpdateError may escape).

Hypothesis draws seeds and factors; geometry and modal models are built from the seeds with numpy,
so each example is small and fast.  ``max_examples`` is kept low: the whole file runs in seconds.
"""

import tomllib

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from bayesupdate.config import StudyConfig, load_study, parse_study
from bayesupdate.ema import FrfSet, identify
from bayesupdate.ema.lsfd import lsfd_residues
from bayesupdate.ema.synthesis import poles_from_modal, residues_from_shapes, synthesize_frf
from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import FEModel, Material, StructureBuilder, circular_tube

FAST = settings(
    max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True
)
N_MODES = 4


# -- FE invariances -----------------------------------------------------------------------------
def random_frame(
    seed: int,
    rotation: np.ndarray | None = None,
    shift=(0.0, 0.0, 0.0),
    length_scale: float = 1.0,
    density_scale: float = 1.0,
    modulus_scale: float = 1.0,
) -> FEModel:
    """A free-free tube frame: a chain of 3-4 random straight runs with a point mass at its end.

    The transformation arguments map the same frame rigidly (rotation (3, 3), shift [m]), scale
    every length (coordinates, tube diameter and wall, mesh size) by ``length_scale`` and masses
    by length_scale^3, or scale the density (and the point mass) or Young's modulus.
    """
    rng = np.random.default_rng(seed)
    n_runs = int(rng.integers(3, 5))
    points = [np.zeros(3)]
    for _ in range(n_runs):
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        points.append(points[-1] + direction * rng.uniform(0.3, 0.8))
    points = np.array(points)
    if rotation is not None:
        points = points @ rotation.T
    points = (points + np.asarray(shift)) * length_scale
    s = length_scale
    material = Material(210e9 * modulus_scale, 0.3, 7850.0 * density_scale, "steel")
    section = circular_tube(0.05 * s, 0.002 * s)
    b = StructureBuilder()
    nodes = [b.add_node(p) for p in points]
    for a, c in zip(nodes[:-1], nodes[1:], strict=True):
        b.add_line(a, c, section, material, part="tube", element_length=0.2 * s)
    b.add_point_mass(nodes[-1], 0.5 * density_scale * s**3, part="mass")
    return FEModel(b.build(), {}, {}, {})


def frame_frequencies(model: FEModel) -> np.ndarray:
    return model.solve({}, n_modes=N_MODES, method="dense").frequencies_hz


@FAST
@given(
    seed=st.integers(0, 10**6),
    rotation_seed=st.integers(0, 10**6),
    shift=st.tuples(*[st.floats(-5.0, 5.0)] * 3),
)
def test_rigid_motion_leaves_frequencies_unchanged(seed, rotation_seed, shift):
    rotation = Rotation.random(random_state=rotation_seed).as_matrix()
    f0 = frame_frequencies(random_frame(seed))
    f1 = frame_frequencies(random_frame(seed, rotation=rotation, shift=shift))
    assert f0[0] > 0.1  # elastic modes, not rigid ones
    np.testing.assert_allclose(f1, f0, rtol=1e-7)


@FAST
@given(seed=st.integers(0, 10**6), s=st.floats(0.1, 10.0))
def test_scaling_all_lengths_scales_frequencies_inversely(seed, s):
    # Timoshenko beams with rotary inertia: K ~ s, M ~ s^3 per unit of the scaled frame -> f ~ 1/s
    f0 = frame_frequencies(random_frame(seed))
    f1 = frame_frequencies(random_frame(seed, length_scale=s))
    np.testing.assert_allclose(f1 * s, f0, rtol=1e-7)


@FAST
@given(seed=st.integers(0, 10**6), c=st.floats(0.05, 20.0))
def test_density_and_modulus_scaling(seed, c):
    f0 = frame_frequencies(random_frame(seed))
    np.testing.assert_allclose(
        frame_frequencies(random_frame(seed, density_scale=c)), f0 / np.sqrt(c), rtol=1e-7
    )
    np.testing.assert_allclose(
        frame_frequencies(random_frame(seed, modulus_scale=c)), f0 * np.sqrt(c), rtol=1e-7
    )


# -- LSCE / LSFD round trips --------------------------------------------------------------------
FREQ_AXIS = np.arange(0.0, 128.0 + 1e-9, 0.125)


def random_modal_model(seed: int, n_modes: int, n_dof: int):
    """Well-separated modes in 15-110 Hz (>= 12 % apart), damping 0.5-3 %, real shapes with a
    driving point (row 0) that sees every mode."""
    rng = np.random.default_rng(seed)
    while True:
        fn = np.sort(rng.uniform(15.0, 110.0, n_modes))
        if np.all(np.diff(fn) / fn[:-1] > 0.12):
            break
    zeta = rng.uniform(0.005, 0.03, n_modes)
    shapes = rng.uniform(-1.0, 1.0, (n_dof, n_modes))
    shapes[0] = rng.choice([-1.0, 1.0], n_modes) * rng.uniform(0.5, 1.0, n_modes)
    return fn, zeta, shapes


def roving_response_frfs(fn, zeta, shapes, kind="accelerance") -> FrfSet:
    """FRFs of every DOF with the force at DOF 0 (a roving accelerometer, fixed hammer)."""
    poles = poles_from_modal(fn, zeta)
    residues = residues_from_shapes(poles, shapes, np.repeat(shapes[:1], shapes.shape[0], axis=0))
    h = synthesize_frf(FREQ_AXIS, poles, residues, kind)
    labels = tuple(f"{k + 1}V" for k in range(shapes.shape[0]))
    return FrfSet(FREQ_AXIS, h, labels, ("1V",) * len(labels), kind=kind)


@FAST
@given(seed=st.integers(0, 10**6), n_modes=st.integers(1, 4), n_dof=st.integers(3, 6))
def test_identify_recovers_random_modal_models(seed, n_modes, n_dof):
    fn, zeta, shapes = random_modal_model(seed, n_modes, n_dof)
    result = identify(roving_response_frfs(fn, zeta, shapes), band_hz=(5.0, 120.0))
    found = result.modes
    assert found.n_modes == n_modes
    np.testing.assert_allclose(found.frequencies_hz, fn, rtol=1e-5)
    np.testing.assert_allclose(found.damping_ratio, zeta, rtol=2e-3)
    rows = [found.dof_labels.index(f"{k + 1}V") for k in range(n_dof)]
    est = found.shapes[rows]
    mac = (np.sum(est * shapes, axis=0) ** 2) / (np.sum(est**2, axis=0) * np.sum(shapes**2, axis=0))
    assert np.all(mac > 0.9999), mac
    # driving point -> mass-normalized scale: the shapes themselves come back, up to sign
    sign = np.sign(np.sum(est * shapes, axis=0))
    np.testing.assert_allclose(est * sign, shapes, atol=2e-3 * np.abs(shapes).max())


@FAST
@given(
    seed=st.integers(0, 10**6),
    n_modes=st.integers(1, 5),
    kind=st.sampled_from(["receptance", "mobility", "accelerance"]),
)
def test_lsfd_recovers_residues_and_residuals_exactly(seed, n_modes, kind):
    # with the true poles the LSFD model is exact: residues and residuals come back to round-off
    rng = np.random.default_rng(seed)
    fn, zeta, shapes = random_modal_model(seed, n_modes, 4)
    poles = poles_from_modal(fn, zeta)
    residues = residues_from_shapes(poles, shapes, np.repeat(shapes[:1], 4, axis=0))
    residues = residues * np.exp(1j * rng.uniform(-0.3, 0.3, residues.shape))  # complex modes
    lower, upper = rng.normal(size=4) * 1e3, rng.normal(size=4) * 1e-6
    h = synthesize_frf(FREQ_AXIS, poles, residues, kind, lower, upper)
    res, lr, ur = lsfd_residues(FREQ_AXIS, h, poles, kind)
    scale = np.abs(residues).max()
    np.testing.assert_allclose(res, residues, atol=1e-8 * scale)
    np.testing.assert_allclose(lr, lower, rtol=1e-6, atol=1e-6 * np.abs(lower).max())
    np.testing.assert_allclose(ur, upper, rtol=1e-6, atol=1e-6 * np.abs(upper).max())


# -- study files with random junk ---------------------------------------------------------------
SECTIONS = {
    "model": ["source", "options", "sensors"],
    "data": ["source", "frequencies_hz", "weights", "sd_hz", "mass", "mass_sd", "cg", "inertia"],
    "pairing": ["method", "extra_modes"],
    "objective": ["mass_kg", "mass_weight", "mac_weight", "mass", "cg_weight", "inertia_weight"],
    "optimizer": ["starts", "method", "design", "seed"],
    "likelihood": ["sigma", "sigma_prior", "mass_sd", "pairing"],
    "sampler": ["walkers", "steps", "seed", "min_autocorr_times", "check_every", "hdi_prob"],
}

toml_scalars = st.one_of(
    st.booleans(),
    st.integers(-(10**6), 10**6),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=8),
)
toml_values = st.recursive(
    toml_scalars,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=6), inner, max_size=3)
    ),
    max_leaves=6,
)
known_section_tables = st.sampled_from(sorted(SECTIONS)).flatmap(
    lambda name: st.tuples(
        st.just(name),
        st.dictionaries(st.sampled_from([*SECTIONS[name], "junk"]), toml_values, max_size=3),
    )
)
parameter_tables = st.dictionaries(
    st.sampled_from(["theta_1", "theta_2", "t_hot_pipe", "nope"]),
    st.dictionaries(st.sampled_from(["bounds", "prior", "start", "junk"]), toml_values, max_size=3),
    max_size=2,
)
documents = st.builds(
    lambda sections, params, junk: {**dict(sections), "parameters": params, **junk},
    st.lists(known_section_tables, max_size=4),
    parameter_tables,
    st.dictionaries(st.sampled_from(["junk", "sampler "]), toml_values, max_size=1),
)


@settings(max_examples=150, deadline=None, derandomize=True)
@given(document=documents)
def test_random_study_documents_parse_or_raise_one_error(document):
    try:
        study = parse_study(document, "junk.toml")
    except BayesUpdateError as exc:
        assert "\n" not in str(exc) and str(exc)
        return
    assert isinstance(study, StudyConfig)


@settings(max_examples=60, deadline=None, derandomize=True)
@given(document=documents)
def test_random_studies_are_validated_before_any_work(document):
    # a parsed study goes through the whole validation of calibrate/sample with a fast model
    from bayesupdate.pipelines.study import prepare

    document = dict(document)
    document["model"] = {"source": "shear_building"}
    if not isinstance(document.get("data"), dict) or not document["data"]:
        document["data"] = {"frequencies_hz": [4.3, 10.8]}
    try:
        prepare(parse_study(document, "junk.toml"))
    except BayesUpdateError as exc:
        assert "\n" not in str(exc) and str(exc)


@settings(max_examples=80, deadline=None, derandomize=True)
@given(junk=st.one_of(st.binary(max_size=200), st.text(max_size=200).map(str.encode)))
def test_random_bytes_as_a_study_file(junk, tmp_path_factory):
    path = tmp_path_factory.mktemp("junk") / "study.toml"
    path.write_bytes(junk)
    try:
        load_study(path)
    except BayesUpdateError as exc:
        assert "study.toml" in str(exc) and "\n" not in str(exc)


def test_junk_strategy_reaches_valid_toml():
    # the documents above are what a TOML file can hold (so the parse tests are realistic)
    text = 'sampler = {walkers = 8}\n[model]\nsource = "shear_building"\n'
    assert parse_study(tomllib.loads(text)).sampler.walkers == 8
    with pytest.raises(BayesUpdateError, match="sampler.walkers"):
        parse_study({"sampler": {"walkers": "8"}}, "x.toml")
