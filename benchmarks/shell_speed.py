"""Shell part of ``benchmarks/fe_speed.py``: a >= 25,000-DOF shell model, first 20 modes, on the
path a user takes (``StructureBuilder.add_shells`` -> ``FEModel`` with thickness parameters),
beside OpenSeesPy and pyfe3d on the same mesh.

Run:  .venv/bin/python benchmarks/fe_speed.py --shells-only [--shell-repeats 3]
      (``benchmarks/fe_speed.py`` runs it after the beam part; this file holds no second copy)

Model: a closed steel box 1.0 x 0.6 x 0.4 m of MITC4 quads (2 mm walls, one thickness parameter
per face, six in all), clamped along the four edges of its bottom face.  Medians over repeats,
BLAS on one thread:
  (a) ours: structure build (``add_shells`` per face, ``build``); model set-up (``FEModel``:
      element geometry, the six faces' thickness-power data, the sparse pattern and the
      constraint elimination, once per geometry); re-assembly of K(theta), M(theta) at new face
      thicknesses (what every ``FEModel.solve`` costs before its eigen-solve); the eigen-solve
      (shift-invert Lanczos on the supported model) with CHOLMOD where scikit-sparse is installed
      and with SuperLU; memory: tracemalloc peak of set-up + re-assembly + solve (numpy buffers;
      the factorizations' own allocations are not traced) and the process's peak RSS before the
      peers run;
  (b) OpenSeesPy on the same nodes, quads and supports: model build (nodes, ShellMITC4 elements;
      its element matrices are formed inside ``eigen``) and ``eigen`` (its default ARPACK; the
      model is supported, so shift 0 is regular); frequencies compared with ours built without
      rotary inertia (ShellMITC4's mass model);
  (c) pyfe3d (if installed): its Quad4 matrices assembled by one Cython call per element,
      solved with our solver; frequencies compared with ours.

Reduced basis (``fe_speed.py --shell-reduced``): the same clamped box, coarser (``RB_CELLS``), six
face thicknesses (2 mm +- 25 %) and the density of the top face (+- 10 %) as parameters: the
certified reduced basis (``fe.reduced``, first 12 modes, tol 1e-4) built once, then the time
per parameter point of a batch of reduced solves against ``FEModel.solve`` (sparse), and the
largest relative frequency difference at fresh random points.
"""

import resource
import time
import tracemalloc

import numpy as np
import scipy.sparse as sp
from timing import time_median

from bayesupdate.fe import Binding, FEModel, Material, StructureBuilder
from bayesupdate.fe import shell_mesh as sm
from bayesupdate.fe.sparse_modal import ModalSettings, cholmod_available, solve_sparse_modes

N_MODES = 20
SIZE = (1.0, 0.6, 0.4)
CELLS = (44, 26, 18)
T0 = 2e-3
STEEL = Material(210e9, 0.3, 7850.0, "steel")


def box_faces(cells):
    """(nodes (N, 3), quads (nq, 4), face (nq,) 0..5 (x = 0, x = lx, y = 0, ...), clamped node
    numbers (the bottom face's four edges))."""
    nodes, quads = sm.box(*SIZE, *cells)
    centre = nodes[quads].mean(axis=1)
    face = np.full(len(quads), -1)
    for axis in range(3):
        face[np.abs(centre[:, axis]) < 1e-9] = 2 * axis
        face[np.abs(centre[:, axis] - SIZE[axis]) < 1e-9] = 2 * axis + 1
    x, y, z = nodes.T
    edge = np.isclose(x, 0) | np.isclose(x, SIZE[0]) | np.isclose(y, 0) | np.isclose(y, SIZE[1])
    return nodes, quads, face, np.flatnonzero(np.isclose(z, 0) & edge)


def build_structure(cells, rotary_inertia=True):
    """The box through the public builder: one part per face, the bottom edges clamped."""
    nodes, quads, face, clamped = box_faces(cells)
    b = StructureBuilder(rotary_inertia=rotary_inertia)
    ids = np.full(len(nodes), -1)
    for f in range(6):
        q = quads[face == f]
        used, local = np.unique(q, return_inverse=True)
        ids[used] = b.add_shells(
            nodes[used], local.reshape(q.shape), thickness=T0, material=STEEL, part=f"face{f}"
        )
    for n in ids[clamped]:
        b.add_support(int(n))
    return b.build()


def make_model(structure) -> FEModel:
    names = {f"t{f}": Binding(f"face{f}", "thickness") for f in range(6)}
    return FEModel(
        structure, names, {k: T0 for k in names}, {k: (0.5e-3, 4e-3) for k in names}, name="box"
    )


def ours(cells, repeats: int) -> dict:
    """Times [s], memory [bytes] and frequencies of our path (module docstring, (a))."""
    t_build, structure = time_median(lambda: build_structure(cells), repeats)
    t_setup, model = time_median(lambda: make_model(structure), repeats)
    g = model._general  # noqa: SLF001 - the model's own assembler: re-assembly timed alone
    props = model.element_properties()
    rng = np.random.default_rng(0)

    def reassemble():
        p = {k: rng.uniform(1e-3, 3e-3) for k in model.parameter_names}
        return g.assemble(props, model.shell_properties(p))

    t_asm, _ = time_median(reassemble, max(10, repeats))
    K, M, _ = g.assemble(props, model.shell_properties())
    solves = {}
    kinds = ("cholmod", "superlu") if cholmod_available() else ("superlu",)
    for kind in kinds:
        settings = ModalSettings(factorization=kind)
        solves[kind] = time_median(lambda s=settings: g.solve(K, M, N_MODES, settings=s), repeats)
    t_full, result = time_median(lambda: model.solve(n_modes=N_MODES), repeats)
    tracemalloc.start()
    m2 = make_model(structure)
    m2.solve(n_modes=N_MODES)
    traced = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    f = {k: v[1].frequencies_hz for k, v in solves.items()}
    return dict(
        n_dof=structure.n_dof, n_free=g.transform.independent.size,
        n_quads=len(structure.shells.quads),
        build=t_build, setup=t_setup, reassembly=t_asm, solve={k: v[0] for k, v in solves.items()},
        model_solve=t_full, traced=traced, rss=_peak_rss(), frequencies=result.frequencies_hz,
        factorization_agreement=float(np.max(np.abs(f["superlu"] / f[kinds[0]] - 1))),
        n_rigid=result.modes.n_rigid,
    )  # fmt: skip


def _peak_rss() -> float:
    """Peak resident set size of this process so far [bytes] (Linux reports KiB)."""
    return 1024.0 * resource.getrusage(resource.RUSAGE_SELF).ru_maxrss


def opensees(cells, repeats: int) -> dict:
    """(b): build and eigen times [s] and frequencies of OpenSeesPy's ShellMITC4 model."""
    import openseespy.opensees as ops

    nodes, quads, _, clamped = box_faces(cells)

    def build():
        ops.wipe()
        ops.model("basic", "-ndm", 3, "-ndf", 6)
        for i, x in enumerate(nodes):
            ops.node(i + 1, *map(float, x))
        for i in clamped:
            ops.fix(int(i) + 1, 1, 1, 1, 1, 1, 1)
        ops.section("ElasticMembranePlateSection", 1, STEEL.youngs_modulus, STEEL.poisson, T0,
                    STEEL.density)  # fmt: skip
        for e, q in enumerate(quads):
            ops.element("ShellMITC4", e + 1, *map(int, q + 1), 1)

    t_build, t_eig, lam = [], [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        build()
        t1 = time.perf_counter()
        lam = np.array(ops.eigen(N_MODES))
        t_eig.append(time.perf_counter() - t1)
        t_build.append(t1 - t0)
    ops.wipe()
    plain = make_model(build_structure(cells, rotary_inertia=False)).solve(n_modes=N_MODES)
    f_ops = np.sqrt(lam) / (2 * np.pi)
    return dict(
        build=float(np.median(t_build)), eigen=float(np.median(t_eig)), frequencies=f_ops,
        max_rel_diff=float(np.max(np.abs(plain.frequencies_hz / f_ops - 1))),
    )  # fmt: skip


def pyfe3d_matrices(nodes, quads, thickness: float, material: Material):
    """K, M CSR of pyfe3d's Quad4 (consistent mass) on nodes (N, 3), quads (nq, 4): one Cython
    call per element for each matrix (also used by ``tests/test_fe_peer_pyfe3d.py``)."""
    from pyfe3d import DOF, INT, Quad4, Quad4Data, Quad4Probe
    from pyfe3d.shellprop_utils import isotropic_plate

    data, probe = Quad4Data(), Quad4Probe()
    ne, n = len(quads), DOF * len(nodes)
    Kr = np.zeros(data.KC0_SPARSE_SIZE * ne, dtype=INT)
    Kc, Kv = np.zeros_like(Kr), np.zeros(len(Kr))
    Mr = np.zeros(data.M_SPARSE_SIZE * ne, dtype=INT)
    Mc, Mv = np.zeros_like(Mr), np.zeros(len(Mr))
    x = np.ascontiguousarray(nodes, dtype=float).ravel()
    prop = isotropic_plate(thickness=thickness, E=material.youngs_modulus, nu=material.poisson,
                           rho=material.density)  # fmt: skip
    for i, q in enumerate(quads):
        el = Quad4(probe)
        el.n1, el.n2, el.n3, el.n4 = map(int, q)
        el.c1, el.c2, el.c3, el.c4 = (DOF * int(k) for k in q)
        el.init_k_KC0, el.init_k_M = i * data.KC0_SPARSE_SIZE, i * data.M_SPARSE_SIZE
        el.update_rotation_matrix(x)
        el.update_probe_xe(x)
        el.update_KC0(Kr, Kc, Kv, prop)
        el.update_M(Mr, Mc, Mv, prop, mtype=0)
    K = sp.coo_matrix((Kv, (Kr, Kc)), shape=(n, n)).tocsr()
    M = sp.coo_matrix((Mv, (Mr, Mc)), shape=(n, n)).tocsr()
    return K, M


def pyfe3d(cells, frequencies) -> dict:
    """(c): pyfe3d Quad4 (consistent mass) assembly time [s], frequencies vs ours."""
    nodes, quads, _, clamped = box_faces(cells)
    t0 = time.perf_counter()
    K, M = pyfe3d_matrices(nodes, quads, T0, STEEL)
    t_asm = time.perf_counter() - t0
    fixed = (6 * clamped[:, None] + np.arange(6)).ravel()
    fp = solve_sparse_modes(K, M, nodes, ModalSettings(n_modes=N_MODES), fixed).frequencies_hz
    return dict(assembly=t_asm, max_rel_diff=float(np.max(np.abs(fp / frequencies - 1))))


RB_CELLS = (20, 12, 8)


def reduced_speed(cells=RB_CELLS, n_points: int = 200, n_full: int = 5) -> dict:
    """Reduced basis on the box (module docstring): build time [s], size, certified error, time
    per point [s] of the reduced batch and of full solves, and their error at ``n_full`` points."""
    from bayesupdate.fe.reduced import reduced_model_for

    structure = build_structure(cells)
    fe = make_model(structure).with_structure(
        structure,
        {"rho_top": Binding("face5", "density")},
        {"rho_top": STEEL.density},
        {"rho_top": (6000.0, 9000.0)},
    )
    # a calibration box: +-25 % on the thicknesses, +-10 % on the density
    bounds = {k: (0.75 * T0, 1.25 * T0) for k in fe.parameter_names if k != "rho_top"}
    bounds["rho_top"] = (0.9 * STEEL.density, 1.1 * STEEL.density)
    t0 = time.perf_counter()
    rom = reduced_model_for(fe, bounds, tol=1e-4, seed=0, n_modes=12)
    t_build = time.perf_counter() - t0
    if not getattr(rom, "certified", False):
        return dict(n_dof=structure.n_dof, build=t_build, certified=False)
    rng = np.random.default_rng(5)
    theta = rom.scale(rng.random((n_points, len(fe.parameter_names))))
    t_rom, f_rom = time_median(lambda: rom.predict_frequencies_batch(theta), 3)
    t0 = time.perf_counter()
    f_full = fe.predict_frequencies_batch(theta[:n_full], fe.parameter_names, 12)
    t_full = (time.perf_counter() - t0) / n_full
    return dict(
        n_dof=structure.n_dof, n_params=len(fe.parameter_names), build=t_build, size=rom.size,
        n_rigid=rom.n_rigid, certified=rom.certified, max_rel_error=rom.max_rel_error,
        per_point_reduced=t_rom / n_points, per_point_full=t_full,
        fresh_max_rel=float(np.max(np.abs(f_rom[:n_full] / f_full - 1))),
    )  # fmt: skip


def print_reduced(out: dict) -> None:
    if not out["certified"]:
        print(f"reduced basis on the {out['n_dof']}-DOF box NOT certified (build "
              f"{out['build']:.1f} s): full solves would be used")  # fmt: skip
        return
    print(f"reduced basis, clamped box {out['n_dof']} DOFs, {out['n_params']} parameters (six "
          "thicknesses, one density), 12 modes, tol 1e-4")  # fmt: skip
    print(f"    build (snapshots, POD, certification)    {out['build']:8.1f} s; size "
          f"{out['size']} ({out['n_rigid']} rigid), certified {out['certified']}, max rel. "
          f"error {out['max_rel_error']:.1e}")  # fmt: skip
    print(f"    per point: reduced batch {1e3 * out['per_point_reduced']:.3f} ms, full sparse "
          f"solve {1e3 * out['per_point_full']:.1f} ms: speed-up x"
          f"{out['per_point_full'] / out['per_point_reduced']:.0f}")  # fmt: skip
    print(f"    max |f_reduced / f_full - 1| at fresh points {out['fresh_max_rel']:.1e}")


def run(repeats: int = 3, cells=CELLS, peers: bool = True) -> dict:
    """All of the above as one dict (times [s], memory [bytes], frequencies [Hz])."""
    out = dict(cells=list(cells), repeats=repeats, peers=peers, ours=ours(cells, repeats))
    out["opensees"] = out["pyfe3d"] = None
    if peers:
        try:
            out["opensees"] = opensees(cells, repeats)
        except ImportError:
            pass
        try:
            out["pyfe3d"] = pyfe3d(cells, out["ours"]["frequencies"])
        except ImportError:
            pass
    out["rss_end"] = _peak_rss()
    return out


def print_shells(out: dict) -> None:
    o = out["ours"]
    fast = next(iter(o["solve"].values()))  # what factorization "auto" takes: CHOLMOD if installed
    ours_total = o["build"] + o["setup"] + o["reassembly"] + fast
    print(f"(d) shells: closed box {out['cells']} cells, {o['n_quads']} MITC4 quads, "
          f"{o['n_dof']} DOFs ({o['n_free']} free), first {N_MODES} modes, 6 thickness "
          f"parameters; medians of {out['repeats']}")  # fmt: skip
    print(f"    structure build (add_shells, build)     {o['build']:8.3f} s")
    print(f"    model set-up (FEModel, once)             {o['setup']:8.3f} s")
    print(f"    re-assembly at new thicknesses           {1e3 * o['reassembly']:8.1f} ms  "
          f"= {100 * o['reassembly'] / fast:.1f} % of the solve (target <= 10 %)")  # fmt: skip
    for kind, t in o["solve"].items():
        print(f"    eigen-solve, {kind:8s}                   {t:8.3f} s")
    if len(o["solve"]) == 1:
        print("    (CHOLMOD: scikit-sparse not installed, pip install 'bayesupdate[fast]')")
    else:
        print(f"    max |f_superlu / f_cholmod - 1|          {o['factorization_agreement']:8.1e}")
    print(f"    FEModel.solve (re-assembly + solve)      {o['model_solve']:8.3f} s")
    print(f"    total build + set-up + assembly + solve  {ours_total:8.3f} s")
    print(f"    memory: tracemalloc peak {o['traced'] / 2**20:.0f} MiB (set-up + solve), peak RSS "
          f"{o['rss'] / 2**20:.0f} MiB before the peers, {out['rss_end'] / 2**20:.0f} MiB "
          "after")  # fmt: skip
    print("    f [Hz] =", np.array2string(o["frequencies"], precision=3, max_line_width=96))
    p = out["opensees"]
    skipped = "not installed" if out["peers"] else "skipped (--no-opensees)"
    if p is None:
        print(f"    OpenSeesPy: {skipped}")
    else:
        print(f"    OpenSees ShellMITC4 build                {p['build']:8.3f} s")
        print(f"    OpenSees eigen (ARPACK)                  {p['eigen']:8.3f} s")
        print(f"    speed-up: total x{(p['build'] + p['eigen']) / ours_total:.1f}, eigen-solve "
              f"x{p['eigen'] / fast:.1f} (target >= 3x); max |f_ours(no rotary inertia) / "
              f"f_opensees - 1| = {p['max_rel_diff']:.1e}")  # fmt: skip
    q = out["pyfe3d"]
    if q is None:
        print(f"    pyfe3d: {skipped}")
    else:
        print(f"    pyfe3d Quad4 assembly (per element)      {q['assembly']:8.3f} s; max "
              f"|f_pyfe3d / f_ours - 1| = {q['max_rel_diff']:.1e}")  # fmt: skip
