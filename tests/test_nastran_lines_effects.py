"""A deck with a bound line-element field, extended by a discovery effect.

``discover`` adds an effect's elements (``discovery.effects.extend_model``) to a deck model
through ``NastranModel.with_structure``; the bound line elements must still be re-built at
the parameter's value (``nastran.lines``), and its modal energies found.  On the MSC beam
deck (``../shared/data/nastran/beam_modes``: CBAR with PBARL 1 ROD, lumped mass), PBARL 1
DIM1 bound: the extended model at a radius must equal, to 1e-10, the same effect added to
the deck edited by hand with that radius and read again (no binding).  Without the radius
moving, the effect must still move the modes.
"""

from pathlib import Path

import numpy as np
import pytest

BEAM = Path(__file__).resolve().parents[2] / "shared" / "data" / "nastran" / "beam_modes"
if not BEAM.is_dir():
    pytest.skip(f"shared data not found: {BEAM}", allow_module_level=True)

LABELS = ("4V", "8V")


def _deck(folder: Path, r1: float) -> Path:
    """The beam deck copied to ``folder`` with PBARL 1's DIM1 (its radius) typed in."""
    folder.mkdir(exist_ok=True)
    (folder / "beam_modes.dat").write_text((BEAM / "beam_modes.dat").read_text())
    lines = (BEAM / "cbar_cbeam.blk").read_text().splitlines()
    out = []
    for i, line in enumerate(lines):
        if i and lines[i - 1].startswith("PBARL "):
            line = f"+       {r1:8.6f}     0.0"  # fixed 8-character fields
        out.append(line)
    (folder / "cbar_cbeam.blk").write_text("\n".join(out) + "\n")
    return folder / "beam_modes.dat"


def _extended(deck: Path, parameters: dict, spec: str):
    from bayesupdate.discovery.effects import extend_model, parse_effect_spec
    from bayesupdate.nastran import load_nastran_model

    model = load_nastran_model(str(deck), parameters, LABELS, {})
    return extend_model(model, parse_effect_spec(spec))


@pytest.mark.parametrize("spec", ["added_mass@8", "boundary_spring@4"])
def test_effect_on_a_deck_with_a_bound_line_field_equals_the_deck_edited_by_hand(tmp_path, spec):
    bound = _extended(BEAM / "beam_modes.dat", {"r1": {"binds": "PBARL 1 DIM1"}}, spec)
    values = bound.default_parameters()
    effect = [n for n in values if n != "r1"]
    assert values["r1"] == 1.0 and effect  # the deck's radius; the effect's own parameters
    base = bound.solve(values, n_modes=6).frequencies_hz
    values["r1"] = 1.173
    moved = bound.solve(values, n_modes=6).frequencies_hz
    edited = _extended(_deck(tmp_path / "d", 1.173), {}, spec)
    direct = edited.solve({n: values[n] for n in effect}, n_modes=6).frequencies_hz
    np.testing.assert_allclose(moved, direct, rtol=1e-10)
    # discover localizes by modal energies (``fe.energy``): the line elements' matrices are
    # there too, so every mode's strain and kinetic energy shares sum to 1 over the parts
    energies = bound.solve(values, n_modes=6, energies=True).energies
    np.testing.assert_allclose(energies.strain_by_part.sum(axis=0), 1.0, rtol=1e-9)
    np.testing.assert_allclose(energies.kinetic_by_part.sum(axis=0), 1.0, rtol=1e-9)
    assert np.abs(moved / base - 1).max() > 1e-2  # the radius does move the modes
    plain = _extended(BEAM / "beam_modes.dat", {}, spec)
    values = plain.default_parameters()
    for name in effect:
        lo, hi = plain.default_bounds()[name]
        values[name] = hi
        # the library's bounds (2 kg, 1e5 N/m) in the deck's units (lbf s^2/in, lbf/in:
        # 4.448222 N / 0.0254 m = 175.127 each): ``effects.model_parameters``
        assert hi * 4.4482216152605 / 0.0254 == pytest.approx(2.0 if "mass" in spec else 1e5)
    stiff_or_heavy = plain.solve(values, n_modes=6).frequencies_hz
    bare = plain.solve({n: plain.default_bounds()[n][0] for n in effect}, n_modes=6)
    change = stiff_or_heavy / bare.frequencies_hz - 1
    if "mass" in spec:  # 2 kg on the 4.6 kg beam
        assert change.max() < 0 and -change.min() > 1e-3
    else:  # a stiffness added can lower no eigenvalue (Rayleigh); 1e5 N/m on this beam: 7.6e-5
        assert change.min() >= -1e-12 and change.max() > 1e-5
