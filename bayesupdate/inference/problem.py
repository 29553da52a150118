"""A calibration problem: a model, test data, the parameters to fit, the pairing and objective.

``build_problem`` validates everything a user can get wrong (names, bounds, starts, priors, mode
counts, weights) before any computation; ``CalibrationProblem.evaluate`` gives the paired
prediction at one parameter point and never raises for a failed model evaluation (it returns
``ok=False``; failures are counted by the callers).
"""

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.mass_properties import MassPropertyTargets, mass_properties_function
from bayesupdate.inference.pairing import (
    PAIRING_METHODS,
    ModePairing,
    PairedModes,
    PairingRules,
    ResidualTable,
    pair_modes,
    reach_modes,
    residual_table,
    screen_test_modes,
    shapes_at,
)
from bayesupdate.inference.parameter_space import ParameterSpec
from bayesupdate.inference.priors import prior_from_mapping
from bayesupdate.modal_data import ModalData
from bayesupdate.model_protocol import ParametricModel, Prediction

#: (model, all its parameters (SI), n_modes) -> the ``Prediction`` there (``build_problem``)
ReferenceSolve = Callable[[ParametricModel, Mapping[str, float], int], Prediction]


@dataclass(frozen=True)
class ObjectiveSpec:
    """Extra terms of the fit objective beside seed eq. 19.

    mass_target_kg / mass_weight : adds mass_weight * ((m - m_T) / m_T)^2 (the seed's mass check).
    mac_weight : adds mac_weight * sum_i (1 - MAC_i) over paired modes (needs shapes).
    mass_properties : measured CG / inertia components, each adding its weighted residual
    (``mass_properties.MassPropertyTargets``; their own weights); None: none measured.
    The masses are in the model's own mass unit, ``mass_unit`` (kg for built-in models; the
    names say ``_kg`` for history).
    """

    mass_target_kg: float | None = None
    mass_weight: float = 0.0
    mac_weight: float = 0.0
    mass_properties: MassPropertyTargets | None = None
    mass_unit: str = "kg"


def build_parameter_specs(
    model: ParametricModel, table: Mapping[str, Mapping] | None = None
) -> tuple[ParameterSpec, ...]:
    """Parameters to calibrate from a study's ``[parameters.NAME]`` tables.

    Each table may hold ``bounds = [low, high]``, ``prior = {...}``, ``start = value``; missing
    entries come from ``model.default_bounds()`` / ``default_parameters()``.  With no tables, every
    parameter that has default bounds is calibrated.
    """
    defaults = dict(model.default_parameters())
    default_bounds = dict(model.default_bounds())
    names = list(table) if table else list(default_bounds)
    if not names:
        raise BayesUpdateError(
            "parameters: the model has no default bounds; list [parameters.NAME]"
        )
    specs = []
    for name in names:
        entry = dict(table[name]) if table else {}
        where = f"parameters.{name}"
        if name not in model.parameter_names:
            raise BayesUpdateError(
                f"{where}: unknown parameter; the model has {list(model.parameter_names)}"
            )
        unknown = sorted(set(entry) - {"bounds", "prior", "start"})
        if unknown:
            raise BayesUpdateError(
                f"{where}: unknown key(s) {unknown}; valid: bounds, prior, start"
            )
        bounds = entry.get("bounds", default_bounds.get(name))
        if bounds is None:
            raise BayesUpdateError(f"{where}: no default bounds; give bounds = [low, high]")
        try:
            low, high = (float(b) for b in bounds)
        except (TypeError, ValueError) as exc:
            raise BayesUpdateError(f"{where}.bounds: must be two numbers [low, high]") from exc
        if not (np.isfinite(low) and np.isfinite(high) and low < high):
            raise BayesUpdateError(f"{where}.bounds: need finite low < high, got {[low, high]}")
        _check_physical_bounds(model, name, (low, high), where)
        start = entry.get("start", defaults.get(name, 0.5 * (low + high)))
        if isinstance(start, bool) or not isinstance(start, int | float):
            raise BayesUpdateError(f"{where}.start: must be a number, got {start!r}")
        start = float(start)
        if not low <= start <= high:
            raise BayesUpdateError(
                f"{where}: start/default value {start} is outside bounds {[low, high]}; "
                "move it inside or widen the bounds"
            )
        prior = entry.get("prior")
        if prior is not None and not isinstance(prior, Mapping):
            raise BayesUpdateError(f'{where}.prior: must be a table like {{kind = "uniform"}}')
        specs.append(
            ParameterSpec(name, (low, high), prior_from_mapping(prior, (low, high), name), start)
        )
    return tuple(specs)


def _check_physical_bounds(model, name: str, bounds: tuple[float, float], where: str) -> None:
    """Reject bounds that reach non-physical values (e.g. a zero or negative thickness or
    density) when the model can say so cheaply (FE models: ``element_properties``), so that a
    run does not silently spend its budget on failing points."""
    check = getattr(model, "element_properties", None)
    if check is None:
        return
    for value in bounds:
        try:
            check({name: value})
        except BayesUpdateError as exc:
            raise BayesUpdateError(
                f"{where}.bounds: {[bounds[0], bounds[1]]} reaches a non-physical value ({exc}); "
                "give bounds inside the physical range"
            ) from exc


@dataclass(frozen=True)
class Evaluation:
    """Paired prediction at one point: frequencies (n_test,) [Hz] in test order, MAC, mass."""

    ok: bool
    frequencies_hz: np.ndarray
    all_frequencies_hz: np.ndarray
    paired: PairedModes | None = None
    mass_kg: float | None = None
    error: str = ""
    mass_properties: np.ndarray | None = None  # (k,) the measured components' model values


@dataclass
class CalibrationProblem:
    """Everything needed to evaluate the objective or the likelihood at a parameter vector.

    parameters : the calibrated parameters (order of theta vectors).  fixed : other model
    parameters held at these values.  pairing : see ``pairing.ModePairing``.  test_modes :
    (n_test,) 1-based number of each of ``data``'s modes in the data source (the modes a study
    selected and the pairing kept; () : 1..n_test).
    """

    model: ParametricModel
    data: ModalData
    parameters: tuple[ParameterSpec, ...]
    pairing: ModePairing
    objective: ObjectiveSpec = field(default_factory=ObjectiveSpec)
    fixed: dict[str, float] = field(default_factory=dict)
    reference: Prediction | None = None
    test_modes: tuple[int, ...] = ()

    @property
    def mode_numbers(self) -> np.ndarray:
        """(n_test,) 1-based source number of each test mode of the problem."""
        if self.test_modes:
            return np.asarray(self.test_modes, dtype=int)
        return np.arange(1, self.data.n_modes + 1)

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.parameters)

    @property
    def lower(self) -> np.ndarray:
        return np.array([p.bounds[0] for p in self.parameters])

    @property
    def upper(self) -> np.ndarray:
        return np.array([p.bounds[1] for p in self.parameters])

    @property
    def start(self) -> np.ndarray:
        return np.array([p.start for p in self.parameters])

    @property
    def weights(self) -> np.ndarray:
        """Seed eq. 19 weights w_i (unit unless the data give weights), (n_test,)."""
        w = self.data.weights
        return np.ones(self.data.n_modes) if w is None else np.asarray(w, dtype=float)

    def as_mapping(self, theta: np.ndarray) -> dict[str, float]:
        return {**self.fixed, **dict(zip(self.names, map(float, theta), strict=True))}

    def evaluate(self, theta: np.ndarray) -> Evaluation:
        """Predict and pair at theta (n_params,).  A raising or NaN model gives ``ok=False``."""
        nan = np.full(self.data.n_modes, np.nan)
        try:
            prediction = self.model.predict(self.as_mapping(theta), n_modes=self.pairing.n_model)
            freqs = np.asarray(prediction.frequencies_hz, dtype=float)
            if freqs.size < self.pairing.n_model or not np.all(np.isfinite(freqs)):
                return Evaluation(False, nan, freqs, error="non-finite or missing frequencies")
            paired = pair_modes(prediction, self.pairing)
            props = self.mass_property_values(self.as_mapping(theta))
        except Exception as exc:  # a user's model may fail anywhere; count it, do not crash
            return Evaluation(False, nan, nan, error=f"{type(exc).__name__}: {exc}")
        return Evaluation(
            True, freqs[paired.model_index], freqs, paired, prediction.mass_kg, "", props
        )

    def mass_property_values(self, params: Mapping[str, float]) -> np.ndarray | None:
        """(k,) the model's values of the measured CG / inertia components at ``params``
        (None when none are measured)."""
        targets = self.objective.mass_properties
        if targets is None:
            return None
        return targets.predicted(mass_properties_function(self.model)(params))

    def expr(self, frequencies_hz: np.ndarray) -> np.ndarray:
        """Seed eq. 19 with the data's weights; frequencies (..., n_test) -> (...)."""
        return objective_expr(frequencies_hz, self.data.frequencies_hz, self.weights)

    def residual_vector(self, evaluation: Evaluation) -> np.ndarray:
        """Weighted residuals whose squared sum is the fit objective (eq. 19 + extra terms)."""
        f_test = self.data.frequencies_hz
        parts = [np.sqrt(self.weights) * (evaluation.frequencies_hz - f_test) / f_test]
        spec = self.objective
        if spec.mass_weight > 0 and spec.mass_target_kg is not None:
            mass = np.nan if evaluation.mass_kg is None else evaluation.mass_kg
            parts.append(
                [np.sqrt(spec.mass_weight) * (mass - spec.mass_target_kg) / spec.mass_target_kg]
            )
        if spec.mass_properties is not None:
            values = evaluation.mass_properties
            parts.append(spec.mass_properties.residuals(
                np.full(len(spec.mass_properties.names), np.nan) if values is None else values
            ))  # fmt: skip
        if spec.mac_weight > 0:
            parts.append(np.sqrt(spec.mac_weight * np.clip(1.0 - evaluation.paired.mac, 0, 1)))
        return np.concatenate([np.asarray(p, dtype=float) for p in parts])

    def table(self, evaluation: Evaluation) -> ResidualTable:
        return residual_table(
            self.data.frequencies_hz,
            evaluation.all_frequencies_hz,
            evaluation.paired,
            self.pairing.method,
            self.mode_numbers,
        )


def _checked_objective(
    objective: ObjectiveSpec | None, extra_modes: int, data: ModalData
) -> ObjectiveSpec:
    """The objective (default: eq. 19 alone) after checking its weights, ``extra_modes`` and
    the data's weights."""
    objective = objective or ObjectiveSpec()
    if not (0 <= objective.mass_weight < np.inf and 0 <= objective.mac_weight < np.inf):
        raise BayesUpdateError(  # NaN fails the chained comparison too
            "objective: mass_weight and mac_weight must be finite numbers >= 0, got "
            f"{objective.mass_weight}, {objective.mac_weight}"
        )
    target = objective.mass_target_kg or 0
    if objective.mass_weight > 0 and not 0 < target < np.inf:
        raise BayesUpdateError(
            "objective.mass_kg: give the measured mass (finite, > 0) for the mass term"
        )
    if int(extra_modes) < 0:
        raise BayesUpdateError(f"pairing.extra_modes: must be >= 0, got {extra_modes}")
    if data.weights is not None and np.all(data.weights == 0):
        raise BayesUpdateError(f"data {data.source!r}: all weights are zero")
    return objective


def _checked_mass_properties(objective: ObjectiveSpec, model: ParametricModel) -> None:
    """A measured CG or inertia needs a model that gives its mass properties."""
    if objective.mass_properties is not None and mass_properties_function(model) is None:
        raise BayesUpdateError(
            "data.cg / data.inertia: this model cannot give its mass properties (an FE model "
            "or a Nastran deck can); remove them"
        )


def _reference_parameters(
    model: ParametricModel,
    parameters: tuple[ParameterSpec, ...],
    fixed: Mapping[str, float] | None,
) -> dict[str, float]:
    """All model parameters at the reference design: the model's defaults, overridden by the
    ``fixed`` values (checked: model parameters that are not calibrated), then the starts."""
    reference_params = dict(model.default_parameters())
    calibrated = {p.name for p in parameters}
    for name, value in (fixed or {}).items():
        if name not in model.parameter_names or name in calibrated:
            raise BayesUpdateError(
                f"fixed parameter {name!r}: not a model parameter, or also calibrated"
            )
        reference_params[name] = float(value)
    reference_params.update({p.name: p.start for p in parameters})
    return reference_params


def _solved(model, params, n_modes: int, solve: ReferenceSolve | None) -> Prediction:
    """The model's prediction of ``n_modes`` modes at ``params``, through ``solve`` if given."""
    if solve is None:
        return model.predict(params, n_modes=n_modes)
    return solve(model, params, n_modes)


def _reference_prediction(
    model: ParametricModel,
    reference_params: dict[str, float],
    n_test: int,
    extra_modes: int,
    solve: ReferenceSolve | None = None,
    data: ModalData | None = None,
) -> tuple[Prediction, int]:
    """(prediction, n_model): the model at the reference design with ``extra_modes`` modes
    beyond ``n_test`` (the test's highest mode number) if it can, else exactly ``n_test``, and
    where ``data`` has shapes more, up to its highest frequency (``pairing.reach_modes``: a
    test that missed lower modes); ``solve`` as in ``build_problem``."""
    reference = None
    n_model = n_test
    for n_try in (n_test + max(int(extra_modes), 0), n_test):
        try:
            reference = _solved(model, reference_params, n_try, solve)
        except BayesUpdateError as exc:
            if n_try == n_test:
                raise BayesUpdateError(
                    f"model: cannot compute the {n_test} modes the test data reach ({exc}); "
                    "choose fewer or lower test modes ([data] modes)"
                ) from exc
            continue
        n_model = n_try
        break
    if data is not None and data.shapes is not None:
        reference, n_model = reach_modes(
            lambda n: _solved(model, reference_params, n, solve), reference, n_model,
            float(np.max(data.frequencies_hz)),
        )  # fmt: skip
    freqs = np.asarray(reference.frequencies_hz)
    if freqs.size < n_test:
        raise BayesUpdateError(
            f"model: computed {freqs.size} modes but the test data reach mode {n_test}; "
            "choose fewer or lower test modes ([data] modes) or give a model with more"
        )
    return reference, n_model


def _resolved_method(pairing: str, data: ModalData, reference: Prediction) -> str:
    """The pairing method, "auto" resolved: "mac" if the test has shapes, else "tracked" if
    the model gives shapes, else "order"; any other method as it is."""
    if pairing != "auto":
        return pairing
    if data.shapes is not None:
        return "mac"
    return "tracked" if reference.shapes is not None else "order"


def _mode_pairing(
    pairing: str, data: ModalData, reference: Prediction, n_model: int, order: tuple = ()
) -> ModePairing:
    """The pairing set up at the reference prediction (``_resolved_method``); ``order``: the
    0-based model mode of each test mode by order (``ModePairing.order``; () : in order)."""
    n_test = data.n_modes
    method = _resolved_method(pairing, data, reference)
    order = () if method == "mac" or tuple(order) == tuple(range(n_test)) else tuple(order)
    labels: tuple[str, ...] = ()
    ref_shapes = test_shapes = None
    if method == "mac":
        if data.shapes is None:
            raise BayesUpdateError("pairing 'mac' needs test shapes; use 'tracked' or 'order'")
        labels = data.dof_labels
        test_shapes = data.shapes
        shapes_at(reference, labels, f"data {data.source!r}")
    elif reference.shapes is not None:
        labels = tuple(reference.dof_labels)
        columns = list(order) if order else slice(0, n_test)
        ref_shapes = np.asarray(reference.shapes)[:, columns]
    elif method == "tracked":
        raise BayesUpdateError("pairing 'tracked' needs model shapes; use 'order'")
    return ModePairing(method, n_test, n_model, labels, ref_shapes, test_shapes, order=order)


def _screened(
    data: ModalData,
    reference: Prediction,
    rules: PairingRules,
    numbers: tuple[int, ...],
) -> tuple[ModalData, tuple[int, ...], tuple]:
    """(data, numbers, refused): the test modes whose MAC pair at the reference design meets
    ``rules`` (``pairing.screen_test_modes``); one line when none does."""
    shapes = shapes_at(reference, data.dof_labels, f"data {data.source!r}")
    model_hz = np.asarray(reference.frequencies_hz, dtype=float)[: shapes.shape[1]]
    kept, refused = screen_test_modes(
        data.frequencies_hz, data.shapes, model_hz, shapes, rules, numbers
    )
    if kept.size == 0:
        raise BayesUpdateError(
            f"pairing: no test mode of {data.source!r} pairs with the model at its reference "
            f"design (MAC >= {rules.mac_threshold:g} within +-{100 * rules.frequency_window:g} "
            f"%: {refused[0].message(rules)}); lower [pairing] mac_threshold, widen "
            "frequency_window or check the test geometry"
        )
    return data.subset(kept), tuple(int(numbers[i]) for i in kept), refused


def build_problem(
    model: ParametricModel,
    data: ModalData,
    parameters: tuple[ParameterSpec, ...] | Mapping | None = None,
    pairing: str = "auto",
    extra_modes: int = 2,
    objective: ObjectiveSpec | None = None,
    fixed: Mapping[str, float] | None = None,
    rules: PairingRules | None = None,
    test_modes: tuple[int, ...] = (),
    reference_solve: ReferenceSolve | None = None,
) -> CalibrationProblem:
    """Validate inputs and set up the pairing at the model's reference design.

    parameters : ParameterSpecs, or a ``{name: {bounds, prior, start}}`` mapping, or None (model
    defaults).  pairing : one of ``PAIRING_METHODS``; "auto" = "mac" if the test has shapes, else
    "tracked" if the model gives shapes, else "order".  extra_modes : model modes computed beyond
    the test's, so a tracked mode can be found after a swap (dropped if the model has fewer).
    fixed : values of model parameters that are not calibrated (default: the model's defaults).
    rules : a MAC pairing's threshold and frequency window (``pairing.PairingRules``): test modes
    without a pair meeting them at the reference design are refused (left out of the problem,
    listed in ``pairing.refused``), and the pairing is redone inside the window (None: every
    test mode is paired, with any model mode).  test_modes : (n_test,) 1-based numbers of
    ``data``'s modes in their source (() : 1..n_test).  reference_solve : ``ReferenceSolve``,
    raising as ``model.predict`` (None: ``model.predict``; ``fe.reference_memo``'s)."""
    if pairing not in PAIRING_METHODS:
        raise BayesUpdateError(f"pairing.method: {pairing!r}; use one of {list(PAIRING_METHODS)}")
    if not isinstance(parameters, tuple):
        parameters = build_parameter_specs(model, parameters)
    objective = _checked_objective(objective, extra_modes, data)
    _checked_mass_properties(objective, model)
    reference_params = _reference_parameters(model, parameters, fixed)
    numbers = tuple(int(n) for n in test_modes) or tuple(range(1, data.n_modes + 1))
    if len(numbers) != data.n_modes:
        raise ValueError(f"build_problem: {len(numbers)} test_modes for {data.n_modes} modes")
    # test mode k of a source is near model mode k: the model computes up to the highest one
    reference, n_model = _reference_prediction(
        model, reference_params, max(numbers), extra_modes, reference_solve, data
    )
    fixed = {k: v for k, v in reference_params.items() if k not in {p.name for p in parameters}}
    refused: tuple = ()
    mac_rules = rules is not None and _resolved_method(pairing, data, reference) == "mac"
    if mac_rules:
        _mode_pairing(pairing, data, reference, n_model)  # its checks (shapes at the labels)
        data, numbers, refused = _screened(data, reference, rules, numbers)
    mode_pairing = _mode_pairing(pairing, data, reference, n_model, tuple(n - 1 for n in numbers))
    if mac_rules:
        mode_pairing = replace(
            mode_pairing, rules=rules, test_hz=data.frequencies_hz, refused=refused
        )
    return CalibrationProblem(
        model=model,
        data=data,
        parameters=parameters,
        pairing=mode_pairing,
        objective=objective,
        fixed=fixed,
        reference=reference,
        test_modes=() if numbers == tuple(range(1, data.n_modes + 1)) else numbers,
    )


def objective_expr(f_sim_hz, f_test_hz, weights=None) -> np.ndarray:
    """Seed eq. 19: Expr = sum_i w_i ((f_si - f_Ti) / f_Ti)^2.

    f_sim_hz : (..., n) simulated frequencies [Hz] (leading axes broadcast, e.g. walkers).
    f_test_hz : (n,) target frequencies [Hz].  weights : (n,) or None for unit weights.
    Returns Expr with the leading shape of ``f_sim_hz``.
    """
    f_sim = np.asarray(f_sim_hz, dtype=float)
    f_test = np.asarray(f_test_hz, dtype=float)
    if f_sim.shape[-1] != f_test.shape[-1]:
        raise ValueError(
            f"objective_expr: {f_sim.shape[-1]} simulated vs {f_test.shape[-1]} test frequencies"
        )
    w = np.ones_like(f_test) if weights is None else np.asarray(weights, dtype=float)
    return np.sum(w * ((f_sim - f_test) / f_test) ** 2, axis=-1)
