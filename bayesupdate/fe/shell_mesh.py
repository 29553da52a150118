"""Structured shell meshes: node coordinates (n, 3) [m] and connectivity, nothing else.

Quads are numbered counter-clockwise seen from their outward (+normal) side; ``split_quads`` cuts
quads into triangles (``plate(..., triangles=True)`` with a checkerboard of diagonals).
"""

import numpy as np


def _grid_quads(n1: int, n2: int, index: np.ndarray) -> np.ndarray:
    """(n1 * n2, 4) quads of a grid whose node numbers are index (n1 + 1, n2 + 1)."""
    i, j = np.meshgrid(np.arange(n1), np.arange(n2), indexing="ij")
    i, j = i.ravel(), j.ravel()
    return np.stack([index[i, j], index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]], axis=1)


def split_quads(quads: np.ndarray, flip=None) -> np.ndarray:
    """(2 nq, 3) triangles from quads (nq, 4), cut along the 1-3 diagonal, or along 2-4 where
    ``flip`` (nq,) bool is set (default: every second quad)."""
    q = np.asarray(quads)
    flip = (np.arange(len(q)) % 2 == 1) if flip is None else np.asarray(flip, bool)
    a = np.stack([q[:, [0, 1, 2]], q[:, [0, 2, 3]]], axis=1)
    b = np.stack([q[:, [0, 1, 3]], q[:, [1, 2, 3]]], axis=1)
    return np.where(flip[:, None, None], b, a).reshape(-1, 3)


def plate(lx: float, ly: float, nx: int, ny: int, triangles: bool = False):
    """Rectangular plate [0, lx] x [0, ly] in the x-y plane (normal +z), nx x ny cells.

    Returns (nodes (N, 3), quads (nq, 4), trias (nt, 3)); with ``triangles`` each cell is split
    in two (diagonals in a checkerboard pattern) and quads is empty.
    Node (i, j) at (i lx / nx, j ly / ny) has number i * (ny + 1) + j.
    """
    x, y = np.meshgrid(np.linspace(0, lx, nx + 1), np.linspace(0, ly, ny + 1), indexing="ij")
    nodes = np.stack([x.ravel(), y.ravel(), np.zeros(x.size)], axis=1)
    index = np.arange(x.size).reshape(nx + 1, ny + 1)
    quads = _grid_quads(nx, ny, index)
    if triangles:  # checkerboard of diagonals: no preferred direction
        checker = (np.repeat(np.arange(nx), ny) + np.tile(np.arange(ny), nx)) % 2 == 1
        return nodes, np.zeros((0, 4), int), split_quads(quads, checker)
    return nodes, quads, np.zeros((0, 3), int)


def cylinder(radius: float, length: float, n_circ: int, n_axial: int):
    """Closed circular cylinder, axis along z from 0 to ``length``, nodes on the radius [m].

    Returns (nodes, quads (n_circ * n_axial, 4)) with outward normals; node (k, j) at angle
    2 pi k / n_circ and height j length / n_axial has number k * (n_axial + 1) + j.
    """
    phi = 2 * np.pi * np.arange(n_circ) / n_circ
    z = np.linspace(0.0, length, n_axial + 1)
    P, Z = np.meshgrid(phi, z, indexing="ij")
    nodes = np.stack([radius * np.cos(P).ravel(), radius * np.sin(P).ravel(), Z.ravel()], axis=1)
    index = np.arange(P.size).reshape(n_circ, n_axial + 1)
    index = np.concatenate([index, index[:1]], axis=0)  # close the circumference
    return nodes, _grid_quads(n_circ, n_axial, index)


def box(lx: float, ly: float, lz: float, nx: int, ny: int, nz: int):
    """Closed box [0, lx] x [0, ly] x [0, lz] of six quad faces sharing their edge nodes.

    Returns (nodes, quads) with outward normals; nx, ny, nz cells along each side.
    """
    ijk = np.stack(
        np.meshgrid(np.arange(nx + 1), np.arange(ny + 1), np.arange(nz + 1), indexing="ij"), -1
    ).reshape(-1, 3)
    on_surface = (
        (ijk[:, 0] % nx == 0) | (ijk[:, 1] % ny == 0) | (ijk[:, 2] % nz == 0)
    )  # i in {0, nx} etc.
    surf = ijk[on_surface]
    number = -np.ones((nx + 1, ny + 1, nz + 1), int)
    number[surf[:, 0], surf[:, 1], surf[:, 2]] = np.arange(len(surf))
    nodes = surf * np.array([lx / nx, ly / ny, lz / nz])
    faces = []
    # (fixed axis, value, the two running axes ordered so that a x b points outwards)
    for axis, end in ((0, 0), (0, nx), (1, 0), (1, ny), (2, 0), (2, nz)):
        a, b = [ax for ax in range(3) if ax != axis]
        outward = end > 0
        if (axis == 1) != (not outward):  # the y faces have a x b = -e_y for (a, b) = (x, z)
            a, b = b, a
        sizes = (nx, ny, nz)
        idx = np.zeros((sizes[a] + 1, sizes[b] + 1), int)
        ia, ib = np.meshgrid(np.arange(sizes[a] + 1), np.arange(sizes[b] + 1), indexing="ij")
        sel = [None, None, None]
        sel[axis], sel[a], sel[b] = np.full(ia.shape, end), ia, ib
        idx = number[sel[0], sel[1], sel[2]]
        faces.append(_grid_quads(sizes[a], sizes[b], idx))
    return nodes, np.concatenate(faces)
