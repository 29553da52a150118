"""Shape correlation shared by the test side and the model side: array maths only.

- MAC (Allemang & Brown 1982): MAC(a, b) = |a^H b|^2 / ((a^H a)(b^H b)), for real or complex
  shapes; AutoMAC, a set against itself.
- COMAC (Lieven & Ewins 1988) per DOF over paired modes.
- Mode pairing by MAC (Hungarian assignment, Kuhn 1955) with a threshold, swaps and unpaired
  modes named (``pair_modes``); frequencies only: in order (``pair_in_order``).
- SEREP (O'Callahan, Avitabile & Riemer 1989): the test-analysis model (TAM) of a model at the
  test DOFs, cross-orthogonality of mass-normalized test shapes with the model's through it,
  the model's pseudo-orthogonality, and test shapes expanded to every model DOF.
"""

from dataclasses import dataclass

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
    """Pair each test mode with a distinct model mode maximizing total MAC (Hungarian method).

    Returns (model_index (m_test,), mac (m_test,)).  Needs m_model >= m_test.
    """
    from scipy.optimize import linear_sum_assignment

    mac = mac_matrix(shapes_test, shapes_model)
    rows, cols = linear_sum_assignment(-mac)
    order = np.argsort(rows)
    return cols[order], mac[rows[order], cols[order]]


#: default MAC below which a test mode is not paired (a common acceptance level for paired modes
#: in test-analysis correlation is 0.9; 0.6 refuses only shapes that plainly differ)
DEFAULT_MAC_THRESHOLD = 0.6


@dataclass(frozen=True)
class ModePairs:
    """Test modes paired with model modes (``pair_modes``); indices are 0-based.

    test, model : (k,) int, the accepted pairs (test ascending).  mac : (k,) their MAC.
    refused : ((test, model, mac), ...) the assignment's pairs below the threshold (not paired).
    swapped : ((test, model), ...) accepted pairs whose model mode is out of the test's order
        (its rank among the paired model modes differs from the test mode's rank).
    unpaired_test, unpaired_model : modes of each set in no accepted pair.
    method : "mac" (Hungarian on the MAC) or "order" (frequencies only: i-th with i-th).
    """

    test: np.ndarray
    model: np.ndarray
    mac: np.ndarray
    refused: tuple[tuple[int, int, float], ...]
    swapped: tuple[tuple[int, int], ...]
    unpaired_test: tuple[int, ...]
    unpaired_model: tuple[int, ...]
    method: str


def _swaps(test: np.ndarray, model: np.ndarray) -> tuple[tuple[int, int], ...]:
    rank_model = np.argsort(np.argsort(model))
    rank_test = np.argsort(np.argsort(test))
    return tuple((int(t), int(m)) for t, m, a, b in zip(test, model, rank_test, rank_model,
                                                         strict=True) if a != b)  # fmt: skip


def pair_modes(mac: np.ndarray, threshold: float = DEFAULT_MAC_THRESHOLD) -> ModePairs:
    """Pairs of test and model modes by MAC: the assignment maximizing the total MAC (Hungarian
    method, Kuhn 1955, ``scipy.optimize.linear_sum_assignment``), then every pair whose MAC is
    below ``threshold`` refused.

    mac : (m_test, m_model) MAC matrix (``mac_matrix(test, model)``); either set may be larger.
    Returns ``ModePairs``: pairs, refused pairs, swaps and the unpaired modes of both sets.
    """
    from scipy.optimize import linear_sum_assignment

    mac = np.asarray(mac, dtype=float)
    rows, cols = linear_sum_assignment(-mac)
    keep = mac[rows, cols] >= threshold
    refused = tuple(
        (int(r), int(c), float(mac[r, c])) for r, c in zip(rows[~keep], cols[~keep], strict=True)
    )
    test, model = rows[keep], cols[keep]
    return ModePairs(
        test=test,
        model=model,
        mac=mac[test, model],
        refused=refused,
        swapped=_swaps(test, model),
        unpaired_test=tuple(int(i) for i in np.setdiff1d(np.arange(mac.shape[0]), test)),
        unpaired_model=tuple(int(j) for j in np.setdiff1d(np.arange(mac.shape[1]), model)),
        method="mac",
    )


def pair_in_order(n_test: int, n_model: int) -> ModePairs:
    """Frequencies only: the i-th test mode with the i-th model mode (MAC unknown: NaN)."""
    k = min(n_test, n_model)
    index = np.arange(k)
    return ModePairs(
        test=index,
        model=index.copy(),
        mac=np.full(k, np.nan),
        refused=(),
        swapped=(),
        unpaired_test=tuple(range(k, n_test)),
        unpaired_model=tuple(range(k, n_model)),
        method="order",
    )


# -- SEREP test-analysis model --------------------------------------------------------------
def serep_transformation(shapes: np.ndarray, shapes_at_test: np.ndarray) -> np.ndarray:
    """SEREP transformation T = Phi Phi_a^+ (n_dof, n_a) from the test DOFs to all model DOFs
    (O'Callahan, Avitabile & Riemer 1989, "System equivalent reduction expansion process",
    Proc. 7th International Modal Analysis Conference).

    shapes : (n_dof, m) the retained model modes at all DOFs; shapes_at_test : (n_a, m) the same
    modes at the test DOFs (n_a >= m for an exact TAM).  Phi_a^+ is the Moore-Penrose inverse.
    """
    return np.asarray(shapes) @ np.linalg.pinv(np.asarray(shapes_at_test))


def serep_tam(transformation: np.ndarray, stiffness, mass) -> tuple[np.ndarray, np.ndarray]:
    """(K_a, M_a) (n_a, n_a): the test-analysis model T^T K T, T^T M T of full matrices K, M
    (n_dof, n_dof, dense or sparse) through a SEREP ``transformation`` T (O'Callahan et al.
    1989).  For retained modes with Phi_a of full column rank, Phi_a^T M_a Phi_a and
    Phi_a^T K_a Phi_a equal the full model's modal mass and stiffness exactly."""
    T = np.asarray(transformation)
    return np.asarray(T.T @ (stiffness @ T)), np.asarray(T.T @ (mass @ T))


def serep_mass(shapes_at_test: np.ndarray) -> np.ndarray:
    """SEREP TAM mass M_a = (Phi_a^+)^T Phi_a^+ (n_a, n_a) of mass-normalized retained modes
    (Phi^T M Phi = I makes T^T M T reduce to this; O'Callahan et al. 1989)."""
    p = np.linalg.pinv(np.asarray(shapes_at_test, dtype=float))
    return p.T @ p


def cross_orthogonality(
    test: np.ndarray, model: np.ndarray, mass_at_test: np.ndarray
) -> np.ndarray:
    """Cross-orthogonality X = Psi_t^T M_a Phi_a (m_t, m_m) of mass-normalized real test shapes
    and model shapes at the test DOFs through the TAM mass M_a (n_a, n_a).  Identical
    mass-normalized sets give the identity; common acceptance levels are |X_ii| >= 0.9 and
    |X_ij| <= 0.1 (NASA-STD-5002, 1996, "Load analyses of spacecraft and payloads")."""
    return np.asarray(test, dtype=float).T @ mass_at_test @ np.asarray(model, dtype=float)


def pseudo_orthogonality(shapes_at_test: np.ndarray, mass_at_test: np.ndarray) -> np.ndarray:
    """Pseudo-orthogonality Phi_a^T M_a Phi_a (m, m) of model shapes at the test DOFs through the
    TAM mass: the identity when the test DOFs tell the retained modes apart (Phi_a of full
    column rank); off-diagonal terms name modes the sensor set cannot separate."""
    return cross_orthogonality(shapes_at_test, shapes_at_test, mass_at_test)


def serep_expand(transformation: np.ndarray, test_shapes: np.ndarray) -> np.ndarray:
    """Test shapes (n_a, m_t) expanded to all model DOFs (n_dof, m_t): T Psi_t, the SEREP
    expansion (O'Callahan et al. 1989); the expanded shapes lie in the span of the retained
    model modes and match the test exactly at the test DOFs when Phi_a has full row rank."""
    return np.asarray(transformation) @ np.asarray(test_shapes)
