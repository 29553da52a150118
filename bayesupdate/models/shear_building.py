"""The two-DOF shear building of Beck & Au (2002), used to verify calibration and sampling.

Floor masses m1 = 16.5e3 kg (first storey), m2 = 16.1e3 kg (roof); storey stiffnesses
k_i = theta_i * 29.7e6 N/m.  With K = [[k1 + k2, -k2], [-k2, k2]] and M = diag(m1, m2) the
eigenvalues lambda = omega^2 solve (Beck & Au 2002, section 6)

    m1 m2 lambda^2 - ((k1 + k2) m2 + k2 m1) lambda + k1 k2 = 0,

so both frequencies fix the sum and the product of two linear forms in theta: given the two
frequencies, (theta_1, theta_2) has two solutions, which makes the posterior bimodal.

Reference: J. L. Beck, S.-K. Au, "Bayesian updating of structural models and reliability using
Markov chain Monte Carlo simulation", J. Eng. Mech. 128(4), 2002, 380-391.
"""

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.model_protocol import Prediction

#: Floor masses [kg] and nominal storey stiffness [N/m] of Beck & Au (2002).
FLOOR_MASSES_KG = (16.5e3, 16.1e3)
NOMINAL_STIFFNESS_N_PER_M = 29.7e6


def shear_building_frequencies(
    theta: np.ndarray,
    masses_kg: tuple[float, float] = FLOOR_MASSES_KG,
    k_nominal: float = NOMINAL_STIFFNESS_N_PER_M,
) -> np.ndarray:
    """Closed-form natural frequencies of the 2-DOF shear building, vectorized over points.

    theta : (..., 2) stiffness factors [-].  Returns (..., 2) ascending frequencies [Hz];
    non-positive stiffness gives NaN.
    """
    theta = np.asarray(theta, dtype=float)
    m1, m2 = masses_kg
    k1 = theta[..., 0] * k_nominal
    k2 = theta[..., 1] * k_nominal
    # roots of m1 m2 l^2 - b l + c = 0 (module docstring)
    b = (k1 + k2) * m2 + k2 * m1
    c = k1 * k2
    disc = np.sqrt(np.maximum(b * b - 4.0 * m1 * m2 * c, 0.0))
    lam = np.stack([(b - disc) / (2 * m1 * m2), (b + disc) / (2 * m1 * m2)], axis=-1)
    ok = (k1 > 0) & (k2 > 0)
    with np.errstate(invalid="ignore"):
        f = np.sqrt(np.maximum(lam, 0.0)) / (2.0 * np.pi)
    return np.where(ok[..., None], f, np.nan)


@dataclass(frozen=True)
class ShearBuildingModel:
    """ParametricModel (and BatchParametricModel) of the 2-DOF shear building.

    Parameters ``theta_1``, ``theta_2`` [-]; sensors ``"1"`` (first floor) and ``"2"`` (roof),
    shapes mass-normalized.  Its batch shapes (``predict_batch_with_shapes``) let a likelihood
    that pairs by MAC evaluate a walker batch in one call (``inference.likelihood``'s
    "shape-batch" mode) instead of one Python call per point.
    """

    masses_kg: tuple[float, float] = FLOOR_MASSES_KG
    k_nominal: float = NOMINAL_STIFFNESS_N_PER_M
    bounds: tuple[float, float] = (0.1, 4.0)
    parameter_names: tuple[str, ...] = ("theta_1", "theta_2")
    dof_labels: tuple[str, ...] = ("1", "2")

    def default_parameters(self) -> dict[str, float]:
        return {"theta_1": 1.0, "theta_2": 1.0}

    def default_bounds(self) -> dict[str, tuple[float, float]]:
        return {name: tuple(self.bounds) for name in self.parameter_names}

    def _theta(self, params: Mapping[str, float]) -> np.ndarray:
        unknown = sorted(set(params) - set(self.parameter_names))
        if unknown:
            raise BayesUpdateError(
                f"shear_building: unknown parameter(s) {unknown}; "
                f"known: {list(self.parameter_names)}"
            )
        full = {**self.default_parameters(), **params}
        theta = np.array([float(full[n]) for n in self.parameter_names])
        if not np.all(np.isfinite(theta)) or np.any(theta <= 0):
            raise BayesUpdateError(
                f"shear_building: stiffness factors must be finite and > 0, got {theta.tolist()}"
            )
        return theta

    def predict(self, params: Mapping[str, float], n_modes: int = 2) -> Prediction:
        """Frequencies [Hz], mass-normalized shapes (2, n_modes) at floors 1, 2, total mass [kg]."""
        if not 1 <= n_modes <= 2:
            raise BayesUpdateError(
                f"shear_building: {n_modes} modes requested but the model has only 2"
            )
        theta = self._theta(params)
        k1, k2 = theta * self.k_nominal
        stiffness = np.array([[k1 + k2, -k2], [-k2, k2]])
        from scipy.linalg import eigh

        lam, phi = eigh(stiffness, np.diag(self.masses_kg))
        # sign convention: roof displacement positive, so shapes compare across parameter points
        phi = phi * np.sign(phi[1, :] + (phi[1, :] == 0))
        return Prediction(
            frequencies_hz=np.sqrt(lam[:n_modes]) / (2 * np.pi),
            shapes=phi[:, :n_modes],
            dof_labels=self.dof_labels,
            mass_kg=float(sum(self.masses_kg)),
        )

    @property
    def sensor_labels(self) -> tuple[str, ...]:
        """The rows of ``predict_batch_with_shapes``'s shapes (the floors)."""
        return self.dof_labels

    def _full_theta(self, theta: np.ndarray, names: tuple[str, ...], n_modes: int) -> np.ndarray:
        """(n_points, 2) stiffness factors from theta (n_points, len(names)), the rest at 1."""
        if not 1 <= n_modes <= 2:
            raise BayesUpdateError(
                f"shear_building: {n_modes} modes requested but the model has only 2"
            )
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        full = np.tile([1.0, 1.0], (theta.shape[0], 1))
        for j, name in enumerate(names):
            if name not in self.parameter_names:
                raise BayesUpdateError(f"shear_building: unknown parameter {name!r}")
            full[:, self.parameter_names.index(name)] = theta[:, j]
        return full

    def predict_frequencies_batch(
        self, theta: np.ndarray, names: tuple[str, ...], n_modes: int = 2
    ) -> np.ndarray:
        """theta (n_points, len(names)) -> (n_points, n_modes) frequencies [Hz] (closed form)."""
        full = self._full_theta(theta, names, n_modes)
        f = shear_building_frequencies(full, self.masses_kg, self.k_nominal)
        return f[:, :n_modes]

    def predict_batch_with_shapes(
        self, theta: np.ndarray, names: tuple[str, ...], n_modes: int = 2
    ) -> tuple[np.ndarray, np.ndarray]:
        """Frequencies (n_points, n_modes) [Hz] and shapes (n_points, 2, n_modes) at floors 1, 2
        (rows on ``sensor_labels``), closed form; failed points (a factor <= 0) give NaN.

        The first row of (K - lambda M) phi = 0 gives phi = (k2, k1 + k2 - lambda m1) up to
        scale (roof positive, as ``predict``; not normalized: a MAC ignores scale)."""
        full = self._full_theta(theta, names, n_modes)
        f = shear_building_frequencies(full, self.masses_kg, self.k_nominal)
        k1, k2 = (full * self.k_nominal).T
        lam = (2 * np.pi * f) ** 2
        roof = (k1 + k2)[:, None] - lam * self.masses_kg[0]
        shapes = np.stack([np.broadcast_to(k2[:, None], roof.shape), roof], axis=1)
        shapes = shapes * np.sign(roof + (roof == 0))[:, None, :]
        return f[:, :n_modes], shapes[:, :, :n_modes]


def build_shear_building_model(
    masses_kg: tuple[float, float] = FLOOR_MASSES_KG,
    k_nominal: float = NOMINAL_STIFFNESS_N_PER_M,
    bounds: tuple[float, float] = (0.1, 4.0),
) -> ShearBuildingModel:
    """Factory used by ``bayesupdate.models.get_model("shear_building")``: two floor masses
    [kg] > 0, the nominal storey stiffness [N/m] > 0 and the factors' bounds (0 < low < high),
    each checked (a study's ``[model] options``)."""
    masses = _finite_numbers(masses_kg, "masses_kg", 2)
    k = _finite_numbers([k_nominal], "k_nominal", 1)
    low, high = _finite_numbers(bounds, "bounds", 2)
    if not (min(masses) > 0 and k[0] > 0 and 0 < low < high):
        raise BayesUpdateError(
            "shear_building: needs masses_kg > 0, k_nominal > 0 and bounds 0 < low < high, got "
            f"masses_kg={list(masses_kg)}, k_nominal={k_nominal}, bounds={list(bounds)}"
        )
    return ShearBuildingModel(masses_kg=tuple(masses), k_nominal=k[0], bounds=(low, high))


def _finite_numbers(values, name: str, count: int) -> list[float]:
    """``count`` finite numbers of option ``name``, or a BayesUpdateError naming it."""
    try:
        out = [float(v) for v in values]
    except (TypeError, ValueError):
        out = []
    if len(out) != count or not all(np.isfinite(out)):
        raise BayesUpdateError(
            f"shear_building: {name} must be {count} finite number(s), got {values!r}"
        )
    return out
