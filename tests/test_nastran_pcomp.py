"""PCOMP / PCOMPG laminates of MAT8 or MAT1 plies (``nastran.cards.laminates``, ``fe.laminate``)
against Navier's closed form, MYSTRAN 18, NX Nastran's own static solution, and the identities
a laminate must keep (isotropic plies = PSHELL, SYM = the full stack, THETA = MCID = turned
plies, Z0 = ZOFFS).

The plate: 0.5 x 0.4 m, four 0.5 mm plies of a carbon/epoxy MAT8 (E1 140 GPa, E2 10 GPa,
NU12 0.3, G12 5 GPa, G1Z 5 GPa, G2Z 3.5 GPa, RHO 1600), CQUAD4 on a regular mesh.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.nastran import load_nastran_model

DATA = Path(__file__).parent / "data"
A, B = 0.5, 0.4
E1, E2, NU12, G12, RHO = 140e9, 10e9, 0.3, 5e9, 1600.0
CROSS = ((0.0, 0.5e-3), (90.0, 0.5e-3), (90.0, 0.5e-3), (0.0, 0.5e-3))


def _pcomp(plies, pid=7, lam="", z0="", mid=3, card="PCOMP") -> list[str]:
    """PCOMP (or PCOMPG) lines, free field: plies (angle [deg], thickness [m][, MID])."""
    head = [card, str(pid), z0, "", "", "", "", "", lam]
    plies = [(*ply, mid)[:3] for ply in plies]
    if card == "PCOMP":
        body = [f for ang, t, m in plies for f in (str(m), f"{t:.6e}", f"{ang:.3f}", "")]
    else:
        body = [f for k, (ang, t, m) in enumerate(plies)
                for f in (str(k + 1), str(m), f"{t:.6e}", f"{ang:.3f}", "", "", "", "")
                ]  # fmt: skip
    fields, lines = head + body, []
    lines.append(",".join(fields[:9]))
    for i in range(9, len(fields), 8):
        lines.append("," + ",".join(fields[i : i + 8]))
    return lines


def plate(path, n=12, plies=CROSS, theta="", support="simple", shear=True, prop=None,
          extra=(), zoffs="") -> str:  # fmt: skip
    """An n x n CQUAD4 plate deck; support "simple" (w and in-plane held on every edge),
    "cantilever" (x = 0 clamped, a 0.05 kg CONM2 at the corner x = a, y = b) or "free"."""
    nid = lambda i, j: 1 + i + j * (n + 1)  # noqa: E731
    lines = ["SOL 103", "CEND", "METHOD = 1", "SPC = 1", "BEGIN BULK", "EIGRL,1,,,10",
             "PARAM,COUPMASS,1"]  # fmt: skip
    lines += [f"GRID,{nid(i, j)},,{A * i / n:.9f},{B * j / n:.9f},0.0"
              for j in range(n + 1) for i in range(n + 1)]  # fmt: skip
    lines += [f"CQUAD4,{1 + i + j * n},7,{nid(i, j)},{nid(i + 1, j)},{nid(i + 1, j + 1)},"
              f"{nid(i, j + 1)},{theta},{zoffs}" for j in range(n) for i in range(n)]  # fmt: skip
    shear_moduli = "5.0e9,3.5e9" if shear else ","
    lines.append(f"MAT8,3,{E1:.4e},{E2:.4e},{NU12},{G12:.4e},{shear_moduli},{RHO}")
    lines += _pcomp(plies) if prop is None else prop
    if support == "simple":
        lines += [f"SPC1,1,123,{nid(i, j)}" for j in range(n + 1) for i in range(n + 1)
                  if i in (0, n) or j in (0, n)]  # fmt: skip
    elif support == "cantilever":
        lines += [f"SPC1,1,123456,{nid(0, j)}" for j in range(n + 1)]
        lines.append(f"CONM2,99999,{nid(n, n)},,0.05")
    lines += [*extra, "ENDDATA"]
    Path(path).write_text("\n".join(lines) + "\n")
    return str(path)


def hz(deck, n_modes=8) -> np.ndarray:
    model = load_nastran_model(str(deck))
    return model.solve(model.default_parameters(), n_modes=n_modes).modes.frequencies_hz


def navier_hz(n_modes=8) -> np.ndarray:
    """Simply supported specially orthotropic plate (D16 = D26 = 0), Kirchhoff: f_mn =
    (pi / 2) sqrt((D11 (m/a)^4 + 2 (D12 + 2 D66) (m/a)^2 (n/b)^2 + D22 (n/b)^4) / (rho h))
    (Reddy 2004, eq. 5.2.13 without rotary inertia), D of the [0/90]s stack by hand."""
    d = 1 - NU12**2 * E2 / E1
    q11, q22, q12, q66 = E1 / d, E2 / d, NU12 * E2 / d, G12
    z = np.array([-2, -1, 0, 1, 2]) * 0.5e-3
    w = (z[1:] ** 3 - z[:-1] ** 3) / 3  # each ply's share of D
    D11 = w @ [q11, q22, q22, q11]
    D22 = w @ [q22, q11, q11, q22]
    D12, D66 = w.sum() * q12, w.sum() * q66
    f = [np.pi / 2 * np.sqrt((D11 * (m / A) ** 4 + 2 * (D12 + 2 * D66) * (m / A) ** 2 * (k / B) ** 2
                              + D22 * (k / B) ** 4) / (RHO * 2e-3))
         for m in range(1, 6) for k in range(1, 6)]  # fmt: skip
    return np.sort(f)[:n_modes]


def test_cross_ply_plate_converges_to_navier(tmp_path):
    """[0/90]s, no transverse shear moduli (the discrete Kirchhoff quadrilateral): the eight
    lowest modes converge as h^2 from above, and Richardson's extrapolation of the 16 x 16 and
    32 x 32 meshes is Navier's to 1.9e-4 (12 and 24: 3.3e-4; mesh 32 alone: 0.71 %).  An error
    of 0.1 % in any of D11, D22, D12 + 2 D66 moves some of these modes by 2.5e-4 or more."""
    coarse = hz(plate(tmp_path / "c.bdf", 16, shear=False))
    fine = hz(plate(tmp_path / "f.bdf", 32, shear=False))
    exact = navier_hz()
    assert np.all(fine > exact) and np.all(coarse > fine)
    assert np.max(fine / exact - 1) < 0.008
    assert np.max(np.abs((4 * fine - coarse) / 3 / exact - 1)) < 2.5e-4


@pytest.mark.parametrize("lam, pshell", [("", "PSHELL,7,13,1.e-3,13,,13"),
                                         ("MEM", "PSHELL,7,13,1.e-3"),
                                         ("BEND", "PSHELL,7,,1.e-3,13,,13")])  # fmt: skip
def test_isotropic_plies_are_the_pshell_of_their_material(tmp_path, lam, pshell):
    """MAT1 plies at any angles (0.3, 0.5, 0.2 mm at 0, 45, -30 degrees) = PSHELL T 1 mm with
    that MAT1 as MID1, MID2 and MID3 (LAM MEM: MID1 alone, a membrane; BEND: MID1 blank): K and
    M the same to 1e-12, and the mass is rho T a b."""
    mat = "MAT1,13,70.e9,,0.3,2700."
    prop = _pcomp(((0.0, 0.3e-3), (45.0, 0.5e-3), (-30.0, 0.2e-3)), mid=13, lam=lam)
    laminate = load_nastran_model(plate(tmp_path / "l.bdf", 6, prop=[mat, *prop], shear=False))
    shell = load_nastran_model(plate(tmp_path / "s.bdf", 6, prop=[mat, pshell], shear=False))
    (K1, M1), (K2, M2) = laminate.matrices()[:2], shell.matrices()[:2]
    assert abs(K1 - K2).max() < 1e-12 * abs(K2).max()
    assert abs(M1 - M2).max() < 1e-12 * abs(M2).max()
    along_x = np.zeros(M1.shape[0])
    along_x[0::6] = 1.0
    assert along_x @ M1 @ along_x == pytest.approx(2700 * 1e-3 * A * B, rel=1e-12)


def test_pshells_beside_a_laminate_keep_their_stiffness(tmp_path):
    """A deck with a laminate gives every shell a section: a sandwich PSHELL (12I/T**3 2.5,
    TS/T 0.5, faces of another MAT1 with NU 0.2) beside the laminate of isotropic plies is the
    same (K and M to 1e-12) as in the deck whose laminate is its PSHELL, which has none."""
    mats = ["MAT1,13,70.e9,,0.3,2700.", "MAT1,14,100.e9,,0.2,2700."]
    sandwich = "PSHELL,8,13,2.e-3,14,2.5,13,0.5"
    prop = _pcomp(((0.0, 0.3e-3), (45.0, 0.7e-3)), mid=13)

    def deck(name, props):
        path = Path(plate(tmp_path / name, 4, prop=[*mats, sandwich, *props], shear=False))
        text = path.read_text()
        for e in range(1, 9):
            text = text.replace(f"\nCQUAD4,{e},7,", f"\nCQUAD4,{e},8,")
        path.write_text(text)
        return load_nastran_model(str(path)).matrices()[:2]

    (K1, M1), (K2, M2) = deck("l.bdf", prop), deck("s.bdf", ["PSHELL,7,13,1.e-3,13,,13"])
    assert abs(K1 - K2).max() < 1e-12 * abs(K2).max()
    assert abs(M1 - M2).max() < 1e-12 * abs(M2).max()


def test_pshell_mid4_is_the_two_material_stack_it_stands_for(tmp_path):
    """PSHELL T 2 mm with MID1 = MID2 = MID3 of E 90 GPa and MID4 of E 5 GPa (NU 0.3) is the
    stack of 1 mm at E 70 GPa under 1 mm at 110 GPa: A = T (Qa + Qb) / 2, B = T^2 (Qb - Qa) / 8
    = T^2 G4, D = T^3 (Qa + Qb) / 24 (Jones sec. 4.5), with TS/T the stack's own transverse
    shear over G3 T (``fe.laminate.transverse_shear``): K and M to 1e-12, on its own GRIDs and
    with ZOFFS 1 mm; without MID4 the plate's (its edges held in plane) modes 1-8 are 0.49-1.6 %
    higher (4 x 4 quads)."""
    from bayesupdate.fe.laminate import Ply, laminate

    mats = ["MAT1,21,70.e9,,0.3,2700.", "MAT1,22,110.e9,,0.3,2700.", "MAT1,23,90.e9,,0.3,2700.",
            "MAT1,24,5.e9,,0.3,2700."]  # fmt: skip
    stack = _pcomp(((0.0, 1e-3, 21), (0.0, 1e-3, 22)))
    G = [e / 2.6 for e in (70e9, 110e9)]
    H = laminate([Ply(e, e, 0.3, g, g, g, 2700.0, 1e-3, 0.0)
                  for e, g in zip((70e9, 110e9), G, strict=True)])[3]  # fmt: skip
    ts = float(H[0, 0] / (90e9 / 2.6 * 2e-3))
    coupled_pshell = [f"PSHELL,7,23,2.e-3,23,,23,{ts!r},", ",,,24"]
    for zoffs in ("", "1.e-3"):
        laminate = plate(tmp_path / "l.bdf", 4, prop=[*mats, *stack], zoffs=zoffs)
        coupled = plate(tmp_path / "s.bdf", 4, prop=[*mats, *coupled_pshell], zoffs=zoffs)
        (K1, M1), (K2, M2) = (load_nastran_model(d).matrices()[:2] for d in (laminate, coupled))
        assert abs(K1 - K2).max() < 1e-12 * abs(K1).max()
        assert abs(M1 - M2).max() < 1e-12 * abs(M1).max()
    plain = plate(tmp_path / "p.bdf", 4, prop=[*mats, f"PSHELL,7,23,2.e-3,23,,23,{ts!r}"])
    assert np.all(hz(plate(tmp_path / "c.bdf", 4, prop=[*mats, *coupled_pshell])) / hz(plain)
                  < 0.996)  # fmt: skip


def test_a_sandwichs_rotary_inertia_is_its_faces(tmp_path):
    """COUPMASS 1: a sandwich of 0.5 mm aluminium faces (RHO 2700) on a 10 mm core (RHO 50)
    carries sum rho_k (z_k^3 - z_k-1^3) / 3 of rotary inertia per area, 2.437 times its mean
    density's rho_mean T^3 / 12: the rx, ry entries of M are the homogeneous plate's of the same
    mean density times that ratio (1e-12), the translational ones the same."""
    mats = ["MAT1,21,70.e9,,0.3,2700.", "MAT1,22,0.1e9,,0.3,50."]
    stack = _pcomp(((0.0, 0.5e-3, 21), (0.0, 10e-3, 22), (0.0, 0.5e-3, 21)))
    M1 = load_nastran_model(plate(tmp_path / "s.bdf", 2, prop=[*mats, *stack])).matrices()[1]
    z = np.array([-5.5e-3, -5e-3, 5e-3, 5.5e-3])
    exact = (2700 * (z[1] ** 3 - z[0] ** 3) + 50 * (z[2] ** 3 - z[1] ** 3)
             + 2700 * (z[3] ** 3 - z[2] ** 3)) / 3  # fmt: skip
    mean = (2700 * 1e-3 + 50 * 1e-2) / 11e-3
    ratio = exact / (mean * 11e-3**3 / 12)
    assert ratio == pytest.approx(2.4372, abs=1e-4)  # 78.64 / 32.27 mm^3 x kg/m^3, by hand
    uniform = [f"MAT1,21,70.e9,,0.3,{mean!r}", *_pcomp(((0.0, 11e-3, 21),))]
    M2 = load_nastran_model(plate(tmp_path / "u.bdf", 2, prop=uniform)).matrices()[1]
    rot = np.zeros(M1.shape[0], bool)
    rot[3::6] = rot[4::6] = True
    d1, d2 = M1.diagonal(), M2.diagonal()
    assert d1[rot] == pytest.approx(ratio * d2[rot], rel=1e-12)
    assert d1[~rot] == pytest.approx(d2[~rot], rel=1e-12)


def test_sym_and_pcompg_read_as_the_full_stack(tmp_path):
    """LAM SYM with the lower half = the full stack listed; PCOMPG (a ply a line) = PCOMP."""
    plies = ((30.0, 0.4e-3), (-45.0, 0.6e-3), (-45.0, 0.6e-3), (30.0, 0.4e-3))
    full = load_nastran_model(plate(tmp_path / "a.bdf", 4, plies)).matrices()[0]
    sym = plate(tmp_path / "b.bdf", 4, prop=_pcomp(plies[:2], lam="SYM"))
    pcompg = plate(tmp_path / "c.bdf", 4, prop=_pcomp(plies, card="PCOMPG"))
    for deck in (sym, pcompg):
        assert abs(load_nastran_model(deck).matrices()[0] - full).max() < 1e-12 * abs(full).max()


def test_theta_and_mcid_turn_the_material_axis(tmp_path):
    """Plies at 30 / -45 from the element's G1-G2 side = plies at 0 / -75 with CQUAD4 THETA 30 =
    the same with MCID 5, a CORD2R turned 30 degrees about z (1e-12 on K; no transverse shear
    moduli: the energy-equivalent shear is found in the stack's own axes, so it is no tensor
    identity of the turn, while A, B and D are)."""
    plies = ((30.0, 5e-4), (-45.0, 5e-4), (-45.0, 5e-4), (30.0, 5e-4))
    K = load_nastran_model(plate(tmp_path / "a.bdf", 4, plies, shear=False))
    turned = ((0.0, 5e-4), (-75.0, 5e-4), (-75.0, 5e-4), (0.0, 5e-4))
    c, s = np.cos(np.radians(30)), np.sin(np.radians(30))
    cord = ("CORD2R,5,,0.,0.,0.,0.,0.,1.", f",{c:.15f},{s:.15f},0.")
    for theta, extra in (("30.", ()), ("5", cord)):
        other = load_nastran_model(plate(tmp_path / f"t{theta}.bdf", 4, turned, theta=theta,
                                         extra=extra, shear=False))  # fmt: skip
        K0 = K.matrices()[0]
        assert abs(other.matrices()[0] - K0).max() < 1e-12 * abs(K0).max()


def test_z0_offsets_the_stack_as_zoffs_does(tmp_path):
    """Z0 = -T/2 + 1 mm (the plies 1 mm above centred) = Z0 blank with CQUAD4 ZOFFS 1 mm (K to
    1e-12), and it couples membrane and bending (K differs from the centred stack)."""
    z0 = load_nastran_model(plate(tmp_path / "a.bdf", 4, prop=_pcomp(CROSS, z0="0.")))
    zoffs = load_nastran_model(plate(tmp_path / "b.bdf", 4, zoffs="1.e-3"))
    centred = load_nastran_model(plate(tmp_path / "c.bdf", 4)).matrices()[0]
    K = z0.matrices()[0]
    assert abs(K - zoffs.matrices()[0]).max() < 1e-12 * abs(K).max()
    assert abs(K - centred).max() > 1e-4 * abs(K).max()


def test_angle_ply_cantilever_against_mystran(tmp_path):
    """A cantilever (32 x 32, a corner mass so that +30 and -30 degree plies differ) of
    [30/-45]s and of [-30/-105]s, transverse shear from G1Z/G2Z: the eight lowest modes within
    1.2 % of MYSTRAN 18's (1.13 %: each code's discretization; ours converges from above as
    h^2, the gap 4 times smaller than at 16 x 16), mode 1 within 0.25 % (0.20 %); the two
    stacks' first modes differ by 32 %, so a turned or mirrored ply angle could not pass."""
    from test_nastran_solids import _mystran_hz

    firsts = []
    for angle in (30.0, -30.0):
        plies = ((angle, 5e-4), (angle - 75, 5e-4), (angle - 75, 5e-4), (angle, 5e-4))
        deck = Path(plate(tmp_path / f"c{angle:+.0f}.bdf", 32, plies, support="cantilever"))
        peer = _mystran_hz(deck)[:8]
        ours = hz(deck)
        assert np.max(np.abs(ours / peer - 1)) < 0.012
        assert abs(ours[0] / peer[0] - 1) < 0.0025
        firsts.append(ours[0])
    assert firsts[0] / firsts[1] - 1 > 0.3


@pytest.mark.parametrize("support, plies, z0", [
    ("simple", ((0.0, 1e-3), (90.0, 1e-3)), "0."),
    ("cantilever", ((30.0, 6e-4), (-60.0, 1e-3), (10.0, 4e-4)), ""),
])  # fmt: skip
def test_unsymmetric_laminates_against_mystran(tmp_path, support, plies, z0):
    """Membrane-bending coupling B (32 x 32): a [0/90] plate on the plate's supports (w and the
    in-plane motion held on every edge) with the stack above its reference plane (Z0 = 0), and
    the corner-massed cantilever of a [30/-60/10] stack (B16, B26 too): the eight lowest modes
    within 1.2 % of MYSTRAN 18's (1.14 % and 1.00 % at the highest, 4 times less than at
    16 x 16).
    Without B the modes are 8-47 % off; with B of the wrong sign the first mode of the offset
    plate is 10 % off."""
    from test_nastran_solids import _mystran_hz

    deck = Path(plate(tmp_path / "u.bdf", 32, support=support, prop=_pcomp(plies, z0=z0)))
    assert np.max(np.abs(hz(deck) / _mystran_hz(deck)[:8] - 1)) < 0.012


def test_a_laminate_seen_from_its_other_side_is_the_same(tmp_path):
    """[0/90] on GRIDs numbered G1-G2-G3-G4 = [90/0] on the same GRIDs numbered G1-G4-G3-G2
    (normal reversed, so the stack reads from the other face; its G1-G2 side is along y, so
    THETA 90 turns the material axis back to x): K to 1e-12 in both orders."""
    up = load_nastran_model(plate(tmp_path / "a.bdf", 4, ((0.0, 1e-3), (90.0, 1e-3))))
    deck = Path(plate(tmp_path / "b.bdf", 4, ((90.0, 1e-3), (0.0, 1e-3)), theta="90."))
    lines = []
    for line in deck.read_text().splitlines():
        if line.startswith("CQUAD4"):
            f = line.split(",")
            f[3:7] = [f[3], f[6], f[5], f[4]]
            line = ",".join(f)
        lines.append(line)
    deck.write_text("\n".join(lines) + "\n")
    K0, K1 = up.matrices()[0], load_nastran_model(str(deck)).matrices()[0]
    assert abs(K1 - K0).max() < 1e-12 * abs(K0).max()


def test_woven_laminate_is_nx_nastrans_on_its_own_static_solution():
    """NX's PCOMPG tensile patch as published (``studies/nx_laminate.py``: ten MAT8 plies, four
    CQUAD4, the bottom edge clamped, 100 N along z): this package's K gives NX's translations
    to its f06's seven digits (1.5e-6 of the largest across, 5e-8 along)."""
    import scipy.sparse.linalg as spla

    nx = json.loads((DATA / "nx_laminate_pcompg.json").read_text())
    model = load_nastran_model(str(DATA / "nx_laminate_pcompg.bdf"))
    K, _ = model.matrices()
    grids = list(model.structure.metadata["nastran"]["grid_ids"])
    F = np.zeros(K.shape[0])
    for g, load in nx["loads_z"].items():
        F[6 * grids.index(int(g)) + 2] = load
    held = np.concatenate([6 * grids.index(g) + np.arange(6) for g in nx["clamped"]])
    free = np.setdiff1d(np.arange(K.shape[0]), held)
    u = np.zeros(K.shape[0])
    u[free] = spla.spsolve(K.tocsc()[free][:, free], F[free])
    ours = u.reshape(-1, 6)[[grids.index(g) for g in nx["grids"]], :3]
    U = np.array(nx["translations"])[:, [0, 2]]  # T2 is zero: the patch lies in the x-z plane
    err = np.abs(ours[:, [0, 2]] - U).max(axis=0) / np.abs(U).max(axis=0)
    assert err[0] < 2e-6 and err[1] < 1e-7


def test_refusals_in_one_message(tmp_path):
    """A Z0 offset on a membrane stack, LAM SMEAR, plies rigid in transverse shear in one plane
    only (G2Z blank on each), a MAT8 under a PSHELL and a cylindrical MCID: one error naming
    each card's file:line."""
    lines = [
        *_pcomp(CROSS, pid=7, lam="MEM", z0="0."),
        *_pcomp(CROSS, pid=8, lam="SMEAR"),
        "MAT8,4,140.e9,10.e9,0.3,5.e9,5.e9,,1600.",
        "PCOMP,9,,,,,,,",
        ",4,5.e-4,0.,,4,5.e-4,0.,",
        "PSHELL,10,3,1.e-3,3",
        "CORD2C,6,,0.,0.,0.,0.,0.,1.",
        ",1.,0.,0.",
    ]
    deck = Path(plate(tmp_path / "bad.bdf", 2, prop=lines))
    pids = {2: "8", 3: "9", 4: "10"}
    text = deck.read_text()
    for e, pid in pids.items():
        text = text.replace(f"CQUAD4,{e},7,", f"CQUAD4,{e},{pid},")
    deck.write_text(text.replace("\nENDDATA", "\nCQUAD4,5,7,1,2,5,4,6\nENDDATA"))
    with pytest.raises(BayesUpdateError) as err:
        load_nastran_model(str(deck))
    msg = str(err.value)
    for why in (
        "PCOMP 7: Z0 = 0 offsets a LAM MEM stack",
        "PCOMP 8: LAM SMEAR",
        "PCOMP 9: its plies are rigid in transverse shear in one plane only",
        "PSHELL 10: material 3 is a MAT8",
        "CQUAD4 5: MCID 6",
    ):
        assert why in msg
    assert "5 card(s) refused" in msg


def test_a_ply_material_cannot_be_a_parameter(tmp_path):
    """A MAT1 E binding on a MAT1 that a PCOMP takes as a ply: refused, naming the PCOMP."""
    mat = "MAT1,13,70.e9,,0.3,2700."
    deck = plate(tmp_path / "p.bdf", 2, prop=[mat, *_pcomp(CROSS, mid=13)], shear=False)
    with pytest.raises(BayesUpdateError, match="PCOMP 7 take"):
        load_nastran_model(deck, {"E": {"binds": "MAT1 13 E"}})
