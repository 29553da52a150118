"""A shared check of the shell tests: an element family's matrices are exact polynomials in its
thickness, the affine split a PSHELL T binding and the reduced basis use
(``shell.power_matrices``)."""

import numpy as np

from bayesupdate.fe.elements import shell


def assert_thickness_polynomials(pieces, n: int, density: float) -> dict:
    """K(t) = sum_p t^p K_p and M(t) likewise (``shell.power_matrices``, with an offset, an
    offset ratio and NSM) equal the directly built matrices (``shell.direct_matrices``) at three
    thicknesses to 1e-12, for the ``LocalPieces`` of n elements; returns the K powers."""
    rho, nsm = np.full(n, density), np.full(n, 0.4)
    offset, ratio = np.full(n, 1e-3), np.full(n, 0.5)
    K, M = shell.power_matrices(pieces, rho, nsm, offset, ratio)
    for t in (1e-3, 4e-3, 2e-2):
        Kd, Md = shell.direct_matrices(pieces, np.full(n, t), rho, nsm, offset, ratio)
        for powers, direct in ((K, Kd), (M, Md)):
            np.testing.assert_allclose(sum(t**q * X for q, X in powers.items()), direct,
                                       rtol=1e-12, atol=1e-12 * np.abs(direct).max())  # fmt: skip
    return K
