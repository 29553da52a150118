"""CHEXA (eight GRIDs) + PSOLID: Nastran's default brick (``fe.elements.hexa``) read from a deck
(``nastran.cards.solids``), against MSC's and NX's own solutions, closed forms and the reader's
refusals.

``tests/data/msc_chexa8.json`` holds what ``studies/msc_chexa8.py`` read from pyNastran's
models (BSD-3-Clause): MSC Nastran 2021.1's static solution of 128 near-cubes (displacements,
each element's grid point forces, the gravity load of the lumped mass) and NX Nastran's single
1 x 1 x 2 brick under a unit pressure on each face.  The bar: a free steel bar 1 x 0.05 x 0.08
m in 20 x 2 x 2 bricks.
"""

import json
from pathlib import Path

import numpy as np
import pytest
from reduced_check import assert_basis_matches_full_solves

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.assembly import ElementProperties
from bayesupdate.fe.elements.base import ElementSettings
from bayesupdate.fe.elements.hexa import CORNERS, Hexahedra
from bayesupdate.fe.elements.solid import elasticity
from bayesupdate.nastran import load_nastran_model

DATA = json.loads((Path(__file__).parent / "data" / "msc_chexa8.json").read_text())
E, NU, RHO = 2.1e11, 0.3, 7850.0
L, B, H = 1.0, 0.05, 0.08


def bricks(corners, E=E, nu=NU, rho=RHO, lumped=True) -> Hexahedra:
    """Hexahedra of corners (n, 8, 3) with one material."""
    n = len(corners)
    return Hexahedra(np.arange(8 * n).reshape(n, 8), np.asarray(corners, float), np.full(n, E),
                     np.full(n, nu), np.full(n, rho), np.full(n, lumped),
                     np.zeros(n, np.int64))  # fmt: skip


def unit_matrices(family: Hexahedra):
    """(K, M) (n, 24, 24) at factor 1 on E and rho."""
    return family.matrices(ElementProperties(family.nominal()), ElementSettings())


def f32(values) -> np.ndarray:
    """The fixture's float32 output, bit for bit."""
    return np.array(values, dtype=np.float32).astype(float)


def test_stiffness_is_mscs_on_its_own_static_solution():
    """K_e u_e of each of MSC's 128 elements at MSC's displacements against the element's grid
    point forces (GPFORCE = -K_e u_e): median 1.4e-5 (2.1 x the float32 floor), 90th percentile
    2.3e-4 (elements with little deformation against their motion).  The bricks Nastran does
    not form miss by far more: the fully integrated one 6e-2 and Wilson-Taylor's incompatible
    modes 5.6e-4 (median; ``studies/msc_chexa8.py``)."""
    msc = DATA["msc"]
    K = unit_matrices(bricks(msc["corners"], msc["E"], msc["nu"]))[0]
    u, f = f32(msc["u"]).reshape(-1, 24), f32(msc["gpforce"]).reshape(-1, 24)
    err = np.linalg.norm(np.einsum("eij,ej->ei", K, u) + f, axis=1) / np.linalg.norm(f, axis=1)
    assert len(err) == 128
    assert np.median(err) < 2e-5
    assert np.percentile(err, 90) < 3e-4


def test_stiffness_is_mscs_on_a_modal_solution_it_was_not_found_on():
    """A fresh case (``studies/msc_solid_shell_bar.py``: MSC's SOL 103 of pyNastran's
    solid_shell_bar tower, not used when the brick was found): its unit-cube CHEXA's K phi in
    each of the three modes is minus MSC's printed grid point forces (GPFORCE = -K_e phi_e, as
    on the static solution above) to 5.1e-6 (the f06's seven digits)."""
    fresh = json.loads((Path(__file__).parent / "data" / "msc_solid_shell_bar_hexa.json")
                       .read_text())  # fmt: skip
    K = unit_matrices(bricks([fresh["corners"]], fresh["E"], fresh["nu"]))[0][0]
    for phi, f in zip(fresh["modes"], fresh["forces"], strict=True):
        f = np.ravel(f)
        assert np.linalg.norm(K @ np.ravel(phi) + f) < 1e-5 * np.linalg.norm(f)


def test_stiffness_is_nxs_single_brick_under_face_pressures():
    """NX's 1 x 1 x 2 brick, its bottom face held: on the four free GRIDs K u equals the
    pressure's load (a quarter of the face's area on each corner, along its normal) for each of
    the five loaded faces, to 1.6e-6 (float32 output)."""
    nx = DATA["nx"]
    X = np.array(nx["corners"])
    K = unit_matrices(bricks(X[None], nx["E"], nx["nu"]))[0][0]
    for case in nx["faces"].values():
        P = X[[nx["grids"].index(g) for g in case["grids"]]]
        normal = np.cross(P[2] - P[0], P[3] - P[1]) / 8  # |cross| / 2 = the area; a quarter
        F = np.zeros((8, 3))
        F[[nx["grids"].index(g) for g in case["grids"]]] = normal
        Ku = K[12:] @ f32(case["u"]).ravel()
        F = F.ravel()[12:]
        assert np.linalg.norm(Ku - np.sign(F @ Ku) * F) < 3e-6 * np.linalg.norm(F)


def test_lumped_mass_is_mscs_gravity_load():
    """MSC's gravity load on the 250 GRIDs only CHEXAs join is the lumped mass times g: each
    corner's share rho x the integral of its N_a (3.6e-8), not an eighth of the element's mass
    (1.2e-4 off on these slightly moved cubes)."""
    msc = DATA["msc"]
    M = unit_matrices(bricks(msc["corners"], msc["E"], msc["nu"], msc["rho"]))[1]
    rows = {g: i for i, g in enumerate(msc["oload_grids"])}
    load = np.zeros(len(rows))
    corner_mass = np.einsum("eii->ei", M)[:, 2::3]
    np.add.at(load, [rows[g] for g in np.ravel(msc["nodes"])], corner_mass.ravel())
    relative = load * msc["gravity_z"] / f32(msc["oload_z"]) - 1
    assert np.max(np.abs(relative)) < 1e-7
    assert np.max(np.abs(np.diff(corner_mass, axis=1))) > 0  # the corners' shares differ


def distorted_brick(seed=150):
    """A seeded brick: the 0.6 x 0.4 x 1.1 box, each corner moved up to 0.08 (fresh seed)."""
    rng = np.random.default_rng(seed)
    return CORNERS * [0.3, 0.2, 0.55] + rng.uniform(-0.08, 0.08, (8, 3))


def test_constant_strain_is_exact_and_the_rigid_motions_cost_nothing():
    """On a distorted brick (the patch test): a linear displacement u = A x + c costs the exact
    strain energy V/2 eps^T D eps (1e-12), and K has exactly six zero eigenvalues (no
    spurious zero-energy mode) and is symmetric."""
    X = distorted_brick()
    family = bricks(X[None])
    K, M = (m[0] for m in unit_matrices(family))
    A = np.random.default_rng(150).standard_normal((3, 3))
    u = (X @ A.T + [0.3, -0.1, 0.2]).ravel()
    s = 0.5 * (A + A.T)
    eps = np.array([s[0, 0], s[1, 1], s[2, 2], 2 * s[0, 1], 2 * s[1, 2], 2 * s[0, 2]])
    volume = M.sum() / 3 / RHO
    D = elasticity(np.array([E]), np.array([NU]))[0]
    assert 0.5 * u @ K @ u == pytest.approx(0.5 * volume * eps @ D @ eps, rel=1e-12)
    eig = np.linalg.eigvalsh(K)
    assert np.all(np.abs(eig[:6]) < 1e-10 * eig[-1]) and eig[6] > 1e-4 * eig[-1]
    assert np.abs(K - K.T).max() < 1e-14 * np.abs(K).max()


def test_bending_and_hourglass_modes_of_a_cube_in_closed_form():
    """On a cube of side h, mode u_x = xi eta (bending: no parasitic shear, the Poisson strain
    along eta free, along zeta held) costs (h/2)(8/3) E / (1 - nu^2), and the hourglass mode
    u_x = xi eta zeta (its normal strain's Poisson strains free, its shear none) costs
    (h/2)(8/9) E: the energies that set Nastran's brick apart (the fully integrated brick:
    (h/2)(8/3)(lambda + 3 mu) and (h/2)(8/9)(lambda + 4 mu))."""
    h = 0.05
    K = unit_matrices(bricks((CORNERS * h / 2)[None]))[0][0]
    xi, eta, zeta = CORNERS.T
    for shape, energy in ((xi * eta, 8 / 3 / (1 - NU**2)), (xi * eta * zeta, 8 / 9)):
        u = np.zeros((8, 3))
        u[:, 0] = shape
        assert u.ravel() @ K @ u.ravel() == pytest.approx(h / 2 * energy * E, rel=1e-12)


def test_consistent_mass_of_a_parallelepiped_is_exact():
    """Consistent mass (COUPMASS 1) on a sheared parallelepiped: the rigid rotation about z
    carries the exact moment of inertia rho int (x^2 + y^2) dV (1e-12), and lumped and
    consistent masses both sum to rho V."""
    X = CORNERS * [0.3, 0.2, 0.5] @ np.array([[1, 0, 0], [0.2, 1, 0], [0.1, -0.3, 1]])
    consistent = unit_matrices(bricks(X[None], lumped=False))[1][0]
    lumped = unit_matrices(bricks(X[None]))[1][0]
    volume = abs(np.linalg.det(np.array([[1, 0, 0], [0.2, 1, 0], [0.1, -0.3, 1]]))) * 0.6 * 0.4
    rotation = np.column_stack([-X[:, 1], X[:, 0], np.zeros(8)]).ravel()
    # the exact integral over the parallelepiped x = F xi (F the scaled shear map)
    F = np.diag([0.3, 0.2, 0.5]) @ np.array([[1, 0, 0], [0.2, 1, 0], [0.1, -0.3, 1]])
    second = volume * F.T @ F / 3  # int x x^T dV over xi in [-1, 1]^3 mapped
    inertia = RHO * (second[0, 0] + second[1, 1])
    assert rotation @ consistent @ rotation == pytest.approx(inertia, rel=1e-12)
    assert consistent.sum() / 3 == pytest.approx(RHO * volume, rel=1e-12)
    assert lumped.sum() / 3 == pytest.approx(RHO * volume, rel=1e-12)


def bar_deck(
    path,
    coupled=False,
    extra=(),
    nx=20,
    ny=2,
    nz=2,
    mirror=False,
    pid=lambda x: 1,
    psolid="PSOLID,1,1",
):
    """The bar in nx x ny x nz bricks; ``mirror``: every brick numbered inside out;
    ``pid(x)``: the PSOLID of the brick whose first corner is at x; ``psolid``: PSOLID 1's
    card."""
    x, y, z = np.linspace(0, L, nx + 1), np.linspace(0, B, ny + 1), np.linspace(0, H, nz + 1)

    def grid(i, j, k):
        return (i * (ny + 1) + j) * (nz + 1) + k + 1

    lines = ["SOL 103", "CEND", "METHOD = 1", "BEGIN BULK", "EIGRL,1,,,12",
             f"MAT1,1,{E:.4E},,{NU},{RHO}", psolid]  # fmt: skip
    lines += ["PARAM,COUPMASS,1"] if coupled else []
    lines += [f"GRID,{grid(i, j, k)},,{x[i]:.7f},{y[j]:.7f},{z[k]:.7f}"
              for i in range(nx + 1) for j in range(ny + 1) for k in range(nz + 1)]  # fmt: skip
    for e, (i, j, k) in enumerate(np.ndindex(nx, ny, nz), 1):
        v = [grid(i, j, k), grid(i + 1, j, k), grid(i + 1, j + 1, k), grid(i, j + 1, k),
             grid(i, j, k + 1), grid(i + 1, j, k + 1), grid(i + 1, j + 1, k + 1),
             grid(i, j + 1, k + 1)]  # fmt: skip
        if mirror:
            v = [v[a] for a in (0, 3, 2, 1, 4, 7, 6, 5)]
        lines.append(f"CHEXA,{e},{pid(x[i])},{','.join(map(str, v[:6]))}\n,{v[6]},{v[7]}")
    path.write_text("\n".join([*lines, *extra, "ENDDATA"]) + "\n")
    return str(path)


def test_free_bar_rigid_modes_mass_and_axial_mode(tmp_path):
    """The free bar: six rigid modes, the mass rho L B H, and the first axial mode against
    c / 2L with Love's lateral-inertia correction (``test_nastran_solids``).  Twenty elements
    along the bar put a rod's mass error (kh)^2 / 24 = 0.10 % below it with lumped mass and
    above it with consistent mass; measured -0.094 % and +0.128 %."""
    k = np.pi / L
    love = np.sqrt(E / RHO) / (2 * L) * (1 - NU**2 * k**2 * (B**2 + H**2) / 12 / 2)
    for coupled, expected in ((False, -0.00094), (True, 0.00128)):
        model = load_nastran_model(bar_deck(tmp_path / f"bar{coupled}.bdf", coupled))
        res = model.solve(model.default_parameters(), n_modes=12)
        shapes = res.modes.shapes
        along = (shapes[0::6] ** 2).sum(axis=0) / (shapes.reshape(-1, 6, 12)[:, :3] ** 2).sum(
            axis=(0, 1)
        )
        assert res.modes.n_rigid == 6
        assert model.total_mass()[0] == pytest.approx(RHO * L * B * H, rel=1e-12)
        f = res.modes.frequencies_hz[int(np.argmax(along))]
        assert f / love - 1 == pytest.approx(expected, abs=1e-4)


def test_mystrans_hexa8_is_the_assumed_shear_brick_without_enhanced_strains(tmp_path):
    """MYSTRAN 18 on the bar (PSOLID IN 2, which MYSTRAN needs and this reader refuses: it reads
    the same bar with IN blank; MYSTRAN's HEXA8 mass is always the
    consistent one, so COUPMASS 1 here): its HEXA8 averages each shear strain over a face's
    Gauss points (``Source/EMG/EMG5/HEXA.f90``), which is this package's assumed shear without
    the enhanced normal strains (``hexa.stiffness(..., enhanced=False)``): with that K beside
    this package's M, the six lowest elastic frequencies are MYSTRAN's to 3.8e-6 (its f06's
    seven digits and its Lanczos); Nastran's brick is 1.4 % below it on the five bending
    modes (the enhanced strains free their Poisson strains) and the same on the torsion mode,
    which is pure shear (2.5e-5)."""
    import scipy.sparse as sp
    from test_nastran_solids import _mystran_hz

    from bayesupdate.fe.elements.hexa import stiffness
    from bayesupdate.fe.sparse_modal import ModalSettings

    deck = Path(bar_deck(tmp_path / "bar.bdf", coupled=True, psolid="PSOLID,1,1,,2"))
    peer = _mystran_hz(deck)[6:12]
    # the same bar with IN blank, as this reader takes it (Nastran's IN 2 is not checked)
    model = load_nastran_model(bar_deck(tmp_path / "ours.bdf", coupled=True))
    K, M = model.matrices()
    h = Hexahedra.of(model.structure)
    D = elasticity(h.E, h.nu)
    change = stiffness(h.corners, D, enhanced=False) - stiffness(h.corners, D)
    dofs = h.dofs()
    rows, cols = np.repeat(dofs, 24, axis=1).ravel(), np.tile(dofs, (1, 24)).ravel()
    K = K + sp.csr_matrix((change.ravel(), (rows, cols)), shape=K.shape)
    assumed_shear = model.general.solve(K, M, 6, settings=ModalSettings()).frequencies_hz
    assert np.max(np.abs(assumed_shear / peer - 1)) < 6e-6
    nastran = model.predict(n_modes=6).frequencies_hz / peer - 1
    assert np.all(np.abs(nastran[:5] + 0.014) < 1e-3) and abs(nastran[5]) < 1e-4


def test_inside_out_numbering_reads_as_nastran_reads_it(tmp_path):
    """Every brick numbered inside out (G1-G4 clockwise from G5-G8) gives the bar's modes
    (1e-12): the reader reverses its faces' order."""
    right = load_nastran_model(bar_deck(tmp_path / "right.bdf", nx=6))
    mirrored = load_nastran_model(bar_deck(tmp_path / "mirror.bdf", nx=6, mirror=True))
    f = right.predict(n_modes=8).frequencies_hz
    assert mirrored.predict(n_modes=8).frequencies_hz == pytest.approx(f, rel=1e-12)


def test_refusals_in_one_message(tmp_path):
    """A twenty-node CHEXA, a CHEXA's PSOLID with ISOP FULL and one with IN 2, a brick with a
    repeated corner, a folded brick and one naming a missing GRID: each refused once with its
    card, in one message."""
    extra = [
        "CHEXA,9001,1,1,2,5,4,10,11", ",14,13,30,31,32,33", ",34,35,36,37,38,39", ",40,41",
        "PSOLID,2,1,,,,FULL",
        "CHEXA,9002,2,1,2,5,4,10,11", ",14,13",
        "CHEXA,9003,1,1,2,5,5,10,11", ",14,13",  # corner 5 twice
        "CHEXA,9004,1,1,2,5,4,10,11", ",13,14",  # the top face's last two corners swapped
        "CHEXA,9005,1,1,2,5,4,10,11", ",14,999999",
        "PSOLID,3,1,,2",
        "CHEXA,9006,3,1,2,5,4,10,11", ",14,13",
    ]  # fmt: skip
    with pytest.raises(BayesUpdateError) as err:
        load_nastran_model(bar_deck(tmp_path / "bad.bdf", nx=6, extra=extra))
    text = str(err.value)
    assert "CHEXA 9001" in text and "20 nodes" in text
    assert "PSOLID 2" in text and "ISOP FULL" in text and text.count("PSOLID 2") == 1
    assert "CHEXA 9003: a corner is repeated" in text
    assert "CHEXA 9004" in text and "folded or collapsed brick" in text
    assert "CHEXA 9005: GRID 999999 does not exist" in text
    assert "PSOLID 3" in text and "IN 2" in text


def _halves(path, factor=1.0):
    """The bar with its far half (x >= L/2) on PSOLID 2 and MAT1 2, whose E is ``factor`` x
    MAT1 1's."""
    extra = [f"MAT1,2,{E * factor:.12E},,{NU},{RHO}", "PSOLID,2,2"]
    return bar_deck(path, nx=8, extra=extra, pid=lambda x: 2 if x >= L / 2 - 1e-9 else 1)


def test_a_bricks_material_as_a_parameter(tmp_path):
    """MAT1 2 E of the far half's bricks as a factor (``hexa_modulus_factor``): at 1.35 the
    modes of the deck with 1.35 E typed in (1e-10), and the certified reduced basis gives full
    solves' modes to 1e-6; MAT1 1 RHO as a value scales the mass."""
    model = load_nastran_model(_halves(tmp_path / "two.bdf"), {"e2": {"binds": "MAT1 2 E scale"}})
    assert model.bindings["e2"].property == "hexa_modulus_factor"
    edited = load_nastran_model(_halves(tmp_path / "edited.bdf", 1.35))
    f = model.predict({"e2": 1.35}, n_modes=8).frequencies_hz
    assert f == pytest.approx(edited.predict(n_modes=8).frequencies_hz, rel=1e-10)
    assert_basis_matches_full_solves(model, "e2", (0.62, 1.83))
    dense = load_nastran_model(_halves(tmp_path / "two.bdf"), {"r": {"binds": "MAT1 1 RHO"}})
    mass = dense.total_mass({"r": 2 * RHO})[0]
    assert mass == pytest.approx(1.5 * RHO * L * B * H, rel=1e-12)


def _mixed(path, e_factor=1.0, rho_factor=1.0, rod=True):
    """The bar in 4 x 2 x 2 bricks, a tetrahedron on its end face, a CQUAD4 on its side and a
    CROD along its edge, all on MAT1 1, whose E and RHO are the factors x the bar's (typed in)."""
    extra = ["GRID,90001,,1.1,0.,0.", "CTETRA,99001,1,37,40,38,90001",  # on the end face
             "PSHELL,5,1,0.002", "CQUAD4,99101,5,1,10,11,2"]  # fmt: skip
    extra += ["PROD,6,1,1.E-4", "CROD,99201,6,1,10"] if rod else []
    deck = Path(bar_deck(path, nx=4, extra=extra))
    material = f"MAT1,1,{E:.4E},,{NU},{RHO}"
    edited = f"MAT1,1,{E * e_factor:.12E},,{NU},{RHO * rho_factor:.12E}"
    deck.write_text(deck.read_text().replace(material, edited))
    return str(deck)


def test_one_material_over_bricks_tetrahedra_shells_and_rods_is_one_parameter(tmp_path):
    """MAT1 1 under the bricks, a tetrahedron, a shell and a rod: its E (as a scale and as a
    value) and RHO each move all four families as the deck with the new value typed in does
    (1e-10); the mass follows RHO exactly; without the rod, the certified reduced basis gives
    the full solves' modes to 1e-6."""
    deck = _mixed(tmp_path / "mixed.bdf")
    model = load_nastran_model(deck, {"e": {"binds": "MAT1 1 E scale"},
                                      "r": {"binds": "MAT1 1 RHO scale"}})  # fmt: skip
    valued = load_nastran_model(deck, {"E": {"binds": "MAT1 1 E"}})
    assert dict(model.bindings["e"].companions) == {"solid_modulus_factor": 1.0,
                                                     "hexa_modulus_factor": 1.0}  # fmt: skip
    assert model.solve(model.default_parameters(), n_modes=6).modes.n_rigid == 6
    for e, r in ((1.35, 1.0), (0.7, 1.6)):
        typed = load_nastran_model(_mixed(tmp_path / f"typed{e}.bdf", e, r))
        f = model.predict({"e": e, "r": r}, n_modes=8).frequencies_hz
        assert f == pytest.approx(typed.predict(n_modes=8).frequencies_hz, rel=1e-10)
        assert model.total_mass({"e": e, "r": r})[0] == pytest.approx(typed.total_mass()[0],
                                                                      rel=1e-12)  # fmt: skip
    f = valued.predict({"E": 1.35 * E}, n_modes=8).frequencies_hz
    assert f == pytest.approx(model.predict({"e": 1.35}, n_modes=8).frequencies_hz, rel=1e-10)
    plain = load_nastran_model(_mixed(tmp_path / "plain.bdf", rod=False),
                               {"e": {"binds": "MAT1 1 E scale"}})  # fmt: skip
    assert_basis_matches_full_solves(plain, "e", (0.62, 1.83))
