"""A large model's full solve at the reference design kept on disk: the pairing's reference
(``inference.problem.build_problem``) is the same solve on every command run on the same model,
so the next command recalls it instead of solving again.

The solve is a pure function of what its key holds (``solve_key``): the assembled K and M at the
point, the supports' and rigid elements' constraints and the rigid motions they allow, the
sensors' read-out, the eigen-solver's settings (``FEModel.small_method``, the structure's
``rigid_set``), the number of modes, the point and the package version.  Unlike a reduced
basis (``fe.reduced.certification``), nothing about the model away from that point enters it,
so a recalled solve needs no check: a model that differs there is another key.  The store is the
bases' (``compute.cache.ArrayStore``: ``BAYESUPDATE_CACHE_DIR``, ``--no-cache``, atomic writes,
checksums, least recently used out).  Only models of ``fe.reduced.settings.LARGE_MODEL_DOFS``
DOFs or more are kept: there a solve costs ~1.5 s of CPU (the shell exhaust's 28,386 DOFs) and
the key ~0.2 s (one assembly); a beam model's solve costs less than its key.
"""

from collections.abc import Mapping

import numpy as np

from bayesupdate import __version__
from bayesupdate.compute.cache import ArrayStore, content_key
from bayesupdate.fe.model import FEModel
from bayesupdate.model_protocol import Prediction

#: format of a kept reference solve; bump when the stored arrays change meaning
SOLVE_FORMAT = "reference-solve-1"


def remembered_solve(model, params: Mapping[str, float], n_modes: int) -> Prediction:
    """``model.predict(params, n_modes)``, recalled from the environment's store
    (``ArrayStore.from_environment``) when a large FE model was solved at ``params`` (SI, every
    parameter) with ``n_modes`` modes before, else solved and kept there.  Other models, or the
    store off: solved.  An error of the solve (``BayesUpdateError``) propagates as
    ``model.predict``'s does, and nothing is kept."""
    store = ArrayStore.from_environment() if large_fe_model(model) else ArrayStore(None)
    if not store.enabled:
        return model.predict(params, n_modes=n_modes)
    key = solve_key(model, params, n_modes)
    kept = prediction_of(store.load(key), n_modes)
    if kept is not None:
        return kept
    prediction = model.predict(params, n_modes=n_modes)
    store.save(key, prediction_arrays(prediction))
    return prediction


def large_fe_model(model) -> bool:
    """Whether ``model`` is an ``FEModel`` of ``fe.reduced.settings.LARGE_MODEL_DOFS`` DOFs or
    more (its reference solve here, its calibration in ``pipelines.calibration_memo``, are
    kept on disk)."""
    # late: the fe.reduced package loads the basis machinery (~320 modules), which a command
    # that only builds a problem does not need
    from bayesupdate.fe.reduced.settings import LARGE_MODEL_DOFS

    return isinstance(model, FEModel) and model.structure.n_dof >= LARGE_MODEL_DOFS


def solve_key(model, params: Mapping[str, float], n_modes: int) -> str:
    """The content key of the full solve of the ``FEModel`` ``model`` at ``params`` with
    ``n_modes`` modes (module docstring): everything ``FEModel.predict`` reads."""
    p = model.full_parameters(params)
    structure = model.structure
    K, M = model.matrices(p)
    return content_key(
        SOLVE_FORMAT, __version__, type(model).__qualname__, p, int(n_modes), K, M,
        structure.constraints, model.rigid_motions(), structure.sensor_dofs(),
        tuple(structure.sensor_labels), structure.metadata.get("rigid_set", "zero_energy"),
        getattr(model, "small_method", ""),
    )  # fmt: skip


def prediction_arrays(prediction: Prediction) -> dict[str, np.ndarray]:
    """What is kept of a ``Prediction``: its frequencies [Hz], sensor shapes and labels, mass
    [kg] (each only when the prediction has it)."""
    arrays = {"frequencies_hz": np.asarray(prediction.frequencies_hz, dtype=float)}
    if prediction.shapes is not None:
        arrays["shapes"] = np.asarray(prediction.shapes, dtype=float)
        arrays["dof_labels"] = np.array(prediction.dof_labels, dtype=str)
    if prediction.mass_kg is not None:
        arrays["mass_kg"] = np.array(float(prediction.mass_kg))
    return arrays


def prediction_of(arrays: dict[str, np.ndarray] | None, n_modes: int) -> Prediction | None:
    """The kept ``prediction_arrays`` as a ``Prediction``; None when there is nothing kept or
    the entry does not hold ``n_modes`` frequencies with their shapes (then it is solved
    again and replaced)."""
    if arrays is None or "frequencies_hz" not in arrays:
        return None
    freqs = arrays["frequencies_hz"]
    shapes = arrays.get("shapes")
    if freqs.shape != (n_modes,) or (shapes is not None and shapes.shape[1:] != (n_modes,)):
        return None
    labels = tuple(str(s) for s in arrays["dof_labels"]) if shapes is not None else ()
    mass = float(arrays["mass_kg"]) if "mass_kg" in arrays else None
    return Prediction(freqs, shapes, labels, mass)
