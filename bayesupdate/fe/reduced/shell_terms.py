"""The exact affine terms of a general structure's shells and of a deck's bound line fields.

Shells are grouped by ``GeneralAssembler`` (same bound parameters, nominal E, rho and part); in a
group with thickness t, modulus E and density rho, exactly (``shell.power_matrices``)

    K = (E / E0) sum_{p=1..3} t^p K_p,     M = M_nsm + rho sum_{p=1..3} t^p M_p,

K_p at the nominal modulus E0, M_p per unit density.  With t = s_t theta_t (s the parameter's
``scale``) each product is a feature pair of ``AffineDecomposition``: theta_t^p (or the fixed
t0^p) times theta_E (or 1), theta_t^p times theta_rho (or 1), the constant factors folded into the
matrices.  Terms with the same feature pair are summed, so a deck with many fixed-thickness
property groups adds to the constant term only.  No interpolation: the decomposition is exact.
General beams and rods join the constant term (``reduced.affine``, through
``fe.elements.base``); a Nastran deck's line-element fields that enter
K and M linearly (``NastranModel.line_terms``: a shear-rigid PBAR's A, I1, I2, J, a PROD's A, J,
NSM) add theta_j x dK_j and the constant -theta0_j x dK_j.

Matrices are kept sparse on the DOFs they touch (``SparsePart``), as assembled by the full model.
"""

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe.model import AffineTerms, FEModel

#: shell property columns: a shell takes at most one parameter per column
_COLUMN = dict(thickness=0, youngs_modulus=1, modulus_factor=1, density=2)


@dataclass(frozen=True)
class SparsePart:
    """A term's matrix on the DOFs it touches: dofs (m,) global DOF numbers, matrix (m, m) CSR."""

    dofs: np.ndarray
    matrix: sp.csr_matrix

    def project(self, V: np.ndarray) -> np.ndarray:
        """(r, r) V^T X V for V (n_dof, r)."""
        Vd = V[self.dofs]
        return Vd.T @ (self.matrix @ Vd)


def pattern_parts(g, data: np.ndarray) -> list[SparsePart]:
    """The ``SparsePart`` of each row of ``data`` (n, nnz) on the general CSR pattern of ``g``
    (``GeneralAssembler``), on one shared sub-pattern: the union of the rows' non-zero entries
    on the DOFs they touch (an entry that is zero in one row is stored as an explicit zero: the
    same matrix).  The interpolation nodes of a deck's line group touch the same entries,
    so the pattern is sorted once instead of once per node."""
    pos = np.flatnonzero(np.any(data != 0, axis=0))
    dofs, inverse = np.unique(np.concatenate([g.rows[pos], g.cols[pos]]), return_inverse=True)
    local = inverse.reshape(2, -1)
    m = dofs.size
    # a CSR template whose entries are the 1-based indices into pos, in CSR order (the
    # pattern's (row, col) pairs are unique, so nothing is summed)
    where = np.arange(1, pos.size + 1, dtype=float)
    template = sp.csr_matrix((where, (local[0], local[1])), shape=(m, m))
    order = pos[template.data.astype(int) - 1]
    return [
        SparsePart(dofs, sp.csr_matrix((row[order], template.indices, template.indptr), (m, m)))
        for row in data
    ]


def power_feature(j: int, p: int, n_params: int) -> int:
    """Column of theta_j^p (p = 1, 2, 3) in the features [1, theta, theta^2, theta^3, ...]."""
    return 1 + (p - 1) * n_params + j


def shell_parameters(terms: AffineTerms, n_shell: int) -> np.ndarray:
    """(n_shell, 3) index of the parameter setting each shell's thickness, modulus and density
    (-1: none); raises when two parameters set the same property of one shell."""
    out = -np.ones((n_shell, 3), dtype=int)
    for j, term in enumerate(terms.parameters):
        if not term.shells.size:
            continue
        c = _COLUMN[term.property]
        taken = out[term.shells, c] >= 0
        if np.any(taken):
            other = terms.parameters[out[term.shells[taken][0], c]].name
            raise BayesUpdateError(
                f"reduced model: parameters {other} and {term.name} set the same property of "
                f"shell {int(term.shells[taken][0])}; bind each shell once"
            )
        out[term.shells, c] = j
    return out


def general_terms(fe: FEModel, terms: AffineTerms, f_ref: np.ndarray):
    """({(a, b): SparsePart} for K, the same for M): the shells' and line elements' terms keyed
    by their feature pair (``AffineDecomposition``; (0, 0) the constant term), each matrix
    multiplied by f_ref[a] f_ref[b] (the features at a reference point, so that the stored
    matrices have the size of their contribution there); empty on the banded beam path."""
    g = fe.general
    if g is None:
        return {}, {}
    n = len(fe.parameter_names)
    K, M = _Accumulator(g, f_ref), _Accumulator(g, f_ref)
    # a deck's line-element fields that enter linearly (``nastran.lines.LineTerm``):
    # K_L(theta) = K_L(deck) + sum_j (theta_j - theta0_j) dK_j, M likewise
    for t in getattr(fe, "line_terms", tuple)():
        j = fe.parameter_names.index(t.name)
        for acc, d in ((K, t.dK), (M, t.dM)):
            nz = np.flatnonzero(d)
            acc.add((1 + j, 0), nz, d[nz])
            acc.add((0, 0), nz, -t.theta0 * d[nz])
    sh = fe.structure.shells
    if sh is not None:
        bound = shell_parameters(terms, sh.n_elements)
        for rep, (pos, Kp, m0, Mp) in zip(g.group_rep, g.terms, strict=True):
            jt, je, jr = bound[rep]
            e_key, e_factor = 0, 1.0
            if je >= 0:
                t = terms.parameters[je]
                e_key = 1 + je
                e_factor = t.scale / (sh.E[rep] if t.property == "youngs_modulus" else 1.0)
            r_key, r_factor = (1 + jr, terms.parameters[jr].scale) if jr >= 0 else (0, sh.rho[rep])
            M.add((0, 0), pos, m0)
            for p in sorted(set(Kp) | set(Mp)):
                if jt >= 0:
                    t_key, t_factor = power_feature(jt, p, n), terms.parameters[jt].scale ** p
                else:
                    t_key, t_factor = 0, sh.thickness[rep] ** p
                if p in Kp:
                    K.add((t_key, e_key), pos, t_factor * e_factor * Kp[p])
                if p in Mp:
                    M.add((t_key, r_key), pos, t_factor * r_factor * Mp[p])
    return K.parts(), M.parts()


class _Accumulator:
    """Values on the positions of the general CSR pattern, collected per feature pair."""

    def __init__(self, g, f_ref):
        self.g = g
        self.f_ref = f_ref
        self.items: dict[tuple[int, int], list] = {}

    def add(self, key, pos, values) -> None:
        if len(pos):
            self.items.setdefault(key, []).append((pos, values))

    def parts(self) -> dict[tuple[int, int], SparsePart]:
        """{feature pair: ``SparsePart``}: each pair's values summed per position of the pattern
        and kept on the DOFs they touch.  The pattern is in CSR order (``GeneralAssembler``: its
        (row, col) keys sorted), so the touched positions, in ascending order, are already a CSR
        matrix's entries: no sort (a coordinate-format build sorted 2 x ~1e6 DOF numbers per
        pair, ~1 s of the shell exhaust's ~1.2 s decomposition)."""
        return {key: self._part(key, items) for key, items in self.items.items()}

    def _part(self, key, items) -> SparsePart:
        g, n_dof = self.g, self.g.n_dof
        pos = np.concatenate([p for p, _ in items])
        vals = np.concatenate([v for _, v in items]) * (self.f_ref[key[0]] * self.f_ref[key[1]])
        where = np.flatnonzero(np.bincount(pos, minlength=g.rows.size))
        summed = np.bincount(pos, weights=vals, minlength=g.rows.size)[where]
        rows, cols = g.rows[where], g.cols[where]
        touched = np.zeros(n_dof, dtype=bool)
        touched[rows] = True
        touched[cols] = True
        local = np.cumsum(touched) - 1
        m = int(local[-1]) + 1
        indptr = np.concatenate([[0], np.cumsum(np.bincount(local[rows], minlength=m))])
        X = sp.csr_matrix((summed, local[cols], indptr), shape=(m, m))
        return SparsePart(np.flatnonzero(touched), X)
