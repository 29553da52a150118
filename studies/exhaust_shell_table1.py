"""The shell exhaust (``exhaust_shell``) at the initial design against seed Table 1, side by side
with the beam exhaust: frequencies, errors, mass, mode characters, and the pairing of each mode
with the beam model's (MAC at the 40 sensor DOFs).  ``--convergence`` adds the mesh check: the 12
modes at mesh densities 16, 24 (default), 32 against a fine mesh (``--fine``, default 64).

    PYTHONPATH=. OPENBLAS_NUM_THREADS=1 python studies/exhaust_shell_table1.py [--convergence]
(about 15 s; with --convergence about 2 minutes more)
"""

import argparse
import time

import numpy as np

from bayesupdate.correlation import mac_matrix
from bayesupdate.models import get_model
from bayesupdate.models.exhaust import mode_character
from bayesupdate.models.exhaust_paper import MEASURED_MASS_KG, TABLE1_FEA_HZ


def _characters(model, result) -> list[str]:
    return [
        f"{c['plane']}{c['nodes']}" for c in mode_character(model.structure, result.modes.shapes)
    ]


def table1() -> None:
    t0 = time.perf_counter()
    shell = get_model("exhaust_shell")
    rs = shell.solve(n_modes=12)
    t1 = time.perf_counter()
    beam = get_model("exhaust")
    rb = beam.solve(n_modes=12)
    es, eb = rs.frequencies_hz / TABLE1_FEA_HZ - 1, rb.frequencies_hz / TABLE1_FEA_HZ - 1
    mac = mac_matrix(rs.sensor_shapes, rb.sensor_shapes)
    cs, cb = _characters(shell, rs), _characters(beam, rb)
    print(
        f"shell model: {shell.structure.n_dof} DOF, {shell.structure.metadata['n_shells']} shells,"
    )
    print(
        f"  build + solve {t1 - t0:.1f} s; mass {rs.mass_kg:.3f} kg (measured {MEASURED_MASS_KG})"
    )
    print(f"  main muffler internals {shell.structure.metadata['mm_internal_mass_kg']:.3f} kg")
    print("mode  Table1   shell   err%  char | beam    err%  char | MAC(shell j, beam j) best")
    for j in range(12):
        best = int(np.argmax(mac[j]))
        print(
            f"{j + 1:4d} {TABLE1_FEA_HZ[j]:7.2f} {rs.frequencies_hz[j]:7.2f} {100 * es[j]:6.1f}  "
            f"{cs[j]:4s} | {rb.frequencies_hz[j]:6.2f} {100 * eb[j]:6.1f}  {cb[j]:4s} | "
            f"{mac[j, j]:.2f}  beam {best + 1} ({mac[j, best]:.2f})"
        )
    for name, e in (("shell", es), ("beam", eb)):
        rms, worst = 100 * np.sqrt(np.mean(e**2)), 100 * np.abs(e).max()
        print(f"{name}: RMS {rms:.2f} %, max {worst:.2f} % against Table 1")


def convergence(fine: int) -> None:
    ref = get_model("exhaust_shell", mesh_density=fine).solve(n_modes=12).frequencies_hz
    print(f"mesh density {fine}: {np.round(ref, 2).tolist()}")
    for n in (16, 24, 32):
        f = get_model("exhaust_shell", mesh_density=n).solve(n_modes=12).frequencies_hz
        d = 100 * (f / ref - 1)
        print(
            f"density {n:3d}: max |df| {np.abs(d).max():.2f} % vs {fine}: {np.round(d, 2).tolist()}"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--convergence", action="store_true")
    ap.add_argument("--fine", type=int, default=64)
    args = ap.parse_args()
    table1()
    if args.convergence:
        convergence(args.fine)


if __name__ == "__main__":
    main()
