"""The contract between a model (FE or a user's own function) and inference/discovery.

Inference never sees K and M: it asks a model for a ``Prediction`` at a parameter point.
Parameters are SI floats keyed by name (e.g. ``t_hot_pipe`` in m, ``rho_catalyst`` in kg/m^3).
"""

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np


@dataclass(frozen=True)
class Prediction:
    """What a model predicts at one parameter point.

    frequencies_hz : (m,) first m elastic natural frequencies [Hz], ascending.
    shapes : (n_dof, m) real mode shapes at ``dof_labels`` (mass-normalized for FE models), or None.
    dof_labels : sensor DOF labels of the shape rows (e.g. ``"7V"``), empty if no shapes.
    mass_kg : total mass [kg] or None.
    """

    frequencies_hz: np.ndarray
    shapes: np.ndarray | None = None
    dof_labels: tuple[str, ...] = ()
    mass_kg: float | None = None


@runtime_checkable
class ParametricModel(Protocol):
    """A model that inference can calibrate.

    ``parameter_names``: names of the parameters it accepts.
    ``default_parameters()``: a full parameter point (SI) - the reference design.
    ``default_bounds()``: name -> (low, high) bounds a user would accept (SI).
    ``predict(params, n_modes)``: Prediction at ``params`` (missing names take defaults); raises
    ``BayesUpdateError`` for an unknown name or a non-physical value.
    """

    parameter_names: tuple[str, ...]

    def default_parameters(self) -> dict[str, float]: ...

    def default_bounds(self) -> dict[str, tuple[float, float]]: ...

    def predict(self, params: Mapping[str, float], n_modes: int = 12) -> Prediction: ...


@runtime_checkable
class BatchParametricModel(ParametricModel, Protocol):
    """Optional: a model that predicts frequencies for many parameter points at once.

    ``predict_frequencies_batch(theta, names, n_modes)`` with theta (n_points, len(names)) in SI
    returns (n_points, n_modes) frequencies [Hz]; a failed point gives a row of NaN.
    """

    def predict_frequencies_batch(
        self, theta: np.ndarray, names: tuple[str, ...], n_modes: int = 12
    ) -> np.ndarray: ...
