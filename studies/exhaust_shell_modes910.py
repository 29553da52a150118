"""Modes 9 and 10 of the shell exhaust (docs/guide/exhaust-shell.md): where they work (strain
energy by part, and within the main muffler by surface, on the best geometry), and how they move
from the previous best (round inlet collar, caps of the mantle's gauge: the pair together at
78-80 Hz) under each candidate for the inlet joint's anisotropy (cap gauge ratio, a vertical
bead band, an oval inlet collar) and under the main muffler's geometry (pipe offsets, cap cone
depth, aspect), and with a rigid inlet joint (the inlet pipe continued inside to the first
baffle), against seed Table 1 (H5 71.0, V5 88.6 Hz).

    PYTHONPATH=. OPENBLAS_NUM_THREADS=1 python studies/exhaust_shell_modes910.py
(about 2 minutes at mesh density 16)
"""

from unittest import mock

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.models import exhaust_shell, get_model
from bayesupdate.models.exhaust import fitted_geometry, mode_character
from bayesupdate.models.exhaust_paper import TABLE1_FEA_HZ
from bayesupdate.models.exhaust_shell_geometry import FITS, shell_geometry

MESH = 16
#: the variants start from the previous best (round collar, caps of the mantle's gauge)
BASE = FITS[3]
VARIANTS = {
    "previous best (geometry=3)": {},
    "pipes 60 mm to the side": {"mm_pipe_dy": 0.06},
    "pipes 110 mm to the side": {"mm_pipe_dy": 0.11},
    "pipes 60 mm to the other side": {"mm_pipe_dy": -0.06},
    "pipes 50 mm up": {"mm_pipe_dz": 0.05},
    "pipes 50 mm down": {"mm_pipe_dz": -0.05},
    "cap cone 20 mm": {"mm_cone": 0.02},
    "cap cone 60 mm": {"mm_cone": 0.06},
    "420 x 160 mm, cone 50 mm": {"mm_width": 0.42, "mm_height": 0.16, "mm_cone": 0.05},
    "420 x 180 mm, cone 40 mm": {"mm_width": 0.42, "mm_height": 0.18, "mm_cone": 0.04},
    # the candidates for the joint's anisotropy (docs/guide/exhaust-shell.md), each alone
    "caps 0.7 x the mantle's gauge": {"mm_cap_ratio": 0.7},
    "caps 1.1 x the mantle's gauge": {"mm_cap_ratio": 1.1},
    "vertical bead band 60 mm, x2.5": {"mm_bead_factor": 2.5, "mm_bead_width": 0.06},
    "collar 40 x 55 mm (y x z)": {"mm_collar_width": 0.04, "mm_collar_height": 0.055},
    "collar 40 x 65 mm": {"mm_collar_width": 0.04, "mm_collar_height": 0.065},
    "collar 40 x 90 mm": {"mm_collar_width": 0.04, "mm_collar_height": 0.09},
    "collar 40 x 120 mm": {"mm_collar_width": 0.04, "mm_collar_height": 0.12},
    "collar 120 x 40 mm": {"mm_collar_width": 0.12, "mm_collar_height": 0.04},
    "collar 40 x 65 mm, cone 28 mm": {"mm_collar_height": 0.065, "mm_cone": 0.028},
}


def muffler_surfaces(model, g: dict) -> dict:
    """Masks (n_shell,) of the main muffler's mantle, inlet cap, outlet cap and baffles, from the
    element centroids (mantle: on the oval; caps: within 60 mm of the body's ends)."""
    s = model.structure
    sh = s.shells
    conn = [sh.quads, sh.trias] if sh.trias.size else [sh.quads]
    cen = np.concatenate([s.nodes[c].mean(axis=1) for c in conn])
    mm = sh.part == s.part_index("main_muffler")
    c = cen[mm]
    mid = 0.5 * (c.max(axis=0) + c.min(axis=0))
    oval = ((c[:, 1] - mid[1]) / (0.5 * g["mm_width"])) ** 2 + (
        (c[:, 2] - mid[2]) / (0.5 * g["mm_height"])
    ) ** 2
    mantle = oval > 0.9
    inlet = ~mantle & (c[:, 0] < c[:, 0].min() + 0.06)
    outlet = ~mantle & (c[:, 0] > c[:, 0].max() - 0.06)
    parts = dict(mantle=mantle, inlet_cap=inlet, outlet_cap=outlet, baffles=~(mantle | inlet))
    parts["baffles"] &= ~outlet
    full = {}
    for name, sub in parts.items():
        mask = np.zeros(sh.n_elements, bool)
        mask[np.flatnonzero(mm)[sub]] = True
        full[name] = mask
    return full


def where_they_work() -> None:
    model = get_model("exhaust_shell", mesh_density=MESH)
    r = model.solve(n_modes=12, energies=True)
    en = r.energies
    masks = muffler_surfaces(model, shell_geometry(FITS[0]))
    for j in (8, 9):
        by_part = np.argsort(-en.strain_by_part[:, j])[:4]
        parts = ", ".join(f"{en.parts[i]} {en.strain_by_part[i, j]:.2f}" for i in by_part)
        surf = ", ".join(f"{k} {en.shell_strain[m, j].sum():.2f}" for k, m in masks.items())
        print(f"mode {j + 1} ({r.frequencies_hz[j]:.1f} Hz) strain: {parts}")
        print(f"  main muffler by surface: {surf}")


def modes_9_10(geometry: dict) -> str:
    """Modes 9 and 10 (frequency, plane and nodes) and the RMS / max error of all 12 against
    seed Table 1."""
    try:
        model = get_model("exhaust_shell", geometry=geometry, mesh_density=MESH)
    except BayesUpdateError as exc:
        return f"not built: {exc}"
    r = model.solve(n_modes=12)
    chars = mode_character(model.structure, r.modes.shapes)
    err = 100 * (r.frequencies_hz / TABLE1_FEA_HZ - 1)
    pair = "  ".join(
        f"{r.frequencies_hz[j]:6.1f} Hz {chars[j]['plane']}{chars[j]['nodes']}" for j in (8, 9)
    )
    return f"{pair}   RMS {np.sqrt(np.mean(err**2)):5.2f} %, max {np.abs(err).max():5.1f} %"


def main() -> None:
    where_they_work()
    print("modes 9, 10 (seed Table 1: 71.0 Hz H5, 88.6 Hz V5)")
    print(f"  {'best (oval collar)':32s} {modes_9_10(dict(FITS[0]))}")
    for name, change in VARIANTS.items():
        print(f"  {name:32s} {modes_9_10({**BASE, **change})}")
    # a rigid inlet joint: the inlet pipe continued inside the muffler to its first baffle
    with mock.patch.dict(exhaust_shell._TUBES, {"mm": ((0, 2),)}):  # noqa: SLF001
        print(f"  {'inlet pipe to the first baffle':32s} {modes_9_10(dict(BASE))}")
    g = fitted_geometry("best")
    for label, kv in (("fitted k_v, k_h", g["joint_log10_k_v"]), ("k_v = k_h", None)):
        h = {**g, "joint_log10_k_v": g["joint_log10_k_h"] if kv is None else kv}
        f = get_model("exhaust", geometry=h).solve(n_modes=12).frequencies_hz
        print(f"beam exhaust, {label}: modes 9, 10 {np.round(f[8:10], 1).tolist()} Hz")


if __name__ == "__main__":
    main()
