"""Modal strain-energy density maps on a model's shells (seed section 3.2, Fig. 6): per shell
element, the strain energy of a mode per unit area, drawn on the shell mesh.

``shell_energy_map`` gathers the numbers from an ``FEResult`` solved with ``energies=True``
(``fe.energy.general_energies``: U_e = 1/2 phi_e^T K_e phi_e of each element of a mass-normalized
mode); ``plot_energy_density_map`` draws one mode (one 3-D panel per shell part, matplotlib,
Agg) and returns the PNG's path.
"""

from dataclasses import dataclass
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.cm import ScalarMappable
from matplotlib.colors import LogNorm
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

from bayesupdate import plotting
from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.elements.shell import quad_frames, tria_frames

#: the colour scale spans this many decades below each mode's peak density
DECADES = 3.0


@dataclass(frozen=True)
class ShellEnergyMap:
    """Strain-energy density of the modes on the shell elements (quads first, then triangles).

    polygons : (n_shell, 4, 3) element corners [m] (a triangle repeats its last corner).
    area : (n_shell,) element areas [m^2] (those the element matrices use).
    part : (n_shell,) index into ``part_names``.
    density : (n_shell, m) strain energy per unit area of each mass-normalized mode [J/m^2 per
        kg m^2 of modal mass]: sum(density[:, k] * area) is the shells' part of the mode's
        strain energy.
    modal_energy : (m,) each mode's whole strain energy lambda / 2 (beams and springs included).
    frequencies_hz : (m,) the modes' frequencies.
    """

    polygons: np.ndarray
    area: np.ndarray
    part: np.ndarray
    part_names: tuple[str, ...]
    density: np.ndarray
    modal_energy: np.ndarray
    frequencies_hz: np.ndarray

    def shell_energy(self) -> np.ndarray:
        """(m,) the strain energy carried by the shells: sum of density x area [J]."""
        return self.density.T @ self.area

    def part_shares(self) -> np.ndarray:
        """(n_parts, m) share of each mode's strain energy in each shell part (fractions)."""
        shares = np.zeros((len(self.part_names), self.density.shape[1]))
        np.add.at(shares, self.part, self.density * self.area[:, None])
        return shares / self.modal_energy


def has_shells(structure) -> bool:
    """True when the structure has shell elements (a map can be drawn)."""
    return structure.shells is not None and structure.shells.n_elements > 0


def shell_energy_map(structure, result) -> ShellEnergyMap:
    """The map of ``result`` (an ``FEResult`` of ``structure`` solved with ``energies=True``)."""
    e = result.energies
    if not has_shells(structure):
        raise BayesUpdateError("strain-energy density map: the model has no shell elements")
    if e is None or e.shell_strain_density is None:
        raise BayesUpdateError(
            "strain-energy density map: the result has no shell energies; solve with energies=True"
        )
    sh, nodes = structure.shells, structure.nodes
    quads = nodes[sh.quads] if len(sh.quads) else np.zeros((0, 4, 3))
    trias = nodes[sh.trias] if len(sh.trias) else np.zeros((0, 3, 3))
    area = np.concatenate([quad_frames(quads).area, tria_frames(trias).area])
    polygons = np.concatenate([quads, np.concatenate([trias, trias[:, -1:]], axis=1)])
    modal_energy = 0.5 * result.modes.eigenvalues
    return ShellEnergyMap(
        polygons=polygons,
        area=area,
        part=np.asarray(sh.part),
        part_names=tuple(structure.parts),
        density=e.shell_strain_density * modal_energy,
        modal_energy=modal_energy,
        frequencies_hz=np.asarray(result.frequencies_hz),
    )


#: the two views of each part (matplotlib azimuths [deg]): from the +x end, from the -x end
VIEWS = (-50.0, -130.0)


def _body_panel(ax, polygons, values, norm, cmap, azim: float) -> None:
    """One shell part in 3-D, coloured by ``values``, at its own (equal-aspect) scale."""
    faces = Poly3DCollection(polygons, cmap=cmap, norm=norm, linewidths=0.05, edgecolors="0.4")
    faces.set_array(values)
    ax.add_collection3d(faces)
    corners = polygons.reshape(-1, 3)
    # a flat part (a plate) gets a thin box rather than a singular axis
    pad = 0.5 * np.maximum(1e-3 * np.ptp(corners, axis=0).max() - np.ptp(corners, axis=0), 0.0)
    low, high = corners.min(axis=0) - pad, corners.max(axis=0) + pad
    ax.set_xlim(low[0], high[0])
    ax.set_ylim(low[1], high[1])
    ax.set_zlim(low[2], high[2])
    ax.set_box_aspect(high - low)
    ax.view_init(elev=25, azim=azim)
    ax.set_axis_off()


def plot_energy_density_map(emap: ShellEnergyMap, mode: int, path) -> Path:
    """Mode ``mode`` (0-based): each shell part's elements coloured by their share of the mode's
    strain energy per m^2 (log scale, ``DECADES`` below the peak), each part seen from both
    ends (``VIEWS``: a closed body hides one cap from any one view); returns ``path``."""
    share = 100.0 * emap.density[:, mode] / emap.modal_energy[mode]  # % of the mode per m^2
    parts = [int(p) for p in np.unique(emap.part)]
    shares = emap.part_shares()[:, mode]
    peak = max(float(share.max()), 1e-300)
    norm = LogNorm(vmin=peak * 10.0**-DECADES, vmax=peak, clip=True)
    cmap = matplotlib.colormaps["inferno"]
    fig = plotting.figure(figsize=(4.2 * len(parts) + 1.0, 7.0))
    for row, azim in enumerate(VIEWS):
        for i, p in enumerate(parts):
            ax = fig.add_subplot(2, len(parts), row * len(parts) + i + 1, projection="3d")
            mine = emap.part == p
            values = np.maximum(share[mine], norm.vmin)
            _body_panel(ax, emap.polygons[mine], values, norm, cmap, azim)
            if row == 0:
                ax.set_title(f"{emap.part_names[p]}: {100 * shares[p]:.1f} %", fontsize=9)
    bar = fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=fig.axes, shrink=0.7, pad=0.02)
    bar.set_label("strain energy [% of the mode per m^2]")
    fig.suptitle(
        f"Mode {mode + 1}, {emap.frequencies_hz[mode]:.2f} Hz: strain-energy density on the "
        f"shells ({100 * shares.sum():.1f} % of the mode's strain energy)",
        fontsize=10,
    )
    return plotting.save(fig, path, dpi=100, tight=True)


def write_energy_density_maps(structure, result, folder, n_show: int | None = None) -> list:
    """One PNG per mode (the first ``n_show``; None: all) in ``folder``: [(path, caption)]."""
    emap = shell_energy_map(structure, result)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    n = emap.density.shape[1] if n_show is None else min(n_show, emap.density.shape[1])
    out = []
    for k in range(n):
        path = plot_energy_density_map(emap, k, folder / f"sed_mode{k + 1:02d}.png")
        out.append(
            (
                path,
                f"Mode {k + 1} ({emap.frequencies_hz[k]:.2f} Hz): modal strain energy per unit "
                "area on the shell bodies (seed Fig. 6), log scale, each body seen from its outlet "
                "end (top) and its inlet end (bottom); the titles give each body's share of the "
                "mode's strain energy.",
            )
        )
    return out
