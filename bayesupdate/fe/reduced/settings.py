"""What a reduced model is built to: modes, tolerance, seed and the sizes of the offline stage."""

from dataclasses import dataclass

from bayesupdate.errors import BayesUpdateError

#: models with at least this many DOFs are built with sensitivities and the greedy by default:
#: there a full solve (seconds) outweighs the vector work (``reduced.sensitivity``,
#: ``reduced.estimator``); a beam model's full solve takes milliseconds and its build is short
LARGE_MODEL_DOFS = 5000
#: default snapshot points without / with design sensitivities (each snapshot then carries
#: n_params + 1 vectors per mode)
SNAPSHOTS_PLAIN, SNAPSHOTS_SENSITIVE = 32, 8
#: default training points of the residual-indicator greedy on a large model: 0, measured not
#: to pay on the shell exhaust (``docs/validation/shells-reduced.md``); opt in with greedy_train
GREEDY_TRAIN = 0


@dataclass(frozen=True)
class ReducedSettings:
    """Settings of a ``ReducedFEModel`` build, validated once.

    n_modes : elastic modes certified; tol : largest relative frequency error accepted on the
    validation points; seed : seed of the scrambled-Sobol snapshot and validation points;
    n_snapshots, n_validation : points per set (n_snapshots None: ``SNAPSHOTS_PLAIN``, or
    ``SNAPSHOTS_SENSITIVE`` with sensitivities); extra_modes : modes beyond ``n_modes`` kept from
    each snapshot; max_size : largest basis (vectors incl. rigid) before falling back to full
    solves; max_rounds : enrichment rounds; interp_tol : relative error of the element-matrix
    interpolation of non-linear parameters (``reduced.affine``); sensitivities : each snapshot
    also gives its modes' design-sensitivity vectors (``reduced.sensitivity``; None: on for
    models of ``LARGE_MODEL_DOFS`` or more); greedy_train : training points of the
    residual-indicator greedy before the validation rounds (``reduced.estimator``; 0: none;
    None: ``GREEDY_TRAIN`` on large models, else 0).  ``resolved(n_dof)`` fills the Nones in.
    """

    n_modes: int = 12
    tol: float = 1e-4
    seed: int = 0
    n_snapshots: int | None = None
    n_validation: int = 32
    extra_modes: int = 4
    max_size: int = 120
    max_rounds: int = 6
    interp_tol: float = 1e-9
    sensitivities: bool | None = None
    greedy_train: int | None = None

    def __post_init__(self):
        for name in ("n_modes", "seed", "n_validation", "extra_modes", "max_size", "max_rounds"):
            object.__setattr__(self, name, int(getattr(self, name)))
        for name in ("n_snapshots", "greedy_train"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, int(getattr(self, name)))
        if self.sensitivities is not None:
            object.__setattr__(self, "sensitivities", bool(self.sensitivities))
        for name in ("tol", "interp_tol"):
            object.__setattr__(self, name, float(getattr(self, name)))
        counts = ("n_modes", "n_validation", "max_size", "max_rounds")
        bad = [n for n in counts if getattr(self, n) < 1]
        bad += ["n_snapshots"] * (self.n_snapshots is not None and self.n_snapshots < 1)
        bad += [n for n in ("tol", "interp_tol") if not getattr(self, n) > 0]
        bad += ["extra_modes"] * (self.extra_modes < 0)
        bad += ["greedy_train"] * (self.greedy_train is not None and self.greedy_train < 0)
        if bad:
            raise BayesUpdateError(
                f"reduced model: {bad[0]} = {getattr(self, bad[0])} is out of range (counts and "
                "tolerances must be > 0, extra_modes and greedy_train >= 0)"
            )

    def resolved(self, n_dof: int) -> "ReducedSettings":
        """These settings with every None filled in for a model of ``n_dof`` DOFs."""
        large = n_dof >= LARGE_MODEL_DOFS
        sens = large if self.sensitivities is None else self.sensitivities
        snaps = SNAPSHOTS_SENSITIVE if sens else SNAPSHOTS_PLAIN
        greedy = (GREEDY_TRAIN if large else 0) if self.greedy_train is None else self.greedy_train
        return ReducedSettings(
            self.n_modes, self.tol, self.seed,
            snaps if self.n_snapshots is None else self.n_snapshots,
            self.n_validation, self.extra_modes, self.max_size, self.max_rounds,
            self.interp_tol, sens, greedy,
        )  # fmt: skip
