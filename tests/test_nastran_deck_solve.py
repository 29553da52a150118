"""Bound line fields of a real deck solved through their records (``nastran.lines.LineFields``):
the mAEWing1 v3.3 deck (``../shared/data/gvt_maewing1/fem``, README there) with ``PBEAM 1003
I1``, ``PBEAM 1004 I1`` (both wings each) and ``PBEAM 1005 A`` bound.

At two points of the box the bound model's K and M must equal those of the deck written with
the values (``--write-bdf``) and read again from scratch, and those of the reference path that
converts the bound cards again (``LineRebuild``), to 1e-12 of the largest entry (measured: 1e-20
and 7e-17 for M).  The frequencies are compared too; they carry the eigen-solve's round-off on
this deck (MAT1 906, E = 6.66e10, beside foam-covered wing beams: measured 1.8e-8 on mode 1
between the two assemblies, and 5e-9 between the dense and the Lanczos solver on the *same*
matrices), asserted at 1e-7.  A deck that really is in two pieces is refused with its GRID ids.
Skipped without the shared data.
"""

from pathlib import Path

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError

FEM = Path(__file__).resolve().parents[2] / "shared" / "data" / "gvt_maewing1" / "fem"
V33 = FEM / "v3.3_hati" / "sol103_mAEWing1_Hati_FEMv3p3.bdf"
BINDS = {"i1_1003": "PBEAM 1003 I1", "i1_1004": "PBEAM 1004 I1", "a_1005": "PBEAM 1005 A"}


def bound_v33():
    """The v3.3 deck as published with ``BINDS`` bound (skips without the shared data)."""
    from bayesupdate.nastran import load_nastran_model

    if not V33.exists():
        pytest.skip(f"shared data not found: {V33}")
    return load_nastran_model(str(V33), {n: {"binds": b} for n, b in BINDS.items()})


@pytest.fixture(scope="module")
def bound():
    return bound_v33()


def _rel(A, B) -> float:
    return float(abs(A - B).max() / abs(B).max())


@pytest.mark.parametrize("factors", [(1.1, 0.9, 1.25), (0.6, 1.8, 0.7)])
def test_bound_wing_fields_equal_the_deck_written_with_them(bound, factors, tmp_path):
    from bayesupdate.nastran import load_nastran_model
    from bayesupdate.nastran.lines import LineAssembler
    from bayesupdate.nastran.writer import write_updated_deck

    g = bound.general
    assert g.fields is not None, g.fields_note  # PBEAM A, I1: records affine in the fields
    assert g.fields.beams.size == 12 and g.fields.masses.size == 24  # both wings, lumped ends
    p = {k: v * f for (k, v), f in zip(bound.default_parameters().items(), factors, strict=True)}
    K, M = bound.matrices(p)
    scratch = load_nastran_model(str(write_updated_deck(bound, p, tmp_path / "v33.bdf")))
    Ks, Ms = scratch.matrices()
    assert _rel(K, Ks) < 1e-12 and _rel(M, Ms) < 1e-12
    reference = LineAssembler(bound.structure, bound._shell_keys(), bound.bdf, bound.bindings,
                              bound.deck, bound._defaults, bound._bounds, fast=False)  # fmt: skip
    reference.values = bound.full_parameters(p)
    Kr, Mr, _ = reference.assemble(bound.element_properties(p))
    assert _rel(K, Kr) < 1e-12 and _rel(M, Mr) < 1e-12
    assert _rel(K, bound.matrices()[0]) > 1e-4  # the point moves K
    f, fs = bound.solve(p, 20).frequencies_hz, scratch.solve(None, 20).frequencies_hz
    np.testing.assert_allclose(f, fs, rtol=1e-7)
    assert bound.total_mass(p)[0] == pytest.approx(scratch.total_mass()[0], rel=1e-12)


def test_bound_model_at_the_deck_values_is_the_deck(bound):
    """At the deck's own values the change of the bound elements is exactly 0: the bound model
    is the deck to the bit (matrices and frequencies)."""
    from bayesupdate.nastran import load_nastran_model

    plain = load_nastran_model(str(V33))
    for X, X0 in zip(bound.matrices(), plain.matrices(), strict=True):
        assert abs(X - X0).max() == 0.0
    f, f0 = bound.solve(None, 20).frequencies_hz, plain.solve(None, 20).frequencies_hz
    np.testing.assert_array_equal(f, f0)


def test_a_disconnected_deck_is_refused_with_its_grid_ids(tmp_path):
    """Two CBARs on GRIDs 1-2-3 and one on GRIDs 11-12 that nothing ties to them: the check on
    the whole read deck names the GRIDs of the lonely piece (not the structure's node numbers),
    with or without a binding on the property both pieces use."""
    from bayesupdate.nastran import load_nastran_model

    deck = tmp_path / "two_pieces.bdf"
    deck.write_text(
        "SOL 103\nCEND\nBEGIN BULK\n"
        "GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,2.,0.,0.\n"
        "GRID,11,,0.,1.,0.\nGRID,12,,1.,1.,0.\n"
        "CBAR,1,7,1,2,0.,0.,1.\nCBAR,2,7,2,3,0.,0.,1.\nCBAR,3,7,11,12,0.,0.,1.\n"
        "PBAR,7,1,0.1,1.-3,1.-3,2.-3\nMAT1,1,7.+10,,0.3,2700.\nENDDATA\n"
    )
    for parameters in (None, {"a": {"binds": "PBAR 7 A"}}):
        with pytest.raises(BayesUpdateError) as err:
            load_nastran_model(str(deck), parameters)
        msg = str(err.value)
        assert "disconnected: 2 separate pieces" in msg and "\n" not in msg
        assert "GRID 11, GRID 12 are not connected to the main piece of 3 nodes" in msg


def test_two_parameters_on_one_card_field_are_refused():
    """``PBEAM 1002 I1`` and a scale of ``PBEAM 1002,1003 I1`` both set card 1002's I1: the
    last would win and the other would look insensitive, so the pair is refused by name (the
    packaged v3.3 deck, so this runs without the shared data)."""
    from bayesupdate.nastran import load_nastran_model

    deck = Path(__file__).resolve().parents[1] / "bayesupdate" / "data" / "maewing1" / "v3.3"
    binds = {"a": "PBEAM 1002 I1", "b": "PBEAM 1002,1003 I1 scale"}
    with pytest.raises(BayesUpdateError, match=r"parameters a .* and b .* act on the same"):
        load_nastran_model(str(deck / "sol103_mAEWing1_Hati_FEMv3p3.bdf"),
                           {n: {"binds": b} for n, b in binds.items()})  # fmt: skip


@pytest.mark.parametrize("point", [(1.05, 3.93, 0.97, 1.02), (12.0, 11.0, 0.2, 6.5)])
def test_a_product_of_two_bound_fields_solves_through_bilinear_records(point, tmp_path):
    """The aircraft case's parameters (``pipelines.aircraft.PARAMETERS``): one scale of the I1
    of seven PBEAMs whose deck values differ, and the wing's MAT1 RHO, whose product is the twist
    inertia rho (I1 + I2) and the lumped ends' inertia.  Their records are bilinear, not affine:
    with the pair terms the records path equals the deck written with the values and read
    again, and the card-converting reference, to 1e-12 of the largest entry (before: the
    reference path at every solve, 12x slower)."""
    from bayesupdate.nastran import load_nastran_model
    from bayesupdate.nastran.lines import LineAssembler
    from bayesupdate.nastran.writer import write_updated_deck
    from bayesupdate.pipelines import aircraft as ac

    spec = {n: {"binds": b, "bounds": list(lim)} for n, (b, lim) in ac.PARAMETERS.items()}
    model = load_nastran_model(str(ac.data_folder() / ac.V33_DECK), spec)
    g = model.general
    assert g.fields is not None, g.fields_note
    fit = g.fields.fit
    assert "beam.torsion_inertia" in fit.pairs
    # the only products: RHO with the I1 of the beams it is the density of (not I1 with I1)
    assert {(fit.names[i], fit.names[j]) for i, j in fit.pair_index} == {
        ("EI_root", "rho_wing"),
        ("EI_outer", "rho_wing"),
    }
    p = dict(zip(ac.PARAMETERS, point, strict=True))
    K, M = model.matrices(p)
    reference = LineAssembler(model.structure, model._shell_keys(), model.bdf, model.bindings,
                              model.deck, model._defaults, model._bounds, fast=False)  # fmt: skip
    reference.values = model.full_parameters(p)
    Kr, Mr, _ = reference.assemble(model.element_properties(p))
    assert _rel(K, Kr) < 1e-12 and _rel(M, Mr) < 1e-12
    scratch = load_nastran_model(str(write_updated_deck(model, p, tmp_path / "v33.bdf")))
    Ks, Ms = scratch.matrices()
    assert _rel(K, Ks) < 1e-12 and _rel(M, Ms) < 1e-12
