"""The knobs of a discovery run (``workflow.discover``), one validated record per concept.

``DiscoverySettings`` holds the seed and four records, each validated once when made:

* ``LibraryScan``: which effects are scanned (``kinds``, ``locations``) and the level ``alpha``
  at which the baseline's modes are flagged;
* ``RefitBudget``: the baseline calibration's starts and the two refit tiers (quick, full);
* ``EvidenceSettings``: the fixed frequency noise level ``sigma`` and the PSIS-LOO budget;
* ``VerdictThresholds``: the prior odds, the thresholds of the verdict and the adequacy check
  (``workflow`` module docstring, step 5).

A study file's ``[discovery]`` table and the CLI options name the knobs flat (``max_refits``,
``sigma``, ...): ``DiscoverySettings.from_flat`` routes them to their records and ``flat``
gives them back in that one namespace (the result file stores them so).
"""

import numbers
from dataclasses import dataclass, field, replace

import numpy as np

from bayesupdate.errors import BayesUpdateError

#: fewest Laplace draws PSIS-LOO can smooth: it fits a generalized Pareto to the largest fifth
#: of the importance ratios (below 226 draws), and to no fewer than 5 of them (Vehtari et al.
#: 2024, "Pareto smoothed importance sampling", JMLR 25(72), sec. 3; ArviZ refuses fewer)
MIN_LOO_DRAWS = 25


def _check_positive_counts(record, names: tuple[str, ...]) -> None:
    for name in names:
        if int(getattr(record, name)) < 1:
            raise BayesUpdateError(f"discovery.{name}: must be >= 1")


@dataclass(frozen=True)
class LibraryScan:
    """kinds / locations : restrict the library (None: all kinds at all admissible locations).
    alpha : level of the baseline's mode flags (z-scores, MAC, shape tests)."""

    kinds: tuple | None = None
    locations: dict | None = None
    alpha: float = 0.05

    def __post_init__(self):
        if not 0 < self.alpha < 1:  # NaN fails too
            raise BayesUpdateError(f"discovery.alpha: must lie in (0, 1), got {self.alpha}")


@dataclass(frozen=True)
class RefitBudget:
    """baseline_starts : starts of the baseline calibration.  quick_refits / per_kind : the
    quick tier's candidates (best by score, plus the best of every kind); quick_nfev : its
    Gauss-Newton iterations.  max_refits : candidates re-fitted to convergence, each (and the
    baseline) with at most ``max_nfev`` evaluations per start."""

    baseline_starts: int = 4
    quick_refits: int = 20
    per_kind: int = 3
    quick_nfev: int = 4
    max_refits: int = 5
    max_nfev: int = 25

    def __post_init__(self):
        _check_positive_counts(
            self, ("baseline_starts", "quick_refits", "quick_nfev", "max_refits", "max_nfev")
        )
        if int(self.per_kind) < 0:
            raise BayesUpdateError(f"discovery.per_kind: must be >= 0, got {self.per_kind}")


@dataclass(frozen=True)
class EvidenceSettings:
    """sigma : fixed relative frequency noise level (None: the data's sd, else inferred).
    loo_top : fits (after the baseline) given PSIS-LOO, each with ``loo_draws`` draws (at least
    ``MIN_LOO_DRAWS``)."""

    sigma: float | None = None
    loo_top: int = 3
    loo_draws: int = 400

    def __post_init__(self):
        if self.sigma is not None and not (np.isfinite(self.sigma) and self.sigma > 0):
            raise BayesUpdateError(f"discovery.sigma: must be > 0, got {self.sigma}")
        if int(self.loo_top) < 0:
            raise BayesUpdateError(f"discovery.loo_top: must be >= 0, got {self.loo_top}")
        if int(self.loo_draws) < MIN_LOO_DRAWS:
            raise BayesUpdateError(
                f"discovery.loo_draws: must be >= {MIN_LOO_DRAWS} (PSIS-LOO smooths the largest "
                f"fifth of the draws' importance ratios, at least 5 of them), got {self.loo_draws}"
            )


@dataclass(frozen=True)
class VerdictThresholds:
    """threshold_log_odds / margin_ln_bf : posterior log odds vs the baseline and ln BF vs the
    runner-up a named effect must beat.  effect_prior : prior probability that one library
    effect is present.  bound_tolerance : fraction of an effect parameter's z range within
    which it counts as pinned on a bound.  adequacy_p : family-wise level of the named model's
    adequacy check.  max_noise_rel : largest inferred relative level that is still noise."""

    threshold_log_odds: float = 3.0
    margin_ln_bf: float = 2.0
    effect_prior: float = 0.5
    bound_tolerance: float = 0.005
    adequacy_p: float = 1e-3
    max_noise_rel: float = 0.01

    def __post_init__(self):
        if not (0 <= self.threshold_log_odds < np.inf and 0 <= self.margin_ln_bf < np.inf):
            raise BayesUpdateError(  # NaN fails the chained comparison too
                "discovery: thresholds on log odds (threshold_log_odds, margin_ln_bf, "
                "--threshold) must be finite numbers >= 0"
            )
        if not 0 < self.effect_prior < 1:
            raise BayesUpdateError(
                "discovery.effect_prior (--effect-prior): the prior probability that a library "
                f"effect is present must lie strictly between 0 and 1, got {self.effect_prior}"
            )
        if not (0 < self.adequacy_p < 1 and 0 <= self.bound_tolerance < 0.5):
            raise BayesUpdateError(
                "discovery: adequacy_p must lie in (0, 1) and bound_tolerance in [0, 0.5), got "
                f"{self.adequacy_p}, {self.bound_tolerance}"
            )
        if not 0 < self.max_noise_rel < np.inf:
            raise BayesUpdateError(
                f"discovery.max_noise_rel: must be a finite number > 0, got {self.max_noise_rel}"
            )

    def prior_log_odds(self, n_candidates: int) -> float:
        """Prior log odds of one of ``n_candidates`` equally likely candidates against the
        baseline: ln(p / (1 - p)) - ln N (``workflow`` module docstring, "Prior odds")."""
        p = self.effect_prior
        return float(np.log(p / (1 - p)) - np.log(max(int(n_candidates), 1)))


#: the flat knob names in the order the result file stores them, each with its record's field
FLAT_NAMES: tuple[tuple[str, str], ...] = (
    ("kinds", "scan"),
    ("locations", "scan"),
    ("sigma", "evidence"),
    ("baseline_starts", "refit"),
    ("seed", ""),
    ("quick_refits", "refit"),
    ("per_kind", "refit"),
    ("quick_nfev", "refit"),
    ("max_refits", "refit"),
    ("max_nfev", "refit"),
    ("threshold_log_odds", "verdict"),
    ("margin_ln_bf", "verdict"),
    ("effect_prior", "verdict"),
    ("bound_tolerance", "verdict"),
    ("adequacy_p", "verdict"),
    ("max_noise_rel", "verdict"),
    ("alpha", "scan"),
    ("loo_top", "evidence"),
    ("loo_draws", "evidence"),
)


@dataclass(frozen=True)
class DiscoverySettings:
    """Knobs of a discovery run (module docstring); ``seed`` seeds the baseline calibration
    and the k-th PSIS-LOO (``seed + k``)."""

    scan: LibraryScan = field(default_factory=LibraryScan)
    refit: RefitBudget = field(default_factory=RefitBudget)
    evidence: EvidenceSettings = field(default_factory=EvidenceSettings)
    verdict: VerdictThresholds = field(default_factory=VerdictThresholds)
    seed: int = 0

    def __post_init__(self):
        if not (isinstance(self.seed, numbers.Integral) and self.seed >= 0):
            raise BayesUpdateError(f"discovery.seed: must be an integer >= 0, got {self.seed}")

    @classmethod
    def from_flat(cls, **values) -> "DiscoverySettings":
        """The record of flat knobs (``FLAT_NAMES``; the rest at their defaults)."""
        return cls().replaced(**values)

    def replaced(self, **changes) -> "DiscoverySettings":
        """A copy with the flat knobs ``changes`` set; each changed record is validated."""
        where = dict(FLAT_NAMES)
        unknown = sorted(set(changes) - set(where))
        if unknown:
            raise BayesUpdateError(f"discovery.{unknown[0]}: unknown setting")
        groups: dict[str, dict] = {}
        for name, value in changes.items():
            groups.setdefault(where[name], {})[name] = value
        top = groups.pop("", {})
        records = {g: replace(getattr(self, g), **v) for g, v in groups.items()}
        return replace(self, **records, **top)

    def flat(self) -> dict:
        """{knob: value} in ``FLAT_NAMES`` order (the result file's ``settings_json``)."""
        return {
            name: getattr(getattr(self, group) if group else self, name)
            for name, group in FLAT_NAMES
        }


def flat_names() -> list[str]:
    """The flat knob names (a study file's ``[discovery]`` keys), sorted."""
    return sorted(name for name, _ in FLAT_NAMES)
