"""Test geometry in, alignment with the model, and automatic test-to-model pairing.

Read a test's geometry (``read_geometry``: UFF 15/2411 nodes, 2420 frames, 82 trace lines, 164
units, or CSV), name its DOFs in any direction (``resolve_dofs``: UFF direction codes in each
node's displacement frame, or skewed vectors a CSV declares), align it with the model and pair
each test point with the model's nearest node or element point (``pair_test``): the result holds
the transform, the per-point pairing and the observation matrix that reads model shapes at the
test DOFs.  ``with_pairing`` puts that observation on a ``fe.Structure`` as its sensors.

One concept per module: ``units``, ``frames``, ``geometry``, ``dofs``, ``uff``, ``csv_io``,
``align``, ``mesh``, ``locate``, ``observation``, ``pairing``.
"""

from dataclasses import replace
from pathlib import Path

from bayesupdate.testgeom.align import Transform, fit_pairs, from_matrix, icp, umeyama
from bayesupdate.testgeom.csv_io import read_csv_geometry, write_csv_geometry
from bayesupdate.testgeom.dofs import TestDof, resolve_dofs
from bayesupdate.testgeom.frames import CoordinateFrame
from bayesupdate.testgeom.geometry import DeclaredDof, TestGeometry, make_geometry
from bayesupdate.testgeom.mesh import ModelMesh, model_mesh
from bayesupdate.testgeom.pairing import PairedPoint, PairingSettings, TestPairing, pair_test
from bayesupdate.testgeom.uff import read_uff_geometry, write_uff_geometry

__all__ = [
    "CoordinateFrame",
    "DeclaredDof",
    "ModelMesh",
    "PairedPoint",
    "PairingSettings",
    "TestDof",
    "TestGeometry",
    "TestPairing",
    "Transform",
    "fit_pairs",
    "from_matrix",
    "icp",
    "make_geometry",
    "model_mesh",
    "pair_structure",
    "pair_test",
    "read_csv_geometry",
    "read_geometry",
    "read_uff_geometry",
    "resolve_dofs",
    "umeyama",
    "with_pairing",
    "write_csv_geometry",
    "write_uff_geometry",
]


def read_geometry(path, length_unit=None) -> TestGeometry:
    """A test geometry file: ``.csv`` (``csv_io``), else a universal file (``uff``: .unv,
    .uff, .bunv).  length_unit : the file's length unit (CSV default metres; a UFF file's 164
    record, when it has one, must agree)."""
    if Path(path).suffix.lower() == ".csv":
        return read_csv_geometry(path, length_unit or "m")
    return read_uff_geometry(path, length_unit)


def pair_structure(structure, geometry: TestGeometry, labels, settings: PairingSettings,
                   model_length_unit: str | None = None) -> TestPairing:  # fmt: skip
    """``pair_test`` of the test DOF ``labels`` on a ``fe.Structure`` (``model_mesh``)."""
    return pair_test(geometry, resolve_dofs(geometry, labels),
                     model_mesh(structure, model_length_unit), settings)  # fmt: skip


def with_pairing(structure, pairing: TestPairing):
    """``structure`` whose sensors are the paired test DOFs: labels, nearest model nodes,
    directions (model frame) and the interpolated read-out (``Structure.sensor_read``); the
    pairing's record (``TestPairing.to_dict``) is kept in ``metadata["test_pairing"]`` for the
    result files."""
    return replace(
        structure,
        sensor_labels=pairing.dof_labels,
        sensor_node=pairing.sensor_nodes,
        sensor_direction=pairing.directions,
        sensor_read=(pairing.sensor_dofs, pairing.sensor_weights),
        metadata={**structure.metadata, "test_pairing": pairing.to_dict()},
    )
