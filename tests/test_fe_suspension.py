"""Suspension modes: a free structure on soft springs to ground (bungees, as in a ground vibration
test) keeps only its zero-energy motions as rigid-body modes; its suspension modes are elastic
modes, numbered with the others (as Nastran without SUPORT and OpenSees report them).

Closed form that could be wrong: a stiff beam of mass m and pitch inertia J about its centre on
two vertical springs k at x = +-a bounces at sqrt(2 k / m) and pitches at sqrt(2 k a^2 / J)
(rigid-body dynamics of a two-spring mount); the beam's flexibility lowers both by about
lambda_suspension / lambda_bending (Rayleigh quotient of the rigid shape against the static
flexible correction): measured 4.9e-5 (bounce) and 1.7e-6 (pitch) against a bound of 1.6e-4.
"""

from dataclasses import replace

import numpy as np
import pytest
from roundoff import frequency_roundoff, largest_eigenvalue

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import FEModel, Material, StructureBuilder, circular_tube
from bayesupdate.fe.assembly import GeneralAssembler
from bayesupdate.fe.sparse_modal import ModalSettings

AL = Material(70e9, 0.33, 2700.0, "aluminium")
TUBE = circular_tube(0.06, 3e-3)
L, A_SPRING, K_SPRING = 2.0, 0.8, 40.0  # beam length [m], spring positions +-a [m], k [N/m]


def _beam(springs: bool):
    """A 2 m aluminium tube along x, centred at the origin, free or on two vertical springs k at
    x = +-a; returns the structure."""
    b = StructureBuilder()
    xs = (-L / 2, -A_SPRING, A_SPRING, L / 2)
    ids = [b.add_node((x, 0.0, 0.0)) for x in xs]
    for n1, n2 in zip(ids[:-1], ids[1:], strict=True):
        b.add_line(n1, n2, TUBE, AL, "tube")
    if springs:
        for n in ids[1:3]:
            b.add_spring(n, None, [0, 0, K_SPRING, 0, 0, 0], "bungee")
    return b.build()


def _mass_and_pitch_inertia(structure):
    """(m [kg], J [kg m^2]): the rigid translation's and the pitch rotation's (about y through
    the centre) kinetic energy in the model's own mass matrix."""
    model = FEModel(structure, {}, {}, {})
    _, M = model.matrices()
    x = structure.nodes[:, 0]
    t = np.zeros(M.shape[0])
    t[2::6] = 1.0
    pitch = np.zeros(M.shape[0])
    pitch[2::6], pitch[4::6] = -x, 1.0  # small rotation about y: u_z = -theta x
    return float(t @ (M @ t)), float(pitch @ (M @ pitch))


@pytest.fixture(scope="module")
def beams():
    return _beam(springs=False), _beam(springs=True)


def test_suspension_modes_are_elastic_modes_one_and_two(beams):
    free_s, hung_s = beams
    m, J = _mass_and_pitch_inertia(hung_s)
    area = np.pi * (0.03**2 - 0.027**2)
    assert m == pytest.approx(2700.0 * area * L, rel=1e-12)  # a consistent mass matrix
    free = FEModel(free_s, {}, {}, {}).solve(n_modes=6)
    hung = FEModel(hung_s, {}, {}, {}).solve(n_modes=8)
    assert free.modes.n_rigid == 6
    assert hung.modes.n_rigid == 4  # sway x, y, yaw and roll about the springs' line are free
    f_bounce = np.sqrt(2 * K_SPRING / m) / (2 * np.pi)
    # round-off (measured 4e-4 of the bounce frequency: 2e-7 of its eigenvalue)
    assert np.all(hung.modes.rigid_frequencies_hz < 1e-3 * f_bounce)
    f_pitch = np.sqrt(2 * K_SPRING * A_SPRING**2 / J) / (2 * np.pi)
    # flexibility lowers the suspension eigenvalues by at most lambda_susp / lambda_bend
    bound = (f_pitch / free.frequencies_hz[0]) ** 2  # 1.5e-4
    np.testing.assert_allclose(hung.frequencies_hz[:2], [f_bounce, f_pitch], rtol=bound)
    assert np.all(hung.frequencies_hz[:2] <= np.array([f_bounce, f_pitch]) * (1 + 1e-10))
    # the first bending modes keep their numbers (3, 4, ... here, after the two suspension
    # modes): the horizontal bending is untouched, the vertical one stiffened a little
    bending = hung.frequencies_hz[2:8]
    np.testing.assert_allclose(bending, free.frequencies_hz, rtol=bound)
    assert np.all(bending >= free.frequencies_hz * (1 - 1e-9))
    assert bending[0] == pytest.approx(free.frequencies_hz[0], rel=1e-8)


def test_dense_banded_and_sparse_paths_agree_on_suspension_modes(beams):
    """The same modes from the three solvers (each on a fresh model: a sparse solve makes the
    model's sparse path its default).  LAPACK on the full pencil and the banded Krylov carry an
    absolute eigenvalue round-off ~ eps x lambda_max(K, M) = 7e-6 rad^2/s^2 (the axial modes are at
    3e10): 2.5e-7 of the bounce's eigenvalue, measured 1.4e-8 in its frequency on the earlier
    development machine and 6.2e-8 with OpenBLAS's SkylakeX kernels, inside the round-off scale of
    tests/roundoff.py (2.6e-7); the sparse path solves the shift-inverted pencil, so its low modes
    carry no such term.  Modes 3-8 agree to 1e-10, the iterative paths' convergence, above
    their round-off (measured 7e-12)."""
    dense, sparse, banded = (
        FEModel(beams[1], {}, {}, {}).solve(n_modes=8, method=m)
        for m in ("dense", "sparse", "krylov")
    )
    assert dense.modes.n_rigid == sparse.modes.n_rigid == banded.modes.n_rigid == 4
    K, M = FEModel(beams[1], {}, {}, {}).matrices()
    scale = frequency_roundoff(K, M, sparse.modes.shapes, largest_eigenvalue(K, M))
    assert 1e-7 < scale[0] < 1e-6  # the bounce: eps x lambda_max / lambda
    tol = np.maximum(scale, 1e-10)
    for other in (dense, banded):
        assert np.all(np.abs(other.frequencies_hz / sparse.frequencies_hz - 1.0) <= tol)


def test_suport_rigid_set_takes_every_rigid_motion_as_a_rigid_mode(beams):
    """MSC Nastran's SUPORT makes the rigid motions of its reference DOFs the rigid set:
    ``rigid_set="rigid_motions"`` reports six rigid modes (the two strained by the springs with
    their Rayleigh quotients: the closed-form bounce and pitch exactly, as the motions are rigid)
    and the elastic modes of the compressed pencil, the same on the dense and Lanczos paths
    (the Lanczos one through the bordered solve).  They are the bending modes with the springs'
    energy in the rigid directions left out: the default's modes 3-8 to 4.1e-9 here."""
    structure = beams[1]
    m, J = _mass_and_pitch_inertia(structure)
    f_closed = np.sqrt(2 * K_SPRING / np.array([m, J / A_SPRING**2])) / (2 * np.pi)
    g = GeneralAssembler(structure)
    K, M, _ = g.assemble(g.beams.default_properties())
    default = g.solve(K, M, 8)
    suport = ModalSettings(rigid_set="rigid_motions")
    dense = g.solve(K, M, 6, settings=suport)
    lanczos = g.solve(K, M, 6, settings=replace(suport, dense_below=0))
    assert default.n_rigid == 4 and dense.n_rigid == lanczos.n_rigid == 6
    np.testing.assert_allclose(np.sort(dense.rigid_frequencies_hz)[4:], f_closed, rtol=1e-9)
    assert np.all(np.sort(dense.rigid_frequencies_hz)[:4] < 1e-3 * f_closed[0])
    np.testing.assert_allclose(lanczos.frequencies_hz, dense.frequencies_hz, rtol=1e-9)
    np.testing.assert_allclose(dense.frequencies_hz, default.frequencies_hz[2:], rtol=1e-7)


def test_unknown_rigid_set_is_refused():
    with pytest.raises(BayesUpdateError, match="rigid_set must be one of"):
        ModalSettings(rigid_set="suspension")
