"""Assembly of the global stiffness K and mass M, vectorised over elements.

``Assembler`` precomputes everything that depends on geometry and connectivity only (element frames,
DOF maps, the sparse pattern, a bandwidth-reducing ordering).  ``assemble(props)`` then builds K and
M for any element property values in one pass with no per-element Python loop: element matrices are
computed as (n_e, 12, 12) stacks and scattered into the fixed CSR pattern by ``np.bincount``.

Density, Young's modulus, point masses and spring stiffnesses enter K and M linearly (``PartTerms``
gives the exact affine terms); wall thickness does not (area and second moments are polynomials in t
and the Timoshenko shear parameter is rational in them), so those parts are re-assembled.
"""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.elements import ElementSettings, families_of
from bayesupdate.fe.elements.base import FamilyMatrices, rigid_mass
from bayesupdate.fe.elements.beam import TubeBeams, element_frames
from bayesupdate.fe.elements.point_mass import offset_link, point_mass_matrices
from bayesupdate.fe.elements.spring import two_node_matrices
from bayesupdate.fe.sections import section_areas
from bayesupdate.fe.structure import Structure


@dataclass(frozen=True)
class ElementProperties:
    """Per-element property values used by one assembly (all SI).

    beam_thickness, beam_rho, beam_E, beam_bend_factor : (E,) - the last multiplies the B31.3 factor
    (1 = none); mass_scale : (P,) factors on point masses; spring_scale : (S,) factors on springs.
    """

    beam_thickness: np.ndarray
    beam_rho: np.ndarray
    beam_E: np.ndarray
    beam_bend_factor: np.ndarray
    mass_scale: np.ndarray
    spring_scale: np.ndarray


class Assembler:
    """Geometry-dependent precomputation for fast repeated assembly of one ``Structure``."""

    def __init__(self, structure: Structure):
        self.structure = s = structure
        self.n_dof = s.n_dof
        x1 = s.nodes[s.beam_nodes[:, 0]]
        x2 = s.nodes[s.beam_nodes[:, 1]]
        self.frames, self.lengths = element_frames(x1, x2, s.beam_up)
        self.beam_dofs = (6 * s.beam_nodes[:, :, None] + np.arange(6)).reshape(-1, 12)
        self.mass_dofs = 6 * s.mass_node[:, None] + np.arange(6)
        # rigid link of point masses: node DOFs -> DOFs at the mass centre
        self._mass_T = offset_link(s.mass_offset)
        grounded = s.spring_nodes[:, 1] < 0
        b_nodes = np.where(grounded, s.spring_nodes[:, 0], s.spring_nodes[:, 1])
        self.spring_dofs = np.concatenate(
            [6 * s.spring_nodes[:, :1] + np.arange(6), 6 * b_nodes[:, None] + np.arange(6)], axis=1
        )
        self.spring_grounded = grounded
        self._spring_offset = s.spring_offsets()
        self._settings = settings = ElementSettings(s.shear, s.rotary_inertia)
        self.tubes = TubeBeams(
            self.frames,
            self.lengths,
            s.beam_shape,
            s.beam_width,
            s.beam_height,
            s.beam_nu,
            s.beam_shear_factor,
            s.beam_elbow,
            s.beam_bend_radius,
        )
        # the registered element families (``fe.elements.base``): no parameter acts on them,
        # so their matrices are computed once
        self.families = tuple(FamilyMatrices.of(f, s.nodes, settings) for f in families_of(s))
        self._build_pattern()
        self._family_K = self._scatter_families("K")
        self._family_M = self._scatter_families("M")

    # -- sparse pattern ------------------------------------------------------------------------
    def _build_pattern(self):
        n = self.n_dof
        blocks = [self.beam_dofs, self.mass_dofs, self.spring_dofs]
        blocks += [f.dofs for f in self.families]
        rows = np.concatenate([np.repeat(d, d.shape[1], axis=1).ravel() for d in blocks])
        cols = np.concatenate([np.tile(d, (1, d.shape[1])).ravel() for d in blocks])
        # every node gets its diagonal so the pattern is never structurally singular
        rows = np.concatenate([rows, np.arange(n)])
        cols = np.concatenate([cols, np.arange(n)])
        key = rows.astype(np.int64) * n + cols
        uniq, inverse = np.unique(key, return_inverse=True)
        self.nnz = uniq.size
        self.pattern_rows = (uniq // n).astype(np.int32)
        self.pattern_cols = (uniq % n).astype(np.int32)
        counts = [d.shape[0] * d.shape[1] ** 2 for d in blocks]
        splits = np.cumsum(counts)
        self._pos_beam = inverse[: splits[0]]
        self._pos_mass = inverse[splits[0] : splits[1]]
        self._pos_spring = inverse[splits[1] : splits[2]]
        self._pos_families = [inverse[a:b] for a, b in zip(splits[2:-1], splits[3:], strict=True)]
        indptr = np.zeros(n + 1, dtype=np.int32)
        np.add.at(indptr, self.pattern_rows + 1, 1)
        self.indptr = np.cumsum(indptr).astype(np.int32)

    def to_csr(self, data: np.ndarray) -> sp.csr_matrix:
        """CSR matrix on the fixed pattern from its (nnz,) data."""
        return sp.csr_matrix((data, self.pattern_cols, self.indptr), shape=(self.n_dof,) * 2)

    # -- element matrices ----------------------------------------------------------------------
    def default_properties(self) -> ElementProperties:
        s = self.structure
        return ElementProperties(
            beam_thickness=s.beam_thickness.copy(),
            beam_rho=s.beam_rho.copy(),
            beam_E=s.beam_E.copy(),
            beam_bend_factor=np.ones(len(s.beam_part)),
            mass_scale=np.ones(len(s.mass_node)),
            spring_scale=np.ones(len(s.spring_part)),
        )

    def beam_matrices(self, props: ElementProperties, elements=None):
        """Global-axis beam matrices (n_e, 12, 12) for ``elements`` (index array, default all)
        (``elements.beam.TubeBeams``)."""
        return self.tubes.matrices(props, self._settings, elements)

    def mass_matrices(self, props: ElementProperties) -> np.ndarray:
        """(P, 6, 6) point-mass matrices at their nodes (rigid offset included)."""
        s = self.structure
        scale = props.mass_scale
        return point_mass_matrices(
            self._mass_T, s.mass_value * scale, s.mass_inertia * scale[:, None, None]
        )

    def spring_matrices(self, props: ElementProperties) -> np.ndarray:
        """(S, 12, 12) spring stiffness on [node_a DOFs, node_b DOFs] (``fe.elements.spring``:
        acting at
        each spring's location); grounded springs have zero blocks on their (dummy) second
        node."""
        s = self.structure
        k = s.spring_k * props.spring_scale[:, None]
        return two_node_matrices(k, s.spring_frame, self.spring_grounded, self._spring_offset)

    def _scatter_families(self, which: str) -> np.ndarray | None:
        """(nnz,) sum of the registered families' K or M (None: no family has any)."""
        data = None
        for f, pos in zip(self.families, self._pos_families, strict=True):
            mats = getattr(f, which)
            if np.any(mats):
                part = self._scatter(pos, mats)
                data = part if data is None else data + part
        return data

    def assemble(self, props: ElementProperties | None = None):
        """Global K and M as CSR matrices, plus the element matrices used (for energies).

        Returns (K, M, parts) where parts = dict(beam_K, beam_M, mass_M, spring_K) (the
        registered families' matrices are ``families``).
        """
        props = self.default_properties() if props is None else props
        check_properties(self.structure, props)
        bK, bM = self._beam_matrices_reusing(props)
        mM, M_mass = self._reusing("mass", props.mass_scale, self.mass_matrices, self._pos_mass)
        sK, K_spring = self._reusing(
            "spring", props.spring_scale, self.spring_matrices, self._pos_spring
        )
        K = self._scatter(self._pos_beam, bK) + K_spring
        M = self._scatter(self._pos_beam, bM) + M_mass
        if self._family_K is not None:
            K += self._family_K
        if self._family_M is not None:
            M += self._family_M
        elem = dict(beam_K=bK, beam_M=bM, mass_M=mM, spring_K=sK)
        return self.to_csr(K), self.to_csr(M), elem

    def _reusing(self, name: str, scale: np.ndarray, matrices, positions):
        """(element matrices, their (nnz,) scatter) of the point masses or springs at factors
        ``scale``, from the previous call when the factors are the same (no parameter on them:
        always).  ``matrices(props)`` needs only the factors; the arrays are read-only."""
        memos = self.__dict__.setdefault("_memos", {})
        memo = memos.get(name)
        if memo is None or not np.array_equal(memo[0], scale):
            kw = {"mass_scale": scale} if name == "mass" else {"spring_scale": scale}
            mats = matrices(_Factors(**kw))
            data = self._scatter(positions, mats)
            mats.flags.writeable = data.flags.writeable = False
            memo = memos[name] = (scale.copy(), mats, data)
        return memo[1], memo[2]

    def _beam_matrices_reusing(self, props: ElementProperties):
        """Beam matrices at ``props``, recomputing only the beams whose properties differ from
        the previous call (a calibration changes a few parts at a time).  The memo holds copies,
        so callers may keep what they get."""
        key = np.stack([props.beam_thickness, props.beam_rho, props.beam_E, props.beam_bend_factor])
        memo = getattr(self, "_beam_memo", None)
        if memo is None or memo[0].shape != key.shape:
            bK, bM = self.beam_matrices(props)
        else:
            changed = np.flatnonzero(np.any(memo[0] != key, axis=0))
            bK, bM = memo[1].copy(), memo[2].copy()
            if changed.size:
                bK[changed], bM[changed] = self.beam_matrices(props, elements=changed)
        self._beam_memo = (key, bK.copy(), bM.copy())
        return bK, bM

    def _scatter(self, positions, element_matrices):
        """Sum element entries into the (nnz,) CSR data (float even for no elements)."""
        return np.bincount(positions, element_matrices.ravel(), self.nnz).astype(float, copy=False)

    def total_mass(self, props: ElementProperties | None = None):
        """Total mass [kg] and centre of gravity (3,) [m] from the beams, point masses and the
        registered families (``elements.base.rigid_mass`` of their M)."""
        props = self.default_properties() if props is None else props
        s = self.structure
        memo = getattr(self, "_area_memo", None)  # areas change only with the wall thickness
        if memo is None or not np.array_equal(memo[0], props.beam_thickness):
            area = section_areas(s.beam_shape, s.beam_width, s.beam_height, props.beam_thickness)
            self._area_memo = memo = (props.beam_thickness.copy(), area)
        m_beam = props.beam_rho * memo[1] * self.lengths
        mid = 0.5 * (s.nodes[s.beam_nodes[:, 0]] + s.nodes[s.beam_nodes[:, 1]])
        m_point = s.mass_value * props.mass_scale
        pos_point = s.nodes[s.mass_node] + s.mass_offset
        total = m_beam.sum() + m_point.sum()
        moment = m_beam @ mid + m_point @ pos_point
        for f in self.families:
            # the rigid-body functional of ``sparse_assembly.GeneralAssembler.total_mass``:
            # trace / 3 of the translational block, the first moments from the
            # translation-rotation coupling
            Mr = rigid_mass(f.M, f.dofs, s.nodes)
            total = total + np.trace(Mr[:3, :3]) / 3.0
            moment = moment + np.array([Mr[1, 5], Mr[2, 3], Mr[0, 4]])
        cog = moment / total
        return float(total), cog


@dataclass(frozen=True)
class _Factors:
    """The point-mass or spring factors alone (what ``mass_matrices`` / ``spring_matrices``
    read of ``ElementProperties``)."""

    mass_scale: np.ndarray | None = None
    spring_scale: np.ndarray | None = None


def check_properties(structure: Structure, props: ElementProperties) -> None:
    """Raise BayesUpdateError naming the part if a property is non-physical."""
    tube = structure.beam_shape != 2  # solid bars have no wall
    checks = (
        ("thickness", props.beam_thickness[tube], structure.beam_part[tube], True),
        ("density", props.beam_rho, structure.beam_part, True),
        ("Young's modulus", props.beam_E, structure.beam_part, True),
        ("bend factor", props.beam_bend_factor, structure.beam_part, True),
        ("point-mass factor", props.mass_scale, structure.mass_part, False),
        ("spring factor", props.spring_scale, structure.spring_part, False),
    )
    for name, values, parts, strictly in checks:
        bad = ~np.isfinite(values) | ((values <= 0) if strictly else (values < 0))
        if np.any(bad):
            part = structure.parts[parts[np.flatnonzero(bad)[0]]]
            limit = "> 0" if strictly else ">= 0"
            raise BayesUpdateError(
                f"part {part!r}: {name} must be finite and {limit}, got "
                f"{values[np.flatnonzero(bad)[0]]}"
            )
    too_thick = tube & (
        2 * props.beam_thickness >= np.minimum(structure.beam_width, structure.beam_height)
    )
    if np.any(too_thick):
        i = np.flatnonzero(too_thick)[0]
        raise BayesUpdateError(
            f"part {structure.parts[structure.beam_part[i]]!r}: wall thickness "
            f"{props.beam_thickness[i]} m is not less than half the section size"
        )
