"""A new element family is one class and its registration (``fe.elements.base``).

The family below is written here, in the test, and registered with ``register``; no file of the
package names it.  On a free-free spring-mass chain it is then assembled (closed-form
frequencies), counted in the modal energies and the total mass, and taken into the reduced
basis (a certified reduced model reproduces the closed form at a new parameter value).  The
same holds for a family with a design parameter (``register_parametric``): the property it
declares (``Bindable``) is bound, checked and split into the reduced basis's affine terms with
no file of the package naming the family, its field or its property.

Closed form: N equal masses m joined in a chain by N - 1 equal springs k, both ends free, have
omega_j^2 = (4 k / m) sin^2(j pi / (2 N)), j = 1 .. N - 1 (Rayleigh, *Theory of Sound*, sec. 120;
the discrete string).  Here every node carries the lumped mass m on its translations and the
rotary inertia J on its rotations, and the zero-length springs have k_t on the translations and
k_r on the rotations: each j gives three modes at (4 k_t / m) sin^2 and three at (4 k_r / J) sin^2.
"""

import inspect
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import Binding, FEModel, StructureBuilder
from bayesupdate.fe.elements import base
from bayesupdate.fe.model import PROPERTY_TERMS
from bayesupdate.fe.reduced import ReducedFEModel
from bayesupdate.fe.reduced.settings import ReducedSettings

N, MASS, INERTIA, K_T, K_R = 6, 2.0, 0.05, 4.0e4, 3.0e2
FAMILY = "test_lumped_mass"


@dataclass(frozen=True)
class LumpedMasses:
    """Lumped masses on one node each: nodes (n, 1), mass (n,) [kg] on the three translations,
    inertia (n,) [kg m^2] on the three rotations, part (n,)."""

    nodes: np.ndarray
    mass: np.ndarray
    inertia: np.ndarray
    part: np.ndarray
    family = FAMILY

    @property
    def n_elements(self) -> int:
        return int(self.nodes.shape[0])

    def dofs(self) -> np.ndarray:
        return 6 * self.nodes[:, :1] + np.arange(6)

    def matrices(self, xyz, settings):
        M = np.zeros((self.n_elements, 6, 6))
        M[:, [0, 1, 2], [0, 1, 2]] = self.mass[:, None]
        M[:, [3, 4, 5], [3, 4, 5]] = self.inertia[:, None]
        return np.zeros_like(M), M

    def has_mass(self) -> bool:
        return bool(np.any(self.mass > 0))

    @classmethod
    def of(cls, structure):
        return base.in_elements(cls, structure)


@pytest.fixture
def registry(monkeypatch):
    """The registry with the family registered, for this test only (restored afterwards)."""
    monkeypatch.setattr(base, "FAMILIES", dict(base.FAMILIES))
    base.register(LumpedMasses)
    return base.FAMILIES


def _chain():
    """N coincident nodes joined by N - 1 springs (part "springs"), a lumped mass on each node
    (part "lumped", the test family)."""
    b = StructureBuilder()
    nodes = [b.add_node((0.0, 0.0, 0.0)) for _ in range(N)]
    for a, c in zip(nodes[:-1], nodes[1:], strict=True):
        b.add_spring(a, c, [K_T] * 3 + [K_R] * 3, "springs")
    s = b.build()
    lumped = LumpedMasses(
        np.array(nodes)[:, None], np.full(N, MASS), np.full(N, INERTIA), np.full(N, len(s.parts))
    )
    return replace(s, parts=(*s.parts, "lumped"), elements=(lumped,))


def _closed_form(factor: float = 1.0) -> np.ndarray:
    """(6 (N - 1),) frequencies [Hz] of the chain with spring factor ``factor``, sorted."""
    s2 = np.sin(np.arange(1, N) * np.pi / (2 * N)) ** 2
    w2 = np.concatenate(
        [np.repeat(4 * factor * K_T / MASS * s2, 3), np.repeat(4 * factor * K_R / INERTIA * s2, 3)]
    )
    return np.sort(np.sqrt(w2)) / (2 * np.pi)


def _model(s):
    return FEModel(
        s, {"ks": Binding("springs", "stiffness_factor")}, {"ks": 1.0}, {"ks": (0.5, 2.0)}
    )


def test_registered_family_assembles_to_the_chain_closed_form(registry):
    assert registry[FAMILY] is LumpedMasses
    fe = _model(_chain())
    n = 6 * (N - 1)
    for method in ("krylov", "sparse"):
        r = fe.solve(n_modes=n, method=method, energies=True)
        np.testing.assert_allclose(r.frequencies_hz, _closed_form(), rtol=1e-9)
        # the springs hold all the strain energy, the family all the kinetic energy
        lumped, springs = fe.structure.part_index("lumped"), fe.structure.part_index("springs")
        np.testing.assert_allclose(r.energies.kinetic_by_part[lumped], 1.0, rtol=1e-12)
        np.testing.assert_allclose(r.energies.strain_by_part[springs], 1.0, rtol=1e-12)
        assert r.mass_kg == pytest.approx(N * MASS, rel=1e-12)


def test_registered_family_enters_the_reduced_basis(registry):
    assert registry[FAMILY] is LumpedMasses
    fe = _model(_chain())
    settings = ReducedSettings(n_modes=12, tol=1e-6, seed=0)
    rom = ReducedFEModel(fe, settings=settings).build()
    assert rom.certified
    f = rom.predict({"ks": 1.7}, n_modes=12).frequencies_hz
    np.testing.assert_allclose(f, _closed_form(1.7)[:12], rtol=1e-6)


def test_unregistered_family_is_refused():
    with pytest.raises(BayesUpdateError, match="not registered"):
        FEModel(_chain(), {}, {}, {})


def test_files_a_new_family_touches(registry):
    """The measure of the contributing guide: the files a new family touches are the files of
    the package that name it (none) and the file of its class (here this test): one file, whose
    one ``register`` call is the registration."""
    package = Path(base.__file__).resolve().parents[2]
    naming = {p for p in package.rglob("*.py") if FAMILY in p.read_text()}
    touched = naming | {Path(inspect.getsourcefile(LumpedMasses)).resolve()}
    assert touched == {Path(__file__).resolve()}
    assert registry[FAMILY] is LumpedMasses


# -- a new family with a design parameter ----------------------------------------------------
PARAM_FAMILY, PARAM_FIELD, PARAM_PROPERTY = "test_scaled_mass", "test_mass_scale", "test_factor"


@dataclass(frozen=True)
class ScaledLumpedMasses(LumpedMasses):
    """``LumpedMasses`` whose mass and inertia a parameter scales: a ``ParametricFamily`` that
    declares its one bindable property (a factor on the part's masses, M linear in it)."""

    family = PARAM_FAMILY
    fields = (PARAM_FIELD,)
    linear = "M"
    properties = (base.Bindable(PARAM_PROPERTY, PARAM_FIELD, "M", rule="factor", positive=False),)

    def nominal(self) -> dict:
        return {PARAM_FIELD: np.ones(self.n_elements)}

    def check(self, props, parts) -> None:
        values = getattr(props, PARAM_FIELD)
        base.check_fields((("mass factor", values, None, False),), self.part, parts)

    def matrices(self, props, settings, elements=None):
        e = np.arange(self.n_elements) if elements is None else elements
        M = LumpedMasses.matrices(self, None, settings)[1][e]
        return None, M * getattr(props, PARAM_FIELD)[e, None, None]

    def masses(self, props, xyz):
        return self.mass * getattr(props, PARAM_FIELD), xyz[self.nodes[:, 0]]


@pytest.fixture
def parametric_registry(monkeypatch):
    """The parametric registry with ``ScaledLumpedMasses`` registered, for this test only."""
    monkeypatch.setattr(base, "PARAMETRIC", dict(base.PARAMETRIC))
    base.register_parametric(ScaledLumpedMasses)
    return base.PARAMETRIC


def _scaled_chain():
    """The chain of ``_chain`` with the parametric family's masses."""
    s = _chain()
    m = s.elements[0]
    return replace(s, elements=(ScaledLumpedMasses(m.nodes, m.mass, m.inertia, m.part),))


def _scaled_model():
    bindings = {
        "ks": Binding("springs", "stiffness_factor"),
        "fm": Binding("lumped", PARAM_PROPERTY),
    }
    return FEModel(
        _scaled_chain(), bindings, {"ks": 1.0, "fm": 1.0}, {"ks": (0.5, 2.0), "fm": (0.5, 2.0)}
    )


def test_bindable_property_of_a_new_family_scales_the_closed_form(parametric_registry):
    """omega^2 = (4 k / (f m)) sin^2: a mass factor f is a spring factor 1 / f."""
    assert PROPERTY_TERMS[PARAM_PROPERTY] == (PARAM_FAMILY, PARAM_FIELD, "M")
    fe = _scaled_model()
    n = 6 * (N - 1)
    for method in ("krylov", "sparse"):
        r = fe.solve({"ks": 1.3, "fm": 1.7}, n_modes=n, method=method, energies=True)
        np.testing.assert_allclose(r.frequencies_hz, _closed_form(1.3 / 1.7), rtol=1e-9)
        lumped = fe.structure.part_index("lumped")
        np.testing.assert_allclose(r.energies.kinetic_by_part[lumped], 1.0, rtol=1e-12)
        assert r.mass_kg == pytest.approx(1.7 * N * MASS, rel=1e-12)
    term = fe.affine_terms().parameters[1]
    assert (term.family, term.field, term.enters, term.scale) == (
        PARAM_FAMILY,
        PARAM_FIELD,
        "M",
        1.0,
    )
    np.testing.assert_array_equal(term.elements, np.arange(N))


def test_bindable_property_of_a_new_family_enters_the_reduced_basis(parametric_registry):
    """The factor enters M linearly: the affine split holds it exactly, so the certified reduced
    model reproduces the closed form at a new factor."""
    fe = _scaled_model()
    rom = ReducedFEModel(fe, settings=ReducedSettings(n_modes=12, tol=1e-6, seed=0)).build()
    assert rom.certified
    f = rom.predict({"ks": 0.8, "fm": 1.9}, n_modes=12).frequencies_hz
    np.testing.assert_allclose(f, _closed_form(0.8 / 1.9)[:12], rtol=1e-6)


def test_bindable_property_of_a_new_family_is_checked(parametric_registry):
    fe = _scaled_model()
    with pytest.raises(BayesUpdateError, match="fm = -0.5: test_factor must be >= 0"):
        fe.solve({"fm": -0.5})
    with pytest.raises(BayesUpdateError, match="part 'springs' has nothing with a test_factor"):
        FEModel(
            _scaled_chain(), {"f": Binding("springs", PARAM_PROPERTY)}, {"f": 1.0}, {"f": (0.5, 2)}
        )
    # registered but absent: a model without the family assembles as before, and its
    # property binds nothing there
    springs = replace(_chain(), elements=())
    fe = _model(springs)
    assert PARAM_FIELD not in fe.element_properties().values
    K1, K2 = fe.matrices({"ks": 1.0})[0], fe.matrices({"ks": 2.0})[0]
    np.testing.assert_allclose((K2 - 2 * K1).toarray(), 0.0, atol=1e-9 * abs(K1).max())
    with pytest.raises(BayesUpdateError, match="part 'lumped' has nothing with a test_factor"):
        FEModel(springs, {"f": Binding("lumped", PARAM_PROPERTY)}, {"f": 1.0}, {"f": (0.5, 2)})
    taken = base.Bindable("mass_factor", PARAM_FIELD, "M")
    clash = type("Clash", (ScaledLumpedMasses,), {"family": "test_clash", "properties": (taken,)})
    with pytest.raises(BayesUpdateError, match="already bound by family 'mass'"):
        base.register_parametric(clash)


def test_files_a_new_parametric_family_touches(parametric_registry):
    """As ``test_files_a_new_family_touches``, for a family with a bindable property: no file of
    the package names the family, its field or its property."""
    package = Path(base.__file__).resolve().parents[2]
    for name in (PARAM_FAMILY, PARAM_FIELD, PARAM_PROPERTY):
        assert not [p for p in package.rglob("*.py") if name in p.read_text()]
    assert Path(inspect.getsourcefile(ScaledLumpedMasses)).resolve() == Path(__file__).resolve()
    assert parametric_registry[PARAM_FAMILY] is ScaledLumpedMasses
