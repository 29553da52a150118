"""``fe.mass_properties.rigid_mass_terms`` with pair terms: a beam deck whose mass matrix holds
a product of two parameters (the MAT1 RHO scale times the PBEAM I1 in the lumped twist inertia
rho (I1 + I2) L / 2) gets one cross term C_ij, and its mass properties equal those of the full
assembly at random points of the box; an additive model (densities, moduli, point masses)
keeps no pair, so its terms are the affine ones.
"""

import numpy as np
import pytest

from bayesupdate.fe.mass_properties import rigid_mass_terms
from bayesupdate.nastran import load_nastran_model

#: a free, curved chain of 5 CBEAMs (inch-lbf-s, WTMASS) with a CONM2 off the axis
DECK = [
    "SOL 103", "CEND", "BEGIN BULK", "PARAM,WTMASS,0.00259", "EIGRL,1,,,6",
    *(f"GRID,{i + 1},,{10.0 * i},{0.5 * i},{0.2 * i * i}" for i in range(6)),
    *(f"CBEAM,{i + 1},1,{i + 1},{i + 2},0.,0.,1." for i in range(5)),
    "PBEAM,1,1,0.5,0.04,0.02,,0.03", "MAT1,1,1.0e7,,0.3,0.1", "CONM2,100,6,,1.0,0.,2.,0.",
    "ENDDATA",
]  # fmt: skip
PARAMETERS = {
    "rho": ("MAT1 1 RHO scale", (0.5, 3.0)),
    "I1": ("PBEAM 1 I1", (0.01, 0.2)),
    "tip": ("CONM2 100 M scale", (0.5, 3.0)),
    "E": ("MAT1 1 E scale", (0.5, 3.0)),
}


def beam_model(tmp_path, names):
    path = tmp_path / "beam.bdf"
    path.write_text("\n".join(DECK) + "\n")
    spec = {n: {"binds": PARAMETERS[n][0], "bounds": list(PARAMETERS[n][1])} for n in names}
    return load_nastran_model(str(path), spec)


@pytest.fixture(scope="module")
def product_model(tmp_path_factory):
    return beam_model(tmp_path_factory.mktemp("beam"), ("rho", "I1", "tip"))


def test_a_density_times_section_product_gets_one_pair_and_matches_the_assembly(product_model):
    model = product_model
    terms = rigid_mass_terms(model)
    assert terms is not None
    assert [(terms.names[i], terms.names[j]) for i, j in terms.pairs] == [("rho", "I1")]
    rng = np.random.default_rng(40)
    bounds = model.default_bounds()
    for _ in range(6):
        point = {n: float(rng.uniform(*bounds[n])) for n in terms.names}
        exact = model.mass_properties(point).vector()
        got = terms(point).vector()
        np.testing.assert_allclose(got, exact, rtol=0, atol=1e-12 * np.abs(exact).max())
    # the cheap form is the one the likelihood uses
    assert model.mass_properties_function() is not model.mass_properties


def test_without_the_pair_the_affine_sum_misses_the_twist_inertia(product_model):
    # the cross term is not round-off: dropping it misses Ixx (about the beam's axis) at a far
    # corner by far more than the 1e-12 the pair form holds
    from dataclasses import replace

    terms = rigid_mass_terms(product_model)
    affine = replace(terms, pairs=(), C=None)
    corner = {"rho": 3.0, "I1": 0.2, "tip": 0.5}
    exact = product_model.mass_properties(corner).vector()
    assert np.abs(affine(corner).vector() - exact).max() > 1e-6 * np.abs(exact).max()


def test_an_additive_model_keeps_no_pairs(tmp_path):
    # density, modulus and point mass on separate terms: the affine check passes, so the
    # terms carry no pair and no C (the affine sum as before)
    model = beam_model(tmp_path, ("rho", "tip", "E"))
    terms = rigid_mass_terms(model)
    assert terms is not None and terms.pairs == () and terms.C is None
    point = {"rho": 2.2, "tip": 0.7, "E": 1.9}
    exact = model.mass_properties(point).vector()
    np.testing.assert_allclose(
        terms(point).vector(), exact, rtol=0, atol=1e-12 * np.abs(exact).max()
    )


@pytest.fixture(scope="module")
def aircraft():
    """The mAEWing1 v3.3 deck with the aircraft study's four parameters: RHO of the wing beams
    times their I1 in the twist inertia, and one scale on seven PBEAM I1 whose deck values
    differ (1 the deck), so the matrices at the defaults are the deck's own."""
    from bayesupdate.pipelines import aircraft as ac

    spec = {k: {"binds": b, "bounds": list(bo)} for k, (b, bo) in ac.PARAMETERS.items()}
    return load_nastran_model(ac.data_folder() / ac.V33_DECK, spec)


def test_the_aircraft_gets_two_density_pairs_and_its_total_mass_from_them(aircraft):
    from bayesupdate.fe.reduced import mass as reduced_mass

    terms = rigid_mass_terms(aircraft)
    assert terms is not None
    pairs = {(terms.names[i], terms.names[j]) for i, j in terms.pairs}
    assert pairs == {("EI_root", "rho_wing"), ("EI_outer", "rho_wing")}
    # built at the defaults: every binding is continuous there (the seven I1 are scaled, not
    # one absolute section), so the checks about the defaults pass
    assert terms.defaults is None
    np.testing.assert_array_equal(terms.theta0, list(aircraft.default_parameters().values()))
    assert terms({}).vector() == pytest.approx(terms(aircraft.default_parameters()).vector())
    aircraft.line_terms()  # the non-linear line fields the reduced basis interpolates
    assert reduced_mass._rigid_terms(aircraft) is not None
    per_term = reduced_mass.ShellMassTerms.of(aircraft)
    rng = np.random.default_rng(41)
    bounds = aircraft.default_bounds()
    for _ in range(4):
        point = aircraft.full_parameters({n: rng.uniform(*bounds[n]) for n in bounds})
        exact = aircraft.mass_properties(point).vector()
        np.testing.assert_allclose(
            terms(point).vector(), exact, rtol=0, atol=1e-12 * np.abs(exact).max()
        )
        # the reduced model's total mass [deck mass, WTMASS in]: the 6 x 6 sum's, the
        # elements' own (converted again) and the full assembly's agree
        mass = reduced_mass.total_mass(aircraft, point)
        assert mass == pytest.approx(per_term.total_mass(aircraft, point), rel=1e-12, abs=0)
        assert mass == pytest.approx(aircraft.total_mass(point)[0], rel=1e-12, abs=0)
