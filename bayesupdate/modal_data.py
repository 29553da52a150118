"""``ModalData``: the hand-off between a modal test (or any source of modes) and a model.

Frequencies in Hz, damping as ratio of critical, shapes as a (n_dof, n_modes) array at named sensor
DOFs (labels such as ``"7V"`` / ``"7H"``; see DESIGN.md vocabulary).  Shapes may be complex (as
identified) or real (as computed by FE).  All optional fields may be ``None``.
"""

from dataclasses import dataclass, field

import numpy as np

from bayesupdate.errors import BayesUpdateError

#: the optional per-mode arrays, (m,) each
_PER_MODE = (
    "damping_ratio",
    "frequency_sd_hz",
    "identification_sd_hz",
    "weights",
    "mpc",
    "shape_sd_rel",
)


@dataclass(frozen=True)
class ModalData:
    """Modal parameters of one structure.

    Attributes
    ----------
    frequencies_hz : (m,) float, natural (undamped) frequencies [Hz], ascending.
    damping_ratio : (m,) float or None, viscous damping ratio [-].
    shapes : (n_dof, m) complex or float or None, mode shapes at ``dof_labels``.
    dof_labels : tuple of n_dof str, e.g. ``("1V", "1H", ...)``.
    frequency_sd_hz : (m,) float or None, standard deviation of each frequency [Hz]: its whole
        error against the model (a stated sd; it replaces an inferred noise level).
    identification_sd_hz : (m,) float or None, standard deviation of each frequency's
        identification from the FRFs [Hz] (``ema.frequency_sd``): the test's part of the
        error only; the likelihood adds it in quadrature to the model-error level sigma.
    weights : (m,) float or None, importance weights w_i of seed eq. 19.
    mpc : (m,) float or None, modal phase collinearity of each identified shape [-].
    shape_sd_rel : (m,) float or None, standard deviation of each shape's components as a
        fraction of that shape's RMS amplitude [-] (known shape noise: 1 - MAC ~ shape_sd_rel^2);
        None when unknown (discovery then infers a level per mode).
    mass_kg : float or None, the measured total mass of the tested structure [kg]: test data,
        like the frequencies (seed section 2 weighs the exhaust: 12.29 kg).
    mass_sd_kg : float or None, its standard deviation [kg] (needs ``mass_kg``).
    source : str, where the data came from (file name, ``paper:ema``, ...).
    """

    frequencies_hz: np.ndarray
    damping_ratio: np.ndarray | None = None
    shapes: np.ndarray | None = None
    dof_labels: tuple[str, ...] = ()
    frequency_sd_hz: np.ndarray | None = None
    weights: np.ndarray | None = None
    mpc: np.ndarray | None = None
    shape_sd_rel: np.ndarray | None = None
    mass_kg: float | None = None
    mass_sd_kg: float | None = None
    source: str = ""
    identification_sd_hz: np.ndarray | None = None  # last: positional calls keep their order
    extra: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        f = np.asarray(self.frequencies_hz, dtype=float).reshape(-1)
        where = f"modal data {self.source!r}" if self.source else "modal data"
        if f.size == 0:
            raise BayesUpdateError(f"{where}: no frequencies; give at least one mode")
        if not np.all(np.isfinite(f)) or np.any(f <= 0):
            raise BayesUpdateError(f"{where}: frequencies must be finite and > 0 Hz")
        object.__setattr__(self, "frequencies_hz", f)
        m = f.size
        for name in _PER_MODE:
            value = getattr(self, name)
            if value is None:
                continue
            arr = np.asarray(value, dtype=float).reshape(-1)
            if arr.size != m:
                raise BayesUpdateError(
                    f"{where}: {name} has {arr.size} values but there are {m} frequencies"
                )
            if not np.all(np.isfinite(arr)):
                raise BayesUpdateError(f"{where}: {name} contains NaN or inf")
            if name in ("frequency_sd_hz", "identification_sd_hz", "weights") and np.any(arr < 0):
                raise BayesUpdateError(f"{where}: {name} must be >= 0")
            if name == "shape_sd_rel" and self.shapes is None:
                raise BayesUpdateError(f"{where}: shape_sd_rel needs shapes")
            if name == "shape_sd_rel" and np.any(arr <= 0):
                raise BayesUpdateError(f"{where}: shape_sd_rel must be > 0")
            object.__setattr__(self, name, arr)
        self._check_mass(where)
        labels = tuple(str(label) for label in self.dof_labels)
        object.__setattr__(self, "dof_labels", labels)
        if len(set(labels)) != len(labels):
            dup = sorted({lab for lab in labels if labels.count(lab) > 1})
            raise BayesUpdateError(f"{where}: duplicated DOF labels {dup}")
        if self.shapes is not None:
            shapes = np.asarray(self.shapes)
            if shapes.ndim != 2 or shapes.shape != (len(labels), m):
                raise BayesUpdateError(
                    f"{where}: shapes must be (n_dof={len(labels)}, n_modes={m}), "
                    f"got {shapes.shape}"
                )
            if not np.all(np.isfinite(shapes)):
                raise BayesUpdateError(f"{where}: shapes contain NaN or inf")
            object.__setattr__(self, "shapes", shapes)

    def _check_mass(self, where: str) -> None:
        for name in ("mass_kg", "mass_sd_kg"):
            value = getattr(self, name)
            if value is None:
                continue
            try:
                value = float(value)
            except (TypeError, ValueError) as exc:
                raise BayesUpdateError(f"{where}: {name} must be a number, got {value!r}") from exc
            if not (np.isfinite(value) and value > 0):
                raise BayesUpdateError(f"{where}: {name} must be a finite number > 0, got {value}")
            object.__setattr__(self, name, value)
        if self.mass_sd_kg is not None and self.mass_kg is None:
            raise BayesUpdateError(f"{where}: mass_sd_kg needs mass_kg")

    @property
    def mass_sd_rel(self) -> float | None:
        """Relative sd of the measured mass [-] (None without a measured mass or its sd)."""
        if self.mass_kg is None or self.mass_sd_kg is None:
            return None
        return self.mass_sd_kg / self.mass_kg

    @property
    def n_modes(self) -> int:
        return int(self.frequencies_hz.size)

    def subset(self, modes) -> "ModalData":
        """Return the modes with indices ``modes`` (any numpy index)."""
        idx = np.arange(self.n_modes)[modes]

        def pick(a, axis=0):
            return None if a is None else np.take(a, idx, axis=axis)

        return ModalData(
            frequencies_hz=self.frequencies_hz[idx],
            damping_ratio=pick(self.damping_ratio),
            shapes=pick(self.shapes, axis=1),
            dof_labels=self.dof_labels,
            frequency_sd_hz=pick(self.frequency_sd_hz),
            identification_sd_hz=pick(self.identification_sd_hz),
            weights=pick(self.weights),
            mpc=pick(self.mpc),
            shape_sd_rel=pick(self.shape_sd_rel),
            mass_kg=self.mass_kg,
            mass_sd_kg=self.mass_sd_kg,
            source=self.source,
        )


def noisy_modes(
    prediction,
    frequency_noise: float,
    shape_noise: float,
    rng: np.random.Generator,
    source: str,
) -> ModalData:
    """Virtual test data from a model ``Prediction``: frequencies times (1 + frequency_noise N(0,1))
    (also given as their sd), and with ``shape_noise`` > 0 the shapes plus Gaussian noise of that
    fraction of each shape's RMS amplitude (so 1 - MAC ~ shape_noise^2), also given as their
    ``shape_sd_rel``.  Modes are listed by noisy frequency, as a test lists them;
    ``shape_noise`` 0 gives frequencies only."""
    f_true = np.asarray(prediction.frequencies_hz, dtype=float)
    f = f_true * (1 + frequency_noise * rng.normal(size=f_true.size))
    if shape_noise <= 0:
        return ModalData(f, frequency_sd_hz=frequency_noise * f, source=source)
    shapes = np.asarray(prediction.shapes, dtype=float)
    rms = np.linalg.norm(shapes, axis=0) / np.sqrt(shapes.shape[0])
    shapes = shapes + shape_noise * rms[None, :] * rng.normal(size=shapes.shape)
    order = np.argsort(f)
    return ModalData(
        f[order],
        shapes=shapes[:, order],
        dof_labels=tuple(prediction.dof_labels),
        frequency_sd_hz=frequency_noise * f[order],
        shape_sd_rel=np.full(f.size, float(shape_noise)),
        source=source,
    )
