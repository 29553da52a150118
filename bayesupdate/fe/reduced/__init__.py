"""Certified parametric reduced basis for the free-free eigenproblem K(theta) u = lambda M(theta) u.

Offline (``ReducedFEModel.build``), one module per step:

1. ``affine``: parameter-separable terms.  Every beam, point mass and spring is grouped by the
   parameters bound to it (``FEModel.affine_terms``); linear parameters scale fixed element
   matrices, wall thickness and bend factor are interpolated in log(value) (``interpolation``:
   barycentric Chebyshev, Berrut & Trefethen, SIAM Rev. 46, 2004) to ``interp_tol``.
   Interpolation weights are linear in the interpolated matrices, so projecting the node
   matrices once gives the reduced matrices for every theta.  Shells (thickness, modulus,
   density), general beams and rods enter exactly, with no interpolation (``shell_terms``:
   shell K and M are polynomials of degree 3 in the thickness).  Supports and rigid elements
   are allowed: the basis holds the rigid motions they allow (none for a clamped structure).
2. ``basis``: elastic mode shapes (n_modes + ``extra_modes``) at seeded scrambled-Sobol points of
   the box (snapshots), rigid-body part removed, compressed by POD in the energy (K) norm of the
   box centre (Quarteroni, Manzoni & Negri, *Reduced Basis Methods for PDEs*, 2016, ch. 6); the
   six rigid-body motions are kept exactly as the first basis vectors.  On large models each
   snapshot also gives its modes' design-sensitivity vectors (``sensitivity``: static
   corrections from one factorization at the snapshot), so 8 snapshots do the work of 32;
   ``estimator``: a residual indicator for an opt-in greedy choice of further snapshots.
3. ``certification``: reduced frequencies are Rayleigh-Ritz upper bounds of the full ones;
   seeded validation points are solved in full and the basis enriched until the largest
   relative frequency error is below ``tol``, else (``max_size``) the model warns and falls back
   to full solves.

Online (``ReducedFEModel.predict_frequencies_batch``, ``model``): reduced K and M for all points by
one matrix product each, rigid coordinates eliminated exactly, stacked Cholesky + ``eigvalsh``
(``fe.batched_eigen``).  ``coarsening``: a coarser basis inside a certified one (screening) and
a model localized on a sub-box.  ``enrichment``: a basis enriched for a local change of the
structure (an added effect) by attachment vectors.  ``settings``: the validated build settings.

Models are immutable: ``build``, ``certify_at``, ``coarsened`` and ``localized`` return new ones.
"""

from bayesupdate.fe.reduced.certification import Certificate
from bayesupdate.fe.reduced.interpolation import (
    barycentric_weights,
    barycentric_weights_columns,
    chebyshev_nodes,
)
from bayesupdate.fe.reduced.model import ReducedFEModel, reduced_model_for
from bayesupdate.fe.reduced.settings import ReducedSettings

__all__ = [
    "Certificate",
    "ReducedFEModel",
    "ReducedSettings",
    "barycentric_weights",
    "barycentric_weights_columns",
    "chebyshev_nodes",
    "reduced_model_for",
]
