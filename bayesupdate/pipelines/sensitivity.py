"""The sensitivity pipeline: which parameters the measured modes can inform, before updating.

Normalized sensitivities S_ij = (d f_i / f_i) / (d p_j / p_j) = d ln f_i / d ln p_j of the model
modes paired with the test (``pipelines.correlate``) to every candidate parameter, at the
model's defaults:

* ``analytic`` (FE models): one modal solve, then per parameter the eigenvalue derivative
  d lambda_i = phi_i^T (dK - lambda_i dM) phi_i of mass-normalized modes (Fox & Kapoor 1968,
  "Rates of change of eigenvalues and eigenvectors", AIAA J. 6(12)), with dK, dM the central
  difference of the assembled matrices in ln p (exact for terms linear in p, O(h^2) for a shell
  thickness's t^2 and t^3 terms); S_ij = d lambda_i / (2 lambda_i).  A repeated eigenvalue has
  no derivative per mode: the pair's values are those of the solver's basis.
* ``fd``: central differences of ln f in ln p on the model's own ``predict``/``solve`` (any
  model), the perturbed modes found again by MAC; with test shapes also d MAC / d ln p.

Then what the test can see (``identifiability``): the singular values of S and their right
singular vectors (directions in log-parameter space; those below ``rank_tol`` x the largest are
not seen), groups of confounded parameters (columns of S parallel or anti-parallel within
``group_cos``, e.g. E and RHO of a material that is all of the structure: only E/RHO moves its
frequencies), and a suggested parameter set, the first ``rank`` pivots of a QR factorization
with column pivoting of S (Businger & Golub 1965, "Linear least squares solutions by
Householder transformations", Numer. Math. 7; Golub & Van Loan, "Matrix Computations", QR with
column pivoting): a rank-revealing choice, a suggestion and no more.

Candidates of a Nastran deck are deck fields (``nastran.bindings``); ``expand_candidates`` turns
``"PSHELL * T"`` into one binding per PSHELL card of the deck.
"""

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from bayesupdate.compute.progress import phase
from bayesupdate.correlation import mac_matrix
from bayesupdate.errors import BayesUpdateError

METHODS = ("auto", "analytic", "fd")


@dataclass(frozen=True)
class SensitivitySettings:
    """method : "auto" (analytic for FE models, else fd), "analytic" or "fd".  step : the
    central-difference step in ln p (> 0, < 0.5).  rank_tol : relative singular value below
    which a direction is not seen, in (0, 1).  group_cos : |cosine| between two parameters'
    columns above which they are one direction, in (0, 1]."""

    method: str = "auto"
    step: float = 1e-3
    rank_tol: float = 0.02
    group_cos: float = 0.99

    def __post_init__(self):
        if self.method not in METHODS:
            raise BayesUpdateError(f"--method {self.method!r}: use one of {list(METHODS)}")
        if not 0.0 < self.step < 0.5:
            raise BayesUpdateError(f"--step {self.step}: give a log step in (0, 0.5)")
        if not 0.0 < self.rank_tol < 1.0:
            raise BayesUpdateError(f"--rank-tol {self.rank_tol}: give a value in (0, 1)")
        if not 0.0 < self.group_cos <= 1.0:
            raise BayesUpdateError(f"--group-cos {self.group_cos}: give a value in (0, 1]")


@dataclass(frozen=True)
class Identifiability:
    """singular_values (n_p,) descending (zero-padded past the number of modes); directions
    (n_p, n_p) rows: right singular vectors over the parameters; rank : directions seen;
    groups : tuples of parameter indices that move frequencies as one direction; suggested :
    parameter indices in pivot order (the first ``rank``)."""

    singular_values: np.ndarray
    directions: np.ndarray
    rank: int
    groups: tuple[tuple[int, ...], ...]
    suggested: tuple[int, ...]


def identifiability(s: np.ndarray, rank_tol: float, group_cos: float) -> Identifiability:
    """What a sensitivity matrix s (n_modes, n_p) lets a test see (module docstring)."""
    from scipy.linalg import qr

    s = np.asarray(s, dtype=float)
    n_p = s.shape[1]
    _, sv, vt = np.linalg.svd(s, full_matrices=True)
    values = np.zeros(n_p)
    values[: sv.size] = sv
    top = values[0] if values.size and values[0] > 0 else 1.0
    rank = int(np.sum(values / top >= rank_tol)) if values[0] > 0 else 0
    _, _, pivots = qr(s, pivoting=True, mode="economic")
    return Identifiability(values, vt, rank, confounded_groups(s, group_cos),
                           tuple(int(p) for p in pivots[:rank]))  # fmt: skip


def confounded_groups(s: np.ndarray, group_cos: float) -> tuple[tuple[int, ...], ...]:
    """Groups (of 2 or more) of columns of s whose pairwise |cosine| >= ``group_cos``, joined
    transitively (a column of zeros is in no group)."""
    norm = np.linalg.norm(s, axis=0)
    unit = s / np.where(norm > 0, norm, 1.0)
    close = (np.abs(unit.T @ unit) >= group_cos) & np.outer(norm > 0, norm > 0)
    label = np.arange(s.shape[1])
    for _ in range(s.shape[1]):  # propagate the smallest index through the links
        label = np.min(np.where(close, label[None, :], s.shape[1]), axis=1)
    groups = [tuple(int(j) for j in np.flatnonzero(label == g)) for g in np.unique(label)]
    return tuple(g for g in groups if len(g) > 1)


@dataclass(frozen=True)
class Sensitivity:
    """Sensitivities of the paired model modes to the candidates, and what the test sees.

    model : its name.  names (n_p,) candidate names; values (n_p,) their values at the base
    point.  modes (k,) 0-based model modes (paired with the test modes ``test_modes``);
    frequencies_hz (k,) [Hz].  matrix (k, n_p): d ln f / d ln p.  mac_matrix (k, n_p) d MAC /
    d ln p of each pair (fd with test shapes only, else None).  method : how S was computed.
    ident : ``Identifiability``.  notes : what a reader must know.
    """

    model: str
    names: tuple[str, ...]
    values: np.ndarray
    modes: np.ndarray
    test_modes: np.ndarray
    frequencies_hz: np.ndarray
    matrix: np.ndarray
    method: str
    ident: Identifiability
    mac_matrix: np.ndarray | None = None
    notes: tuple[str, ...] = ()

    @property
    def singular_values(self) -> np.ndarray:
        return self.ident.singular_values

    @property
    def rank(self) -> int:
        return self.ident.rank

    @property
    def groups(self) -> tuple[tuple[str, ...], ...]:
        return tuple(tuple(self.names[j] for j in g) for g in self.ident.groups)

    @property
    def suggested(self) -> tuple[str, ...]:
        return tuple(self.names[j] for j in self.ident.suggested)

    def direction_terms(self, k: int, smallest: float = 0.1) -> tuple[tuple[str, float], ...]:
        """Direction k as ((name, weight), ...), weights of magnitude >= ``smallest``, largest
        first (sign fixed so the largest weight is positive)."""
        v = self.ident.directions[k]
        v = v * (1.0 if v[np.argmax(np.abs(v))] >= 0 else -1.0)
        order = np.argsort(-np.abs(v), kind="stable")
        return tuple((self.names[j], float(v[j])) for j in order if abs(v[j]) >= smallest)

    @property
    def unseen(self) -> tuple[int, ...]:
        """Indices of the directions the test cannot see (relative singular value below the
        tolerance)."""
        return tuple(range(self.rank, len(self.names)))


def analytic_sensitivity(
    model, base: Mapping[str, float], modes: np.ndarray, n_modes: int, step: float
) -> tuple[np.ndarray, np.ndarray]:
    """(frequencies (k,) [Hz], S (k, n_p)) of the FE ``model``'s ``modes`` (0-based) to each
    parameter of ``base`` by the eigenvalue derivative (module docstring)."""
    r = model.solve(dict(base), n_modes)
    lam = r.modes.eigenvalues[modes]
    phi = r.modes.shapes[:, modes]
    s = np.zeros((modes.size, len(base)))
    with phase("sensitivities (eigenvalue derivatives)", len(base), "parameter") as shown:
        for j, name in enumerate(base):
            plus, minus = (
                model.matrices({**base, name: base[name] * np.exp(d)}) for d in (step, -step)
            )
            dK, dM = (plus[0] - minus[0]) / (2 * step), (plus[1] - minus[1]) / (2 * step)
            dlam = np.sum(phi * (dK @ phi), axis=0) - lam * np.sum(phi * (dM @ phi), axis=0)
            s[:, j] = 0.5 * dlam / lam
            shown.advance()
    return r.frequencies_hz[modes], s


@dataclass(frozen=True)
class _Solved:
    frequencies_hz: np.ndarray
    shapes: np.ndarray | None


def fd_sensitivity(
    predict: Callable[[dict], _Solved],
    base: Mapping[str, float],
    modes: np.ndarray,
    step: float,
    test_shapes: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(frequencies (k,), S (k, n_p), d MAC / d ln p (k, n_p) or None) by central differences in
    ln p of ``predict(params) -> (frequencies (m,), shapes (n_a, m) at the test DOFs or None)``;
    each base mode is found again by MAC at the perturbed points (by index without shapes).
    test_shapes (n_a, k) : the test shapes paired with ``modes`` (for the MAC derivative)."""
    ref = predict(dict(base))
    s = np.zeros((modes.size, len(base)))
    dmac = None if test_shapes is None or ref.shapes is None else np.zeros_like(s)
    with phase("sensitivities (central differences)", len(base), "parameter") as shown:
        for j, name in enumerate(base):
            (fp, ip), (fm, im) = (
                _tracked(predict, {**base, name: base[name] * np.exp(d)}, ref, modes)
                for d in (step, -step)
            )
            s[:, j] = (np.log(fp.frequencies_hz[ip]) - np.log(fm.frequencies_hz[im])) / (2 * step)
            if dmac is not None:
                mp = np.diag(mac_matrix(test_shapes, fp.shapes[:, ip]))
                mm = np.diag(mac_matrix(test_shapes, fm.shapes[:, im]))
                dmac[:, j] = (mp - mm) / (2 * step)
            shown.advance()
    return ref.frequencies_hz[modes], s, dmac


def _tracked(predict, params: dict, ref: _Solved, modes: np.ndarray) -> tuple[_Solved, np.ndarray]:
    """The solution at ``params`` and the index of each of the reference's ``modes`` in it (by
    MAC with the reference shapes; by index without shapes)."""
    at = predict(params)
    if ref.shapes is None or at.shapes is None:
        return at, modes
    return at, np.argmax(mac_matrix(ref.shapes[:, modes], at.shapes), axis=1)


@dataclass(frozen=True)
class SensitivityInput:
    """model, its name, the candidate parameters' base values (name -> value), the 0-based
    model modes to differentiate and the test modes paired with them (0-based in the test's
    source: its ``[data] modes`` number less one), the test's shapes at the
    model's shape labels for those pairs (n_a, k) and those labels (empty: no shapes)."""

    model: object
    name: str
    base: dict
    modes: np.ndarray
    test_modes: np.ndarray
    test_shapes: np.ndarray | None = None
    labels: tuple[str, ...] = ()
    notes: tuple[str, ...] = field(default_factory=tuple)


def _is_fe(model) -> bool:
    return hasattr(model, "matrices") and hasattr(model, "solve")


def _predictor(model, labels: tuple[str, ...], n_modes: int):
    def predict(params: dict) -> _Solved:
        p = model.predict(params, n_modes)
        shapes = None
        if p.shapes is not None and labels:
            index = {lab: i for i, lab in enumerate(p.dof_labels)}
            shapes = np.asarray(p.shapes)[[index[lab] for lab in labels]]
        return _Solved(np.asarray(p.frequencies_hz), shapes)

    return predict


def run_sensitivity(inp: SensitivityInput, settings: SensitivitySettings):
    """The ``Sensitivity`` of ``inp`` (module docstring)."""
    method = settings.method
    if method == "auto":
        method = "analytic" if _is_fe(inp.model) else "fd"
    if method == "analytic" and not _is_fe(inp.model):
        raise BayesUpdateError(
            "--method analytic: the model gives no K and M (not an FE model); use --method fd"
        )
    n_modes = int(inp.modes.max()) + 3
    dmac = None
    if method == "analytic":
        f, s = analytic_sensitivity(inp.model, inp.base, inp.modes, n_modes, settings.step)
    else:
        predict = _predictor(inp.model, inp.labels, n_modes)
        f, s, dmac = fd_sensitivity(predict, inp.base, inp.modes, settings.step, inp.test_shapes)
    ident = identifiability(s, settings.rank_tol, settings.group_cos)
    return Sensitivity(
        model=inp.name,
        names=tuple(inp.base),
        values=np.array(list(inp.base.values()), dtype=float),
        modes=inp.modes,
        test_modes=inp.test_modes,
        frequencies_hz=np.asarray(f),
        matrix=s,
        method=method,
        ident=ident,
        mac_matrix=dmac,
        notes=inp.notes,
    )


def write_sensitivity_h5(path, result: Sensitivity) -> None:
    """Write ``result`` to HDF5 atomically.  Layout (group ``/sensitivity``, attributes
    ``model``, ``method``, ``rank``): ``names`` (n_p,) strings, ``values`` (n_p,), ``modes`` and
    ``test_modes`` (k,) 0-based (the test's: in its source), ``frequencies_hz`` (k,), ``matrix``
    (k, n_p) d ln f / d ln p,
    ``mac_matrix`` (k, n_p) when computed, ``singular_values`` (n_p,), ``directions`` (n_p, n_p)
    rows over the parameters, ``suggested`` (rank,) parameter indices, ``groups`` (n_p,) group
    number of each parameter (-1: none), ``notes`` strings."""
    import h5py

    from bayesupdate.atomic import atomic_path

    group_of = -np.ones(len(result.names), dtype=int)
    for g, members in enumerate(result.ident.groups):
        group_of[list(members)] = g
    with atomic_path(path, suffix=".h5") as tmp, h5py.File(tmp, "w") as fh:
        g = fh.create_group("sensitivity")
        g.attrs.update(model=result.model, method=result.method, rank=result.rank)
        g["names"] = np.array(result.names, dtype=h5py.string_dtype())
        g["notes"] = np.array(result.notes, dtype=h5py.string_dtype())
        for name in ("values", "modes", "test_modes", "frequencies_hz", "matrix"):
            g[name] = getattr(result, name)
        if result.mac_matrix is not None:
            g["mac_matrix"] = result.mac_matrix
        g["singular_values"] = result.singular_values
        g["directions"] = result.ident.directions
        g["suggested"] = np.array(result.ident.suggested, dtype=int)
        g["groups"] = group_of


# -- candidates ------------------------------------------------------------------------------
def expand_candidates(specs, card_ids: Callable[[str], list[int]]) -> dict[str, dict]:
    """Parameter tables ``{name: {"binds": spec}}`` of candidate specs: ``"CARD * FIELD"``
    becomes one binding per card id that ``card_ids(CARD)`` lists (named ``"CARD id FIELD"``);
    any other spec (``"MAT1 2 E"``, ``"PSHELL 3,5 T"``) is one candidate as written."""
    out: dict[str, dict] = {}
    for spec in specs:
        words = str(spec).split()
        if len(words) >= 3 and words[1] == "*":
            card, rest = words[0].upper(), " ".join(words[2:])
            ids = card_ids(card)
            if not ids:
                raise BayesUpdateError(f"--candidates {spec!r}: the deck has no {card} card")
            for i in ids:
                out[f"{card} {i} {rest}"] = {"binds": f"{card} {i} {rest}"}
        else:
            out[" ".join(words)] = {"binds": " ".join(words)}
    if not out:
        raise BayesUpdateError('--candidates: give at least one, e.g. "PSHELL * T"')
    return out
