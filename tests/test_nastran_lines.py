"""Line-element fields bound as parameters (``bayesupdate.nastran.lines``) on the MSC beam deck
(``../shared/data/nastran/beam_modes``: CBAR with PBARL ROD, CBEAM with PBEAML ROD, MAT1 2,
lumped mass, INCLUDEd bulk data) and on a variant of it edited by hand (PBAR and PBEAM with
the same numbers, and two CRODs with PROD 2).  At random parameter points, the model's
frequencies must equal those of the deck edited by hand with those values and read again
(rel 1e-10), and so must those of the deck ``--write-bdf`` writes.
"""

import shutil
from pathlib import Path

import numpy as np
import pytest

BEAM = Path(__file__).resolve().parents[2] / "shared" / "data" / "nastran" / "beam_modes"
if not BEAM.is_dir():
    pytest.skip(f"shared data not found: {BEAM}", allow_module_level=True)


def _load(deck, parameters=None):
    from bayesupdate.nastran import load_nastran_model

    return load_nastran_model(str(deck), parameters or {})


def _deck(folder: Path, edit) -> Path:
    """The beam deck copied to ``folder`` with its bulk file's lines passed through ``edit``."""
    folder.mkdir(exist_ok=True)
    shutil.copy(BEAM / "beam_modes.dat", folder / "beam_modes.dat")
    lines = (BEAM / "cbar_cbeam.blk").read_text().splitlines()
    (folder / "cbar_cbeam.blk").write_text("\n".join(edit(lines)) + "\n")
    return folder / "beam_modes.dat"


def _msc(r1=1.0, r3=1.0, e=3.0e7, rho=7.4851e-4):
    """The MSC deck with PBARL 1 / PBEAML 3 DIM1, MAT1 2 E and RHO typed in."""

    def edit(lines):
        out = []
        for i, line in enumerate(lines):
            if line.startswith("MAT1"):
                line = f"MAT1,2,{e!r},1.1628+7,.29,{rho!r},0.0,,0.0"
            elif i and lines[i - 1].startswith(("PBARL", "PBEAML")):
                # fixed 8-character fields: the radii have 6 decimals
                line = f"+       {r1 if lines[i - 1].startswith('PBARL ') else r3:8.6f}     0.0"
            out.append(line)
        return out

    return edit


def _variant(a=np.pi, i1=np.pi / 4, i2=np.pi / 4, j=np.pi / 2, beam_i1=np.pi / 4,
             rod_a=1.0, rod_j=0.3, e=3.0e7):  # fmt: skip
    """The deck edited by hand: PBAR 1 and PBEAM 3 (shear flexible, K1 = K2 = 1) for the ROD
    sections, PROD 2 with J, CROD 20, 21 from GRID 6 to 12 to 7, MAT1 2 with G blank (Nastran
    derives it from E and NU)."""

    def edit(lines):
        out = []
        skip = False
        for line in lines:
            if skip:
                skip = False
                continue
            if line.startswith("PBARL"):
                line, skip = f"PBAR,1,2,{a!r},{i1!r},{i2!r},{j!r}", True
            elif line.startswith("PBEAML"):
                line = f"PBEAM,3,2,{np.pi!r},{beam_i1!r},{np.pi / 4!r},,{np.pi / 2!r}"
                skip = True
            elif line.startswith("MAT1"):
                line = f"MAT1,2,{e!r},,.29,7.4851-4,0.0,,0.0"
            elif line.startswith("PROD"):
                line = f"PROD,2,2,{rod_a!r},{rod_j!r}\nCROD,20,2,6,12\nCROD,21,2,12,7"
            out.append(line)
        return out

    return edit


def _hz(model, values=None):
    return model.solve(values, n_modes=10).frequencies_hz


def test_msc_deck_pbarl_pbeaml_dims_and_mat1_equal_the_deck_edited_by_hand(tmp_path):
    from bayesupdate.nastran.writer import write_updated_deck

    params = {
        "r1": {"binds": "PBARL 1 DIM1"},
        "r3": {"binds": "PBEAML 3 DIM1"},
        "e": {"binds": "MAT1 2 E"},
        "rho": {"binds": "MAT1 2 RHO scale"},
    }
    model = _load(BEAM / "beam_modes.dat", params)
    assert model.default_parameters() == {"r1": 1.0, "r3": 1.0, "e": 3.0e7, "rho": 1.0}
    np.testing.assert_allclose(_hz(model), _hz(_load(BEAM / "beam_modes.dat")), rtol=1e-12)
    rng = np.random.default_rng(19)
    for k in range(2):
        x = np.round(rng.uniform(0.7, 1.3, 4), 6) * [1, 1, 3e7, 1]
        v = dict(zip(params, map(float, x), strict=True))
        edit = _msc(v["r1"], v["r3"], v["e"], 7.4851e-4 * v["rho"])
        direct = _hz(_load(_deck(tmp_path / f"d{k}", edit)))
        np.testing.assert_allclose(_hz(model, v), direct, rtol=1e-10)
    # --write-bdf: the bound cards are in the INCLUDEd file, whose text is written in its place
    out = write_updated_deck(model, v, tmp_path / "written.bdf")
    np.testing.assert_allclose(_hz(_load(out)), direct, rtol=1e-10)


def test_pbar_pbeam_prod_fields_equal_the_deck_edited_by_hand(tmp_path):
    from bayesupdate.nastran.writer import write_updated_deck

    deck = _deck(tmp_path / "nominal", _variant())
    params = {
        "a": {"binds": "PBAR 1 A"},
        "i1": {"binds": "PBAR 1 I1"},
        "j": {"binds": "PBAR 1 J"},
        "bi1": {"binds": "PBEAM 3 I1"},
        "ra": {"binds": "PROD 2 A"},
        "rj": {"binds": "PROD 2 J"},
        "e": {"binds": "MAT1 2 E"},
    }
    model = _load(deck, params)
    nominal = model.default_parameters()
    deck_values = dict(a=np.pi, i1=np.pi / 4, j=np.pi / 2, bi1=np.pi / 4, ra=1.0, rj=0.3, e=3e7)
    assert nominal == pytest.approx(deck_values)
    rng = np.random.default_rng(7)
    v = {n: float(x * rng.uniform(0.7, 1.3)) for n, x in nominal.items()}
    edited = _variant(v["a"], v["i1"], np.pi / 4, v["j"], v["bi1"], v["ra"], v["rj"], v["e"])
    direct = _hz(_load(_deck(tmp_path / "edited", edited)))
    got = _hz(model, v)
    np.testing.assert_allclose(got, direct, rtol=1e-10)
    assert np.max(np.abs(got / _hz(model) - 1)) > 0.02  # the fields matter
    out = write_updated_deck(model, v, tmp_path / "written.bdf")
    np.testing.assert_allclose(_hz(_load(out)), direct, rtol=1e-10)


def test_bad_line_bindings_are_one_line_errors(tmp_path):
    from bayesupdate.errors import BayesUpdateError

    for binds, bounds, message in [
        ("PBARL 1 DIM2", None, "PBARL 1 (ROD) has 1 dimensions"),
        ("PROD 2 A", None, "PROD 2 A': no element uses it"),
        ("PBAR 1 A", None, "the deck has no PBAR 1"),
        ("PBARL 1 DIM1", [-1.0, 2.0], "the low bound must be > 0"),
    ]:
        with pytest.raises(BayesUpdateError) as info:
            _load(BEAM / "beam_modes.dat", {"p": {"binds": binds, "bounds": bounds}})
        assert message in str(info.value) and "\n" not in str(info.value)
    model = _load(BEAM / "beam_modes.dat", {"p": {"binds": "PBARL 1 DIM1"}})
    with pytest.raises(BayesUpdateError, match="p = -0.5"):
        model.solve({"p": -0.5})


def test_dvprel1_on_a_pbar_field_number_is_a_parameter(tmp_path):
    def with_desvar(lines):  # PBAR 1 A (field 4) = 2 x AREA
        return [*_variant()(lines), "DESVAR,1,AREA,1.5,1.0,5.0", "DVPREL1,10,PBAR,1,4,,,0.,+D",
                "+D,1,2.0"]  # fmt: skip

    model = _load(_deck(tmp_path / "dv", with_desvar))
    assert model.parameter_names == ("AREA",)
    assert model.default_bounds() == {"AREA": (1.0, 5.0)}
    direct = _load(_deck(tmp_path / "edited", _variant(a=3.4)))
    np.testing.assert_allclose(_hz(model, {"AREA": 1.7}), _hz(direct), rtol=1e-10)
