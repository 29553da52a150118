"""A new element family is one class and its registration (``fe.elements.base``).

The family below is written here, in the test, and registered with ``register``; no file of the
package names it.  On a free-free spring-mass chain it is then assembled (closed-form
frequencies), counted in the modal energies and the total mass, and taken into the reduced
basis (a certified reduced model reproduces the closed form at a new parameter value).

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
