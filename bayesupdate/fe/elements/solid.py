"""What every solid element family shares: its record (corner nodes and positions, isotropic
material, lumping, part) and the factors on E and rho that its parameters are.

A solid family (``tetra``, ``hexa``) is a frozen dataclass deriving from ``Solids``; it names its
registry ``family`` and its two ``fields`` and ``properties`` (``factors``: the factor on E
first, on rho second), and gives ``matrices`` and ``masses``; ``strain_matrix`` and
``elasticity`` are every solid's B and D.  SI units: corners [m], E [Pa],
rho [kg/m^3].
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.fe.elements.base import Bindable, check_fields, in_elements


def factors(prefix: str, noun: str) -> tuple[tuple[str, str], tuple[Bindable, Bindable]]:
    """(``fields``, ``properties``) of a solid family: the factor on E, which K is linear in
    (field ``<prefix>_modulus_scale``, property ``<prefix>_modulus_factor``), then on rho, which
    M is linear in (``<prefix>_density_*``); ``noun`` names its elements ("bricks")."""
    fields = (f"{prefix}_modulus_scale", f"{prefix}_density_scale")
    properties = (
        Bindable(f"{prefix}_modulus_factor", fields[0], "K", rule="factor",
                 acts_on=f"factor on the E of the part's {noun}"),
        Bindable(f"{prefix}_density_factor", fields[1], "M", rule="factor",
                 acts_on=f"factor on the density of the part's {noun}"),
    )  # fmt: skip
    return fields, properties


@dataclass(frozen=True)
class Solids:
    """n solid elements of k corners: nodes (n, k) corner node indices; corners (n, k, 3) their
    positions [m]; E [Pa], nu [-], rho [kg/m^3] (n,); lumped (n,) bool (mass lumped at the
    corners, else consistent); part (n,) part indices."""

    #: K is linear in the factor on E, M in the factor on rho (``factors``)
    linear = "KM"

    nodes: np.ndarray
    corners: np.ndarray
    E: np.ndarray
    nu: np.ndarray
    rho: np.ndarray
    lumped: np.ndarray
    part: np.ndarray

    @property
    def n_elements(self) -> int:
        return int(self.nodes.shape[0])

    def nominal(self) -> dict[str, np.ndarray]:
        """Factor 1 on every element's E and rho."""
        return {f: np.ones(self.n_elements) for f in self.fields}

    def check(self, props, parts: tuple[str, ...]) -> None:
        """Factors finite and > 0 (each named as its property)."""
        checks = tuple((p.name.replace("_", " "), getattr(props, p.field), None, True)
                       for p in self.properties)  # fmt: skip
        check_fields(checks, self.part, parts)

    def dofs(self) -> np.ndarray:
        """(n, 3k) global DOF numbers: the three translations of each corner in turn."""
        k = self.nodes.shape[1]
        return (6 * self.nodes[:, :, None] + np.arange(3)).reshape(-1, 3 * k)

    def has_mass(self) -> bool:
        return bool(np.any(self.rho > 1e-200))

    @classmethod
    def of(cls, structure):
        """The structure's elements of this family (None: none)."""
        return in_elements(cls, structure)


def strain_matrix(gradient: np.ndarray) -> np.ndarray:
    """(n, 6, 3k) B of the strain (xx, yy, zz, xy, yz, zx; engineering shears) from the
    shape-function gradients (n, 3, k) of k corners (4: the constant strain of a tetrahedron):
    column 3a + j is corner a's translation j."""
    n, _, k = gradient.shape
    B = np.zeros((n, 6, 3 * k))
    gx, gy, gz = gradient[:, 0], gradient[:, 1], gradient[:, 2]  # (n, k) each
    B[:, 0, 0::3], B[:, 3, 0::3], B[:, 5, 0::3] = gx, gy, gz
    B[:, 1, 1::3], B[:, 3, 1::3], B[:, 4, 1::3] = gy, gx, gz
    B[:, 2, 2::3], B[:, 4, 2::3], B[:, 5, 2::3] = gz, gy, gx
    return B


def elasticity(E: np.ndarray, nu: np.ndarray) -> np.ndarray:
    """(n, 6, 6) isotropic D [Pa] in the Voigt order of ``strain_matrix``: Lame's lambda =
    E nu / ((1 + nu)(1 - 2 nu)) and mu = E / (2 (1 + nu)) (-1 < nu < 0.5)."""
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    mu = E / (2 * (1 + nu))
    D = np.zeros((len(E), 6, 6))
    D[:, :3, :3] = lam[:, None, None]
    idx = np.arange(3)
    D[:, idx, idx] += 2 * mu[:, None]
    D[:, idx + 3, idx + 3] = mu[:, None]
    return D
