"""The correlate pipeline: a model, test modes and the sensor mapping between them -> how far
the model is from the test before any parameter moves.

Inputs are three: the model (any ``ParametricModel``; an FE model also gives its shapes at all
DOFs for SEREP), the test's ``ModalData``, and a ``SensorMapping`` (per test DOF the model node
and direction it reads, and the rigid transform from the test's frame to the model's).  Today
the mapping is the one ``calibrate`` and ``sample`` use (a built-in model's sensors, a Nastran
deck's ``[model.test_points]``: ``nastran.test_points``) and the transform is the identity; a
test-geometry pairing fills the same record (test coordinates, distances, the fitted transform).

``correlate(model, data, mapping, settings)`` returns the frozen ``Correlation``: the paired
modes (by ``inference.pairing.screen_pairs``, the one rule ``calibrate``, ``sample`` and
``discover`` keep pairs by: a MAC threshold and a relative frequency window, the study's
``[pairing]``; every other test mode refused with the rule that refused it; in order for
frequencies only),
the MAC matrix and the test's AutoMAC, COMAC per test DOF, and, for an FE model, the SEREP TAM
of the model at the test DOFs (``correlation.serep_*``): the model's pseudo-orthogonality, the
cross-orthogonality where the test's shapes are mass-normalized, and the test shapes expanded to
every model DOF.  ``write_correlation_h5`` writes it (layout in its docstring).
"""

from dataclasses import dataclass, field

import numpy as np

from bayesupdate.correlation import (
    ModePairs,
    auto_mac,
    comac,
    cross_orthogonality,
    mac_matrix,
    pair_in_order,
    pseudo_orthogonality,
    serep_expand,
    serep_mass,
    serep_transformation,
)
from bayesupdate.errors import BayesUpdateError
from bayesupdate.inference.pairing import (
    PairingRules,
    RefusedMode,
    ScreenedPairs,
    label_rows,
    reach_modes,
    screen_pairs,
)
from bayesupdate.modal_data import ModalData
from bayesupdate.pipelines.model_source import paired_study_model, study_model


@dataclass(frozen=True)
class CorrelateSettings:
    """rules : what a MAC pair must meet (``inference.pairing.PairingRules``: the study's
    ``[pairing]`` mac_threshold and frequency_window, the rules ``calibrate`` keeps pairs by).
    extra_modes : model modes computed beyond the test's highest mode number (so a test mode
    can pair past a swap; the study's ``[pairing] extra_modes``, as ``calibrate`` computes
    them), >= 0.  parameters : the model's parameter point (SI, or a deck's units; empty: its
    defaults)."""

    rules: PairingRules = field(default_factory=PairingRules)
    extra_modes: int = 2
    parameters: dict = field(default_factory=dict)

    def __post_init__(self):
        if self.extra_modes < 0:
            raise BayesUpdateError(f"--extra-modes {self.extra_modes}: must be >= 0")


@dataclass(frozen=True)
class SensorPoint:
    """One test DOF on the model.  dof : its label (``"7V"``); test_node : the test's node
    (the label's number); model_node : the model node it reads (a deck's GRID id, a built-in
    model's node index; None when the model has no nodes); model_xyz : that node's coordinates
    in the model's frame (its units) or None; direction : (3,) unit vector in the model's frame
    or None; distance : test point to model point after the transform (None: no test
    geometry)."""

    dof: str
    test_node: str
    model_node: int | None
    model_xyz: tuple[float, float, float] | None
    direction: tuple[float, float, float] | None
    distance: float | None = None


@dataclass(frozen=True)
class SensorMapping:
    """Test DOFs on the model: transform (4, 4) test frame -> model frame (the identity without
    test geometry), rms_residual of its fit (None: not fitted), points one per test DOF, source
    (where the mapping came from)."""

    transform: np.ndarray
    points: tuple[SensorPoint, ...]
    source: str
    rms_residual: float | None = None


@dataclass(frozen=True)
class Correlation:
    """What ``correlate`` found (indices 0-based; arrays in the order of the test's DOFs and
    modes and the model's modes).

    model, data : names.  dof_labels (n_a,).  test_hz (m_t,), model_hz (m_m,) [Hz].
    pairs : ``correlation.ModePairs`` (its ``refused``: (test, best model mode, MAC) of each
    refused test mode).  mac (m_t, m_m), test_auto_mac (m_t, m_t), comac (n_a,)
    over the paired modes: None without test shapes.  mapping : ``SensorMapping``.
    test_shapes (n_a, m_t) real (realized) test shapes, model_shapes (n_a, m_m) model shapes at
    the test DOFs: None without test shapes.  pseudo_orthogonality (k, k) of the paired model
    modes through the SEREP TAM, cross_orthogonality (k, k) test vs model (mass-normalized test
    shapes only), expanded (n_dof, k) the paired test shapes expanded by SEREP: None where not
    computed.  notes : what a reader must know (why something is missing).  model_nodes
    (n_nodes, 3) the model's node coordinates (its own units) for the report's picture of the
    test points on the model; None for a model without a structure.  test_numbers (m_t,) each
    test mode's 1-based number in its source (a study's ``[data] modes``; () : 1..m_t), the
    number a reader is shown (``number``).  rules : the pairing rules (None: paired in order,
    frequencies only).  refused : each refused test mode with the rule that refused it, in
    test order (``inference.pairing.RefusedMode``).
    """

    model: str
    data: str
    dof_labels: tuple[str, ...]
    test_hz: np.ndarray
    model_hz: np.ndarray
    pairs: ModePairs
    mapping: SensorMapping
    mac: np.ndarray | None = None
    test_auto_mac: np.ndarray | None = None
    comac: np.ndarray | None = None
    test_shapes: np.ndarray | None = None
    model_shapes: np.ndarray | None = None
    pseudo_orthogonality: np.ndarray | None = None
    cross_orthogonality: np.ndarray | None = None
    expanded: np.ndarray | None = None
    notes: tuple[str, ...] = ()
    model_nodes: np.ndarray | None = None
    test_numbers: tuple[int, ...] = ()
    rules: PairingRules | None = None
    refused: tuple[RefusedMode, ...] = ()

    def number(self, t: int) -> int:
        """The source's 1-based number of test mode ``t`` (0-based index here)."""
        return int(self.test_numbers[t]) if self.test_numbers else int(t) + 1

    @property
    def error_pct(self) -> np.ndarray:
        """(k,) model minus test frequency of each pair, in % of the test's."""
        f_t = self.test_hz[self.pairs.test]
        return 100.0 * (self.model_hz[self.pairs.model] - f_t) / f_t

    def worst_points(self, n: int) -> tuple[tuple[str, float], ...]:
        """The ``n`` test DOFs of lowest COMAC, lowest first: ((label, COMAC), ...)."""
        if self.comac is None:
            return ()
        order = np.argsort(self.comac, kind="stable")[:n]
        return tuple((self.dof_labels[i], float(self.comac[i])) for i in order)


def sensor_mapping(model, labels) -> SensorMapping:
    """The mapping ``calibrate`` uses: an FE model's sensors at ``labels`` (their nodes,
    directions and coordinates; a deck's GRID ids), else the labels alone."""
    structure = getattr(model, "structure", None)
    if structure is None or not structure.sensor_labels:
        points = tuple(SensorPoint(str(x), _test_node(x), None, None, None) for x in labels)
        return SensorMapping(np.eye(4), points, "the model's shape labels")
    index = {lab: i for i, lab in enumerate(structure.sensor_labels)}
    deck = structure.metadata.get("nastran")
    ids = np.asarray(deck["grid_ids"]) if deck else np.arange(len(structure.nodes))
    points = []
    for label in labels:
        i = index[label]
        node = int(structure.sensor_node[i])
        points.append(
            SensorPoint(
                str(label),
                _test_node(label),
                int(ids[node]),
                tuple(float(v) for v in structure.nodes[node]),
                tuple(float(v) for v in structure.sensor_direction[i]),
            )
        )
    source = "[model.test_points] (test node = GRID id by default)" if deck else "built-in sensors"
    return SensorMapping(np.eye(4), tuple(points), source)


def _test_node(label) -> str:
    text = str(label)
    digits = len(text) - len(text.lstrip("0123456789"))
    return text[:digits] or text


@dataclass(frozen=True)
class ModelModes:
    """The model's modes: frequencies_hz (m,), shapes (n_labels, m) at ``labels`` (None: no
    shapes), full (n_dof, m) mass-normalized shapes at every DOF (FE models only, else None)."""

    frequencies_hz: np.ndarray
    labels: tuple[str, ...]
    shapes: np.ndarray | None
    full: np.ndarray | None


def model_modes(model, n_modes: int, parameters=None) -> ModelModes:
    """Solve ``model`` at ``parameters`` for ``n_modes`` modes (an FE model: also its shapes at
    every DOF, through ``solve``)."""
    if hasattr(model, "solve") and hasattr(model, "structure"):
        r = model.solve(parameters or None, n_modes)
        return ModelModes(r.frequencies_hz, tuple(r.sensor_labels), r.sensor_shapes, r.modes.shapes)
    p = model.predict(parameters or {}, n_modes)
    shapes = None if p.shapes is None else np.asarray(p.shapes)
    return ModelModes(np.asarray(p.frequencies_hz), tuple(p.dof_labels), shapes, None)


def _rows(modes: ModelModes, labels) -> np.ndarray:
    return label_rows(modes.labels, labels, "correlate",
                      "map them in [test], [model.test_points] or rename them")  # fmt: skip


def geometry_mapping(pairing) -> SensorMapping:
    """The ``SensorMapping`` of a ``testgeom.TestPairing`` (the study's ``[test]`` geometry,
    aligned and paired): its transform and fit residual, and per test DOF its model point
    (the nearest model node's label; ``model_xyz`` the paired point, on an element where the
    pairing chose one), its direction in the model frame and its distance."""
    t = pairing.transform
    by_node = {p.test_node: p for p in pairing.points}
    points = []
    for label, direction in zip(pairing.dof_labels, pairing.directions, strict=True):
        node = _test_node(label)
        paired = by_node[int(node)] if node.lstrip("-").isdigit() else None
        points.append(
            SensorPoint(
                str(label),
                node,
                None if paired is None else int(paired.model_node),
                None if paired is None else tuple(float(v) for v in paired.model_xyz),
                tuple(float(v) for v in direction),
                None if paired is None else float(paired.distance),
            )
        )
    source = f"[test] geometry ({t.method}; lengths in {pairing.unit})"
    return SensorMapping(np.asarray(t.matrix, float), tuple(points), source, float(t.rms))


def study_correlation_model(study, test_labels=()) -> tuple:
    """(model, ``SensorMapping`` or None): the study's model (``model_source``; a Nastran deck
    also without bound parameters: correlation moves none) whose sensors are the test DOFs
    ``test_labels``; with a ``[test]`` geometry they are paired with it by position and the
    mapping says how, else the model's own sensors (a deck's ``[model.test_points]``) read
    them and the mapping is None (``sensor_mapping`` then)."""
    if study.test is None:
        return study_model(study, test_labels, needs_parameters=False), None
    model, pairing = paired_study_model(study, test_labels, needs_parameters=False)
    return model, None if pairing is None else geometry_mapping(pairing)


def correlate(
    model,
    data: ModalData,
    settings: CorrelateSettings,
    name: str = "model",
    mapping: SensorMapping | None = None,
    numbers: tuple[int, ...] = (),
) -> Correlation:
    """Correlate ``model`` with the test ``data`` (module docstring); ``mapping``: the test
    DOFs on the model when a test geometry paired them (``geometry_mapping``), else the
    model's own sensors (``sensor_mapping``).  ``numbers`` (m_t,): each test mode's 1-based
    number in its source when ``data`` holds a selection of it (``inference.data.select_modes``;
    () : 1..m_t); without shapes test mode k is paired with model mode k, so the model computes
    up to the highest number plus ``settings.extra_modes``."""
    numbers = tuple(int(n) for n in numbers) or tuple(range(1, data.n_modes + 1))
    if len(numbers) != data.n_modes:
        raise ValueError(f"correlate: {len(numbers)} numbers for {data.n_modes} test modes")
    n_first = max(numbers) + settings.extra_modes
    modes = model_modes(model, n_first, settings.parameters)
    if data.shapes is None or modes.shapes is None:
        return _frequencies_only(model, data, modes, name, numbers)
    first_hz = float(np.max(modes.frequencies_hz))
    modes, n = reach_modes(lambda k: model_modes(model, k, settings.parameters), modes,
                           n_first, float(np.max(data.frequencies_hz)))  # fmt: skip
    reached = () if n == n_first else (
        f"the model's first {n_first} modes stop at {first_hz:.4g} Hz, below the test's "
        f"highest ({float(np.max(data.frequencies_hz)):.4g} Hz): {n} computed, up to "
        f"{float(np.max(modes.frequencies_hz)):.4g} Hz (the test may have missed lower "
        "modes; calibrate computes as many)",
    )  # fmt: skip
    rows = _rows(modes, data.dof_labels)
    model_at = modes.shapes[rows]
    mac = mac_matrix(data.shapes, model_at)
    rules = settings.rules
    screened = screen_pairs(mac, data.frequencies_hz, modes.frequencies_hz, rules, numbers)
    pairs = _mode_pairs(screened, numbers, mac.shape[1])
    notes = [*reached, *_pair_notes(pairs, screened.refused, rules, numbers)]
    base = Correlation(
        model=name,
        data=data.source,
        dof_labels=data.dof_labels,
        test_hz=data.frequencies_hz,
        model_hz=np.asarray(modes.frequencies_hz),
        pairs=pairs,
        mapping=mapping or sensor_mapping(model, data.dof_labels),
        mac=mac,
        test_auto_mac=auto_mac(data.shapes),
        comac=comac(data.shapes[:, pairs.test], model_at[:, pairs.model])
        if pairs.test.size
        else None,
        test_shapes=_realize(data.shapes),
        model_shapes=model_at,
        model_nodes=_nodes(model),
        test_numbers=_shown(numbers),
        rules=rules,
        refused=screened.refused,
    )
    return _with_serep(base, modes, rows, data, notes)


def _mode_pairs(screened: ScreenedPairs, numbers: tuple[int, ...], n_model: int) -> ModePairs:
    """The ``ModePairs`` of the pairs ``screen_pairs`` kept, its refused test modes as
    (test, best model mode, MAC) (0-based), swaps and the modes of each set in no pair."""
    index = {n: t for t, n in enumerate(numbers)}
    test, model = screened.test, screened.model
    order = np.argsort(model, kind="stable")
    rank_model = np.empty_like(order)
    rank_model[order] = np.arange(order.size)
    out_of_order = rank_model != np.arange(test.size)
    return ModePairs(
        test=test,
        model=model,
        mac=screened.mac,
        refused=tuple((index[r.number], r.model_mode - 1, r.mac) for r in screened.refused),
        # a pair whose model mode's rank among the paired ones is not its test mode's
        swapped=tuple((int(test[k]), int(model[k])) for k in np.flatnonzero(out_of_order)),
        unpaired_test=tuple(int(t) for t in np.setdiff1d(np.arange(len(numbers)), test)),
        unpaired_model=tuple(int(m) for m in np.setdiff1d(np.arange(n_model), model)),
        method="mac",
    )


def _nodes(model) -> np.ndarray | None:
    structure = getattr(model, "structure", None)
    return None if structure is None else np.asarray(structure.nodes, float)


def _shown(numbers: tuple[int, ...]) -> tuple[int, ...]:
    """The numbers a ``Correlation`` keeps: () when they are 1..m (the whole source)."""
    return () if numbers == tuple(range(1, len(numbers) + 1)) else numbers


def _frequencies_only(
    model, data: ModalData, modes: ModelModes, name: str, numbers: tuple[int, ...]
) -> Correlation:
    why = "the test has no shapes" if data.shapes is None else "the model gives no shapes"
    labels = data.dof_labels if modes.shapes is not None else ()
    return Correlation(
        model=name,
        data=data.source,
        dof_labels=tuple(labels),
        test_hz=data.frequencies_hz,
        model_hz=np.asarray(modes.frequencies_hz),
        pairs=_pairs_in_order(numbers, modes.frequencies_hz.size),
        mapping=sensor_mapping(model, labels),
        notes=(f"{why}: modes are paired in order (no MAC, COMAC or orthogonality)",),
        test_numbers=_shown(numbers),
    )


def _pairs_in_order(numbers: tuple[int, ...], n_model: int) -> ModePairs:
    """Frequencies only: test mode number k of its source with model mode k (a selection of a
    source's modes keeps the source's numbers; all of them: ``correlation.pair_in_order``)."""
    if numbers == tuple(range(1, len(numbers) + 1)):
        return pair_in_order(len(numbers), n_model)
    model = np.asarray(numbers, dtype=int) - 1
    test = np.flatnonzero(model < n_model)
    paired = set(model[test].tolist())
    return ModePairs(
        test=test,
        model=model[test],
        mac=np.full(test.size, np.nan),
        refused=(),
        swapped=(),
        unpaired_test=tuple(int(t) for t in np.flatnonzero(model >= n_model)),
        unpaired_model=tuple(m for m in range(n_model) if m not in paired),
        method="order",
    )


def _realize(shapes: np.ndarray) -> np.ndarray:
    from bayesupdate.ema.lsfd import realize

    return realize(shapes) if np.iscomplexobj(shapes) else np.asarray(shapes, dtype=float)


def _pair_notes(
    pairs: ModePairs, refused: tuple[RefusedMode, ...], rules: PairingRules, numbers
) -> list[str]:
    notes = [r.message(rules) for r in refused]
    if pairs.swapped:
        named = ", ".join(f"test {numbers[t]} - model {m + 1}" for t, m in pairs.swapped)
        notes.append(f"swapped (model modes out of the test's order): {named}")
    return notes


def _with_serep(
    base: Correlation, modes: ModelModes, rows: np.ndarray, data: ModalData, notes: list
) -> Correlation:
    """``base`` with the SEREP TAM results of the paired modes (FE models)."""
    from dataclasses import replace

    pairs = base.pairs
    k, n_a = pairs.test.size, rows.size
    if modes.full is None or k == 0:
        why = "no pairs" if k == 0 else "the model gives no shapes at all DOFs (not an FE model)"
        notes.append(f"no SEREP TAM: {why}")
        return replace(base, notes=tuple(notes))
    phi_a = base.model_shapes[:, pairs.model]
    if k > n_a or np.linalg.matrix_rank(phi_a) < k:
        notes.append(
            f"the {n_a} test DOFs do not tell the {k} paired model modes apart (rank "
            f"{np.linalg.matrix_rank(phi_a)}): the SEREP TAM is not exact"
        )
    transform = serep_transformation(modes.full[:, pairs.model], phi_a)
    mass_a = serep_mass(phi_a)
    test_real = base.test_shapes[:, pairs.test]
    # a realized shape's sign is arbitrary: turn each towards its paired model shape
    test_real = test_real * np.where(np.sum(test_real * phi_a, axis=0) < 0, -1.0, 1.0)
    xor = None
    scaled = np.asarray(data.extra.get("mass_normalized", np.zeros(data.n_modes)), dtype=bool)
    if scaled.size == data.n_modes and scaled[pairs.test].all():
        xor = cross_orthogonality(test_real, phi_a, mass_a)
    else:
        notes.append("no cross-orthogonality: the test's shapes are not all mass-normalized")
    return replace(
        base,
        pseudo_orthogonality=pseudo_orthogonality(phi_a, mass_a),
        cross_orthogonality=xor,
        expanded=serep_expand(transform, test_real),
        notes=tuple(notes),
    )


def write_correlation_h5(path, result: Correlation) -> None:
    """Write ``result`` to HDF5 atomically.  Layout (group ``/correlation``, attributes
    ``model``, ``data``, ``pairing`` (mac | order), ``mapping_source``, ``rms_residual`` of the
    alignment (NaN: none fitted), ``mac_threshold`` and ``frequency_window`` of the pairing
    rules (NaN: paired in order)):

    - ``test_hz`` (m_t,), ``model_hz`` (m_m,) [Hz]; ``dof_labels`` (n_a,) strings;
      ``test_numbers`` (m_t,) each test mode's 1-based number in its source;
    - ``pairs/test``, ``pairs/model`` (k,) 0-based, ``pairs/mac`` (k,), ``pairs/error_pct`` (k,);
    - ``refused/test`` (r,) 1-based numbers of the refused test modes, ``refused/model`` (r,)
      1-based model mode of each one's best MAC, ``refused/mac`` (r,), ``refused/error_pct``
      (r,), ``refused/reason`` (r,) strings: ``mac`` (below the threshold), ``window`` (outside
      the frequency window) or ``taken`` (that model mode is paired with another test mode);
    - ``transform`` (4, 4) test -> model; ``points/model_node`` (n_a,) (-1: none),
      ``points/model_xyz`` (n_a, 3), ``points/direction`` (n_a, 3), ``points/distance`` (n_a,)
      test point to its model point after the transform (NaN: none);
    - where computed: ``mac`` (m_t, m_m), ``test_auto_mac`` (m_t, m_t), ``comac`` (n_a,),
      ``test_shapes`` (n_a, m_t) realized, ``model_shapes`` (n_a, m_m),
      ``pseudo_orthogonality`` (k, k), ``cross_orthogonality`` (k, k), ``expanded`` (n_dof, k);
    - ``notes`` strings.
    """
    import h5py

    from bayesupdate.atomic import atomic_path

    pts = result.mapping.points
    with atomic_path(path, suffix=".h5") as tmp, h5py.File(tmp, "w") as fh:
        g = fh.create_group("correlation")
        rms = result.mapping.rms_residual
        rules = result.rules
        g.attrs.update(model=result.model, data=result.data, pairing=result.pairs.method,
                       mapping_source=result.mapping.source,
                       rms_residual=np.nan if rms is None else rms)  # fmt: skip
        g.attrs["mac_threshold"] = np.nan if rules is None else rules.mac_threshold
        g.attrs["frequency_window"] = np.nan if rules is None else rules.frequency_window
        g["test_hz"], g["model_hz"] = result.test_hz, result.model_hz
        g["test_numbers"] = np.array([result.number(t) for t in range(result.test_hz.size)])
        g["dof_labels"] = np.array(result.dof_labels, dtype=h5py.string_dtype())
        g["notes"] = np.array(result.notes, dtype=h5py.string_dtype())
        pairs = g.create_group("pairs")
        pairs["test"], pairs["model"] = result.pairs.test, result.pairs.model
        pairs["mac"], pairs["error_pct"] = result.pairs.mac, result.error_pct
        refused = g.create_group("refused")
        refused["test"] = np.array([r.number for r in result.refused], dtype=int)
        refused["model"] = np.array([r.model_mode for r in result.refused], dtype=int)
        refused["mac"] = np.array([r.mac for r in result.refused], dtype=float)
        refused["error_pct"] = np.array([r.error_pct for r in result.refused], dtype=float)
        refused["reason"] = np.array([r.reason for r in result.refused], dtype=h5py.string_dtype())
        g["transform"] = result.mapping.transform
        points = g.create_group("points")
        points["model_node"] = np.array([-1 if p.model_node is None else p.model_node for p in pts])
        points["model_xyz"] = np.array([p.model_xyz or (np.nan,) * 3 for p in pts]).reshape(-1, 3)
        points["direction"] = np.array([p.direction or (np.nan,) * 3 for p in pts]).reshape(-1, 3)
        points["distance"] = np.array([np.nan if p.distance is None else p.distance for p in pts])
        for name in _OPTIONAL_ARRAYS:
            value = getattr(result, name)
            if value is not None:
                g[name] = value


_OPTIONAL_ARRAYS = (
    "mac",
    "test_auto_mac",
    "comac",
    "test_shapes",
    "model_shapes",
    "pseudo_orthogonality",
    "cross_orthogonality",
    "expanded",
)
