"""Build the same frame model in OpenSeesPy as a bayesupdate ``Structure`` (peer check only).

Used by ``benchmarks/fe_speed.py`` and ``tests/test_fe_peer_opensees.py``; never by the package.
The two codes share only the section numbers (``bayesupdate.fe.sections.section_properties``) and
the geometry; element matrices, rigid links, springs, assembly and the eigen-solver are OpenSees'.

Like-for-like mapping (checked against OpenSees' element source, ElasticTimoshenkoBeam3d.cpp and
ElasticBeam3d.cpp, and by extracting their 12x12 matrices):

* ``shear=True, rotary_inertia=True`` -> ``ElasticTimoshenkoBeam -cMass``: its consistent mass is
  Przemieniecki's Timoshenko mass *including* rotary inertia (the same as bayesupdate's).
* ``shear=False, rotary_inertia=False`` -> ``elasticBeamColumn -cMass``: classical 1/420
  Euler-Bernoulli consistent mass, no rotary inertia.
* Torsional inertia: OpenSees uses rho * J (torsion constant), bayesupdate the polar moment
  rho * (Iy + Iz) (they differ for the oval tube).  Passed exactly by giving OpenSees
  Jx' = Iy + Iz, G' = G J / Jx' and shear areas A_v' = A_v Jx' / J, which leave G J, G A_v and all
  other terms unchanged.
* ASME B31.3 elbow factor k (bend elements, EI / k): re-implemented here from the formula
  (k = max(1, 1.65 / h), h = t R / r^2, r mean radius) and passed as Iy / k, Iz / k.  That is
  exact only without rotary inertia (OpenSees' rotary inertia is rho Iy, so it would also be
  divided by k); with rotary inertia a structure with k > 1 is refused.
* Point masses: nodal ``mass`` at a node at the mass centre, tied by ``rigidLink beam`` to its
  node (``constraints Transformation``).  OpenSees nodal mass is diagonal, so a non-diagonal
  inertia tensor is represented exactly by three pairs of translational masses at +-d along its
  principal axes (q_k = 2 m_k d^2 = (I_1 + I_2 + I_3) / 2 - I_k), also rigidly linked.
* Springs: ``zeroLength`` with six ``Elastic`` uniaxial materials, ``-orient`` = spring frame;
  springs to ground end on a fixed extra node.

Eigen-solver: ``-fullGenLapack`` (dense QZ) handles the free-free (singular K) problem; the rigid
modes come out as ~0 eigenvalues and are dropped by count.  QZ on the whole singular pencil
carries round-off of ~1e-10 (Timoshenko exhaust) to ~5e-9 (Euler-Bernoulli exhaust) on the
lowest elastic frequencies, on OpenSees' matrices and on ours alike (scipy's ``eig(K, M)``), so
the like-for-like comparison (``like_for_like``) reads OpenSees' own assembled K and M
(``opensees_matrices``) and puts both pencils through one accurate solver.
"""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

try:  # optional peer: the example frame is usable without it
    import openseespy.opensees as ops
except ImportError:  # pragma: no cover
    ops = None

from bayesupdate.fe import STEEL, Material, StructureBuilder, circular_tube, oval_tube
from bayesupdate.fe.assembly import Assembler, ElementProperties
from bayesupdate.fe.sections import section_properties
from bayesupdate.fe.sparse_modal import ModalSettings, solve_sparse_modes
from bayesupdate.fe.structure import Structure


@dataclass(frozen=True)
class OpenSeesBuild:
    """What ``build_opensees`` put into the OpenSees domain."""

    element: str  # OpenSees element type used for the beams
    n_nodes: int  # including extra nodes for offset masses and ground
    n_beams: int
    n_springs: int
    n_rigid_links: int
    #: 6 for a free body; 0 with springs to ground, where OpenSees keeps the suspension modes
    #: that bayesupdate removes (compare those structures mode by mode, not by index)
    n_rigid_expected: int


def elbow_factor(thickness, bend_radius, outer_diameter):
    """ASME B31.3 flexibility factor k = max(1, 1.65 / h), h = t R / r^2, r = (D - t) / 2; 1 for
    straight elements (R = 0).  (n,) arrays in m."""
    r = 0.5 * (outer_diameter - thickness)
    h = thickness * bend_radius / r**2
    bent = np.asarray(bend_radius) > 0  # a solid straight rod has h = 0: no 1.65 / 0
    return np.where(bent, np.maximum(1.0, 1.65 / np.where(bent, h, 1.0)), 1.0)


def _beam_element(structure: Structure) -> str:
    if structure.shear and structure.rotary_inertia:
        return "ElasticTimoshenkoBeam"
    if not structure.shear and not structure.rotary_inertia:
        return "elasticBeamColumn"
    raise ValueError(
        f"OpenSees has no like-for-like beam for shear={structure.shear}, "
        f"rotary_inertia={structure.rotary_inertia}; use both on (ElasticTimoshenkoBeam) or "
        "both off (elasticBeamColumn)"
    )


def _mass_cloud(mass, inertia):
    """Offsets (6, 3) and masses (6,) of three pairs of point masses along the principal axes of
    ``inertia`` (about the centre) and the remaining centre mass; raises if the tensor violates
    the triangle inequality (not a rigid body)."""
    if not mass > 0:
        raise ValueError("a point mass with a non-diagonal inertia tensor needs a mass > 0")
    moments, axes = np.linalg.eigh(inertia)
    q = 0.5 * moments.sum() - moments
    if np.any(q < -1e-12 * moments.sum()):
        raise ValueError(f"inertia tensor with principal moments {moments} is not a rigid body's")
    q = np.maximum(q, 0.0)
    d2 = 2.0 * q.sum() / mass  # the pairs then carry half the mass
    m_pair = q / (2.0 * d2)
    offsets = np.concatenate([axes.T, -axes.T]) * np.sqrt(d2)
    return offsets, np.concatenate([m_pair, m_pair]), mass - 2.0 * m_pair.sum()


def build_opensees(
    structure: Structure, props: ElementProperties | None = None, polar_torsion: bool = True
) -> OpenSeesBuild:
    """Wipe the OpenSees domain and build ``structure`` in it (at ``props``, default: the
    structure's own values; thickness, density, E, bend factors, mass and spring scales as used by
    ``bayesupdate.fe.assembly``).  ``polar_torsion=False`` keeps OpenSees' own torsional inertia
    rho J (to show that the mapping matters)."""
    s = structure
    props = Assembler(s).default_properties() if props is None else props
    element = _beam_element(s)
    ops.wipe()
    ops.model("basic", "-ndm", 3, "-ndf", 6)
    for i, xyz in enumerate(s.nodes):
        ops.node(i + 1, *map(float, xyz))
    next_node = s.n_nodes + 1

    sec = section_properties(
        s.beam_shape, s.beam_width, s.beam_height, props.beam_thickness, s.beam_nu
    )
    E = props.beam_E
    G = E / (2.0 * (1.0 + s.beam_nu))
    k_bend = props.beam_bend_factor * np.where(
        s.beam_elbow, elbow_factor(props.beam_thickness, s.beam_bend_radius, s.beam_width), 1.0
    )
    if element == "ElasticTimoshenkoBeam" and np.any(k_bend != 1.0):
        raise ValueError(
            "bend flexibility with rotary inertia has no exact OpenSees equivalent; build the "
            "structure with elbow_flexibility=False or without shear and rotary inertia"
        )
    polar = sec["Iy"] + sec["Iz"]
    # torsional inertia rho * Jx' = rho * (Iy + Iz), see the module docstring
    c = polar / sec["J"] if polar_torsion else np.ones_like(polar)
    mass_per_length = props.beam_rho * sec["A"]
    for e in range(len(s.beam_part)):
        n1, n2 = (int(v) + 1 for v in s.beam_nodes[e])
        ops.geomTransf("Linear", e + 1, *map(float, s.beam_up[e]))
        Iy, Iz = sec["Iy"][e] / k_bend[e], sec["Iz"][e] / k_bend[e]
        if element == "ElasticTimoshenkoBeam":
            args = (E[e], G[e] / c[e], sec["A"][e], c[e] * sec["J"][e], Iy, Iz)
            args += (sec["Asy"][e] * c[e], sec["Asz"][e] * c[e])
        else:
            args = (sec["A"][e], E[e], G[e] / c[e], c[e] * sec["J"][e], Iy, Iz)
        ops.element(
            element, e + 1, n1, n2, *map(float, args), e + 1,
            "-mass", float(mass_per_length[e]), "-cMass",
        )  # fmt: skip

    # point masses: diagonal nodal masses accumulate on their node, the rest gets extra nodes
    nodal = np.zeros((s.n_nodes, 6))
    extra_masses = []  # (master node tag, xyz, 6 mass values)
    for p in range(len(s.mass_node)):
        node = int(s.mass_node[p])
        m = float(s.mass_value[p] * props.mass_scale[p])
        J = s.mass_inertia[p] * props.mass_scale[p]
        offset = s.mass_offset[p]
        centre = s.nodes[node] + offset
        diagonal = np.allclose(J, np.diag(np.diag(J)), rtol=0, atol=1e-12 * max(np.trace(J), 0))
        if diagonal:
            m_centre, rot = m, np.diag(J)
        else:
            offsets, m_cloud, m_centre = _mass_cloud(m, J)
            for d, mk in zip(offsets, m_cloud, strict=True):
                extra_masses.append((node + 1, centre + d, [mk, mk, mk, 0.0, 0.0, 0.0]))
            rot = np.zeros(3)
        values = np.concatenate([[m_centre] * 3, rot])
        if np.linalg.norm(offset) == 0.0:
            nodal[node] += values
        else:
            extra_masses.append((node + 1, centre, values))
    for i in np.flatnonzero(np.any(nodal != 0.0, axis=1)):
        ops.mass(int(i) + 1, *map(float, nodal[i]))
    for master, xyz, values in extra_masses:
        ops.node(next_node, *map(float, xyz))
        ops.mass(next_node, *map(float, values))
        ops.rigidLink("beam", master, next_node)
        next_node += 1

    # springs: one Elastic material per non-zero stiffness, zeroLength oriented by the frame
    mat_tag = 1
    ele_tag = len(s.beam_part) + 1
    for k in range(len(s.spring_part)):
        a, b = (int(v) for v in s.spring_nodes[k])
        if b < 0:  # a fixed node at the same place (zeroLength wants coincident nodes)
            b_tag = next_node
            ops.node(b_tag, *map(float, s.nodes[a]))
            ops.fix(b_tag, 1, 1, 1, 1, 1, 1)
            next_node += 1
        else:
            b_tag = b + 1
        stiff = s.spring_k[k] * props.spring_scale[k]
        dirs = [int(i) + 1 for i in np.flatnonzero(stiff > 0)]
        if not dirs:
            continue
        mats = []
        for i in dirs:
            ops.uniaxialMaterial("Elastic", mat_tag, float(stiff[i - 1]))
            mats.append(mat_tag)
            mat_tag += 1
        frame = s.spring_frame[k]
        ops.element(
            "zeroLength", ele_tag, a + 1, b_tag, "-mat", *mats, "-dir", *dirs,
            "-orient", *map(float, frame[0]), *map(float, frame[1]),
        )  # fmt: skip
        ele_tag += 1
    n_rigid = 0 if np.any(s.spring_nodes[:, 1] < 0) else 6
    return OpenSeesBuild(
        element=element,
        n_nodes=next_node - 1,
        n_beams=len(s.beam_part),
        n_springs=ele_tag - 1 - len(s.beam_part),
        n_rigid_links=len(extra_masses),
        n_rigid_expected=n_rigid,
    )


def well_posed_solver(n_rigid: int) -> str:
    """OpenSees eigen solver that does not factorize a singular K.

    OpenSees' ARPACK runs in shift-invert mode at shift 0, so on a free body (``n_rigid`` > 0)
    it factorizes the singular stiffness: whether the zero pivot is caught (``aii <
    minDiagTol``) or turns into garbage eigenvalues depends on round-off, i.e. on the BLAS and
    the numbering.  Its dense generalized LAPACK solver (QZ) needs no factorization of K and is
    exact for free bodies; a supported structure keeps the banded ARPACK solver."""
    return "-fullGenLapack" if n_rigid else "-genBandArpack"


def eigen_frequencies(
    n_modes: int, n_rigid: int = 6, solver: str | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Eigen-solve the current OpenSees domain (built by ``build_opensees``): (elastic
    frequencies (n_modes,) [Hz], the dropped rigid eigenvalues (n_rigid,) [rad^2/s^2]).
    ``solver`` None picks ``well_posed_solver(n_rigid)``."""
    solver = solver or well_posed_solver(n_rigid)
    ops.wipeAnalysis()  # a second eigen on the same domain needs a fresh analysis
    ops.constraints("Transformation")  # rigid links of the point masses
    ops.numberer("RCM")
    lam = np.sort(np.asarray(ops.eigen(solver, n_modes + n_rigid), dtype=float))
    rigid, elastic = lam[:n_rigid], lam[n_rigid:]
    return np.sqrt(elastic) / (2.0 * np.pi), rigid


def opensees_frequencies(
    structure: Structure,
    n_modes: int = 12,
    props: ElementProperties | None = None,
    solver: str | None = None,
    polar_torsion: bool = True,
) -> np.ndarray:
    """First ``n_modes`` elastic frequencies [Hz] of ``structure`` computed by OpenSees, with
    ``well_posed_solver`` unless ``solver`` is given."""
    info = build_opensees(structure, props, polar_torsion)
    f, rigid = eigen_frequencies(n_modes, info.n_rigid_expected, solver)
    if info.n_rigid_expected and np.max(np.abs(rigid)) > 1e-6 * (2 * np.pi * f[0]) ** 2:
        raise RuntimeError(f"OpenSees rigid-body eigenvalues not ~0: {rigid}")
    return f


def opensees_matrices(n_nodes: int) -> tuple[np.ndarray, np.ndarray]:
    """OpenSees' own assembled (K, M), dense (6 n_nodes, 6 n_nodes), of the domain that
    ``build_opensees`` made, in bayesupdate's DOF order (node i, component c at 6 i + c).

    Read with the ``GimmeMCK`` integrator (the system matrix is m M + c C + k K) into a
    ``FullGeneral`` system, printed by ``printA``; the ``Transformation`` constraint handler
    condenses the rigidly linked extra nodes (offset masses) onto their masters and removes the
    fixed ground nodes, so the equations are exactly the structure's own DOFs."""
    out = []
    for m, k in ((0.0, 1.0), (1.0, 0.0)):
        ops.wipeAnalysis()
        ops.system("FullGeneral")
        ops.numberer("Plain")
        ops.constraints("Transformation")
        ops.algorithm("Linear")
        ops.integrator("GimmeMCK", m, 0.0, k)
        ops.analysis("Transient")
        ops.analyze(1, 0.0)
        A = np.asarray(ops.printA("-ret"), dtype=float)
        n = int(round(np.sqrt(A.size)))
        out.append(A.reshape(n, n))
    eq = np.concatenate([ops.nodeDOFs(i + 1) for i in range(n_nodes)])
    if eq.size != n or np.unique(eq).size != n or eq.min() < 0:
        raise ValueError(f"OpenSees has {n} equations, not the structure's {6 * n_nodes} DOFs")
    return out[0][np.ix_(eq, eq)], out[1][np.ix_(eq, eq)]


def accurate_frequencies(K, M, nodes, n_modes: int) -> np.ndarray:
    """First ``n_modes`` elastic frequencies [Hz] of a free-free pencil (K, M) (n, n) by the
    package's shift-invert Lanczos with exact rigid modes (``fe.sparse_modal``, forced at any
    size: its dense branch works on the ill-conditioned projected pencil and carries ~1e-10)."""
    settings = ModalSettings(n_modes=n_modes, dense_below=0)
    return solve_sparse_modes(sp.csr_matrix(K), sp.csr_matrix(M), nodes, settings).frequencies_hz


@dataclass(frozen=True)
class LikeForLike:
    """OpenSees against bayesupdate on one free-free beam structure (relative differences).

    matrix_k, matrix_m : max |X_opensees - X| / max |X| of the assembled K and M;
    same_solver : frequencies of the two pencils through ``accurate_frequencies``;
    our_solve : ``FEModel.solve`` (the user's path) against OpenSees' pencil so solved;
    peer_solve : OpenSees' own eigen (``well_posed_solver``: dense QZ) against the same;
    qz_on_ours : scipy's QZ (``eig(K, M)``) on *our* pencil against ``accurate_frequencies`` of
    it, i.e. the round-off of that kind of solver alone."""

    matrix_k: float
    matrix_m: float
    same_solver: float
    our_solve: float
    peer_solve: float
    qz_on_ours: float


def like_for_like(model, params=None, n_modes: int = 12) -> LikeForLike:
    """``LikeForLike`` of an ``FEModel`` of a free-free beam structure at ``params``."""
    import scipy.linalg as sl

    s = model.structure
    props = model.element_properties(model.full_parameters(params))
    info = build_opensees(s, props)
    if info.n_rigid_expected != 6:
        raise ValueError("like_for_like compares free-free structures (no springs to ground)")
    peer, _ = eigen_frequencies(n_modes, info.n_rigid_expected)
    K_os, M_os = opensees_matrices(s.n_nodes)
    K, M, _ = model.assembler.assemble(props)
    K, M = K.toarray(), M.toarray()
    ref_os = accurate_frequencies(K_os, M_os, s.nodes, n_modes)
    ref = accurate_frequencies(K, M, s.nodes, n_modes)
    lam = sl.eig(K, M, right=False)
    lam = np.sort(lam.real[np.isfinite(lam)])  # the 6 rigid ~0, the elastic ones, (massless inf)
    qz = np.sqrt(lam[6 : 6 + n_modes]) / (2 * np.pi)
    ours = model.solve(params, n_modes=n_modes).frequencies_hz

    def rel(a, b):
        return float(np.max(np.abs(a / b - 1.0)))

    return LikeForLike(
        matrix_k=float(np.abs(K_os - K).max() / np.abs(K).max()),
        matrix_m=float(np.abs(M_os - M).max() / np.abs(M).max()),
        same_solver=rel(ref, ref_os),
        our_solve=rel(ours, ref_os),
        peer_solve=rel(peer, ref_os),
        qz_on_ours=rel(qz, ref),
    )


def _pin_hole_rod(diameter):
    """Solid rod as a tube with a 1e-4 d bore: ``solid_round`` is rejected by
    ``fe.assembly.check_properties`` (zero wall thickness), see tests/test_fe_peer_opensees.py."""
    return circular_tube(diameter, 0.49995 * diameter)


def example_frame(
    shear=True, rotary_inertia=True, elbow=False, rod=_pin_hole_rod, element_length=0.1
) -> Structure:
    """A 2.3 m exhaust-like frame: bent pipe - joint spring - oval muffler - bent tail pipe, a
    hanger rod with a tip mass, a flange mass and offset muffler internals (full inertia)."""
    b = StructureBuilder(shear=shear, rotary_inertia=rotary_inertia)
    h = element_length
    shell = Material(STEEL.youngs_modulus, STEEL.poisson, 10.0e3, "shell")
    pipe = b.add_pipe_run(
        [(0, 0, 0), (0.8, 0, 0), (0.8, 0.5, 0), (1.4, 0.5, 0.3)],
        circular_tube(0.045, 1.5e-3),
        STEEL,
        "pipe",
        bend_radii=[0.10, 0.12],
        element_length=h,
        elbow_flexibility=elbow,
    )
    axis = b.node_xyz(pipe[-1]) - b.node_xyz(pipe[-2])
    axis /= np.linalg.norm(axis)
    side = np.cross((0.0, 0.0, 1.0), axis)
    side /= np.linalg.norm(side)
    frame = np.array([axis, side, np.cross(axis, side)])
    inlet = b.add_node(b.node_xyz(pipe[-1]))
    b.add_spring(pipe[-1], inlet, [1e7, 2e7, 3e7, 2e4, 3e4, 5e4], "joint", frame=frame)
    outlet = b.add_node(b.node_xyz(inlet) + 0.45 * axis)
    muffler = b.add_line(
        inlet, outlet, oval_tube(0.30, 0.15, 1.0e-3), shell, "muffler", element_length=0.9 * h
    )
    corner = b.node_xyz(outlet) + 0.3 * axis
    b.add_pipe_run(
        [b.node_xyz(outlet), corner, corner + (0.0, 0.0, -0.25)],
        circular_tube(0.040, 1.2e-3),
        STEEL,
        "tail",
        bend_radii=[0.08],
        start_node=outlet,
        element_length=h,
        elbow_flexibility=elbow,
    )
    rod_tip = b.add_node(b.node_xyz(pipe[3]) + (0.0, 0.0, -0.15))
    b.add_line(pipe[3], rod_tip, rod(0.012), STEEL, "rod", element_length=0.5 * h)
    b.add_point_mass(pipe[0], 1.2, "flange", inertia=[2e-3, 3e-3, 4e-3])
    internals_inertia = [[0.020, 0.004, 0.001], [0.004, 0.030, -0.002], [0.001, -0.002, 0.035]]
    b.add_point_mass(
        muffler[len(muffler) // 2], 2.0, "internals", internals_inertia, offset=(0, 0.02, 0.04)
    )
    b.add_point_mass(rod_tip, 0.3, "rod", inertia=[1e-4, 1e-4, 2e-4], offset=(0.01, 0, -0.02))
    return b.build()
