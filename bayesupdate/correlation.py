"""Shape correlation shared by the test side and the model side.

MAC (Allemang & Brown 1982): MAC(a, b) = |a^H b|^2 / ((a^H a)(b^H b)), for real or complex shapes.
COMAC (Lieven & Ewins 1988) per DOF over paired modes.
"""

import numpy as np


def mac_matrix(shapes_a: np.ndarray, shapes_b: np.ndarray) -> np.ndarray:
    """Modal assurance criterion between every column of ``shapes_a`` and of ``shapes_b``.

    shapes_a : (n_dof, m_a), shapes_b : (n_dof, m_b), real or complex.
    Returns (m_a, m_b) values in [0, 1].
    A zero vector gives MAC 0.
    """
    a = np.asarray(shapes_a)
    b = np.asarray(shapes_b)
    if a.ndim == 1:
        a = a[:, None]
    if b.ndim == 1:
        b = b[:, None]
    if a.shape[0] != b.shape[0]:
        raise ValueError(f"mac_matrix: shapes have {a.shape[0]} and {b.shape[0]} DOFs")
    cross = np.abs(a.conj().T @ b) ** 2
    na = np.real(np.sum(a.conj() * a, axis=0))
    nb = np.real(np.sum(b.conj() * b, axis=0))
    denom = np.outer(na, nb)
    with np.errstate(invalid="ignore", divide="ignore"):
        mac = np.where(denom > 0, cross / np.where(denom > 0, denom, 1.0), 0.0)
    return np.clip(mac, 0.0, 1.0)


def auto_mac(shapes: np.ndarray) -> np.ndarray:
    """AutoMAC of a shape set, (m, m): off-diagonal values show spatial aliasing of the sensors."""
    return mac_matrix(shapes, shapes)


def comac(shapes_a: np.ndarray, shapes_b: np.ndarray) -> np.ndarray:
    """Coordinate MAC per DOF over paired modes (columns already paired), (n_dof,) in [0, 1].

    Each shape pair is first scaled by the modal scale factor so the sign/scale of a column does
    not matter; low values point at DOFs where the two sets disagree.
    """
    a = np.asarray(shapes_a)
    b = np.asarray(shapes_b)
    # modal scale factor (Allemang 2003) aligns each column of b to a, so sign and scale drop out
    norm_b = np.sum(np.abs(b) ** 2, axis=0)
    msf = np.sum(b.conj() * a, axis=0) / np.where(norm_b > 0, norm_b, 1.0)
    b = b * msf[None, :]
    num = np.abs(np.sum(a * b.conj(), axis=1)) ** 2
    den = np.sum(np.abs(a) ** 2, axis=1) * np.sum(np.abs(b) ** 2, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)


def pair_by_mac(shapes_test: np.ndarray, shapes_model: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pair each test mode with a distinct model mode maximising total MAC (Hungarian method).

    Returns (model_index (m_test,), mac (m_test,)).  Needs m_model >= m_test.
    """
    from scipy.optimize import linear_sum_assignment

    mac = mac_matrix(shapes_test, shapes_model)
    rows, cols = linear_sum_assignment(-mac)
    order = np.argsort(rows)
    return cols[order], mac[rows[order], cols[order]]
