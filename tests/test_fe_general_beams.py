"""General beams (arbitrary sections, offsets, pin flags), standard sections, rods and trusses,
node-local frames, each against a closed form or an independent path.

- general section = tube section: the same A, I, J, shear areas give the same element matrices
  as ``fe.elements.beam`` (to ~1e-16, asserted 1e-12) and the same modes;
- I12 != 0: the unsymmetric-bending tip deflection of a cantilever, v = P L^3 Iy / (3 E D),
  w = -P L^3 Iyz / (3 E D), D = Iy Iz - Iyz^2 (exact for one cubic element), and the same modes
  as the beam with the principal properties turned by the principal angle;
- offsets: a beam with rigid end offsets = the beam between the offset points plus an RBE2 to
  each node (exact equivalence, ~1e-12);
- pin flags: clamped-pinned Euler-Bernoulli beam, beta L = 3.926602, 7.068583, 10.210176; the
  pin = the same end held in translations and twist only (exact with lumped mass; with
  consistent mass the static condensation is a Ritz restriction, a hair above);
- trusses: a 2-D Warren truss against a separate 2-D truss assembly written here (direction
  cosines, lumped and consistent mass);
- frames: a support in a rotated rectangular frame = the whole structure rotated; a ring held
  radially in a cylindrical frame keeps exactly one rigid mode (the spin) and equals per-node
  rectangular frames written here; spherical axes against their formula;
- standard sections against closed forms and against a raster integration of the shape;
- optional peer: OpenSeesPy ElasticTimoshenkoBeam on a frame of I, box, bar and channel members
  with rigid offsets (OpenSees' rigidLink), 1.8e-12 (measured).
"""

from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg as sl
from scipy.spatial.transform import Rotation

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import STEEL, FEModel, Material, StructureBuilder, circular_tube
from bayesupdate.fe import standard_sections as ss
from bayesupdate.fe.assembly import Assembler
from bayesupdate.fe.frames import CoordinateFrame


def line_matrices(structure) -> list:
    """[(dofs, K, M)] of the structure's element families (``fe.elements.base``), as assembled."""
    return [(f.dofs, f.K, f.M) for f in Assembler(structure).families]


def _solve(structure, n_modes=8):
    return FEModel(structure, {}, {}, {}).solve(n_modes=n_modes, method="dense")


def _chain(b, points):
    ids = [b.add_node(p) for p in points]
    return ids, np.c_[ids[:-1], ids[1:]]


# -- general section against the tube section --------------------------------------------------
def test_general_section_reproduces_tube_beam():
    tube = circular_tube(0.05, 2e-3)
    pts = [(0.0, 0.1 * i, 0.03 * i) for i in range(11)]

    def build(general):
        b = StructureBuilder()
        ids, pairs = _chain(b, pts)
        if general:
            b.add_beams(pairs, ss.from_tube(tube, STEEL.poisson), STEEL, "p")
        else:
            for a, c in pairs:
                b.add_beam(a, c, tube, STEEL, "p")
        b.add_point_mass(ids[-1], 0.4, "tip")
        b.add_support(ids[0])
        return b.build()

    old, new = build(False), build(True)
    a = Assembler(old)
    K0, M0 = a.matrices("beam", a.default_properties())
    ((_, K1, M1),) = line_matrices(new)
    assert np.abs(K1 - K0).max() <= 1e-12 * np.abs(K0).max()
    assert np.abs(M1 - M0).max() <= 1e-12 * np.abs(M0).max()
    f0, f1 = _solve(old).frequencies_hz, _solve(new).frequencies_hz
    np.testing.assert_allclose(f1, f0, rtol=1e-12)


# -- product of inertia -------------------------------------------------------------------------
def test_product_of_inertia_unsymmetric_bending_closed_form():
    """One Euler-Bernoulli element (cubic: exact for a tip load), clamped at node 0."""
    L, E, P = 1.3, 70e9, 100.0
    sec = ss.general_section(area=4e-4, iy=3e-8, iz=5e-8, torsion=4e-8, iyz=1.5e-8)
    b = StructureBuilder()
    n0, n1 = b.add_node((0, 0, 0)), b.add_node((L, 0, 0))
    b.add_beams([[n0, n1]], sec, Material(E, 0.33, 2700.0), "bar", up=(0, 0, 1))
    ((_, K, _),) = line_matrices(b.build())
    u = np.linalg.solve(K[0][6:, 6:], np.r_[0.0, P, 0, 0, 0, 0])  # tip load along local y
    D = sec.iy * sec.iz - sec.iyz**2
    assert u[1] == pytest.approx(P * L**3 * sec.iy / (3 * E * D), rel=1e-12)
    assert u[2] == pytest.approx(-P * L**3 * sec.iyz / (3 * E * D), rel=1e-12)


def test_product_of_inertia_equals_turned_principal_beam():
    iy, iz, iyz = 2e-7, 6e-7, -1.2e-7
    alpha = 0.5 * np.arctan2(2 * iyz, iz - iy)
    c, s = np.cos(alpha), np.sin(alpha)
    principal = ss.general_section(
        2e-3, s**2 * iz - 2 * c * s * iyz + c**2 * iy, c**2 * iz + 2 * c * s * iyz + s**2 * iy,
        3e-7, 0.0, 0.7, 0.7,
    )  # fmt: skip
    coupled = ss.general_section(2e-3, iy, iz, 3e-7, iyz, 0.7, 0.7)
    pts = [(0.12 * i, 0.05 * i, 0.0) for i in range(13)]
    axis = np.subtract(pts[1], pts[0]) / np.linalg.norm(np.subtract(pts[1], pts[0]))
    ey = np.cross((0, 0, 1), axis)
    ez = np.cross(axis, ey)

    def build(section, up):
        b = StructureBuilder()
        ids, pairs = _chain(b, pts)
        b.add_beams(pairs, section, STEEL, "p", up=up)
        b.add_support(ids[0])
        return b.build()

    # the principal z axis is -sin(alpha) y + cos(alpha) z
    f_coupled = _solve(build(coupled, ez)).frequencies_hz
    f_principal = _solve(build(principal, -s * ey + c * ez)).frequencies_hz
    np.testing.assert_allclose(f_coupled, f_principal, rtol=1e-10)
    assert abs(alpha) > 0.2  # a real rotation


# -- offsets ------------------------------------------------------------------------------------
def test_offset_beam_equals_rbe2_to_offset_points():
    sec = ss.box_section(0.08, 0.05, 3e-3, 4e-3)
    w = np.array([[0.0, 0.04, 0.07], [0.02, -0.03, 0.05]])
    xa, xb = np.array([0.0, 0.0, 0.0]), np.array([1.2, 0.3, 0.1])

    def build(offsets):
        b = StructureBuilder()
        a, c = b.add_node(xa), b.add_node(xb)
        if offsets:
            b.add_beams([[a, c]], sec, STEEL, "p", offsets=w, up=(0, 0, 1))
        else:
            ea, eb = b.add_node(xa + w[0]), b.add_node(xb + w[1])
            b.add_beams([[ea, eb]], sec, STEEL, "p", up=(0, 0, 1))
            b.add_rbe2(a, [ea])
            b.add_rbe2(c, [eb])
        b.add_point_mass(c, 2.0, "tip", inertia=[0.01, 0.02, 0.03])
        b.add_support(a)
        return b.build()

    f_off, f_rbe = _solve(build(True), 6).frequencies_hz, _solve(build(False), 6).frequencies_hz
    np.testing.assert_allclose(f_off, f_rbe, rtol=1e-11)


# -- pin flags ----------------------------------------------------------------------------------
CLAMPED_PINNED_BETA_L = np.array([3.926602312, 7.068582745, 10.21017612])


def _pinned_beam(pins: bool, n=40, length=2.0, d=0.02, mass="consistent"):
    b = StructureBuilder(rotary_inertia=False)
    ids, pairs = _chain(b, [(length * i / n, 0, 0) for i in range(n + 1)])
    rod = replace(ss.rod_section(d), shear_y=0.0, shear_z=0.0)  # Euler-Bernoulli
    pin = [("", "")] * (n - 1) + [("", "56")]
    b.add_beams(pairs, rod, STEEL, "p", pins=pin if pins else None, mass=mass)
    b.add_support(ids[0])
    b.add_support(ids[-1], "123456" if pins else "1234")
    return b.build()


def test_pin_flag_gives_clamped_pinned_euler_bernoulli_beam():
    r = _solve(_pinned_beam(True), 6)
    length, d = 2.0, 0.02
    c = np.sqrt(STEEL.youngs_modulus * d**2 / 16 / STEEL.density)  # sqrt(EI / rho A)
    exact = CLAMPED_PINNED_BETA_L**2 / (2 * np.pi * length**2) * c
    err = r.frequencies_hz.reshape(3, 2) / exact[:, None] - 1  # bending pairs in y and z
    # consistent-mass Hermite elements converge from above, as h^4 (measured 6e-8, 7e-7, 3e-6)
    assert np.all(err > 0) and np.all(err < 1e-5), err
    # the same end held in translations and twist only: its rotations stay DOFs with their own
    # inertia, where the pin condenses them statically (Guyan), so the pin is a hair stiffer
    held = _solve(_pinned_beam(False), 6).frequencies_hz
    rel = r.frequencies_hz / held - 1
    assert np.all(rel >= -1e-13) and np.all(rel < 1e-8), rel  # measured <= 2e-9
    lumped = _solve(_pinned_beam(True, mass="lumped"), 6).frequencies_hz
    held = _solve(_pinned_beam(False, mass="lumped"), 6).frequencies_hz
    np.testing.assert_allclose(lumped, held, rtol=1e-10)  # no inertia on the released DOFs


# -- rods and trusses ---------------------------------------------------------------------------
def _truss_2d(xy, members, area, E, rho, lumped, fixed):
    """A separate 2-D truss: 2 DOFs per node, K from direction cosines; returns f [Hz]."""
    n = 2 * len(xy)
    K, M = np.zeros((n, n)), np.zeros((n, n))
    for i, j in members:
        d = xy[j] - xy[i]
        L = np.hypot(*d)
        c, s = d / L
        k = E * area / L * np.outer([-c, -s, c, s], [-c, -s, c, s])
        m = rho * area * L
        dofs = [2 * i, 2 * i + 1, 2 * j, 2 * j + 1]
        K[np.ix_(dofs, dofs)] += k
        mm = m / 2 * np.eye(4) if lumped else m / 6 * np.kron([[2, 1], [1, 2]], np.eye(2))
        M[np.ix_(dofs, dofs)] += mm
    free = np.setdiff1d(np.arange(n), fixed)
    lam = sl.eigh(K[np.ix_(free, free)], M[np.ix_(free, free)], eigvals_only=True)
    return np.sqrt(lam) / (2 * np.pi)


@pytest.mark.parametrize("lumped", [True, False])
def test_warren_truss_matches_2d_truss_assembly(lumped):
    xy = np.array([(0, 0), (1, 0), (2, 0), (3, 0), (0.5, 0.8), (1.5, 0.8), (2.5, 0.8)], float)
    members = [(0, 1), (1, 2), (2, 3), (4, 5), (5, 6), (0, 4), (4, 1), (1, 5), (5, 2), (2, 6),
               (6, 3)]  # fmt: skip
    area, al = 3e-4, Material(70e9, 0.33, 2700.0)
    expected = _truss_2d(xy, members, area, 70e9, 2700.0, lumped, fixed=[0, 1, 7])
    b = StructureBuilder()
    ids = [b.add_node((x, y, 0.0)) for x, y in xy]
    b.add_rods(members, area, al, "truss", mass="lumped" if lumped else "consistent")
    for n in ids:
        b.add_support(n, "3456")  # a plane truss: out-of-plane and rotations held
    b.add_support(ids[0], "12")
    b.add_support(ids[3], "2")
    r = _solve(b.build(), n_modes=len(expected))
    np.testing.assert_allclose(r.frequencies_hz, expected, rtol=1e-10)


# -- node frames --------------------------------------------------------------------------------
def _portal(rotation: np.ndarray, framed: bool):
    """A 3-D frame; its last foot slides on a plane (support '2' in a tilted frame), a mass
    hangs on an RBE2 in the tilted frame's components 1, 2 (a spring along 3), another on an
    RBE3 reference whose components 1, 2 are dependent in the tilted frame.  With ``framed``
    the structure is as given and those nodes have the tilted frame; otherwise every point is
    turned by ``rotation`` (rows = the frame's axes) and the components are global."""
    pts = np.array([(0, 0, 0), (0, 0, 1.2), (1.5, 0, 1.2), (1.5, 0.8, 1.2), (1.5, 0.8, 0),
                    (1.2, 0.3, 1.5), (0.8, 0.4, 1.3)], float)  # fmt: skip
    turn = np.eye(3) if framed else rotation
    b = StructureBuilder()
    ids = [b.add_node(turn @ p) for p in pts]
    sec = ss.i_section(0.12, 0.06, 5e-3, 8e-3)
    for k in range(4):
        up = turn @ (np.array([1.0, 0, 0]) if k in (0, 3) else np.array([0, 0, 1.0]))
        b.add_beams([[ids[k], ids[k + 1]]], sec, STEEL, "frame", up=up)
    b.add_support(ids[0])
    if framed:
        b.set_frame(ids[4:], CoordinateFrame.from_axes("rectangular", (0, 0, 0), rotation))
    b.add_support(ids[4], "2")
    b.add_point_mass(ids[2], 5.0, "mass")
    b.add_rbe2(ids[2], [ids[5]], "12")
    b.add_support(ids[5], "456")
    b.add_spring(ids[5], None, [0, 0, 3e5, 0, 0, 0], "spring", frame=rotation if framed else None)
    b.add_point_mass(ids[5], 1.5, "mass")
    b.add_rbe3(ids[6], ids[1:4], [1.0, 2.0, 1.5], components="12")
    b.add_support(ids[6], "3456")
    b.add_point_mass(ids[6], 2.5, "mass")
    return b.build()


def test_support_in_rotated_frame_equals_rotated_structure():
    A = Rotation.from_euler("xyz", [25, -40, 70], degrees=True).as_matrix().T  # rows = axes
    r1 = _solve(_portal(A, True), 8)
    r2 = _solve(_portal(A, False), 8)
    # measured 8e-11 (round-off of the turned geometry); the RBE2 or RBE3 read in global
    # instead of the tilted frame is off by 8e-3 and 7e-3
    np.testing.assert_allclose(r1.frequencies_hz, r2.frequencies_hz, rtol=1e-9)
    # the foot moves only in the frame's 1-3 plane: no motion along its axis 2
    foot = r1.modes.shapes[24:27]
    assert np.abs(A[1] @ foot).max() <= 1e-12 * np.abs(foot).max()


def _ring(frame_of):
    b = StructureBuilder()
    phi = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    ids = [b.add_node((np.cos(p), np.sin(p), 0.0)) for p in phi]
    pairs = np.c_[ids, np.roll(ids, -1)]
    b.add_beams(pairs, ss.tube_section(0.04, 2e-3), STEEL, "ring")
    for n, p in zip(ids, phi, strict=True):
        frame_of(b, n, p)
        b.add_support(n, "13")  # radial and axial
    return b.build()


def test_cylindrical_frame_ring_held_radially():
    cyl = CoordinateFrame.from_points("cylindrical", (0, 0, 0), (0, 0, 1), (1, 0, 0))
    by_cylinder = _ring(lambda b, n, p: b.set_frame(n, cyl))

    def by_hand(b, n, p):
        axes = [(np.cos(p), np.sin(p), 0.0), (-np.sin(p), np.cos(p), 0.0), (0, 0, 1.0)]
        b.set_frame(n, CoordinateFrame.from_axes("rectangular", (0, 0, 0), axes))

    r1, r2 = _solve(by_cylinder, 6), _solve(_ring(by_hand), 6)
    assert r1.modes.n_rigid == 1  # the ring may spin about z: u = theta x r is tangential
    np.testing.assert_allclose(r1.frequencies_hz, r2.frequencies_hz, rtol=1e-12)


def test_spherical_axes():
    sph = CoordinateFrame.from_points("spherical", (1, 2, 3), (1, 2, 4), (2, 2, 3))
    t, p = 0.7, 2.1
    x = np.array([1, 2, 3]) + 2.5 * np.array(
        [np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)]
    )
    e = sph.axes_at(x[None])[0]
    expected = [
        (np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)),
        (np.cos(t) * np.cos(p), np.cos(t) * np.sin(p), -np.sin(t)),
        (-np.sin(p), np.cos(p), 0.0),
    ]
    np.testing.assert_allclose(e, expected, atol=1e-14)


# -- standard sections --------------------------------------------------------------------------
def _raster(inside, width, height, n=2000):
    """A, iy, iz, iyz about the centroid of the set ``inside(y, z)`` in the box [0, width] x
    [0, height], by the midpoint rule on an n x n grid: exact when the walls lie on cell edges
    (as the dimensions below are chosen) once each cell's own d^2 / 12 is added."""
    dy, dz = width / n, height / n
    y = (np.arange(n) + 0.5) * dy
    z = (np.arange(n) + 0.5) * dz
    Y, Z = np.meshgrid(y, z, indexing="ij")
    w = inside(Y, Z) * dy * dz
    A = w.sum()
    yc, zc = (w * Y).sum() / A, (w * Z).sum() / A
    iy = (w * (Z - zc) ** 2).sum() + A * dz**2 / 12
    iz = (w * (Y - yc) ** 2).sum() + A * dy**2 / 12
    return A, iy, iz, (w * (Y - yc) * (Z - zc)).sum()


def test_i_beam_closed_form_and_raster():
    h, b, tw, tf = 0.3, 0.15, 7.5e-3, 10.5e-3
    s = ss.i_section(h, b, tw, tf)
    assert s.iy == pytest.approx((b * h**3 - (b - tw) * (h - 2 * tf) ** 3) / 12, rel=1e-14)
    A, iy, iz, _ = _raster(
        lambda y, z: (z < tf) | (z > h - tf) | (np.abs(y - b / 2) < tw / 2), b, h
    )
    assert (s.area, s.iy, s.iz) == pytest.approx((A, iy, iz), rel=1e-9)
    # Cowper's thin-walled I for shear along the web: about the web share of the area
    assert 0.9 * (h - 2 * tf) * tw / s.area < s.shear_z < 1.1 * (h - 2 * tf) * tw / s.area


def test_channel_and_box_against_raster():
    h, b, tw, tf = 0.2, 0.08, 8e-3, 12e-3
    s = ss.channel_section(h, b, tw, tf)
    A, iy, iz, iyz = _raster(lambda y, z: (z < tf) | (z > h - tf) | (y < tw), b, h)
    assert (s.area, s.iy, s.iz) == pytest.approx((A, iy, iz), rel=1e-9)
    assert abs(iyz) < 1e-9 * iy and s.iyz == 0.0
    bx = ss.box_section(0.1, 0.06, 4e-3, 6e-3)
    A, iy, iz, _ = _raster(lambda y, z: ~((np.abs(y - 0.05) < 0.046) & (np.abs(z - 0.03) < 0.024)),
                           0.1, 0.06)  # fmt: skip
    assert (bx.area, bx.iy, bx.iz) == pytest.approx((A, iy, iz), rel=1e-9)


def test_tee_against_raster_and_thin_wall_torsion():
    """A T of height 0.2 (z), flange 0.1 x 0.012 at z = 0.2, web 0.008: A and the second
    moments about the centroid as the raster's; J the thin walls' on their mid-lines, the
    flange's and the web's shear areas; the flange at z = 0 (Nastran's T2) is the same
    section."""
    h, b, tw, tf = 0.2, 0.1, 8e-3, 12e-3
    s = ss.tee_section(h, b, tw, tf)
    A, iy, iz, iyz = _raster(lambda y, z: (z > h - tf) | (np.abs(y - b / 2) < tw / 2), b, h)
    assert (s.area, s.iy, s.iz) == pytest.approx((A, iy, iz), rel=1e-9)
    assert abs(iyz) < 1e-9 * iy and s.iyz == 0.0
    A2, iy2, iz2, _ = _raster(lambda y, z: (z < tf) | (np.abs(y - b / 2) < tw / 2), b, h)
    assert (A2, iy2, iz2) == pytest.approx((A, iy, iz), rel=1e-12)
    assert s.torsion == pytest.approx((b * tf**3 + (h - tf / 2) * tw**3) / 3, rel=1e-14)
    assert (s.shear_y, s.shear_z) == pytest.approx((b * tf / A, (h - tf) * tw / A), rel=1e-12)


def test_box_shear_factor_and_bar_torsion_closed_forms():
    nu = 0.3
    sq = ss.box_section(0.1, 0.1, 2e-3, 2e-3, nu)
    assert sq.shear_y == sq.shear_z == pytest.approx(20 * (1 + nu) / (48 + 39 * nu), rel=1e-14)
    assert ss.bar_section(0.02, 0.05).shear_z == pytest.approx(10 * 1.3 / (12 + 11 * 0.3))
    # Roark's J against the exact series (Timoshenko & Goodier, sec. 109): within 0.5 %
    for ratio in (1.0, 2.0, 5.0):
        a, c = ratio * 0.01, 0.01
        n = np.arange(1, 200, 2)
        exact = (
            a
            * c**3
            / 3
            * (1 - 192 * c / (np.pi**5 * a) * np.sum(np.tanh(n * np.pi * a / (2 * c)) / n**5))
        )
        assert ss.bar_section(a, c).torsion == pytest.approx(exact, rel=5e-3)
    tube = ss.tube_section(0.06, 3e-3)
    assert tube.torsion == pytest.approx(np.pi / 32 * (0.06**4 - 0.054**4), rel=1e-14)


# -- bad input ----------------------------------------------------------------------------------
def _frame_builder():
    b = StructureBuilder()
    ids = [b.add_node((i, 0, 0)) for i in range(3)]
    return b, ids


@pytest.mark.parametrize(
    "kwargs, pairs, words",
    [
        ({}, [[0, 1], [2, 2]], "element 1 repeats node 2"),
        ({"offsets": [[0, 0, 0], [-1, 0, 0]]}, [[0, 1]], "element 0 has zero length"),
        ({"up": (1, 0, 0)}, [[0, 1], [1, 2]], "element 0: the orientation vector"),
        ({"pins": ("1", "1")}, [[0, 1]], "element 0: its pin flags"),
        ({"pins": [("", ""), ("4", "4")]}, [[0, 1], [1, 2]], "element 1: its pin flags"),
    ],
)
def test_bad_beams_are_one_line_errors_naming_the_element(kwargs, pairs, words):
    b, _ = _frame_builder()
    with pytest.raises(BayesUpdateError) as err:
        b.add_beams(pairs, ss.rod_section(0.02), STEEL, "frame", **kwargs)
    assert words in str(err.value) and "part 'frame'" in str(err.value)
    assert "\n" not in str(err.value)


def test_bad_sections_and_rods():
    with pytest.raises(BayesUpdateError, match="iy must be finite and >= 0"):
        ss.general_section(1e-4, -1e-8, 1e-8, 1e-8)
    with pytest.raises(BayesUpdateError, match="area must be finite and > 0"):
        ss.general_section(0.0, 1e-8, 1e-8, 1e-8)
    assert ss.general_section(1e-4, 0.0, 1e-8, 0.0).iy == 0.0  # MSC's PBAR allows I = 0
    with pytest.raises(BayesUpdateError, match="iy iz > iyz"):
        ss.general_section(1e-4, 1e-8, 1e-8, 1e-8, iyz=2e-8)
    b, _ = _frame_builder()
    with pytest.raises(BayesUpdateError, match="element 1 needs area > 0"):
        b.add_rods([[0, 1], [1, 2]], [1e-4, 0.0], STEEL, "truss")
    with pytest.raises(BayesUpdateError, match="node 1 already has a coordinate frame"):
        f = CoordinateFrame.from_axes("cylindrical", (0, 0, 0), np.eye(3))
        b.set_frame([1, 1], f)


# -- the README tour ----------------------------------------------------------------------------
def _readme_frame(hinge: bool, mass: str = "consistent"):
    """README 'Shells, supports and rigid elements': an I-section portal on clamped feet whose
    box-section beam sits on 0.1 m rigid offsets and is pinned (ry released) at its end B.
    ``hinge``: the same with the pin as a node at the offset point tied by an RBE2 in all but
    ry."""
    b = StructureBuilder()
    feet = [b.add_node((0, 0, 0)), b.add_node((4, 0, 0))]
    tops = [b.add_node((0, 0, 3)), b.add_node((4, 0, 3))]
    column, beam = ss.i_section(0.2, 0.1, 6e-3, 9e-3), ss.box_section(0.1, 0.2, 5e-3, 5e-3)
    b.add_beams(np.c_[feet, tops], column, STEEL, "columns", up=(1, 0, 0))
    offsets = [(0.1, 0, 0), (-0.1, 0, 0)]
    if hinge:
        end = b.add_node((3.9, 0, 3))
        b.add_beams([[tops[0], end]], beam, STEEL, "beam", offsets=[offsets[0], (0, 0, 0)],
                    mass=mass)  # fmt: skip
        b.add_rbe2(tops[1], [end], "12346")
    else:
        b.add_beams([tops], beam, STEEL, "beam", offsets=offsets, pins=("", "5"), mass=mass)
    for foot in feet:
        b.add_support(foot)
    return b.build()


def test_readme_frame_pin_and_offsets_equal_a_hinge_node():
    # lumped mass puts no inertia on the released rotation: the condensation is then exact
    lumped = _solve(_readme_frame(False, "lumped"), 4).frequencies_hz
    hinge = _solve(_readme_frame(True, "lumped"), 4).frequencies_hz
    np.testing.assert_allclose(lumped, hinge, rtol=1e-10)
    # consistent mass: the pin is the hinge model restricted to the statically condensed end
    # rotation, a Ritz subspace, so its frequencies lie above (measured: up to 3e-4 here)
    r = _solve(_readme_frame(False), 4)
    rel = r.frequencies_hz / _solve(_readme_frame(True), 4).frequencies_hz - 1
    assert r.modes.n_rigid == 0 and np.all(rel >= -1e-13) and np.all(rel < 1e-3), rel
    readme = [3.830, 8.288, 16.507, 32.824]  # the numbers the README prints
    np.testing.assert_allclose(r.frequencies_hz, readme, atol=5e-4)


# -- optional peer: OpenSeesPy ------------------------------------------------------------------
def _peer_frame():
    """Nodes, members (i, j, section, up, offsets) of a clamped 3-D frame of standard sections."""
    xyz = np.array([(0, 0, 0), (0, 0, 1.5), (1.2, 0, 1.5), (1.2, 0.9, 1.5), (1.2, 0.9, 0),
                    (0.6, 0, 1.5)], float)  # fmt: skip
    i_sec, box = ss.i_section(0.12, 0.08, 5e-3, 7e-3), ss.box_section(0.1, 0.06, 4e-3, 5e-3)
    members = [
        (0, 1, i_sec, (1, 0, 0), [(0, 0, 0), (0, 0, 0)]),
        (1, 5, box, (0, 0, 1), [(0.05, 0, 0), (0, 0, 0.03)]),
        (5, 2, box, (0, 0, 1), [(0, 0, 0.03), (-0.05, 0.02, 0)]),
        (2, 3, ss.bar_section(0.04, 0.07), (0, 0, 1), [(0, 0.04, 0), (0, -0.04, 0)]),
        (3, 4, ss.channel_section(0.1, 0.05, 5e-3, 7e-3), (1, 1, 0), [(0, 0, 0), (0, 0, 0)]),
    ]
    return xyz, members


def test_frame_matches_opensees_elastic_timoshenko_beam():
    """The same frame in OpenSees: ElasticTimoshenkoBeam -cMass between the offset points, each
    tied to its node by OpenSees' own ``rigidLink beam`` (its geomTransf -jntOffset gave
    different frequencies, by 0.1-36 %, from both ours and its own rigid links, so it is not the
    reference).  OpenSees' torsional inertia is rho J, ours rho (iy + iz): the frame is given
    rho J here (``torsion_inertia``) so that both hold the same physics."""
    ops = pytest.importorskip("openseespy.opensees")
    xyz, members = _peer_frame()
    b = StructureBuilder()
    ids = [b.add_node(p) for p in xyz]
    for i, j, sec, up, off in members:
        b.add_beams([[ids[i], ids[j]]], sec, STEEL, "frame", up=up, offsets=off,
                    torsion_inertia=STEEL.density * sec.torsion)  # fmt: skip
    b.add_support(ids[0])
    b.add_support(ids[4])
    ours = _solve(b.build(), 10).frequencies_hz

    ops.wipe()
    ops.model("basic", "-ndm", 3, "-ndf", 6)
    for k, p in enumerate(xyz):
        ops.node(k + 1, *map(float, p))
    for k in (1, 5):
        ops.fix(k, 1, 1, 1, 1, 1, 1)
    E, G, rho = STEEL.youngs_modulus, STEEL.youngs_modulus / 2.6, STEEL.density
    extra = len(xyz)
    for e, (i, j, sec, up, off) in enumerate(members):
        ends = []
        for node, w in zip((i, j), np.asarray(off, float), strict=True):
            if np.any(w):
                extra += 1
                ops.node(extra, *map(float, xyz[node] + w))
                ops.rigidLink("beam", node + 1, extra)
                ends.append(extra)
            else:
                ends.append(node + 1)
        ops.geomTransf("Linear", e + 1, *map(float, up))
        ops.element("ElasticTimoshenkoBeam", e + 1, *ends, E, G, sec.area, sec.torsion,
                    sec.iy, sec.iz, sec.shear_y * sec.area, sec.shear_z * sec.area, e + 1,
                    "-mass", rho * sec.area, "-cMass")  # fmt: skip
    ops.constraints("Transformation")
    lam = np.asarray(ops.eigen("-fullGenLapack", 10), float)
    ops.wipe()
    np.testing.assert_allclose(ours, np.sqrt(lam) / (2 * np.pi), rtol=1e-9)


def test_line_element_energies_balance_the_eigenvalue():
    """Energy shares count general beams (and rods): on the framed portal the frame's strain
    share is phi^T K_beams phi / lambda, and the shares of all parts add up to 1 with the
    spring's phi^T K_spring phi / lambda, i.e. nothing is left out."""
    rotation = Rotation.from_euler("xyz", [0.3, -0.4, 0.7]).as_matrix()
    s = _portal(rotation, framed=True)
    r = FEModel(s, {}, {}, {}).solve(n_modes=4, method="dense", energies=True)
    phi, lam = r.modes.shapes, r.modes.eigenvalues
    ((dofs, K, _),) = line_matrices(s)
    u = np.einsum("eim,eij,ejm->m", phi[dofs], K, phi[dofs])
    share = r.energies.strain_by_part[s.part_index("frame")]
    np.testing.assert_allclose(share, u / lam, rtol=1e-8)
    assert np.all(share > 0.05)
