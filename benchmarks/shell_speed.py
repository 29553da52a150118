"""Speed and memory of the shell FE path on a >= 25,000-DOF model, beside OpenSeesPy and pyfe3d.

Run:  .venv/bin/python benchmarks/shell_speed.py [--repeats 3] [--cells 44 26 18]

Model: a closed steel box 1.0 x 0.6 x 0.4 m of MITC4 quads (2 mm walls, one thickness parameter
per face), clamped along the four edges of its bottom face; first 20 elastic modes.  Times
(medians over repeats, BLAS on one thread):
  (a) ours: assembly (geometry precomputation + element matrices + CSR), solve (shift-invert
      Lanczos, sparse LU), parametric re-assembly K(theta), M(theta) for new face thicknesses, and
      its one-off set-up; memory: peak RSS of the process and tracemalloc peak of one assembly +
      solve (numpy buffers; SuperLU's own allocations are not traced);
  (b) OpenSeesPy on the same mesh and supports: model build + ShellMITC4 elements, and
      ``eigen`` (its default ARPACK; the structure is supported, so shift 0 is regular);
      frequencies compared with ours (consistent mass, no rotary inertia = ShellMITC4's model);
  (c) pyfe3d (if installed): its Quad4 matrices assembled by its per-element Cython calls, solved
      with our solver; frequencies compared.
"""

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_name] = "1"

import argparse  # noqa: E402
import resource  # noqa: E402
import time  # noqa: E402
import tracemalloc  # noqa: E402

import numpy as np  # noqa: E402
import scipy.sparse as sp  # noqa: E402
from timing import time_median  # noqa: E402

from bayesupdate.fe import shell_mesh as sm  # noqa: E402
from bayesupdate.fe.shell_model import ShellAssembly, ThicknessParametrisation, shell_mesh  # noqa: E402
from bayesupdate.fe.sparse_modal import ModalSettings, solve_sparse_modes  # noqa: E402

N_MODES = 20
STEEL = dict(E=210e9, nu=0.3, rho=7850.0)


def build_box(cells):
    """Box mesh, per-element face number (0..5) and the clamped DOFs (bottom-face edges)."""
    nodes, quads = sm.box(1.0, 0.6, 0.4, *cells)
    centre = nodes[quads].mean(axis=1)
    ext = np.array([1.0, 0.6, 0.4])
    face = np.full(len(quads), -1)
    for axis in range(3):
        face[np.abs(centre[:, axis]) < 1e-9] = 2 * axis
        face[np.abs(centre[:, axis] - ext[axis]) < 1e-9] = 2 * axis + 1
    mesh = shell_mesh(nodes, quads, thickness=0.002, **STEEL)
    x, y, z = nodes.T
    edge = (
        (np.abs(x) < 1e-9)
        | (np.abs(x - 1.0) < 1e-9)
        | (np.abs(y) < 1e-9)
        | (np.abs(y - 0.6) < 1e-9)
    )
    bottom = np.flatnonzero((z < 1e-9) & edge)
    fixed = (6 * bottom[:, None] + np.arange(6)).ravel()
    return mesh, face, fixed


def ours(mesh, face, fixed, repeats):
    settings = ModalSettings(n_modes=N_MODES)

    def assemble():
        return ShellAssembly(mesh).assemble()

    t_asm, (K, M) = time_median(assemble, repeats)
    t_solve, modes = time_median(
        lambda: solve_sparse_modes(K, M, mesh.nodes, settings, fixed), repeats
    )
    t0 = time.perf_counter()
    par = ThicknessParametrisation(ShellAssembly(mesh), face)
    t_setup = time.perf_counter() - t0
    rng = np.random.default_rng(0)
    t_par, _ = time_median(lambda: par.assemble(rng.uniform(1e-3, 3e-3, 6)), max(5, repeats))
    tracemalloc.start()
    K2, M2 = assemble()
    solve_sparse_modes(K2, M2, mesh.nodes, settings, fixed)
    traced = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return dict(
        assembly=t_asm, solve=t_solve, param_setup=t_setup, param=t_par, traced=traced,
        modes=modes, K=K, M=M,
    )  # fmt: skip


def opensees(mesh, fixed, repeats):
    """(build time, eigen time, frequencies) with ShellMITC4 / ElasticMembranePlateSection."""
    import openseespy.opensees as ops

    flags = np.zeros((len(mesh.nodes), 6), int)
    flags.reshape(-1)[fixed] = 1

    def build():
        ops.wipe()
        ops.model("basic", "-ndm", 3, "-ndf", 6)
        for i, x in enumerate(mesh.nodes):
            ops.node(i + 1, *map(float, x))
        for i in np.flatnonzero(flags.any(axis=1)):
            ops.fix(int(i) + 1, *map(int, flags[i]))
        ops.section("ElasticMembranePlateSection", 1, STEEL["E"], STEEL["nu"], 0.002, STEEL["rho"])
        for e, q in enumerate(mesh.quads):
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
    return float(np.median(t_build)), float(np.median(t_eig)), np.sqrt(lam) / (2 * np.pi)


def pyfe3d_matrices(mesh):
    """Global K, M from pyfe3d's Quad4 (consistent mass), one Cython call per element."""
    from pyfe3d import DOF, INT, Quad4, Quad4Data, Quad4Probe
    from pyfe3d.shellprop_utils import isotropic_plate

    data, probe = Quad4Data(), Quad4Probe()
    ne, n = len(mesh.quads), DOF * len(mesh.nodes)
    Kr = np.zeros(data.KC0_SPARSE_SIZE * ne, dtype=INT)
    Kc, Kv = np.zeros_like(Kr), np.zeros(len(Kr))
    Mr = np.zeros(data.M_SPARSE_SIZE * ne, dtype=INT)
    Mc, Mv = np.zeros_like(Mr), np.zeros(len(Mr))
    x = np.ascontiguousarray(mesh.nodes).ravel()
    prop = isotropic_plate(thickness=0.002, E=STEEL["E"], nu=STEEL["nu"], rho=STEEL["rho"])
    for i, q in enumerate(mesh.quads):
        el = Quad4(probe)
        el.n1, el.n2, el.n3, el.n4 = map(int, q)
        el.c1, el.c2, el.c3, el.c4 = (DOF * int(k) for k in q)
        el.init_k_KC0, el.init_k_M = i * data.KC0_SPARSE_SIZE, i * data.M_SPARSE_SIZE
        el.update_rotation_matrix(x)
        el.update_probe_xe(x)
        el.update_KC0(Kr, Kc, Kv, prop)
        el.update_M(Mr, Mc, Mv, prop, mtype=0)
    K = sp.coo_matrix((Kv, (Kr, Kc)), shape=(n, n)).tocsr()
    return K, sp.coo_matrix((Mv, (Mr, Mc)), shape=(n, n)).tocsr()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--cells", type=int, nargs=3, default=[44, 26, 18])
    args = ap.parse_args()
    mesh, face, fixed = build_box(tuple(args.cells))
    print(f"box {args.cells}: {len(mesh.nodes)} nodes, {len(mesh.quads)} quads, "
          f"{mesh.n_dof} DOFs ({mesh.n_dof - fixed.size} free), {N_MODES} modes")  # fmt: skip
    r = ours(mesh, face, fixed, args.repeats)
    f = r["modes"].frequencies_hz
    print(f"ours: assembly {r['assembly']:.3f} s, solve {r['solve']:.3f} s, "
          f"total {r['assembly'] + r['solve']:.3f} s")  # fmt: skip
    print(f"ours: parametric re-assembly {1e3 * r['param']:.1f} ms = "
          f"{100 * r['param'] / r['solve']:.1f} % of the solve (one-off set-up "
          f"{r['param_setup']:.2f} s)")  # fmt: skip
    print(f"ours: tracemalloc peak {r['traced'] / 2**20:.0f} MiB")
    print("ours: f [Hz] =", np.array2string(f, precision=3, max_line_width=100))
    try:
        t_build, t_eig, f_ops = opensees(mesh, fixed, args.repeats)
        Kn, Mn = ShellAssembly(mesh, rotary_inertia=False).assemble()
        f_nr = solve_sparse_modes(Kn, Mn, mesh.nodes, ModalSettings(n_modes=N_MODES), fixed)
        dev = np.max(np.abs(f_nr.frequencies_hz / f_ops - 1))
        print(f"OpenSees ShellMITC4: build {t_build:.3f} s, eigen {t_eig:.3f} s, total "
              f"{t_build + t_eig:.3f} s; speed-up ours vs OpenSees: total "
              f"{(t_build + t_eig) / (r['assembly'] + r['solve']):.1f}x, solve "
              f"{t_eig / r['solve']:.1f}x; max |f_ours(no rotary) / f_ops - 1| = "
              f"{dev:.2e}")  # fmt: skip
    except ImportError:
        print("OpenSees: not installed")
    try:
        t0 = time.perf_counter()
        Kp, Mp = pyfe3d_matrices(mesh)
        t_py = time.perf_counter() - t0
        fp = solve_sparse_modes(Kp, Mp, mesh.nodes, ModalSettings(n_modes=N_MODES), fixed)
        dev = np.max(np.abs(fp.frequencies_hz / f - 1))
        print(f"pyfe3d Quad4: assembly {t_py:.3f} s (ours {r['assembly']:.3f} s); "
              f"max |f_pyfe3d / f_ours - 1| = {dev:.2e}")  # fmt: skip
    except ImportError:
        print("pyfe3d: not installed")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    print(f"peak RSS of this process (all of the above): {peak:.0f} MiB")


if __name__ == "__main__":
    main()
