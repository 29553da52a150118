"""Modal data to and from HDF5.

Layout (group ``/modes``): datasets ``frequencies_hz`` (m,), ``damping_ratio`` (m,),
``shapes_real`` and ``shapes_imag`` (n_dof, m), ``dof_labels`` (n_dof,) strings, optional
``mpc``, ``frequency_sd_hz``, ``identification_sd_hz``, ``weights``, ``shape_sd_rel`` (m,), any
``extra`` arrays under ``/modes/extra``; attributes ``source`` and, when measured, ``mass_kg``
and ``mass_sd_kg`` (the structure's weighed mass, test data like the frequencies); on the root,
``timings_json`` ({phase: wall time [s]} of the ``identify`` run that wrote it).  Written
atomically.

``identify`` on several files with more than one run group (:mod:`bayesupdate.ema.run_groups`)
adds under ``/modes/extra``: ``group_frequencies_hz``, ``group_damping_ratio``,
``group_sd_hz``, ``group_mpc``, ``group_sees`` (m, G) per mode and group;
``frequency_spread_hz``, ``pole_shift``, ``group_poles_used`` (residues at each group's own
pole), ``mpc_one_pole``, ``frequency_one_pole_hz`` (one pole over all runs) (m,); and
``group_of_file`` (n_files,), each file's group (from 0).  The modes' ``frequencies_hz``,
``damping_ratio``, ``identification_sd_hz`` (spread included), ``shapes`` and ``mpc`` are then
the groups' combined values and assembled shapes.
"""

import json
import os

import h5py
import numpy as np

from bayesupdate.atomic import atomic_path
from bayesupdate.errors import BayesUpdateError
from bayesupdate.modal_data import ModalData

_OPTIONAL = (
    "damping_ratio",
    "mpc",
    "frequency_sd_hz",
    "identification_sd_hz",
    "weights",
    "shape_sd_rel",
)
_MASS = ("mass_kg", "mass_sd_kg")


def write_modal_h5(path: str | os.PathLike, modes: ModalData, timings: dict | None = None) -> None:
    """Write ``modes`` to ``path`` (HDF5) atomically; ``timings`` ({phase name: wall time [s]}
    of the run that made them, ``compute.progress.timings``) as the JSON attribute
    ``timings_json`` when given."""
    with atomic_path(path, suffix=".h5") as tmp, h5py.File(tmp, "w") as fh:
        if timings is not None:
            fh.attrs["timings_json"] = json.dumps(timings)
        g = fh.create_group("modes")
        g.attrs["source"] = modes.source
        for name in _MASS:
            if getattr(modes, name) is not None:
                g.attrs[name] = float(getattr(modes, name))
        g["frequencies_hz"] = modes.frequencies_hz
        for name in _OPTIONAL:
            value = getattr(modes, name)
            if value is not None:
                g[name] = value
        if modes.shapes is not None:
            g["shapes_real"] = np.real(modes.shapes)
            g["shapes_imag"] = np.imag(modes.shapes)
        g["dof_labels"] = np.array(modes.dof_labels, dtype=h5py.string_dtype())
        extra = g.create_group("extra")
        for key, value in modes.extra.items():
            arr = np.asarray(value)
            if arr.dtype.kind in "biuf":
                extra[key] = arr


#: keys of ``extra`` that files written before release 0.2.0 spell otherwise (one spelling:
#: -ize, as numpy and scipy write it)
_RENAMED = {"mass_normalised": "mass_normalized"}


def read_modal_h5(path: str | os.PathLike) -> ModalData:
    """Read ModalData written by :func:`write_modal_h5`."""
    if not os.path.isfile(path):
        raise BayesUpdateError(f"{path}: file not found")
    try:
        with h5py.File(path, "r") as fh:
            g = fh["modes"]
            kwargs = {name: g[name][()] for name in _OPTIONAL if name in g}
            shapes = None
            if "shapes_real" in g:
                shapes = g["shapes_real"][()] + 1j * g["shapes_imag"][()]
                if not np.any(shapes.imag):
                    shapes = shapes.real
            labels = tuple(
                x.decode() if isinstance(x, bytes) else str(x) for x in g["dof_labels"][()]
            )
            extra = {k: v[()] for k, v in g["extra"].items()} if "extra" in g else {}
            extra = {_RENAMED.get(k, k): v for k, v in extra.items()}
            return ModalData(
                frequencies_hz=g["frequencies_hz"][()],
                shapes=shapes,
                dof_labels=labels,
                source=str(g.attrs.get("source", "")),
                extra=extra,
                **{name: float(g.attrs[name]) for name in _MASS if name in g.attrs},
                **kwargs,
            )
    except (OSError, KeyError) as exc:
        raise BayesUpdateError(f"{path}: not a modal-data HDF5 file ({exc})") from None
