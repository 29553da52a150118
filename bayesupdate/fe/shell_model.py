"""A shell mesh as data (``ShellMesh``), its checks, and its parametric assembly.

``shell_mesh(...)`` validates and broadcasts the inputs (errors name the node or element);
``ShellAssembly`` precomputes frames, element pieces and the sparse pattern once, then builds the
global K and M for any element thicknesses, either directly or - for thickness *parameters*
(groups of elements sharing one thickness) - as the exact affine sum
K(theta) = K_fixed + sum_j sum_p theta_j^p K_jp (``shell.power_matrices``), which costs a few
vector operations on the CSR data.  Element numbering: quads first, then triangles.
"""

import warnings
from dataclasses import dataclass

import numpy as np

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.elements import shell
from bayesupdate.fe.laminate import SectionMatrices
from bayesupdate.fe.sparse_modal import SparsePattern, element_dofs

#: warp (largest node distance from the mean plane / mean diagonal) above which a quad is reported:
#: the flat element drops the out-of-plane offsets, an error of the order of the warp itself.
WARP_LIMIT = 0.01


class ShellMeshWarning(UserWarning):
    """A shell element is usable but distorted (warped quad)."""


@dataclass(frozen=True)
class ShellMesh:
    """Shell elements as arrays (SI).  nodes (N, 3) [m]; quads (nq, 4), trias (nt, 3) node
    numbers; per element (nq + nt,), quads first: thickness [m], E [Pa], nu, rho [kg/m^3],
    offset [m] and offset_ratio [-] (reference plane at offset + offset_ratio t below the
    mid-surface), nsm [kg/m^2] non-structural mass per area; bending_ratio and shear_ratio
    (n_el,) or None: the bending inertia over t^3 / 12 (default 1) and the transverse shear
    thickness over t (default 5/6; quads only, the DKT triangle is shear rigid), Nastran's
    PSHELL 12I/T**3 and TS/T (``shell.local_pieces``); a quad whose shear_ratio is inf has no
    transverse shear flexibility (a PSHELL with MID3 blank: the discrete Kirchhoff
    quadrilateral, ``shell.quad_operators``); bending_nu (n_el,) or None (nu): the Poisson
    ratio of the bending material (PSHELL MID2, another MAT1 than MID1); membrane_ratio
    (n_el,) or None (1): 0 for a shell with no membrane (PSHELL MID1 blank).  A membrane
    (PSHELL MID2 blank) has bending_ratio and shear_ratio 0 (``shell.local_pieces``).
    section : ``fe.laminate.SectionMatrices`` (n_el rows, each element's local axes) or None:
    anisotropic sections (laminates) whose stiffness replaces E, nu and the ratios; E, nu and
    the ratios stay for the checks, the families and the thickness powers."""

    nodes: np.ndarray
    quads: np.ndarray
    trias: np.ndarray
    thickness: np.ndarray
    E: np.ndarray
    nu: np.ndarray
    rho: np.ndarray
    offset: np.ndarray
    offset_ratio: np.ndarray
    nsm: np.ndarray
    bending_ratio: np.ndarray | None = None
    shear_ratio: np.ndarray | None = None
    bending_nu: np.ndarray | None = None
    membrane_ratio: np.ndarray | None = None
    section: SectionMatrices | None = None

    @property
    def n_elements(self) -> int:
        return len(self.quads) + len(self.trias)

    @property
    def n_dof(self) -> int:
        return 6 * len(self.nodes)

    def element_name(self, e: int) -> str:
        nq = len(self.quads)
        return f"quad {e}" if e < nq else f"tria {e - nq}"


def shell_mesh(
    nodes,
    quads=None,
    trias=None,
    thickness=1e-3,
    E=210e9,
    nu=0.3,
    rho=7850.0,
    offset=0.0,
    offset_ratio=0.0,
    nsm=0.0,
    warp_limit: float = WARP_LIMIT,
    bending_ratio=None,
    shear_ratio=None,
    bending_nu=None,
    membrane_ratio=None,
) -> ShellMesh:
    """Validated ``ShellMesh``; scalars broadcast to every element (``bending_ratio`` and
    ``shear_ratio``: None keeps the solid section's 1 and 5/6; ``bending_nu``: None keeps nu
    in bending; ``membrane_ratio``: None keeps the membrane).  Raises BayesUpdateError naming
    the element or node at fault; warns (``ShellMeshWarning``) for warped quads."""
    nodes = np.asarray(nodes, dtype=float)
    q = np.zeros((0, 4), int) if quads is None else np.asarray(quads, dtype=np.int64)
    t = np.zeros((0, 3), int) if trias is None else np.asarray(trias, dtype=np.int64)
    if nodes.ndim != 2 or nodes.shape[1] != 3 or not np.all(np.isfinite(nodes)):
        raise BayesUpdateError("shell mesh: nodes must be a finite (N, 3) array of coordinates")
    if q.ndim != 2 or q.shape[1] != 4 or t.ndim != 2 or t.shape[1] != 3:
        raise BayesUpdateError("shell mesh: quads must be (nq, 4) and trias (nt, 3) node numbers")
    n_el = len(q) + len(t)
    if n_el == 0:
        raise BayesUpdateError("shell mesh: no elements")
    props = {}
    values = dict(
        thickness=thickness, E=E, nu=nu, rho=rho, offset=offset, offset_ratio=offset_ratio, nsm=nsm
    )
    ratios = dict(bending_ratio=bending_ratio, shear_ratio=shear_ratio, bending_nu=bending_nu,
                  membrane_ratio=membrane_ratio)  # fmt: skip
    values.update({k: v for k, v in ratios.items() if v is not None})
    for name, value in values.items():
        v = np.asarray(value, dtype=float)
        if v.ndim > 1 or (v.ndim == 1 and v.size != n_el):
            raise BayesUpdateError(f"shell mesh: {name} must be a scalar or one value per element")
        props[name] = np.broadcast_to(v, (n_el,)).copy()
    mesh = ShellMesh(nodes, q, t, **props)
    check_mesh(mesh, warp_limit)
    return mesh


def _first(mask):
    return int(np.flatnonzero(mask)[0])


def check_mesh(mesh: ShellMesh, warp_limit: float = WARP_LIMIT) -> None:
    """Connectivity, geometry and property checks (see ``shell_mesh``)."""
    n = len(mesh.nodes)
    conn = [mesh.quads, mesh.trias]
    offset = [0, len(mesh.quads)]
    for c, off in zip(conn, offset, strict=True):
        if c.size and (c.min() < 0 or c.max() >= n):
            e = _first(np.any((c < 0) | (c >= n), axis=1)) + off
            raise BayesUpdateError(
                f"shell mesh: {mesh.element_name(e)} uses a node not in 0..{n - 1}"
            )
        s = np.sort(c, axis=1)
        rep = np.any(s[:, 1:] == s[:, :-1], axis=1)
        if np.any(rep):
            e = _first(rep) + off
            raise BayesUpdateError(
                f"shell mesh: {mesh.element_name(e)} repeats a node ({c[e - off].tolist()})"
            )
    used = np.zeros(n, bool)
    for c in conn:
        used[c.ravel()] = True
    if not np.all(used):
        raise BayesUpdateError(
            f"shell mesh: node {_first(~used)} is used by no element; remove it or connect it"
        )
    _check_properties(mesh)
    _check_geometry(mesh, warp_limit)


def _check_properties(mesh: ShellMesh) -> None:
    checks = (
        ("thickness", mesh.thickness, lambda v: v > 0, "> 0"),
        ("E", mesh.E, lambda v: v > 0, "> 0"),
        ("nu", mesh.nu, lambda v: (v > -1) & (v < 0.5), "in (-1, 0.5)"),
        ("rho", mesh.rho, lambda v: v >= 0, ">= 0"),
        ("nsm", mesh.nsm, lambda v: v >= 0, ">= 0"),
        ("offset", mesh.offset, lambda v: np.ones(v.shape, bool), "finite"),
        ("offset_ratio", mesh.offset_ratio, lambda v: np.ones(v.shape, bool), "finite"),
    )
    shear = mesh.shear_ratio
    if shear is not None:  # +inf is a shear-rigid (Kirchhoff) element, not a fault
        shear = np.where(shear == np.inf, 1.0, shear)
    ratios = (("bending_ratio", mesh.bending_ratio), ("shear_ratio", shear),
              ("membrane_ratio", mesh.membrane_ratio))  # fmt: skip
    checks += tuple((n, v, lambda v: v >= 0, ">= 0") for n, v in ratios if v is not None)
    if mesh.bending_nu is not None:
        checks += (("bending_nu", mesh.bending_nu, lambda v: (v > -1) & (v < 0.5), "in (-1, 0.5)"),)
    _check(checks, mesh)
    _check_parts(mesh)


def _check_parts(mesh: ShellMesh) -> None:
    """A shell has a membrane or a bending part, and a bending part its transverse shear (a
    zero shear ratio leaves the deflection free of the rotations)."""
    n = mesh.n_elements
    bending = np.ones(n) if mesh.bending_ratio is None else mesh.bending_ratio
    membrane = np.ones(n) if mesh.membrane_ratio is None else mesh.membrane_ratio
    shear = np.ones(n) if mesh.shear_ratio is None else mesh.shear_ratio
    rules = ((bending + membrane > 0, "it has neither membrane nor bending stiffness"),
             ((bending == 0) | (shear > 0), "its bending has no transverse shear stiffness"),
             ((bending > 0) | (shear == 0), "it has transverse shear but no bending"))  # fmt: skip
    for ok, why in rules:
        if not np.all(ok):
            raise BayesUpdateError(f"shell mesh: {mesh.element_name(_first(~ok))}: {why}")


def _check(checks, mesh: ShellMesh) -> None:
    """Raise on the first element whose value breaks its rule: checks (name, (n_el,) values,
    rule function, rule text)."""
    for name, v, ok, rule in checks:
        bad = ~np.isfinite(v) | ~ok(v)
        if np.any(bad):
            e = _first(bad)
            raise BayesUpdateError(
                f"shell mesh: {mesh.element_name(e)} has {name} = {v[e]}; it must be {rule}"
            )


def _check_geometry(mesh: ShellMesh, warp_limit: float) -> None:
    nq = len(mesh.quads)
    for c, off in ((mesh.quads, 0), (mesh.trias, nq)):
        if not c.size:
            continue
        x = mesh.nodes[c]
        edges = np.linalg.norm(np.roll(x, -1, axis=1) - x, axis=2)
        f = shell.quad_frames(x) if c.shape[1] == 4 else shell.tria_frames(x)
        scale = edges.max(axis=1)
        tiny = (edges.min(axis=1) <= 1e-8 * scale) | ~(f.area > 1e-10 * scale**2)
        if np.any(tiny):
            e = _first(tiny) + off
            raise BayesUpdateError(
                f"shell mesh: {mesh.element_name(e)} has zero area or a zero-length edge "
                f"(nodes {c[e - off].tolist()})"
            )
        if c.shape[1] == 4:
            ops = shell.quad_operators(f.xy)
            bad = np.any(ops.wdet <= 0, axis=1)
            if np.any(bad):
                e = _first(bad)
                raise BayesUpdateError(
                    f"shell mesh: quad {e} is not convex or its nodes are not in order around "
                    f"it (nodes {c[e].tolist()})"
                )
            warped = f.warp > warp_limit
            if np.any(warped):
                e = _first(warped)
                warnings.warn(
                    f"shell mesh: {int(warped.sum())} quad(s) warped beyond {warp_limit:g}, e.g. "
                    f"quad {e} (warp {f.warp[e]:.3g}); split them into triangles for accuracy",
                    ShellMeshWarning,
                    stacklevel=4,
                )


def _families(mesh: ShellMesh) -> list[tuple[np.ndarray, str]]:
    """(element indices, kind) of the mesh's element families: MITC4 quads, shear-rigid quads
    (``shear_ratio`` inf: the discrete Kirchhoff quadrilateral), triangles; empty ones left
    out.  Without a shear-rigid quad the families are the quads and the triangles, as they
    always were (the same order, so the same sums)."""
    nq = len(mesh.quads)
    rigid = np.zeros(nq, bool) if mesh.shear_ratio is None else mesh.shear_ratio[:nq] == np.inf
    out = [(np.flatnonzero(~rigid), "quad"), (np.flatnonzero(rigid), "kirchhoff quad"),
           (nq + np.arange(len(mesh.trias)), "tria")]  # fmt: skip
    return [(idx, kind) for idx, kind in out if idx.size]


class ShellAssembly:
    """Geometry-dependent precomputation of a ``ShellMesh``: element frames, the sources of the
    thickness-free element pieces (``shell.PieceSource``: the pieces themselves are computed in
    chunks when needed, not kept) and the sparse pattern.  ``lumped``: lumped (row-sum) mass;
    ``rotary_inertia=False`` drops the rho t^3 / 12 rotary inertia (for peers without it)."""

    def __init__(self, mesh: ShellMesh, lumped: bool = False, rotary_inertia: bool = True):
        self.mesh = mesh
        self.families = []  # (element indices, dofs (n_e, d), frames, piece source)
        for idx, kind in _families(mesh):
            conn = mesh.quads[idx] if kind != "tria" else mesh.trias[idx - len(mesh.quads)]
            x = mesh.nodes[conn]
            f = shell.tria_frames(x) if kind == "tria" else shell.quad_frames(x)
            b, s, n, m = shell.optional_rows(idx, mesh.bending_ratio, mesh.shear_ratio,
                                             mesh.bending_nu, mesh.membrane_ratio)  # fmt: skip
            source = shell.PieceSource(
                f.xy,
                f.height,
                mesh.E[idx],
                mesh.nu[idx],
                lumped,
                rotary_inertia,
                b,
                s,
                kirchhoff=kind == "kirchhoff quad",
                bending_nu=n,
                membrane_ratio=m,
                section=None if mesh.section is None else mesh.section.rows(idx),
            )
            self.families.append((idx, element_dofs(conn), f, source))
        self.pattern = SparsePattern(mesh.n_dof, [fam[1] for fam in self.families])

    def element_matrices(self, thickness=None):
        """Global-axis element matrices at ``thickness`` (n_el,) [m] (default: the mesh's),
        computed directly: list of (K (n_e, d, d), M (n_e, d, d)) per family."""
        m = self.mesh
        t = m.thickness if thickness is None else np.asarray(thickness, dtype=float)
        out = []
        for idx, _, f, p in self.families:
            K, M = shell.direct_matrices(
                p, t[idx], m.rho[idx], m.nsm[idx], m.offset[idx], m.offset_ratio[idx]
            )
            out.append((shell.to_global(K, f.R), shell.to_global(M, f.R)))
        return out

    def assemble(self, thickness=None, include=None):
        """Global (K, M) CSR [N/m, kg] at element thicknesses (n_el,) [m], direct path;
        ``include`` (n_el,) bool keeps only some elements."""
        mats = self.element_matrices(thickness)
        if include is not None:
            keep = [np.asarray(include)[idx][:, None, None] for idx, *_ in self.families]
            mats = [(k * w, m * w) for (k, m), w in zip(mats, keep, strict=True)]
        pat = self.pattern
        return pat.csr(pat.data([k for k, _ in mats])), pat.csr(pat.data([m for _, m in mats]))

    def power_data(self, elements=None, scale=None):
        """Per-power CSR data of the elements ``elements`` (bool/int index, default all):
        (K {p: (nnz,)}, M {p: (nnz,)}) with K = sum_p t^p K_p for a common thickness t;
        ``scale`` (n_el,) (default ones): element e has thickness scale_e t, so its power-p
        matrices are multiplied by scale_e^p.

        Elements go through their pieces, ``power_matrices`` and ``to_global`` in chunks of
        ``shell.CHUNK`` (each chunk vectorized), so the (n, d, d) temporaries of the pieces and the
        seven powers never exist for the whole mesh at once; a power that is zero everywhere is
        left out."""
        m = self.mesh
        sel = np.zeros(m.n_elements, bool)
        sel[np.arange(m.n_elements) if elements is None else elements] = True
        scale = np.ones(m.n_elements) if scale is None else np.asarray(scale, dtype=float)
        store = ({}, {})
        for b, (idx, _, f, source) in enumerate(self.families):
            pos = self.pattern.positions[b].reshape(len(idx), -1)
            for k, sub in source.chunks(np.flatnonzero(sel[idx])):
                i = idx[k]
                mats = shell.power_matrices(sub, m.rho[i], m.nsm[i], m.offset[i], m.offset_ratio[i])
                for out, by_power in zip(store, mats, strict=True):
                    for power, X in by_power.items():
                        if np.any(X):
                            X = X * (scale[i] ** power)[:, None, None]
                            _add_into(
                                out, power, pos[k], shell.to_global(X, f.R[k]), self.pattern.nnz
                            )
        return store


def _add_into(out: dict, power: int, pos: np.ndarray, X: np.ndarray, nnz: int) -> None:
    """out[power] (nnz,) += the element stack X (n, d, d) summed at CSR positions pos (n, d^2);
    the bincount spans only the chunk's range of positions."""
    lo, hi = int(pos.min()), int(pos.max()) + 1
    if power not in out:
        out[power] = np.zeros(nnz)
    out[power][lo:hi] += np.bincount((pos - lo).ravel(), X.ravel(), hi - lo)


class ThicknessParametrization:
    """K(theta), M(theta) for thickness parameters theta (n_par,) [m]: element e takes the
    thickness theta[group[e]] (group[e] = -1 keeps the mesh's thickness).  The per-power data
    are stored once on each group's own CSR positions, so an evaluation costs
    O(nnz x powers) vector operations and no element computation."""

    def __init__(self, assembly: ShellAssembly, group):
        self.assembly = assembly
        group = np.asarray(group, dtype=np.int64)
        mesh = assembly.mesh
        if group.shape != (mesh.n_elements,) or group.max() < 0:
            raise BayesUpdateError("thickness groups: need one group number (>= -1) per element")
        self.n_par = int(group.max()) + 1
        K, M = assembly.assemble(include=group < 0)
        self.K0, self.M0 = K.data.copy(), M.data.copy()
        self.terms = []  # (positions, {p: K values}, {p: M values}) per group
        for j in range(self.n_par):
            Kp, Mp = assembly.power_data(group == j)
            pos = np.flatnonzero(np.any([np.abs(v) > 0 for v in (*Kp.values(), *Mp.values())], 0))
            self.terms.append(
                (pos, {p: v[pos] for p, v in Kp.items()}, {p: v[pos] for p, v in Mp.items()})
            )

    def data(self, theta):
        """(K data, M data) (nnz,) each at thickness parameters theta (n_par,) [m]."""
        theta = np.asarray(theta, dtype=float)
        if theta.shape != (self.n_par,) or not np.all(np.isfinite(theta) & (theta > 0)):
            raise BayesUpdateError(
                f"thickness parameters: need {self.n_par} finite values > 0, got {theta}"
            )
        K, M = self.K0.copy(), self.M0.copy()
        for tj, (pos, Kp, Mp) in zip(theta, self.terms, strict=True):
            K[pos] += sum(tj**p * v for p, v in Kp.items())
            M[pos] += sum(tj**p * v for p, v in Mp.items())
        return K, M

    def assemble(self, theta):
        """Global (K, M) CSR at thickness parameters theta."""
        K, M = self.data(theta)
        pat = self.assembly.pattern
        return pat.csr(K), pat.csr(M)


@dataclass(frozen=True)
class ShellElements:
    """The shell elements of a ``Structure`` (global node numbers, quads first): quads (nq, 4),
    trias (nt, 3), and per element (nq + nt,) part index, thickness [m], E [Pa], nu,
    rho [kg/m^3], offset [m], offset_ratio [-], nsm [kg/m^2] as in ``ShellMesh``;
    thickness_factor (nq + nt,) or None (all 1): the element's thickness over its part's
    thickness parameter, where one binds it (t_e = factor_e theta: caps of another gauge than the
    mantle under one design variable; K stays the exact sum of theta^p factor_e^p K_ep);
    bending_ratio, shear_ratio, bending_nu, membrane_ratio (nq + nt,) or None as in
    ``ShellMesh``; lumped : the mass lumped at the nodes by row sums, translational only (no
    rotary inertia; Nastran's PARAM COUPMASS -1, its default), instead of consistent; section
    : anisotropic sections or None, as in ``ShellMesh``."""

    quads: np.ndarray
    trias: np.ndarray
    part: np.ndarray
    thickness: np.ndarray
    E: np.ndarray
    nu: np.ndarray
    rho: np.ndarray
    offset: np.ndarray
    offset_ratio: np.ndarray
    nsm: np.ndarray
    thickness_factor: np.ndarray | None = None
    bending_ratio: np.ndarray | None = None
    shear_ratio: np.ndarray | None = None
    bending_nu: np.ndarray | None = None
    membrane_ratio: np.ndarray | None = None
    lumped: bool = False
    section: SectionMatrices | None = None

    @property
    def n_elements(self) -> int:
        return len(self.quads) + len(self.trias)

    def factor(self) -> np.ndarray:
        """(n_el,) ``thickness_factor`` (ones where it is None)."""
        if self.thickness_factor is None:
            return np.ones(self.n_elements)
        return np.asarray(self.thickness_factor, dtype=float)

    def mesh(self, nodes: np.ndarray, **changes) -> ShellMesh:
        """The elements on the structure's nodes (N, 3) as a ``ShellMesh`` (not re-checked: nodes
        used by beams only are allowed here); ``changes`` replace property arrays."""
        names = ("thickness", "E", "nu", "rho", "offset", "offset_ratio", "nsm", "bending_ratio",
                 "shear_ratio", "bending_nu", "membrane_ratio", "section")  # fmt: skip
        props = {n: getattr(self, n) for n in names} | changes
        return ShellMesh(nodes, self.quads, self.trias, **props)

    def edges(self) -> np.ndarray:
        """(n, 2) node pairs along the element edges (for connectivity checks)."""
        q, t = self.quads, self.trias
        e = [np.stack([c, np.roll(c, -1, axis=1)], -1).reshape(-1, 2) for c in (q, t) if c.size]
        return np.concatenate(e) if e else np.zeros((0, 2), int)
