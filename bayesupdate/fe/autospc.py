"""DOFs with no stiffness, found per node and held as Nastran's AUTOSPC holds them.

At each node the constrained stiffness T^T K T (``constraints.constraint_transform``) has a 3 x 3
block for the node's independent translations and one for its rotations, in the node's own
(CD) axes.  A direction n of such a block with n^T B n <= ``RATIO`` x its largest eigenvalue
is singular (MSC Nastran's grid point singularity test and MYSTRAN's AUTOSPC_RAT use the same
ratio, 1e-8), and since K is positive semidefinite, B n = 0 means K n = 0: the direction
carries no stiffness at all and couples to no other DOF.

* A singular direction along one of the node's axes is held by a single-point constraint of
  that component (Nastran's AUTOSPC), exactly.
* A singular subspace off the node's axes that carries no mass (a membrane's rotations in a
  plane skewed to the axes: only the drilling rotation has stiffness) is held through d of the
  node's components chosen so that no singular direction is left free (the d x d part of the
  null basis on them is the best conditioned one).  Exact: the space splits into the held
  components' complement and the null space, the null space has no stiffness, no mass and no
  coupling, so the finite eigenpairs are the same as with the null space itself held.
* A singular subspace off the axes that carries mass (a flat membrane skewed to the axes: its
  normal motion) cannot be held by components without changing the answer; it is not held
  but reported (``SingularDofs.loose``: left free it would give zero-frequency modes), and the
  Nastran reader refuses the deck, naming the GRIDs, so that it is held along its own
  direction (an SPC in a CD frame along it).
"""

from dataclasses import dataclass
from itertools import combinations

import numpy as np
import scipy.sparse as sp

#: eigenvalue ratio below which a direction of a node's 3 x 3 block is singular
RATIO = 1e-8
#: a block whose largest entry is below this fraction of K's largest diagonal is all singular
ABSOLUTE = 1e-12


@dataclass(frozen=True)
class SingularDofs:
    """held (k,) global DOF numbers to hold (in the node's axes); loose (m,) node numbers with a
    singular direction off their axes that carries mass (left free); off_axis (p,) node numbers
    whose massless singular directions off their axes were held through chosen components."""

    held: np.ndarray
    loose: np.ndarray
    off_axis: np.ndarray


def _blocks(A, dofs: np.ndarray, n_groups: int, group: np.ndarray) -> np.ndarray:
    """(n_groups, 3, 3) diagonal blocks of the reduced matrix A (n_ind, n_ind): entries whose row
    and column are in the same group; ``group`` (n_ind,) each independent DOF's group,
    ``dofs`` (n_ind,) its global DOF number (position in the block: dof % 3)."""
    A = sp.coo_matrix(A)
    same = group[A.row] == group[A.col]
    out = np.zeros((n_groups, 3, 3))
    np.add.at(out, (group[A.row[same]], dofs[A.row[same]] % 3, dofs[A.col[same]] % 3),
              A.data[same])  # fmt: skip
    return out


def singular_dofs(K, M, independent: np.ndarray, axes=None) -> SingularDofs:
    """The DOFs to hold (see the module's rules), numbered 6 node + component in each node's
    axes.

    K, M : reduced stiffness and mass T^T K T, T^T M T (n_ind, n_ind), sparse; independent
    (n_ind,) the global DOF number (6 node + component) of each reduced DOF; axes (n_nodes, 3,
    3) or None: each node's axes (rows) in the axes of its reduced DOFs (Nastran's CD frame),
    applied where all three translations or rotations of the node are independent.
    """
    independent = np.asarray(independent)
    key = independent // 3  # 2 node + 0 (translations) or 1 (rotations)
    groups, group = np.unique(key, return_inverse=True)
    Kb = _blocks(K, independent, groups.size, group)
    Mb = _blocks(M, independent, groups.size, group)
    present = np.zeros((groups.size, 3), bool)
    present[group, independent % 3] = True
    if axes is not None:  # B -> A B A^T on the full blocks
        full = present.all(axis=1)
        A = np.asarray(axes)[groups[full] // 2]
        Kb[full] = A @ Kb[full] @ A.transpose(0, 2, 1)
        Mb[full] = A @ Mb[full] @ A.transpose(0, 2, 1)
    floor = ABSOLUTE * max(float(np.abs(K.diagonal()).max(initial=0.0)), 1.0)
    m_floor = ABSOLUTE * max(float(np.abs(M.diagonal()).max(initial=0.0)), 1e-300)
    whole, partial = _null_spaces(Kb, present, floor)
    # a block singular in all three directions is held whole (each axis is a null direction)
    held, loose, off_axis = list((3 * groups[whole][:, None] + np.arange(3)).ravel()), [], []
    for g, comps, N in partial:
        aligned = np.all(np.linalg.norm(N[comps], axis=1) > 1 - 1e-9)
        massive = np.abs(N.T @ Mb[g] @ N).max() > m_floor
        if aligned or not massive:
            held += [3 * groups[g] + c for c in comps]
            if not aligned:
                off_axis.append(groups[g] // 2)
        else:
            loose.append(groups[g] // 2)
    as_int = lambda v: np.unique(np.array(v, np.int64))  # noqa: E731
    return SingularDofs(as_int(held), as_int(loose), as_int(off_axis))


def _null_spaces(Kb: np.ndarray, present: np.ndarray, floor: float):
    """(the groups whose full block is singular in all three directions, the others: (group,
    components to hold, null basis N (3, d) in the block's axes) of each block of Kb (n, 3, 3)
    with a singular direction among its ``present`` (n, 3) components); eigenvalues below
    RATIO times the block's largest are singular, and every one where the largest is below
    ``floor`` (an absolute test on the block, not on each direction: a thin shell's drilling is
    small beside a stiff spring elsewhere, and it is no singularity).  Full blocks are solved
    as one batch; blocks with a fixed or dependent component one by one."""
    full = np.flatnonzero(present.all(axis=1))
    lam, vec = np.linalg.eigh(Kb[full])
    null = (lam <= RATIO * lam[:, -1:]) | (lam[:, -1:] <= floor)
    whole = null.all(axis=1)
    batch = (full, null & ~whole[:, None], vec)
    return full[whole], _partial_null_spaces(Kb, present, floor, batch)


def _partial_null_spaces(Kb, present, floor, batch):
    """The second part of ``_null_spaces``: the full blocks singular in one or two directions
    (``batch``: their indices, null flags and eigenvectors), then the blocks with a fixed or
    dependent component."""
    full, null, vec = batch
    for i in np.flatnonzero(null[:, 0]):
        N = vec[i][:, null[i]]
        yield full[i], _held_components(N, np.arange(3)), N
    for g in np.flatnonzero(~present.all(axis=1) & present.any(axis=1)):
        c = np.flatnonzero(present[g])
        lam_g, vec_g = np.linalg.eigh(Kb[g][np.ix_(c, c)])
        null = (lam_g <= RATIO * lam_g[-1]) | (lam_g[-1] <= floor)
        if null.any():
            N = np.zeros((3, int(null.sum())))
            N[c] = vec_g[:, null]
            yield g, _held_components(N, c), N


def _held_components(N: np.ndarray, present: np.ndarray) -> list:
    """The d of the ``present`` components (d = N's columns) on which the null basis N (3, d)
    is best conditioned (largest |det| of its d x d rows): holding them leaves no null
    direction free."""
    choices = [list(c) for c in combinations(present.tolist(), N.shape[1])]
    return max(choices, key=lambda c: abs(np.linalg.det(N[c])))
