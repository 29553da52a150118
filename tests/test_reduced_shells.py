"""Shell thickness, modulus and density parameters in the certified reduced basis: the affine
decomposition (``fe.reduced.shell_terms``) against direct element assembly (``shell.
direct_matrices``: offset transform as the product T^T X T), and reduced frequencies against full
sparse solves on a free closed box, on a plate clamped along one edge carrying a mass on a rigid
element, and on a Nastran deck with PSHELL T bindings."""

import numpy as np
import pytest
import scipy.sparse as sp

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import Binding, FEModel, Material, StructureBuilder
from bayesupdate.fe import shell_mesh as sm
from bayesupdate.fe.reduced import ReducedFEModel, ReducedSettings, shell_terms
from bayesupdate.fe.reduced.affine import decompose
from bayesupdate.fe.shell_model import ShellAssembly

STEEL = Material(210e9, 0.3, 7850.0, "steel")
N_MODES = 8
#: built to half the accepted error: the certificate holds on its 16 validation points, fresh
#: points may come a little above it
SETTINGS = ReducedSettings(n_modes=N_MODES, tol=5e-5, seed=0, n_snapshots=16, n_validation=16)


def _add_part(b, nodes, quads, part, **kw):
    used, local = np.unique(quads, return_inverse=True)
    return b.add_shells(nodes[used], local.reshape(quads.shape), material=STEEL, part=part, **kw)


def box_model() -> FEModel:
    """A free closed steel box 0.5 x 0.4 x 0.3 m (4 x 3 x 2 quads a side, 324 DOFs): lids 2 mm
    with an offset (reference plane 0.2 mm + t/2 below the mid-surface) and 0.5 kg/m^2 of
    non-structural mass, walls 1.5 mm; thickness of both, modulus of the lids, wall density."""
    nodes, quads = sm.box(0.5, 0.4, 0.3, 4, 3, 2)
    z = nodes[quads].mean(axis=1)[:, 2]
    lid = np.isclose(z, 0.0) | np.isclose(z, 0.3)
    b = StructureBuilder()
    _add_part(b, nodes, quads[lid], "lids", thickness=2e-3, offset=2e-4, offset_ratio=0.5,
              nsm=0.5)  # fmt: skip
    _add_part(b, nodes, quads[~lid], "walls", thickness=1.5e-3)
    bindings = {
        "t_lids": Binding("lids", "thickness"),
        "t_walls": Binding("walls", "thickness"),
        "E_lids": Binding("lids", "youngs_modulus"),
        "rho_walls": Binding("walls", "density"),
    }
    defaults = dict(t_lids=2e-3, t_walls=1.5e-3, E_lids=210e9, rho_walls=7850.0)
    bounds = dict(t_lids=(1e-3, 3e-3), t_walls=(1e-3, 3e-3), E_lids=(150e9, 250e9),
                  rho_walls=(6000.0, 9000.0))  # fmt: skip
    return FEModel(b.build(), bindings, defaults, bounds, name="box")


def clamped_plate_model() -> FEModel:
    """A 0.6 x 0.4 m steel plate, 6 x 4 quads, clamped along x = 0 (no rigid-body motion left):
    inner and outer halves with their own thickness, and a 0.5 kg point mass 5 cm above the
    outer half carried by a rigid element (RBE2) on the plate nodes within 12 cm, its mass
    factor a third parameter."""
    nodes, quads, _ = sm.plate(0.6, 0.4, 6, 4)
    outer = nodes[quads].mean(axis=1)[:, 0] > 0.3
    b = StructureBuilder()
    ids = np.full(len(nodes), -1)
    for part, sel in (("inner", ~outer), ("outer", outer)):
        used = np.unique(quads[sel])
        ids[used] = _add_part(b, nodes, quads[sel], part, thickness=3e-3)
    for n in ids[np.isclose(nodes[:, 0], 0.0)]:
        b.add_support(int(n))
    centre = b.add_node((0.45, 0.2, 0.05))
    b.add_rbe2(centre, ids[np.linalg.norm(nodes[:, :2] - (0.45, 0.2), axis=1) < 0.12])
    b.add_point_mass(centre, 0.5, "mass")
    bindings = {
        "t_in": Binding("inner", "thickness"),
        "t_out": Binding("outer", "thickness"),
        "m": Binding("mass", "mass_factor"),
    }
    defaults = dict(t_in=3e-3, t_out=3e-3, m=1.0)
    bounds = dict(t_in=(2e-3, 5e-3), t_out=(1.5e-3, 4e-3), m=(0.5, 2.0))
    return FEModel(b.build(), bindings, defaults, bounds, name="plate")


@pytest.fixture(scope="module")
def box():
    return box_model()


def _points(fe, n, seed):
    rng = np.random.default_rng(seed)
    lo, hi = np.array([fe.default_bounds()[k] for k in fe.parameter_names]).T
    return lo + rng.random((n, lo.size)) * (hi - lo)


def test_decomposition_matches_direct_assembly(box):
    # K(theta), M(theta) summed from the decomposition's terms (projected on the identity) against
    # the element matrices computed directly at the parameters' thicknesses, moduli, densities
    fe = box
    d = decompose(fe, fe.default_bounds(), 1e-9)
    eye = np.eye(fe.structure.n_dof)
    Kt, Mt = d.project(eye, d.k_stacks), d.project(eye, d.m_stacks)
    assert len(d.groups) == 0  # shells need no interpolation
    theta = _points(fe, 5, seed=3)
    cK, cM = d.coefficients(theta)
    for i, row in enumerate(theta):
        t, E, rho = fe.shell_properties(dict(zip(fe.parameter_names, row, strict=True)))
        mesh = fe.structure.shells.mesh(fe.structure.nodes, thickness=t, E=E, rho=rho)
        K, M = (X.toarray() for X in ShellAssembly(mesh).assemble())
        K_aff = np.tensordot(cK[i], Kt, axes=1)
        M_aff = np.tensordot(cM[i], Mt, axes=1)
        assert np.abs(K_aff - K).max() <= 1e-12 * np.abs(K).max()
        assert np.abs(M_aff - M).max() <= 1e-12 * np.abs(M).max()


def test_shell_term_parts_equal_a_coordinate_format_sum(box):
    # each feature pair's part, built on the CSR-ordered pattern without sorting, against the
    # same values summed by scipy's coordinate format on the DOFs np.unique finds: the same
    # DOFs, entries (the constant mass term sums both parts' non-structural and unit-density
    # values on shared edges) and values to round-off
    fe, g = box, box.general
    n = len(fe.parameter_names)
    f_ref = np.linspace(1.0, 2.0, 1 + 3 * n)
    acc = shell_terms._Accumulator(g, f_ref)
    for pos, _, m0, mp in g.terms:
        acc.add((0, 0), pos, m0)
        acc.add((1, 0), pos, mp[1])
    parts = acc.parts()
    for key, items in acc.items.items():
        pos = np.concatenate([p for p, _ in items])
        vals = np.concatenate([v for _, v in items]) * f_ref[key[0]] * f_ref[key[1]]
        dofs, inverse = np.unique(np.concatenate([g.rows[pos], g.cols[pos]]), return_inverse=True)
        local = inverse.reshape(2, -1)
        ref = sp.coo_matrix((vals, (local[0], local[1])), shape=(dofs.size,) * 2).tocsr()
        ref.sort_indices()
        part = parts[key]
        assert np.array_equal(part.dofs, dofs)
        assert np.array_equal(part.matrix.indptr, ref.indptr)
        assert np.array_equal(part.matrix.indices, ref.indices)
        assert np.abs(part.matrix.data - ref.data).max() <= 1e-15 * np.abs(ref.data).max()
    assert len(np.unique(np.concatenate([p for p, _ in acc.items[(0, 0)]]))) < sum(
        len(p) for p, _ in acc.items[(0, 0)]
    )  # the two parts share positions: the sum is tested


def test_decomposition_has_offset_and_rotary_powers(box):
    # the offset lids give t^2 stiffness terms; rotary inertia t^3 mass terms; four parameters
    # give the features 1, theta, theta^2, theta^3 (13 columns)
    d = decompose(box, box.default_bounds(), 1e-9)
    n = len(box.parameter_names)
    t_lids = box.parameter_names.index("t_lids")
    a, b, _ = d.k_gather
    assert (1 + n + t_lids) in set(a) | set(b)  # theta_lids^2 in K
    a, b, _ = d.m_gather
    assert (1 + 2 * n + t_lids) in set(a) | set(b)  # theta_lids^3 in M


def _check_reduced(fe, rom, n_points, seed):
    theta = _points(fe, n_points, seed)
    f_rom = rom.predict_frequencies_batch(theta)
    f_full = fe.predict_frequencies_batch(theta, fe.parameter_names, N_MODES)
    rel = f_rom / f_full - 1.0
    return rel


def test_reduced_box_is_certified_and_matches_full_solves(box):
    rom = ReducedFEModel(box, settings=SETTINGS).build()
    assert rom.certified and rom.n_rigid == 6
    assert rom.max_rel_error <= 5e-5
    rel = _check_reduced(box, rom, 5, seed=11)
    assert np.abs(rel).max() <= 1e-4
    assert rel.min() >= -1e-9  # Rayleigh-Ritz: reduced frequencies bound the full ones above
    # the reduced prediction's mass is the model's (rho and t of the walls enter it)
    p = dict(t_lids=2.5e-3, t_walls=1.2e-3, E_lids=200e9, rho_walls=8000.0)
    assert rom.predict(p, N_MODES).mass_kg == pytest.approx(box.total_mass(p)[0], rel=1e-12)


def test_reduced_clamped_plate_with_rigid_element_has_no_rigid_coordinates():
    fe = clamped_plate_model()
    rom = ReducedFEModel(fe, settings=SETTINGS).build()
    assert rom.certified and rom.n_rigid == 0
    rel = _check_reduced(fe, rom, 5, seed=12)
    assert np.abs(rel).max() <= 1e-4
    assert rel.min() >= -1e-9


def test_two_parameters_on_one_shell_property_are_rejected():
    fe = box_model()
    fe = FEModel(
        fe.structure,
        {"a": Binding("lids", "thickness"), "b": Binding("lids", "thickness")},
        {"a": 2e-3, "b": 2e-3},
        {"a": (1e-3, 3e-3), "b": (1e-3, 3e-3)},
    )
    with pytest.raises(BayesUpdateError, match=r"parameters a and b set the same property"):
        decompose(fe, fe.default_bounds(), 1e-9)


def test_nastran_deck_pshell_thicknesses_reduce_without_a_hook(tmp_path):
    # a deck model (``NastranModel``) binding PSHELL T: its affine terms carry the shells and the
    # deck factor, so the reduced basis applies as it is
    from test_nastran_params import _model, _plate

    deck = _plate(tmp_path / "plate.bdf")
    fe = _model(deck, {"t1": {"binds": "PSHELL 1 T", "bounds": [0.0015, 0.003]},
                       "t2": {"binds": "PSHELL 2 T", "bounds": [0.002, 0.004]}})  # fmt: skip
    settings = ReducedSettings(n_modes=5, tol=5e-5, seed=0, n_snapshots=8, n_validation=8)
    rom = ReducedFEModel(fe, settings=settings).build()
    assert rom.certified and rom.n_rigid == 6
    theta = _points(fe, 3, seed=4)
    f_rom = rom.predict_frequencies_batch(theta)
    f_full = fe.predict_frequencies_batch(theta, fe.parameter_names, 5)
    assert np.abs(f_rom / f_full - 1.0).max() <= 1e-4
