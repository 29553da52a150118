"""Matrix products over a batch of points whose rows do not depend on the batch.

A BLAS gemm (or gemv) rounds an output row by its place in the kernel's block of rows and by the
size of the call: OpenBLAS with the SkylakeX kernels (the machine of 2026-11-29) computes rows in
blocks of 12, the earlier development machine's in blocks of 8 (or 4), and a call's last
rows go through edge kernels; numpy's own row sums take another path for a single row.  So the
same point evaluated in two batches can differ in its last bits, and a batch split between this
process and a worker (``inference.evaluators.SplitDensity``) would not give the serial chain.

``row_product`` computes C @ T for a batch of ``MIN_ROWS`` rows or more in calls of exactly
``PRODUCT_ROWS`` rows, the last padded with zeros: every row then lies in a full block of a call
of the same size, whatever the batch, on any kernel whose block of rows divides 24.  A smaller
batch takes one plain product: padding a calibration's residual calls of 1-4 points to 48 rows
made ``sample --model exhaust --data paper:ema``'s 17 starts 1.74-1.90 s against 1.33-1.44 s,
and such batches are never the parts of a split one (``inference.evaluators.SPLIT_MIN_POINTS``
is twice ``MIN_ROWS``).  ``SplitDensity`` still checks the first split batch of a run against
the whole batch, for a BLAS where the blocks do not divide 24 (one of 16 rows: the split stops,
the values stay the serial run's).
"""

import numpy as np

__all__ = ["MIN_ROWS", "PRODUCT_ROWS", "row_product"]

#: the fewest rows computed in ``PRODUCT_ROWS``-row calls (module docstring)
MIN_ROWS = 5

#: rows of every call (a multiple of 2, 3, 4, 6, 8 and 12).  Not 48 (which 16 divides too): the
#: padding costs a call's rows, and the demo's shell posterior (16 walkers, batches of 8, a
#: 96-vector basis: C (8, 30) @ T (30, 9216) 0.19 ms in 8 rows, 0.36 ms in 24, 0.63 ms in 48)
#: makes about 4,000 such products
PRODUCT_ROWS = 24


def row_product(C: np.ndarray, T: np.ndarray) -> np.ndarray:
    """C @ T for C (B, a) and T (a, b) or (a,), each row of the result the same bits in any batch
    of ``MIN_ROWS`` rows or more (module docstring).  Returns (B, b), or (B,) for a vector T."""
    B = C.shape[0]
    if B < MIN_ROWS:
        return C @ T
    vector = T.ndim == 1
    T2 = T[:, None] if vector else T
    out = np.empty((B, T2.shape[1]))
    block = np.zeros((PRODUCT_ROWS, C.shape[1]))
    for lo in range(0, B, PRODUCT_ROWS):
        part = C[lo : lo + PRODUCT_ROWS]
        n = part.shape[0]
        if n < PRODUCT_ROWS:
            block[:n] = part
            part = block
        out[lo : lo + n] = (part @ T2)[:n]
    return out[:, 0] if vector else out
