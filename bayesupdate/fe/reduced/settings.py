"""What a reduced model is built to: modes, tolerance, seed and the sizes of the offline stage."""

from dataclasses import dataclass

from bayesupdate.errors import BayesUpdateError


@dataclass(frozen=True)
class ReducedSettings:
    """Settings of a ``ReducedFEModel`` build, validated once.

    n_modes : elastic modes certified; tol : largest relative frequency error accepted on the
    validation points; seed : seed of the scrambled-Sobol snapshot and validation points;
    n_snapshots, n_validation : points per set; extra_modes : modes beyond ``n_modes`` kept from
    each snapshot; max_size : largest basis (vectors incl. rigid) before falling back to full
    solves; max_rounds : enrichment rounds; interp_tol : relative error of the element-matrix
    interpolation of non-linear parameters (``reduced.affine``).
    """

    n_modes: int = 12
    tol: float = 1e-4
    seed: int = 0
    n_snapshots: int = 32
    n_validation: int = 32
    extra_modes: int = 4
    max_size: int = 120
    max_rounds: int = 6
    interp_tol: float = 1e-9

    def __post_init__(self):
        for name in ("n_modes", "seed", "n_snapshots", "n_validation", "extra_modes"):
            object.__setattr__(self, name, int(getattr(self, name)))
        for name in ("max_size", "max_rounds"):
            object.__setattr__(self, name, int(getattr(self, name)))
        for name in ("tol", "interp_tol"):
            object.__setattr__(self, name, float(getattr(self, name)))
        counts = ("n_modes", "n_snapshots", "n_validation", "max_size", "max_rounds")
        bad = [n for n in counts if getattr(self, n) < 1]
        bad += [n for n in ("tol", "interp_tol") if not getattr(self, n) > 0]
        bad += ["extra_modes"] * (self.extra_modes < 0)
        if bad:
            raise BayesUpdateError(
                f"reduced model: {bad[0]} = {getattr(self, bad[0])} is out of range (counts and "
                "tolerances must be > 0, extra_modes >= 0)"
            )
