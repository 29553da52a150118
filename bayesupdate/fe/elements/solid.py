"""What every solid element family shares: its record (corner nodes and positions, isotropic
material, lumping, part) and the factors on E and rho that its parameters are.

A solid family (``tetra``, ``hexa``) is a frozen dataclass deriving from ``Solids``; it names its
registry ``family``, its two ``fields`` (the factor on E first, on rho second), ``linear = "KM"``
and its ``properties``, and gives ``matrices`` and ``masses``.  SI units: corners [m], E [Pa],
rho [kg/m^3].
"""

from dataclasses import dataclass

import numpy as np

from bayesupdate.fe.elements.base import check_fields, in_elements


@dataclass(frozen=True)
class Solids:
    """n solid elements of k corners: nodes (n, k) corner node indices; corners (n, k, 3) their
    positions [m]; E [Pa], nu [-], rho [kg/m^3] (n,); lumped (n,) bool (mass lumped at the
    corners, else consistent); part (n,) part indices."""

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
