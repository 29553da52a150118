"""A user's own model, ``package.module:function``, adapted to the ParametricModel protocol.

The function takes a mapping parameter name -> value (SI) and returns either the predicted
frequencies [Hz] (array-like) or a mapping with ``frequencies_hz`` and optionally ``shapes``
((n_sensors, m), rows at the sensor labels given in the study) and ``mass_kg``.  Its parameters,
bounds and reference values come from the study file (the function carries none).
"""

import importlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.model_protocol import Prediction


@dataclass(frozen=True)
class FunctionModel:
    """ParametricModel wrapping ``function(params) -> frequencies | mapping`` (module docstring)."""

    function: Callable
    parameter_names: tuple[str, ...]
    defaults: tuple[tuple[str, float], ...]
    bounds: tuple[tuple[str, tuple[float, float]], ...]
    dof_labels: tuple[str, ...] = ()
    label: str = ""

    def default_parameters(self) -> dict[str, float]:
        return dict(self.defaults)

    def default_bounds(self) -> dict[str, tuple[float, float]]:
        return dict(self.bounds)

    def predict(self, params: Mapping[str, float], n_modes: int = 12) -> Prediction:
        unknown = sorted(set(params) - set(self.parameter_names))
        if unknown:
            raise BayesUpdateError(f"model {self.label}: unknown parameter(s) {unknown}")
        values = {**self.default_parameters(), **params}
        try:
            out = self.function(values)
        except Exception as exc:  # the user's code: name it (callers count failing points)
            raise BayesUpdateError(
                f"model {self.label}: raised {type(exc).__name__}: {exc} at {values}"
            ) from exc
        shapes = mass = None
        if isinstance(out, Mapping):
            if "frequencies_hz" not in out:
                raise BayesUpdateError(
                    f"model {self.label}: returned a mapping without frequencies_hz"
                )
            freqs = out["frequencies_hz"]
            shapes = out.get("shapes")
            mass = out.get("mass_kg")
        else:
            freqs = out
        freqs = self._numbers(freqs, "frequencies")
        if freqs.ndim != 1:
            raise BayesUpdateError(
                f"model {self.label}: returned frequencies of shape {freqs.shape}; give one "
                "value per mode"
            )
        if freqs.size < n_modes:
            raise BayesUpdateError(
                f"model {self.label}: returned {freqs.size} frequencies, {n_modes} requested"
            )
        if shapes is not None:
            shapes = self._numbers(shapes, "shapes")
            if shapes.ndim != 2 or shapes.shape[1] < n_modes:
                raise BayesUpdateError(
                    f"model {self.label}: shapes must be (n_sensors, >= {n_modes})"
                )
            shapes = shapes[:, :n_modes]
            if len(self.dof_labels) != shapes.shape[0]:
                raise BayesUpdateError(
                    f"model {self.label}: {shapes.shape[0]} shape rows but {len(self.dof_labels)} "
                    "sensor labels in [model] sensors"
                )
        return Prediction(
            frequencies_hz=freqs[:n_modes],
            shapes=shapes,
            dof_labels=self.dof_labels if shapes is not None else (),
            mass_kg=None if mass is None else float(mass),
        )

    def _numbers(self, values, what: str) -> np.ndarray:
        """``values`` as a float array, or a BayesUpdateError naming the model."""
        try:
            return np.asarray(values, dtype=float)
        except (TypeError, ValueError):
            text = repr(values)
            raise BayesUpdateError(
                f"model {self.label}: returned {what} that are not numbers: {text[:80]}"
            ) from None


def import_function(spec: str) -> Callable:
    """Import ``package.module:function``; BayesUpdateError if it does not import."""
    if not isinstance(spec, str) or spec.count(":") != 1:
        raise BayesUpdateError(
            f"model.source {spec!r}: use a built-in name or 'package.module:function'"
        )
    module_name, name = spec.split(":")
    try:
        module = importlib.import_module(module_name)
    except Exception as exc:  # ImportError, or the user's module failing at import
        raise BayesUpdateError(
            f"model.source {spec!r}: module {module_name!r} does not import "
            f"({type(exc).__name__}: {exc}); check PYTHONPATH and the name"
        ) from exc
    function = getattr(module, name, None)
    if not callable(function):
        raise BayesUpdateError(f"model.source {spec!r}: {module_name} has no function {name!r}")
    return function


def load_user_model(
    spec: str,
    parameters: Mapping[str, Mapping],
    sensors: tuple[str, ...] = (),
) -> FunctionModel:
    """FunctionModel for ``spec`` with parameters from ``{name: {bounds, start}}`` tables.

    Reference value of each parameter: ``start`` or the middle of the bounds.
    """
    function = import_function(spec)
    if not parameters:
        raise BayesUpdateError(
            f"model.source {spec!r}: a custom model needs [parameters.NAME] tables with bounds"
        )
    bounds, defaults = [], []
    for name, entry in parameters.items():
        if "bounds" not in entry:
            raise BayesUpdateError(f"parameters.{name}: a custom model needs bounds = [low, high]")
        try:
            low, high = (float(b) for b in entry["bounds"])
        except (TypeError, ValueError) as exc:
            raise BayesUpdateError(f"parameters.{name}.bounds: must be two numbers") from exc
        bounds.append((name, (low, high)))
        defaults.append((name, float(entry.get("start", 0.5 * (low + high)))))
    return FunctionModel(
        function=function,
        parameter_names=tuple(parameters),
        defaults=tuple(defaults),
        bounds=tuple(bounds),
        dof_labels=tuple(sensors),
        label=spec,
    )
