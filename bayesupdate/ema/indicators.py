"""Mode indicators and quality checks: sum-FRF, CMIF, MAC/AutoMAC/COMAC, FRF correlation.

CMIF (Shih et al. 1988): the singular values of the FRF matrix H(f) (n_out x n_in) at every
line; peaks of the first singular value mark modes, a second curve peaking at the same place
marks a repeated or closely spaced pair.  Missing response/reference pairs are zero in H(f).
FRAC (frequency response assurance criterion) compares a synthesized FRF with the measured one
like MAC compares shapes.
"""

import numpy as np

from bayesupdate.correlation import auto_mac, comac, mac_matrix
from bayesupdate.ema.bands import sum_frf
from bayesupdate.ema.frf_set import FrfSet


def frf_matrix(frfs: FrfSet) -> tuple[np.ndarray, tuple, tuple]:
    """FRF matrix (n_f, n_out, n_in) with zeros for unmeasured pairs, and its labels."""
    outs = tuple(dict.fromkeys(frfs.response_labels))
    ins = tuple(dict.fromkeys(frfs.reference_labels))
    mat = np.zeros((frfs.frequencies_hz.size, len(outs), len(ins)), complex)
    for k in range(frfs.n_frf):
        mat[:, outs.index(frfs.response_labels[k]), ins.index(frfs.reference_labels[k])] = frfs.frf[
            k
        ]
    return mat, outs, ins


def cmif(frfs: FrfSet) -> np.ndarray:
    """Complex mode indicator function: singular values (n_sv, n_f), largest first."""
    mat, _, _ = frf_matrix(frfs)
    return np.linalg.svd(mat, compute_uv=False).T


def frf_correlation(measured: np.ndarray, synthesized: np.ndarray) -> np.ndarray:
    """FRAC of each FRF row (n_frf,): |m^H s|^2 / ((m^H m)(s^H s)), 1 = identical shape."""
    m = np.atleast_2d(measured)
    s = np.atleast_2d(synthesized)
    num = np.abs(np.sum(m.conj() * s, axis=1)) ** 2
    den = np.sum(np.abs(m) ** 2, axis=1) * np.sum(np.abs(s) ** 2, axis=1)
    return np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)


__all__ = ["sum_frf", "cmif", "frf_matrix", "frf_correlation", "mac_matrix", "auto_mac", "comac"]
