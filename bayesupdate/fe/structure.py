"""Building a 3D frame structure in Python: nodes, beams, pipe runs with bends, point masses,
springs and sensors, every element in a named part.

``StructureBuilder`` is the user-facing, mutable builder; ``build()`` returns a frozen
``Structure`` holding plain arrays, which the assembly and solver read.  Lengths in m, masses in kg,
stiffness in N/m and N m/rad, inertia in kg m^2.

Bends follow ASME B31.3 (Appendix D): flexibility characteristic h = t R / r^2 with r the mean pipe
radius, flexibility factor k = max(1, 1.65 / h); the bend's bending stiffness is divided by k.
"""

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.constraints import Constraints
from bayesupdate.fe.elements.base import held_families
from bayesupdate.fe.sections import _SHAPE_CODE, Section
from bayesupdate.fe.shell_model import ShellElements

if TYPE_CHECKING:
    from bayesupdate.fe.elements.damper import Dampers
    from bayesupdate.fe.elements.general_beam import GeneralBeams
    from bayesupdate.fe.elements.rod import Rods
    from bayesupdate.fe.elements.scalar_mass import ScalarMasses


@dataclass(frozen=True)
class Material:
    """Linear elastic isotropic material: Young's modulus [Pa], Poisson ratio, density [kg/m^3]."""

    youngs_modulus: float
    poisson: float
    density: float
    name: str = ""

    def __post_init__(self):
        if not (self.youngs_modulus > 0 and self.density > 0 and -1 < self.poisson < 0.5):
            raise BayesUpdateError(
                f"material {self.name!r}: need E > 0, density > 0 and -1 < poisson < 0.5"
            )


STEEL = Material(210e9, 0.3, 7850.0, "steel")

#: sensor direction letters (DESIGN.md: V = vertical z, H = horizontal y) and axis names
DIRECTIONS = {
    "V": (0.0, 0.0, 1.0),
    "H": (0.0, 1.0, 0.0),
    "X": (1.0, 0.0, 0.0),
    "x": (1.0, 0.0, 0.0),
    "y": (0.0, 1.0, 0.0),
    "z": (0.0, 0.0, 1.0),
}


@dataclass(frozen=True)
class Structure:
    """A frame structure as arrays (built by ``StructureBuilder.build``).

    nodes : (N, 3) coordinates [m]; 6 DOFs per node (ux uy uz rx ry rz), DOF = 6 * node + i.
    Beams (E of them): beam_nodes (E, 2), beam_part (E,), beam_shape (E,) codes of
    ``sections.SHAPES``, beam_width / beam_height / beam_thickness (E,) [m], beam_E, beam_nu,
    beam_rho (E,), beam_up (E, 3) local-z reference, beam_bend (E,) index into ``bends`` or -1,
    beam_bend_radius (E,) [m] (0 for straight), beam_elbow (E,) bool: apply the B31.3 factor.
    Point masses (P): mass_node, mass_value [kg], mass_inertia (P, 3, 3) about their own centre
    [kg m^2], mass_offset (P, 3) from the node [m], mass_part.
    Springs (S): spring_nodes (S, 2) with -1 for ground, spring_k (S, 6) in the spring frame,
    spring_frame (S, 3, 3) rows = spring axes in global coordinates, spring_part;
    spring_offset None (every spring acts on its nodes' own DOFs) or (S, 2, 3) [m] from node A
    and node B to the spring's location (``fe.elements.spring``: Nastran CBUSH with separated ends).
    Sensors: sensor_labels, sensor_node, sensor_direction (n_s, 3) unit vectors.
    parts, bends : names.
    beam_shear_factor : None (each section's own shear areas) or (E,) shear area / area imposed
    on both axes where > 0 (a Nastran PBARL ROD has 0.9, not Cowper's value).
    shells : ``ShellElements`` or None; constraints : supports and rigid elements
    (``constraints.Constraints``) or None.  A structure with either is solved on the sparse path
    (``fe.assembly``); without them it is the beam structure of before, solved as before.
    general_beams : ``general_beam.GeneralBeams`` (arbitrary sections, offsets, pin flags) or
    None; rods : ``rod.Rods`` or None; either also puts the structure on the sparse path.
    dampers : ``damper.Dampers`` or None: viscous dampers as data (normal modes ignore them).
    scalar_masses : ``scalar_mass.ScalarMasses`` or None (Nastran CMASS1/CMASS2).
    sensor_read : None (each sensor reads its node's translations along its direction) or
    (DOFs (n_s, K), weights (n_s, K)): sensor s reads sum_k weights[s, k] * shape[DOFs[s, k]]
    (a test point between nodes, interpolated with a rigid arm: ``testgeom.observation``).
    elements : instances of registered element families with no field of their own
    (``fe.elements.base``: assembled, in the energies, the mass and the reduced basis).
    """

    nodes: np.ndarray
    beam_nodes: np.ndarray
    beam_part: np.ndarray
    beam_shape: np.ndarray
    beam_width: np.ndarray
    beam_height: np.ndarray
    beam_thickness: np.ndarray
    beam_E: np.ndarray
    beam_nu: np.ndarray
    beam_rho: np.ndarray
    beam_up: np.ndarray
    beam_bend: np.ndarray
    beam_bend_radius: np.ndarray
    beam_elbow: np.ndarray
    mass_node: np.ndarray
    mass_value: np.ndarray
    mass_inertia: np.ndarray
    mass_offset: np.ndarray
    mass_part: np.ndarray
    spring_nodes: np.ndarray
    spring_k: np.ndarray
    spring_frame: np.ndarray
    spring_part: np.ndarray
    sensor_labels: tuple[str, ...]
    sensor_node: np.ndarray
    sensor_direction: np.ndarray
    parts: tuple[str, ...]
    bends: tuple[str, ...]
    shear: bool = True
    rotary_inertia: bool = True
    metadata: dict = field(default_factory=dict, compare=False)
    shells: ShellElements | None = None
    constraints: Constraints | None = None
    beam_shear_factor: np.ndarray | None = None
    general_beams: "GeneralBeams | None" = None
    rods: "Rods | None" = None
    dampers: "Dampers | None" = None
    spring_offset: np.ndarray | None = None
    scalar_masses: "ScalarMasses | None" = None
    sensor_read: tuple[np.ndarray, np.ndarray] | None = None
    elements: tuple = ()

    def spring_offsets(self) -> np.ndarray:
        """(S, 2, 3) offsets [m] from each spring's nodes to its location (zeros: at the
        nodes)."""
        n = len(self.spring_part)
        if self.spring_offset is None:
            return np.zeros((n, 2, 3))
        if self.spring_offset.shape != (n, 2, 3):
            raise BayesUpdateError(
                f"structure: spring_offset has shape {self.spring_offset.shape}, needs "
                f"({n}, 2, 3) (one per spring; fe.modify.with_spring keeps them in step)"
            )
        return self.spring_offset

    @property
    def is_general(self) -> bool:
        """True if the structure has shells, supports, rigid elements, node frames, general
        beams or rods."""
        return (
            self.shells is not None
            or (self.constraints is not None and not self.constraints.is_empty)
            or self.general_beams is not None
            or self.rods is not None
        )

    @property
    def n_nodes(self) -> int:
        return int(self.nodes.shape[0])

    @property
    def n_dof(self) -> int:
        return 6 * self.n_nodes

    def part_index(self, name: str) -> int:
        if name not in self.parts:
            raise BayesUpdateError(f"unknown part {name!r}; parts are {list(self.parts)}")
        return self.parts.index(name)

    def sensor_dofs(self) -> tuple[np.ndarray, np.ndarray]:
        """DOF indices (n_s, K) each sensor reads and their weights (n_s, K): its node's
        translations (K = 3) and its direction, or ``sensor_read``."""
        if self.sensor_read is not None:
            return self.sensor_read
        dofs = 6 * self.sensor_node[:, None] + np.arange(3)[None, :]
        return dofs, self.sensor_direction


class StructureBuilder:
    """Mutable builder of a ``Structure``.

    Example
    -------
    >>> b = StructureBuilder()
    >>> n = b.add_pipe_run([(0, 0, 0), (1, 0, 0), (1, 1, 0)], circular_tube(0.045, 1.5e-3), STEEL,
    ...                    part="pipe", bend_radii=[0.1], bend_names=["elbow"])
    >>> s = b.build()
    """

    def __init__(self, shear: bool = True, rotary_inertia: bool = True):
        self._nodes: list[tuple[float, float, float]] = []
        self._beams: list[dict] = []
        self._masses: list[dict] = []
        self._springs: list[dict] = []
        self._sensors: list[tuple[str, int, tuple]] = []
        self._parts: list[str] = []
        self._bends: list[str] = []
        self.shear = shear
        self.rotary_inertia = rotary_inertia
        self.metadata: dict = {}
        #: how the connectivity check names node k (e.g. a Nastran deck's "GRID 1203"); None:
        #: "node k"
        self.node_names = None
        self._shell_blocks: list[dict] = []
        self._supports: list[tuple[int, np.ndarray]] = []
        self._rbe2: list[tuple[int, list[int], np.ndarray]] = []
        self._rbe3: list[tuple] = []  # (reference, components, nodes, weights, node sets, UM)
        self._mpcs: list[list[tuple[int, int, float]]] = []  # (node, component 0-5, coef)
        self._general_beams: list = []
        self._rods: list = []
        self._frames: dict[int, np.ndarray] = {}
        self._dampers: list[dict] = []
        self._scalar_masses: list[dict] = []

    # -- nodes and parts ------------------------------------------------------------------
    def add_node(self, xyz) -> int:
        p = tuple(float(v) for v in xyz)
        if len(p) != 3 or not all(np.isfinite(p)):
            raise BayesUpdateError(f"node coordinates must be 3 finite numbers, got {xyz}")
        self._nodes.append(p)
        return len(self._nodes) - 1

    def node_xyz(self, node: int) -> np.ndarray:
        return np.array(self._nodes[node])

    def _part(self, name: str) -> int:
        if not name or not isinstance(name, str):
            raise BayesUpdateError("every element needs a part name (a non-empty string)")
        if name not in self._parts:
            self._parts.append(name)
        return self._parts.index(name)

    def _check_node(self, node):
        if not (0 <= int(node) < len(self._nodes)):
            raise BayesUpdateError(f"node {node} does not exist (there are {len(self._nodes)})")
        return int(node)

    # -- elements ---------------------------------------------------------------------------
    def add_beam(
        self,
        n1,
        n2,
        section: Section,
        material: Material,
        part: str,
        up=None,
        bend: str | None = None,
        bend_radius: float = 0.0,
        elbow_flexibility: bool = True,
    ) -> int:
        """One beam element between existing nodes.  ``up``: local z reference (default global
        z, or global y for a vertical element).  Returns the element index."""
        n1, n2 = self._check_node(n1), self._check_node(n2)
        x1, x2 = self.node_xyz(n1), self.node_xyz(n2)
        axis = x2 - x1
        length = np.linalg.norm(axis)
        if length <= 0:
            raise BayesUpdateError(f"beam in part {part!r}: nodes {n1} and {n2} coincide")
        if up is None:
            up = (0.0, 0.0, 1.0) if abs(axis[2]) < 0.99 * length else (0.0, 1.0, 0.0)
        up = np.asarray(up, dtype=float)
        if np.linalg.norm(np.cross(up, axis)) < 1e-6 * length * np.linalg.norm(up):
            raise BayesUpdateError(f"beam in part {part!r}: 'up' vector is parallel to the beam")
        bend_index = -1
        if bend is not None:
            if bend not in self._bends:
                self._bends.append(bend)
            bend_index = self._bends.index(bend)
        self._beams.append(
            dict(
                nodes=(n1, n2),
                part=self._part(part),
                section=section,
                material=material,
                up=tuple(up),
                bend=bend_index,
                bend_radius=float(bend_radius),
                elbow=bool(elbow_flexibility),
            )
        )
        return len(self._beams) - 1

    def add_line(self, n1, n2, section, material, part, element_length=0.1, up=None) -> list[int]:
        """A straight run from node n1 to node n2 meshed into equal elements no longer than
        ``element_length``.  Returns the node indices along the run (n1 first, n2 last)."""
        n1, n2 = self._check_node(n1), self._check_node(n2)
        x1, x2 = self.node_xyz(n1), self.node_xyz(n2)
        n_el = max(1, int(np.ceil(np.linalg.norm(x2 - x1) / element_length - 1e-9)))
        ids = [n1]
        for k in range(1, n_el):
            ids.append(self.add_node(x1 + (x2 - x1) * k / n_el))
        ids.append(n2)
        for a, b in zip(ids[:-1], ids[1:], strict=True):
            self.add_beam(a, b, section, material, part, up=up)
        return ids

    def add_pipe_run(
        self,
        points,
        section: Section,
        material: Material,
        part: str,
        bend_radii=None,
        bend_names=None,
        element_length: float = 0.1,
        max_bend_angle_deg: float = 15.0,
        start_node: int | None = None,
        end_node: int | None = None,
        elbow_flexibility: bool = True,
        up=None,
    ) -> list[int]:
        """A pipe along a centre-line polyline with circular-arc bends at its interior vertices.

        points : (k, 3) polyline vertices [m].  bend_radii : (k-2,) bend radius at each interior
        vertex (0 = sharp corner).  bend_names : optional names (None entries allowed), used by
        ``bend_flexibility@NAME``.  Arcs are meshed into straight elements spanning at most
        ``max_bend_angle_deg``.  ``start_node`` / ``end_node`` reuse existing nodes (must coincide
        with the first / last point).  Returns the node indices along the run.
        """
        pts = np.asarray(points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 3 or len(pts) < 2:
            raise BayesUpdateError(f"pipe run {part!r}: points must be (k>=2, 3)")
        k_int = len(pts) - 2
        radii = np.zeros(k_int) if bend_radii is None else np.asarray(bend_radii, dtype=float)
        names = [None] * k_int if bend_names is None else list(bend_names)
        if radii.shape != (k_int,) or len(names) != k_int:
            raise BayesUpdateError(
                f"pipe run {part!r}: need one bend radius/name per interior vertex ({k_int})"
            )
        path = _centre_line(pts, radii, names, 0.5 * section.width, part)
        ids = [self._run_end(start_node, pts[0], f"pipe run {part!r}: start_node")]
        beam = dict(up=up, elbow_flexibility=elbow_flexibility)
        for seg_index, seg in enumerate(path):
            default_name = f"{part}_bend{len(self._bends)}"
            new_pts, bend_info = _segment_points(
                seg, element_length, max_bend_angle_deg, default_name
            )
            last_segment = seg_index == len(path) - 1
            for j, p in enumerate(new_pts):
                last = last_segment and j == len(new_pts) - 1
                nid = self._run_end(end_node if last else None, p, f"pipe run {part!r}: end_node")
                bname, R = bend_info[j]
                self.add_beam(
                    ids[-1], nid, section, material, part, bend=bname, bend_radius=R, **beam
                )
                ids.append(nid)
        return ids

    def _run_end(self, node: int | None, xyz: np.ndarray, what: str) -> int:
        """``node`` checked to lie at ``xyz`` [m], or a new node there when None."""
        if node is None:
            return self.add_node(xyz)
        if np.linalg.norm(self.node_xyz(node) - xyz) > 1e-9:
            raise BayesUpdateError(f"{what} is not at the run's end point")
        return self._check_node(node)

    def add_point_mass(self, node, mass: float, part: str, inertia=None, offset=(0, 0, 0)) -> int:
        """Rigid point mass [kg] with a 3x3 inertia tensor about its own centre [kg m^2] (global
        axes), at ``offset`` [m] from ``node`` (rigid link)."""
        node = self._check_node(node)
        if not np.isfinite(mass) or mass < 0:
            raise BayesUpdateError(f"point mass in part {part!r}: mass must be >= 0 kg, got {mass}")
        J = np.zeros((3, 3)) if inertia is None else np.asarray(inertia, dtype=float)
        if J.shape == (3,):
            J = np.diag(J)
        if J.shape != (3, 3) or np.any(np.linalg.eigvalsh(0.5 * (J + J.T)) < -1e-12):
            raise BayesUpdateError(f"point mass in part {part!r}: inertia must be a 3x3 PSD tensor")
        self._masses.append(
            dict(
                node=node,
                mass=float(mass),
                inertia=0.5 * (J + J.T),
                offset=np.asarray(offset, dtype=float),
                part=self._part(part),
            )
        )
        return len(self._masses) - 1

    def add_spring(self, node_a, node_b, stiffness, part: str, frame=None, location=None) -> int:
        """6-DOF spring between ``node_a`` and ``node_b`` (None = ground).

        stiffness : 6 values (kx, ky, kz [N/m], krx, kry, krz [N m/rad]) along the rows of
        ``frame`` (3x3, default global axes).  location : None (the spring acts on the nodes' own
        DOFs: meant for coincident nodes) or the point p (3,) [m] where it acts, rigidly linked to
        both nodes (``fe.elements.spring``, Nastran CBUSH: a point on GA-GB at S, or an OCID
        offset): the
        springs see the relative motion at p, so separated ends keep moment equilibrium."""
        node_a = self._check_node(node_a)
        node_b = -1 if node_b is None else self._check_node(node_b)
        k, R = _six_along_frame(stiffness, frame, f"spring in part {part!r}: stiffness")
        offset = self._location(node_a, node_b, location, f"spring in part {part!r}")
        self._springs.append(
            dict(nodes=(node_a, node_b), k=k, frame=R, part=self._part(part), offset=offset)
        )
        return len(self._springs) - 1

    def _location(self, node_a: int, node_b: int, location, what: str) -> np.ndarray:
        """(2, 3) offsets [m] from the nodes to ``location`` (zeros for None)."""
        if location is None:
            return np.zeros((2, 3))
        p = np.asarray(location, dtype=float)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise BayesUpdateError(f"{what}: location must be 3 finite coordinates [m]")
        from bayesupdate.fe.elements.spring import location_offsets

        xb = None if node_b < 0 else self.node_xyz(node_b)
        return location_offsets(self.node_xyz(node_a), xb, p)

    def add_scalar_mass(
        self, node_a, component_a, mass: float, part: str, node_b=None, component_b=None,
        frame_a=None, frame_b=None,
    ) -> int:  # fmt: skip
        """Scalar mass between one DOF of ``node_a`` and one of ``node_b`` (None = ground):
        Nastran CMASS1/CMASS2 (``fe.elements.scalar_mass``), M = [[m, -m], [-m, m]] on the two DOFs.

        component_a, component_b : 1-6 or a name ('ux' ... 'rz'): a translation or rotation of
        the node's displacement frame ``frame_a`` / ``frame_b`` (3x3, rows = its axes in global
        coordinates; default global axes); or a unit vector (6,) on the node's six global DOFs
        (a mode of a 6x6 mass matrix, Nastran CONM1; the frame is then unused).  mass : >= 0,
        in kg on a translation and kg m^2 on a rotation (a rotary inertia about that axis).
        Returns the element index."""
        what = f"scalar mass in part {part!r}"
        node_a = self._check_node(node_a)
        node_b = -1 if node_b is None else self._check_node(node_b)
        if not (np.isfinite(mass) and mass >= 0):
            raise BayesUpdateError(f"{what}: mass must be finite and >= 0, got {mass}")
        if (node_b >= 0) != (component_b is not None):
            raise BayesUpdateError(f"{what}: give node_b and component_b together (or neither)")
        dirs = np.zeros((2, 6))
        ends = [(node_a, component_a, frame_a)]
        if node_b >= 0:
            ends.append((node_b, component_b, frame_b))
        for end, (node, comp, frame) in enumerate(ends):
            dirs[end] = _scalar_direction(comp, frame, f"{what}: node {node}")
        self._scalar_masses.append(
            dict(nodes=(node_a, node_b), direction=dirs, mass=float(mass), part=self._part(part))
        )
        return len(self._scalar_masses) - 1

    def add_damper(self, node_a, node_b, damping, part: str, frame=None, location=None) -> int:
        """6-component viscous damper between ``node_a`` and ``node_b`` (None = ground), kept as
        data (``fe.elements.damper``: normal modes ignore it; ``damping_matrix`` gives C).

        damping : 6 values (cx, cy, cz [N s/m], crx, cry, crz [N m s/rad]) along the rows of
        ``frame`` (3x3, default global axes); location : as ``add_spring``."""
        node_a = self._check_node(node_a)
        node_b = -1 if node_b is None else self._check_node(node_b)
        c, R = _six_along_frame(damping, frame, f"damper in part {part!r}: damping")
        offset = self._location(node_a, node_b, location, f"damper in part {part!r}")
        self._dampers.append(
            dict(nodes=(node_a, node_b), c=c, frame=R, part=self._part(part), offset=offset)
        )
        return len(self._dampers) - 1

    # -- shells, supports and rigid elements (``fe.builder_elements``) --------------------------
    def add_shells(self, points, quads=None, trias=None, *, thickness, material, part, **kw):
        """Flat shell elements on ``points`` (n, 3) [m]; see ``builder_elements.add_shells``.
        Returns the structure node number of each point (points on existing nodes reuse them)."""
        from bayesupdate.fe.builder_elements import add_shells

        return add_shells(self, points, quads, trias, thickness, material, part, **kw)

    def add_support(self, node, components="123456") -> None:
        """Single-point constraint: hold ``components`` of ``node`` at zero ('123456' = all,
        '123' = translations, or names such as ('uz', 'rx'))."""
        from bayesupdate.fe.constraints import parse_components

        node = self._check_node(node)
        self._supports.append((node, parse_components(components, f"support at node {node}")))

    def add_mpc(self, terms) -> int:
        """Multipoint constraint sum_i coef_i u_i = 0 over ``terms`` [(node, component digit
        1-6 or name, coef)], the first term's DOF dependent (Nastran MPC, exact elimination).
        Returns the equation's number used in error messages."""
        from bayesupdate.fe.constraints import parse_components

        i = len(self._mpcs)
        out = []
        for node, component, coef in terms:
            mask = parse_components(component, f"mpc {i}")
            if mask.sum() != 1 or not np.isfinite(coef):
                raise BayesUpdateError(f"mpc {i}: each term needs one component and a finite "
                                       f"coefficient, got {component!r}, {coef!r}")  # fmt: skip
            out.append((self._check_node(node), int(np.flatnonzero(mask)[0]), float(coef)))
        if len(out) < 2:  # a zero first coefficient is refused by the elimination itself
            raise BayesUpdateError(f"mpc {i}: needs two terms or more")
        self._mpcs.append(out)
        return i

    def add_rbe2(self, independent, dependents, components="123456") -> int:
        """Rigid element: ``components`` of every dependent node follow ``independent`` rigidly
        (exact elimination).  Returns the RBE2 number used in error messages."""
        from bayesupdate.fe.constraints import parse_components

        i = len(self._rbe2)
        deps = [self._check_node(d) for d in np.atleast_1d(dependents)]
        ind = self._check_node(independent)
        if not deps or ind in deps:
            raise BayesUpdateError(
                f"rbe2 {i}: needs dependent nodes other than its independent node {ind}"
            )
        self._rbe2.append((ind, deps, parse_components(components, f"rbe2 {i}")))
        return i

    def add_rbe3(
        self, reference, nodes, weights=None, components="123456", node_components="123", um=None
    ) -> int:
        """Interpolation element: ``components`` of ``reference`` become the weighted
        least-squares rigid motion of ``nodes`` (their ``node_components``: one set for all, or
        a list of one set per node, as Nastran RBE3's weight groups give them; weights default
        1).  um : None, or [(node, components)], the DOFs made dependent instead of the
        reference's (Nastran RBE3 UM; as many as ``components``, on the element's nodes or
        reference).  Adds no stiffness.  Returns the RBE3 number used in error messages."""
        from bayesupdate.fe.constraints import parse_components

        i = len(self._rbe3)
        ref = self._check_node(reference)
        ns = [self._check_node(n) for n in np.atleast_1d(nodes)]
        w = np.ones(len(ns)) if weights is None else np.asarray(weights, dtype=float).ravel()
        if not ns or ref in ns or w.shape != (len(ns),) or not np.all(np.isfinite(w) & (w > 0)):
            raise BayesUpdateError(
                f"rbe3 {i}: needs nodes other than its reference {ref} and one weight > 0 each"
            )
        ref_c = parse_components(components, f"rbe3 {i}")
        # a list of digit sets is one set per node (a list of names is one set)
        per_node = isinstance(node_components, list | tuple) and all(
            isinstance(c, int | np.integer) or (isinstance(c, str) and c.isdigit())
            for c in node_components
        )
        each = list(node_components) if per_node else [node_components] * len(ns)
        if len(each) != len(ns):
            raise BayesUpdateError(f"rbe3 {i}: give one node_components set or one per node")
        node_c = [parse_components(c, f"rbe3 {i} node_components") for c in each]
        um_sets = [(self._check_node(n), parse_components(c, f"rbe3 {i} um")) for n, c in um or ()]
        self._rbe3.append((ref, ref_c, ns, w, node_c, um_sets))
        return i

    # -- general beams, rods and node frames (``fe.builder_elements``) ---------------------------
    def add_beams(self, node_pairs, section, material, part, **kw) -> np.ndarray:
        """General beams on node pairs (n, 2): any ``standard_sections.BeamSection``, optional
        ``up``, ``offsets``, ``pins``, ``mass``, ``nsm`` (``builder_elements.add_beams``).
        Returns their element indices."""
        from bayesupdate.fe.builder_elements import add_beams

        return add_beams(self, node_pairs, section, material, part, **kw)

    def add_rods(self, node_pairs, area, material, part, **kw) -> np.ndarray:
        """Axial rods (truss members) on node pairs (n, 2), area [m^2]; optional ``torsion``,
        ``nsm``, ``mass`` (``builder_elements.add_rods``).  Returns their element indices."""
        from bayesupdate.fe.builder_elements import add_rods

        return add_rods(self, node_pairs, area, material, part, **kw)

    def set_frame(self, nodes, frame) -> None:
        """DOF axes of ``nodes`` from a ``frames.CoordinateFrame`` (rectangular, cylindrical,
        spherical): supports and rigid-element components on them act in those axes."""
        from bayesupdate.fe.builder_elements import set_frame

        set_frame(self, nodes, frame)

    def add_sensor(self, label: str, node, direction) -> None:
        """A measurement DOF: translation of ``node`` along ``direction`` ('V', 'H', 'x', ... or a
        vector)."""
        node = self._check_node(node)
        if isinstance(direction, str):
            if direction not in DIRECTIONS:
                raise BayesUpdateError(f"sensor {label}: unknown direction {direction!r}")
            direction = DIRECTIONS[direction]
        d = np.asarray(direction, dtype=float)
        d = d / np.linalg.norm(d)
        if any(s[0] == label for s in self._sensors):
            raise BayesUpdateError(f"sensor label {label!r} used twice")
        self._sensors.append((str(label), node, tuple(d)))

    # -- build ---------------------------------------------------------------------------------
    def build(self, check: bool = True) -> "Structure":
        """The ``Structure``; ``check``: every node used and the structure in one piece
        (``check_connected``); off for a part of a structure (a deck's re-built elements)."""
        if not self._nodes:
            raise BayesUpdateError("the structure has no nodes")
        beams = self._beams
        nb = len(beams)

        def col(fn, dtype=float):
            return np.array([fn(b) for b in beams], dtype=dtype).reshape(nb, *([] if nb else []))

        structure = Structure(
            nodes=np.array(self._nodes, dtype=float),
            beam_nodes=np.array([b["nodes"] for b in beams], dtype=int).reshape(nb, 2),
            beam_part=col(lambda b: b["part"], int),
            beam_shape=col(lambda b: _SHAPE_CODE[b["section"].shape], int),
            beam_width=col(lambda b: b["section"].width),
            beam_height=col(lambda b: b["section"].height),
            beam_thickness=col(lambda b: b["section"].thickness),
            beam_E=col(lambda b: b["material"].youngs_modulus),
            beam_nu=col(lambda b: b["material"].poisson),
            beam_rho=col(lambda b: b["material"].density),
            beam_up=np.array([b["up"] for b in beams], dtype=float).reshape(nb, 3),
            beam_bend=col(lambda b: b["bend"], int),
            beam_bend_radius=col(lambda b: b["bend_radius"]),
            beam_elbow=col(lambda b: b["elbow"], bool),
            mass_node=np.array([m["node"] for m in self._masses], dtype=int),
            mass_value=np.array([m["mass"] for m in self._masses], dtype=float),
            mass_inertia=np.array([m["inertia"] for m in self._masses]).reshape(-1, 3, 3),
            mass_offset=np.array([m["offset"] for m in self._masses]).reshape(-1, 3),
            mass_part=np.array([m["part"] for m in self._masses], dtype=int),
            spring_nodes=np.array([s["nodes"] for s in self._springs], dtype=int).reshape(-1, 2),
            spring_k=np.array([s["k"] for s in self._springs]).reshape(-1, 6),
            spring_frame=np.array([s["frame"] for s in self._springs]).reshape(-1, 3, 3),
            spring_part=np.array([s["part"] for s in self._springs], dtype=int),
            spring_offset=_spring_offsets(self._springs),
            sensor_labels=tuple(s[0] for s in self._sensors),
            sensor_node=np.array([s[1] for s in self._sensors], dtype=int),
            sensor_direction=np.array([s[2] for s in self._sensors], dtype=float).reshape(-1, 3),
            parts=tuple(self._parts),
            bends=tuple(self._bends),
            shear=self.shear,
            rotary_inertia=self.rotary_inertia,
            metadata=dict(self.metadata),
        )
        if self._dampers:
            structure = replace(structure, dampers=_dampers(self._dampers))
        if self._scalar_masses:
            structure = replace(structure, scalar_masses=_scalar_masses(self._scalar_masses))
        general = (self._general_beams, self._rods, self._frames)
        constraints = (self._supports, self._rbe2, self._rbe3, self._mpcs)
        if self._shell_blocks or any(constraints) or any(general):
            from bayesupdate.fe.builder_elements import general_parts

            structure = replace(structure, **general_parts(self))
        if check:
            check_connected(structure, self.node_names)
        return structure


def _six_along_frame(values, frame, what: str) -> tuple[np.ndarray, np.ndarray]:
    """(6,) values >= 0 of a spring or damper and its frame (3, 3) rotation (default global
    axes), checked; ``what`` names the element and quantity in the error."""
    v = np.asarray(values, dtype=float).reshape(-1)
    if v.shape != (6,) or np.any(~np.isfinite(v)) or np.any(v < 0):
        raise BayesUpdateError(f"{what} must be 6 values >= 0")
    R = np.eye(3) if frame is None else np.asarray(frame, dtype=float)
    if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-9):
        raise BayesUpdateError(f"{what.rsplit(':', 1)[0]}: frame must be a 3x3 rotation")
    return v, R


def _spring_offsets(records: list[dict]) -> np.ndarray | None:
    """(S, 2, 3) spring (or damper) offsets, or None when every one acts at its nodes."""
    if not any(np.any(r["offset"]) for r in records):
        return None
    return np.array([r["offset"] for r in records], dtype=float)


def _scalar_direction(component, frame, what: str) -> np.ndarray:
    from bayesupdate.fe.constraints import parse_components
    from bayesupdate.fe.elements.scalar_mass import component_direction

    if not isinstance(component, str | int | np.integer) and np.size(component) == 6:
        d = np.asarray(component, dtype=float).reshape(6)
        if not np.all(np.isfinite(d)) or abs(np.linalg.norm(d) - 1) > 1e-9:
            raise BayesUpdateError(f"{what}: a direction must be 6 finite values of norm 1")
        return d
    mask = parse_components(component, what)
    if mask.sum() != 1:
        raise BayesUpdateError(f"{what}: needs exactly one component (1-6), got {component!r}")
    R = np.eye(3) if frame is None else np.asarray(frame, dtype=float)
    if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-9):
        raise BayesUpdateError(f"{what}: frame must be a 3x3 rotation")
    return component_direction(int(np.flatnonzero(mask)[0]), R)


def _scalar_masses(records: list[dict]) -> "ScalarMasses":
    from bayesupdate.fe.elements.scalar_mass import ScalarMasses

    return ScalarMasses(
        nodes=np.array([r["nodes"] for r in records], dtype=int),
        direction=np.array([r["direction"] for r in records], dtype=float),
        mass=np.array([r["mass"] for r in records], dtype=float),
        part=np.array([r["part"] for r in records], dtype=int),
    )


def _dampers(records: list[dict]) -> "Dampers":
    from bayesupdate.fe.elements.damper import Dampers

    return Dampers(
        nodes=np.array([d["nodes"] for d in records], dtype=int),
        damping=np.array([d["c"] for d in records]),
        frame=np.array([d["frame"] for d in records]),
        part=np.array([d["part"] for d in records], dtype=int),
        offset=_spring_offsets(records),
    )


def check_connected(structure: Structure, node_names=None) -> None:
    """Raise BayesUpdateError if some nodes are not connected to the rest by any element.

    node_names : callable node index -> its name in the message (a deck's GRID id); None:
    "node k"."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    def name(nodes) -> str:
        return ", ".join(node_names(int(k)) if node_names else str(int(k)) for k in nodes)

    n = structure.n_nodes
    pairs = [structure.beam_nodes]
    sp = structure.spring_nodes[(structure.spring_nodes >= 0).all(axis=1)]
    pairs.append(sp)
    if structure.shells is not None:
        pairs.append(structure.shells.edges())
    if structure.constraints is not None:
        pairs.append(structure.constraints.edges())
    family_nodes = [f.nodes.reshape(f.n_elements, -1) for f in held_families(structure)]
    for nodes in family_nodes:
        # an element joins its nodes; one with a grounded end (-1) joins none
        joined = nodes[(nodes >= 0).all(axis=1)]
        pairs.append(np.stack([joined[:, :-1], joined[:, 1:]], axis=-1))
    edges = np.concatenate([p.reshape(-1, 2) for p in pairs], axis=0)
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    n_comp, labels = connected_components(graph, directed=False)
    used = np.zeros(n, bool)
    used[edges.ravel()] = True
    used[structure.mass_node] = True
    used[structure.spring_nodes[:, 0]] = True
    for nodes in family_nodes:
        used[nodes[nodes >= 0]] = True
    if structure.is_general and not np.all(used):
        raise BayesUpdateError(
            f"node {name(np.flatnonzero(~used)[:1])} is used by no element; remove it or connect it"
        )
    if n_comp > 1:
        sizes = np.bincount(labels)
        main = np.argmax(sizes)
        lonely = np.flatnonzero(labels != main)
        raise BayesUpdateError(
            f"the structure is disconnected: {n_comp} separate pieces; nodes {name(lonely[:10])}"
            f"{' ...' if lonely.size > 10 else ''} are not connected to the main piece of "
            f"{sizes[main]} nodes (add a beam or spring)"
        )


def _element_count(ratio: float, length: float) -> int:
    """ceil(``ratio``) elements (at least 1) for a segment ``length`` [m] long, refused above
    ``MAX_SEGMENT_ELEMENTS``."""
    if not ratio <= MAX_SEGMENT_ELEMENTS:  # NaN and inf too
        raise BayesUpdateError(
            f"a pipe segment {length:.4g} m long would need more than {MAX_SEGMENT_ELEMENTS} "
            "elements; check the geometry's lengths (metres)"
        )
    return max(1, int(np.ceil(ratio - 1e-9)))


def _centre_line(pts: np.ndarray, radii: np.ndarray, names: list, outer_radius: float, part: str):
    """A pipe run's centre-line as segments: ("line", a, b) straight from a to b [m], or
    ("arc", centre, u, v, R, angle, name) a circular bend of radius R [m] through ``angle`` [rad]
    starting at centre + R u, turning towards v; sharp corners where the radius is 0."""
    path = []
    cursor = pts[0]
    for i in range(1, len(pts) - 1):
        d1 = pts[i] - pts[i - 1]
        d2 = pts[i + 1] - pts[i]
        d1 /= np.linalg.norm(d1)
        d2 /= np.linalg.norm(d2)
        angle = np.arccos(np.clip(d1 @ d2, -1.0, 1.0))
        R = radii[i - 1]
        if R > 0 and R <= outer_radius:
            raise BayesUpdateError(
                f"pipe run {part!r}: bend radius {R} m at vertex {i} is not larger than the "
                f"pipe's outer radius {outer_radius} m"
            )
        if R <= 0 or angle < 1e-9:
            path.append(("line", cursor, pts[i]))
            cursor = pts[i]
            continue
        tangent = R * np.tan(angle / 2)
        a = pts[i] - tangent * d1
        b = pts[i] + tangent * d2
        if (
            tangent > np.linalg.norm(pts[i] - cursor) + 1e-12
            or tangent > np.linalg.norm(pts[i + 1] - pts[i]) + 1e-12
        ):
            raise BayesUpdateError(
                f"pipe run {part!r}: bend radius {R} m at vertex {i} does not fit between "
                "the neighbouring straight segments"
            )
        normal = d2 - (d1 @ d2) * d1
        normal /= np.linalg.norm(normal)
        centre = a + R * normal
        if np.linalg.norm(a - cursor) > 1e-12:
            path.append(("line", cursor, a))
        path.append(("arc", centre, -normal, d1, R, angle, names[i - 1]))
        cursor = b
    path.append(("line", cursor, pts[-1]))
    return path


#: most beam elements one centre-line segment of a pipe run may take (a longer one is a typo)
MAX_SEGMENT_ELEMENTS = 100_000


def _segment_points(seg, element_length: float, max_bend_angle_deg: float, default_name: str):
    """Element end points of one centre-line segment (``_centre_line``) and (bend name, radius)
    per element: at most ``element_length`` [m] long, arcs also at most ``max_bend_angle_deg``."""
    if seg[0] == "line":
        _, a, b = seg
        length = np.linalg.norm(b - a)
        if length < 1e-12:
            return [], []
        n_el = _element_count(length / element_length, length)
        return [a + (b - a) * j / n_el for j in range(1, n_el + 1)], [(None, 0.0)] * n_el
    _, centre, u, v, R, angle, name = seg
    n_el = max(
        2,
        int(np.ceil(np.degrees(angle) / max_bend_angle_deg - 1e-9)),
        _element_count(R * angle / element_length, R * angle),
    )
    phis = angle * np.arange(1, n_el + 1) / n_el
    new_pts = [centre + R * (np.cos(p) * u + np.sin(p) * v) for p in phis]
    return new_pts, [(name if name is not None else default_name, R)] * n_el
