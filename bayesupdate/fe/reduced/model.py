"""``ReducedFEModel``: the certified reduced basis of an ``FEModel`` as a parametric model.

Points inside the box of the basis are solved reduced (all at once); points outside it, more
modes than certified, or an uncertified model go to full solves (``outer``, by default the FE
model).  The model is immutable: ``build`` and ``certify_at`` return new models.
"""

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.model import FEModel
from bayesupdate.fe.reduced import certification, coarsening
from bayesupdate.fe.reduced import mass as reduced_mass
from bayesupdate.fe.reduced.certification import UNBUILT, Certificate, Certification
from bayesupdate.fe.reduced.settings import ReducedSettings
from bayesupdate.model_protocol import Prediction


@dataclass(frozen=True, eq=False)
class ReducedFEModel:
    """A certified reduced-basis surrogate of an ``FEModel`` (see ``bayesupdate.fe.reduced``).

    Same ``parameter_names``, defaults and bounds as the wrapped model; implements
    ``ParametricModel`` and ``BatchParametricModel``.  fe : the FE model; bounds : name ->
    (low, high) of the box (SI; missing names take the model's default bounds); settings :
    ``ReducedSettings``; outer : the model predicting points outside the box (default ``fe``).
    ``ReducedFEModel(fe, ...)`` is not built yet (every prediction a full solve): ``build()``
    returns the built one.  After the build: ``size`` (basis vectors incl. the rigid motions),
    ``max_rel_error`` (certified on full solves), ``certified`` (False -> every prediction is a
    full solve).
    """

    fe: FEModel
    bounds: Mapping[str, tuple[float, float]] | None = None
    settings: ReducedSettings = ReducedSettings()
    outer: object = None
    name: str | None = None
    certification: Certification = UNBUILT
    low: np.ndarray = field(init=False, repr=False)
    high: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        names = self.fe.parameter_names
        b = dict(self.fe.default_bounds(), **dict(self.bounds or {}))
        bounds = {k: (float(b[k][0]), float(b[k][1])) for k in names}
        for k, (lo, hi) in bounds.items():
            if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
                raise BayesUpdateError(f"reduced model: bounds of {k} must be finite, low < high")
        object.__setattr__(self, "bounds", bounds)
        object.__setattr__(self, "outer", self.fe if self.outer is None else self.outer)
        object.__setattr__(self, "name", self.name or f"{self.fe.name} (reduced)")
        object.__setattr__(self, "low", np.array([bounds[k][0] for k in names]))
        object.__setattr__(self, "high", np.array([bounds[k][1] for k in names]))

    # -- state ---------------------------------------------------------------------------------
    @property
    def parameter_names(self) -> tuple[str, ...]:
        return self.fe.parameter_names

    @property
    def n_modes(self) -> int:
        return self.settings.n_modes

    @property
    def tol(self) -> float:
        return self.settings.tol

    @property
    def certified(self) -> bool:
        return self.certification.certified

    @property
    def max_rel_error(self) -> float:
        return self.certification.max_rel_error

    @property
    def certificate(self) -> Certificate:
        return self.certification.certificate

    @property
    def size(self) -> int:
        """Basis vectors incl. the rigid motions (0 before the build)."""
        basis = self.certification.basis
        return 0 if basis is None else basis.size

    @property
    def n_rigid(self) -> int:
        """Rigid motions in the basis (0 before the build)."""
        basis = self.certification.basis
        return 0 if basis is None else basis.n_rigid

    @property
    def sensor_labels(self) -> tuple[str, ...]:
        return tuple(self.fe.structure.sensor_labels)

    def default_parameters(self) -> dict[str, float]:
        return self.fe.default_parameters()

    def default_bounds(self) -> dict[str, tuple[float, float]]:
        return self.fe.default_bounds()

    def __str__(self) -> str:
        state = "certified" if self.certified else "NOT certified: full solves are used"
        return (
            f"reduced basis of {self.fe.name}: size {self.size} ({self.n_rigid} rigid + "
            f"{self.size - self.n_rigid} "
            f"elastic), {self.n_modes} modes, max relative frequency error "
            f"{self.max_rel_error:.2e} over {self.certificate.n_points} full solves "
            f"(tol {self.tol:g}); {state}"
        )

    def summary(self) -> dict:
        """JSON-ready {"size", "max_rel_error", "certified", "tol", "n_modes"}."""
        return {
            "size": int(self.size),
            "max_rel_error": float(self.max_rel_error),
            "certified": bool(self.certified),
            "tol": self.tol,
            "n_modes": self.n_modes,
        }

    # -- box -----------------------------------------------------------------------------------
    def centre(self) -> np.ndarray:
        """(n_params,) the defaults if inside the box, else the box centre (SI)."""
        d = np.array([self.fe.default_parameters()[k] for k in self.parameter_names])
        inside = np.all((d >= self.low) & (d <= self.high))
        return d if inside else 0.5 * (self.low + self.high)

    def scale(self, u: np.ndarray) -> np.ndarray:
        """Points u (B, n_params) of the unit cube -> the box (SI)."""
        return self.low + u * (self.high - self.low)

    def mapping(self, row) -> dict[str, float]:
        return dict(zip(self.parameter_names, map(float, row), strict=True))

    def _theta_full(self, theta: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
        if names == self.parameter_names:  # the sampler's case: no defaults to fill in
            return np.array(theta, dtype=float)
        unknown = [n for n in names if n not in self.parameter_names]
        if unknown:
            raise BayesUpdateError(
                f"unknown parameters {unknown} for model {self.fe.name}; "
                f"parameters are {list(self.parameter_names)}"
            )
        d = self.fe.default_parameters()
        full = np.tile([d[n] for n in self.parameter_names], (theta.shape[0], 1))
        for c, n in enumerate(names):
            full[:, self.parameter_names.index(n)] = theta[:, c]
        return full

    def _inside(self, full: np.ndarray) -> np.ndarray:
        return np.all((full >= self.low) & (full <= self.high), axis=1)

    # -- offline -------------------------------------------------------------------------------
    def build(self, executor=None) -> "ReducedFEModel":
        """The built model: decomposed, snapshots compressed, certified (``reduced.certification``;
        an uncertified one, with a warning, when the size limit is reached first).  The full
        solves run on ``executor`` (``compute.executors``; None: in this process)."""
        return replace(self, certification=certification.build(self, executor))

    def certify_at(
        self,
        theta: np.ndarray,
        names: tuple[str, ...] | None = None,
        enrich: bool = True,
        enrich_above: float | None = None,
    ) -> tuple["ReducedFEModel", float]:
        """Check the reduced frequencies against full solves at extra points (e.g. the posterior
        mean), theta (k, len(names)); points outside the box are skipped.  If the error there
        exceeds ``tol`` (or ``enrich_above``, when smaller: a data sd the basis must not bias)
        and ``enrich``, their shapes join the basis and all checked points are re-verified; if
        the tolerance still fails (or the size limit is hit), the returned model falls back to
        full solves with a warning.  Returns (the model with this check recorded, largest
        relative error at the points; NaN when none is checked)."""
        names = tuple(self.parameter_names if names is None else names)
        full = self._theta_full(np.atleast_2d(np.asarray(theta, dtype=float)), names)
        full = full[self._inside(full)]
        if not self.certified or full.shape[0] == 0:
            return self, float("nan")
        checked, err = certification.certify_points(self, full, enrich, enrich_above)
        return replace(self, certification=checked), err

    def content_key(self) -> str:
        """SHA-256 (hex) of everything this model's certified basis depends on (the FE model's
        terms and matrices, the box, the settings, the sensors, the package version): the key
        ``build`` keeps the basis under (``compute.cache``); computed without a build."""
        return certification.basis_key(self)

    def coarsened(self, tol=5e-3, n_train=128, n_check=64, min_size=None) -> "ReducedFEModel":
        """A smaller model inside this basis for screening proposals (``reduced.coarsening``)."""
        return coarsening.coarsened(self, tol, n_train, n_check, min_size)

    def localized(self, samples, names=None, widen=0.5, **settings) -> "ReducedFEModel":
        """A built model on the box of ``samples``, this one outside it (``reduced.coarsening``)."""
        return coarsening.localized(self, samples, names, widen, **settings)

    # -- online --------------------------------------------------------------------------------
    def reduced_matrices(self, theta_full: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Reduced pencils at theta_full (B, n_params) (``ReducedBasis.matrices``)."""
        return self.certification.basis.matrices(theta_full)

    def _usable(self, n_modes: int) -> bool:
        return self.certified and n_modes <= self.n_modes

    def predict_frequencies_batch(
        self, theta: np.ndarray, names: tuple[str, ...] | None = None, n_modes: int | None = None
    ) -> np.ndarray:
        """(B, n_modes) elastic frequencies [Hz] at theta (B, len(names)) (SI).

        Points inside the box of the basis: reduced solve (all at once).  Points outside it, more
        modes than certified, or an uncertified model: full solves.  Non-physical rows: NaN."""
        names = tuple(self.parameter_names if names is None else names)
        n_modes = self.n_modes if n_modes is None else int(n_modes)
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        full = self._theta_full(theta, names)
        if not self._usable(n_modes):
            if not self.certified:
                warnings.warn(f"{self}", RuntimeWarning, stacklevel=2)
            return self.fe.predict_frequencies_batch(full, self.parameter_names, n_modes)
        out = np.full((theta.shape[0], n_modes), np.nan)
        finite = np.all(np.isfinite(full), axis=1)
        inside = finite & self._inside(full)
        if np.any(inside):
            lam = self.certification.basis.eigen(full[inside], n_modes)
            out[inside] = np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)
        outside = finite & ~inside
        if np.any(outside):
            out[outside] = self.outer.predict_frequencies_batch(
                full[outside], self.parameter_names, n_modes
            )
        return out

    def predict_batch_with_shapes(
        self, theta: np.ndarray, names: tuple[str, ...] | None = None, n_modes: int | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Frequencies (B, n_modes) [Hz] and sensor shapes (B, n_sensors, n_modes) at theta
        (B, len(names)), rows on ``sensor_labels``; shapes are not normalized (MAC ignores scale).

        Reduced points: one batched solve with eigenvectors, phi_sensors = V_sensor @ y (no
        full-size shape is formed).  Points outside the box, more modes than certified or an
        uncertified model: full solves (``predict``) one by one.  Failed points: NaN."""
        names = tuple(self.parameter_names if names is None else names)
        n_modes = self.n_modes if n_modes is None else int(n_modes)
        full = self._theta_full(np.atleast_2d(np.asarray(theta, dtype=float)), names)
        usable = self._usable(n_modes)
        basis = self.certification.basis
        if usable and np.all((full >= self.low) & (full <= self.high)):
            # every point inside the box (the sampler's usual batch): one batched solve
            lam, y = basis.eigen(full, n_modes, vectors=True)
            return np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi), basis.V_sensor @ y
        n_s = len(self.sensor_labels)
        freqs = np.full((full.shape[0], n_modes), np.nan)
        shapes = np.full((full.shape[0], n_s, n_modes), np.nan)
        finite = np.all(np.isfinite(full), axis=1)
        inside = finite & self._inside(full) & usable
        if np.any(inside):
            lam, y = basis.eigen(full[inside], n_modes, vectors=True)
            freqs[inside] = np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)
            shapes[inside] = basis.V_sensor @ y  # (s, r) @ (B, r, m): BLAS, unlike einsum
        model = self.outer if self.certified else self.fe
        for i in np.flatnonzero(finite & ~inside):
            try:
                pred = model.predict(self.mapping(full[i]), n_modes)
            except BayesUpdateError:
                continue
            freqs[i] = pred.frequencies_hz
            shapes[i] = pred.shapes
        return freqs, shapes

    def mass_kg(self, params: Mapping[str, float] | None = None) -> float:
        """Total mass [kg] of the FE model at ``params`` from its per-term masses
        (``fe.reduced.mass``: values validated, no K, M assembly)."""
        return reduced_mass.total_mass(self.fe, self.fe.full_parameters(params))

    def predict(self, params: Mapping[str, float] | None = None, n_modes: int = 12) -> Prediction:
        """Prediction with reduced frequencies and shapes (full solve outside the certified use)."""
        p = self.fe.full_parameters(params)
        row = np.array([[p[k] for k in self.parameter_names]])
        if not self._usable(n_modes) or np.any(row < self.low) or np.any(row > self.high):
            return (self.fe if not self.certified else self.outer).predict(p, n_modes)
        basis = self.certification.basis
        lam, y = basis.eigen(row, n_modes, vectors=True)
        phi = basis.V @ y[0]
        idx = np.argmax(np.abs(phi), axis=0)
        phi = phi * np.sign(phi[idx, np.arange(phi.shape[1])])
        mass = self.mass_kg(p)
        freqs = np.sqrt(np.maximum(lam[0], 0.0)) / (2 * np.pi)
        return Prediction(freqs, self.fe.sensor_shapes(phi), self.fe.structure.sensor_labels, mass)


def reduced_model_for(
    fe_model,
    bounds: Mapping[str, tuple[float, float]] | None = None,
    tol: float = 1e-4,
    seed: int = 0,
    n_modes: int = 12,
    executor=None,
    **options,
):
    """A built, certified ``ReducedFEModel`` of ``fe_model``; the model itself (with a warning)
    when it is not an ``FEModel`` or has no reduced form (not free-free, overlapping bindings).
    An uncertified reduced model (size limit) is returned too: it falls back to full solves.
    ``options``: other ``ReducedSettings`` fields, or ``outer``.  executor : where the
    snapshot and certification solves run (``compute.executors``; None: in this process)."""
    if not isinstance(fe_model, FEModel):
        return fe_model
    outer = options.pop("outer", None)
    try:
        settings = ReducedSettings(n_modes=n_modes, tol=tol, seed=seed, **options)
        return ReducedFEModel(fe_model, bounds, settings, outer).build(executor)
    except BayesUpdateError as exc:
        warnings.warn(f"{exc}; using full solves", RuntimeWarning, stacklevel=2)
        return fe_model
