"""Synthetic modal models for the EMA tests and benchmarks (not part of the package: nothing a
user runs needs them): free-free beam bending shapes and a 12-mode model with the seed's Table 2
frequencies and planes."""

import numpy as np

#: beta_r L of the first free-free Euler-Bernoulli beam bending modes (cosh b cos b = 1)
FREE_BEAM_BETA_L = np.array(
    [
        4.730040745,
        7.853204624,
        10.995607838,
        14.137165491,
        17.278759657,
        20.420352245,
        23.561944902,
        26.703537556,
    ]
)


def free_beam_shapes(x_over_length: np.ndarray, n_modes: int) -> np.ndarray:
    """Free-free beam bending shapes (n_x, n_modes) at x/L, normalized to 2 at the ends."""
    x = np.asarray(x_over_length, dtype=float)[:, None]
    b = FREE_BEAM_BETA_L[:n_modes][None, :]
    sigma = (np.cosh(b) - np.cos(b)) / (np.sinh(b) - np.sin(b))
    return np.cosh(b * x) + np.cos(b * x) - sigma * (np.sinh(b * x) + np.sin(b * x))


def exhaust_like_model(n_points: int = 20, mass_kg: float = 12.0):
    """A 12-mode test model with the seed's Table 2 frequencies and planes (for demos/tests).

    Shapes: free-free beam bending shapes at ``n_points`` equally spaced sensors in V and H,
    assigned to the modes in frequency order per plane; "H" modes have no V motion, "V" modes no
    H motion and "HV" modes mix both (0.8 V, +-0.6 H).  Scaled as for a uniform beam of
    ``mass_kg`` (phi^T M phi = 1).  Damping 0.5 % rising to 3 %.  Returns (natural_hz (12,),
    damping (12,), shapes (2 n_points, 12), labels ``1V..nV, 1H..nH``).
    """
    from bayesupdate.models.exhaust_paper import TABLE2_EMA_HZ, TABLE2_PLANE

    x = (np.arange(n_points) + 0.5) / n_points
    phi = free_beam_shapes(x, 7)
    k_v = [0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 6]
    k_h = [0, 1, 0, 1, 1, 2, 2, 3, 3, 4, 5, 6]
    shapes = np.zeros((2 * n_points, 12))
    for r, plane in enumerate(TABLE2_PLANE):
        v = phi[:, k_v[r]] if "V" in plane else np.zeros(n_points)
        h = phi[:, k_h[r]] if "H" in plane else np.zeros(n_points)
        if plane == "HV":
            v, h = 0.8 * v, 0.6 * (-1) ** r * h
        shapes[:n_points, r], shapes[n_points:, r] = v, h
    labels = tuple(f"{k}V" for k in range(1, n_points + 1)) + tuple(
        f"{k}H" for k in range(1, n_points + 1)
    )
    damping = np.linspace(0.005, 0.03, 12)
    return TABLE2_EMA_HZ.copy(), damping, shapes / np.sqrt(mass_kg), labels
