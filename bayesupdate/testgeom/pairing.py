"""Test to model: align the test geometry, pair each test point with the model, and build the
observation that reads a model shape at the test DOFs in the test directions.

``pair_test(geometry, dofs, mesh, settings)`` -> ``TestPairing``: the transform (``align``),
per test point the model node or element point it sits on (``locate``) and its distance, the
test points that share a model point (allowed, reported), and the observation matrix H
(test DOFs x model DOFs, sparse; ``observation``) with test DOF readings = H @ model shapes.
A test point farther than ``pair_tolerance`` from the model is an error naming it.
"""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from bayesupdate.errors import BayesUpdateError
from bayesupdate.testgeom.align import Transform, fit_pairs, from_matrix, icp
from bayesupdate.testgeom.geometry import TestGeometry
from bayesupdate.testgeom.locate import Location, Locator
from bayesupdate.testgeom.mesh import ModelMesh
from bayesupdate.testgeom.observation import observation_matrix, padded, read_weights


@dataclass(frozen=True)
class PairingSettings:
    """align: 'auto' | 'none' | a 3x4 matrix [R | t] (test coordinates in the model's length
    unit to model coordinates); pairs: ((test node, model node), ...) for 'auto' (none: ICP);
    scale: allow one uniform scale; tolerance [m]: the farthest a test point may be from the
    model; on_elements: pair with points on line elements and shell faces (else nodes only)."""

    align: str | tuple = "auto"
    pairs: tuple = ()
    scale: bool = False
    tolerance: float = 0.01
    on_elements: bool = True


@dataclass(frozen=True)
class PairedPoint:
    """One test node on the model: model_node (label of the nearest model node), element
    ('line 12', 'quad 7', ...; None when paired with the node itself), model_xyz (3,)
    [model unit], distance [model unit] from the aligned test point; coincident: labels of the
    other model nodes at model_node's position (a joint's other side: which side the test
    point is on, position cannot tell)."""

    test_node: int
    model_node: int
    element: str | None
    model_xyz: np.ndarray
    distance: float
    coincident: tuple[int, ...] = ()


@dataclass(frozen=True)
class TestPairing:
    """transform (test to model); points (one per test node the DOFs name, in first-use
    order); shared: groups of test nodes on one model point; dof_labels (n,); directions
    (n, 3) unit vectors in the model frame; sensor_dofs / sensor_weights (n, K): the rows of H
    in padded form; sensor_nodes (n,) nearest model node rows; observation: H (n, n_dof)
    csr; unit, metres: the model's length unit and metres per unit."""

    __test__ = False  # not a pytest class

    transform: Transform
    points: tuple[PairedPoint, ...]
    shared: tuple[tuple[int, ...], ...]
    dof_labels: tuple[str, ...]
    directions: np.ndarray
    sensor_dofs: np.ndarray
    sensor_weights: np.ndarray
    sensor_nodes: np.ndarray
    observation: sp.csr_matrix
    unit: str
    metres: float

    def to_dict(self) -> dict:
        """JSON-able record: ``transform`` (``matrix`` 4x4 test to model, ``rms_residual``,
        ``scale``, ``method``, ``residuals`` per aligned point), ``points`` (per test node:
        ``test_node``, ``model_node`` (null when paired with an element point), ``nearest_node``,
        ``element``, ``model_xyz``, ``distance``, ``coincident``), ``shared``, ``dofs`` (label,
        direction in the model frame) and ``length_unit`` (of every length here)."""
        t = self.transform
        points = [
            dict(test_node=p.test_node, model_node=p.model_node if p.element is None else None,
                 nearest_node=p.model_node, element=p.element,
                 model_xyz=[float(v) for v in p.model_xyz], distance=float(p.distance),
                 coincident=list(p.coincident))
            for p in self.points
        ]  # fmt: skip
        return dict(
            transform=dict(matrix=t.matrix.tolist(), rms_residual=float(t.rms), scale=t.scale,
                           method=t.method, residuals=[float(r) for r in t.residuals]),
            points=points,
            shared=[list(g) for g in self.shared],
            dofs=[dict(label=k, direction=d.tolist())
                  for k, d in zip(self.dof_labels, self.directions, strict=True)],
            length_unit=self.unit,
        )  # fmt: skip


def _transform(settings, test_xyz, geometry: TestGeometry, mesh) -> Transform:
    """The alignment of the test points (n, 3) [model unit] to ``mesh``; named pairs may name
    any node of the geometry."""
    align = settings.align
    if isinstance(align, str) and align == "none":
        return Transform(np.eye(4), 1.0, np.zeros(0), 0.0, "none")
    if not isinstance(align, str):
        return from_matrix(align, settings.scale)
    if align != "auto":
        raise BayesUpdateError(f"test.align = {align!r}: give 'auto', 'none' or a 3x4 matrix")
    if not settings.pairs:
        on_model = _on_model(mesh) if settings.on_elements else None
        return icp(test_xyz, mesh.nodes, settings.scale, refine=on_model)
    src, dst = [], []
    for test, model in settings.pairs:
        where = f"test.pairs: [{test}, {model}]"
        src.append(geometry.xyz[geometry.index(test, where)] / mesh.metres)
        dst.append(mesh.nodes[mesh.row_of(model, where)])
    return fit_pairs(src, dst, settings.scale, [f"[{t}, {m}]" for t, m in settings.pairs])


def _on_model(mesh: ModelMesh):
    """points (n, 3) -> (distances (n,), nearest model points (n, 3)): ICP's polish onto the
    elements (``locate``), or None for a mesh of nodes only."""
    if not (len(mesh.lines) or len(mesh.quads) or len(mesh.trias)):
        return None

    locator = Locator(mesh)

    def closest(points):
        found = locator(points, weights=False)
        return np.array([f.distance for f in found]), np.array([f.foot for f in found])

    return closest


def _paired_point(node, location: Location, locator: Locator) -> PairedPoint:
    ids = locator.mesh.node_ids
    element = None if location.kind == "node" else f"{location.kind} {location.element}"
    if location.kind == "edge":
        element = "shell edge " + "-".join(str(ids[n]) for n in location.nodes)
    others = tuple(int(ids[r]) for r in locator.coincident(location.nearest))
    return PairedPoint(int(node), int(ids[location.nearest]), element, location.foot,
                       location.distance, others)  # fmt: skip


def _check_distances(points, mesh: ModelMesh, tolerance: float) -> None:
    far = [p for p in points if p.distance * mesh.metres > tolerance]
    if far:
        p = max(far, key=lambda q: q.distance)
        raise BayesUpdateError(
            f"test point {p.test_node} is {p.distance:.4g} {mesh.unit} "
            f"({p.distance * mesh.metres * 1e3:.4g} mm) from the model (nearest node "
            f"{p.model_node}), beyond pair_tolerance {tolerance * 1e3:.4g} mm "
            f"({len(far)} point(s) beyond); check the alignment and length_unit, or raise it"
        )


def _shared(points, mesh) -> tuple[tuple[int, ...], ...]:
    """Groups of test nodes whose model points coincide (to 1e-9 of the model's size)."""
    size = max(float(np.ptp(mesh.nodes)), 1e-300)
    groups: list[list[int]] = []
    for i, p in enumerate(points):
        for g in groups:
            if np.linalg.norm(points[g[0]].model_xyz - p.model_xyz) <= 1e-9 * size:
                g.append(i)
                break
        else:
            groups.append([i])
    return tuple(tuple(points[i].test_node for i in g) for g in groups if len(g) > 1)


def pair_test(geometry: TestGeometry, dofs, mesh: ModelMesh, settings: PairingSettings):
    """``TestPairing`` of the test DOFs ``dofs`` (``TestDof``s) on ``mesh`` (module
    docstring); one-line errors for a bad alignment or a point beyond the tolerance."""
    dofs = tuple(dofs)
    nodes = list(dict.fromkeys(d.node for d in dofs)) or [int(n) for n in geometry.node_ids]
    rows = [geometry.index(n, "test DOF") for n in nodes]
    test_xyz = geometry.xyz[rows] / mesh.metres
    transform = _transform(settings, test_xyz, geometry, mesh)
    aligned = transform.apply(test_xyz)
    locator = Locator(mesh)
    locations = locator(aligned, settings.on_elements)
    points = tuple(_paired_point(n, loc, locator) for n, loc in zip(nodes, locations, strict=True))
    _check_distances(points, mesh, settings.tolerance)
    at = {n: i for i, n in enumerate(nodes)}
    directions = np.array([transform.rotation @ d.direction for d in dofs]).reshape(-1, 3)
    reads = [read_weights(locations[at[d.node]], u, aligned[at[d.node]])
             for d, u in zip(dofs, directions, strict=True)]  # fmt: skip
    sensor_dofs, sensor_weights = padded(reads)
    H = observation_matrix(sensor_dofs, sensor_weights, 6 * len(mesh.nodes))
    nearest = np.array([locations[at[d.node]].nearest for d in dofs], dtype=np.int64)
    return TestPairing(transform, points, _shared(points, mesh), tuple(d.label for d in dofs),
                       directions, sensor_dofs, sensor_weights, nearest, H, mesh.unit,
                       mesh.metres)  # fmt: skip
