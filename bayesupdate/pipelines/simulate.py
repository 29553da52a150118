"""The simulate pipeline: a model with a hidden truth -> a virtual roving-hammer test (FRFs).

The seed's modal test (section 4) on an FE model: its modes at the true parameters (with any
hidden effects), seeded random modal damping of 0.5-3 %, the accelerometers placed where the
in-band modes are best seen (``ema.virtual_test.best_reference_points``), then
``ema.virtual_test.virtual_impact_test`` with relative noise on the time signals.
"""

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from bayesupdate.discovery.effects import extend_model
from bayesupdate.ema.frf_set import FrfSet
from bayesupdate.ema.virtual_test import best_reference_points, seed_layout, virtual_impact_test

#: upper end of the simulated test's band [Hz] (the seed's 0-150 Hz)
BAND_HZ = 150.0


@dataclass(frozen=True)
class VirtualTestSettings:
    """The hidden truth and the test's knobs (checked by the caller).

    parameters : true parameter values (SI; the others take the model's defaults).
    effects : hidden effects (``discovery.effects.Effect``) the true structure carries.
    noise : relative time-signal noise, in [0, 1).  seed : every random draw derives from it.
    n_modes : modes superposed (those above the band act as residuals).
    """

    parameters: Mapping[str, float] = field(default_factory=dict)
    effects: tuple = ()
    noise: float = 0.01
    seed: int = 0
    n_modes: int = 20


@dataclass(frozen=True)
class VirtualTest:
    """The simulated test and its truth.

    frfs : the FRFs (accelerance, seed layout).  frequencies_hz, damping_ratio : (n_modes,) true
    modes [Hz], [-].  mass_kg : true mass.  parameters : the true parameter point (SI).
    effects : spec strings of the hidden effects.  shapes : (n_dof, n_modes) true mass-normalized
    shapes at ``dof_labels``.  reference_points : the accelerometer points (V, H).
    """

    frfs: FrfSet
    frequencies_hz: np.ndarray
    damping_ratio: np.ndarray
    mass_kg: float
    parameters: dict
    effects: tuple[str, ...]
    shapes: np.ndarray
    dof_labels: tuple[str, ...]
    reference_points: tuple[int, int]


def simulate_test(model, settings: VirtualTestSettings) -> VirtualTest:
    """The virtual test of FE ``model`` extended by ``settings.effects`` at its parameters."""
    for effect in settings.effects:
        model = extend_model(model, effect)
    n_modes = settings.n_modes
    result = model.solve(settings.parameters, n_modes=n_modes)
    rng = np.random.default_rng(settings.seed)
    damping = rng.uniform(0.005, 0.03, size=n_modes)
    # like a test engineer, place the accelerometers where the (nominal) modes in band are seen
    in_band = result.frequencies_hz <= BAND_HZ
    layout, ref_v, ref_h = roving_layout(result.sensor_shapes[:, in_band], result.sensor_labels)
    frfs = virtual_impact_test(
        result.frequencies_hz,
        damping,
        result.sensor_shapes,
        result.sensor_labels,
        layout=layout,
        noise=settings.noise,
        seed=rng,
    )
    return VirtualTest(
        frfs=frfs,
        frequencies_hz=result.frequencies_hz,
        damping_ratio=damping,
        mass_kg=result.mass_kg,
        parameters=result.parameters,
        effects=tuple(e.spec() for e in settings.effects),
        shapes=result.sensor_shapes,
        dof_labels=result.sensor_labels,
        reference_points=(ref_v, ref_h),
    )


def roving_layout(shapes: np.ndarray, labels) -> tuple[list[tuple[str, str]], int, int]:
    """(layout, V reference point, H reference point): the seed's roving-hammer layout
    (``ema.virtual_test.seed_layout``) over the test points that carry both a V and an H label
    (``<point>V``, ``<point>H``), whatever their numbers, references placed by
    ``best_reference_points``.  shapes : (n_dof, m) at ``labels``."""
    from bayesupdate.errors import BayesUpdateError

    def split(label):
        return (int(label[:-1]), label[-1]) if label[:-1].isdigit() else (None, "")

    found = [split(str(lab)) for lab in labels]
    points = sorted({p for p, d in found if d == "V"} & {p for p, d in found if d == "H"})
    if len(points) < 2:
        raise BayesUpdateError(
            f"simulate: the model has {len(points)} test point(s) with V and H sensors; "
            "a roving-hammer test needs at least 2"
        )
    # the layout's points are 1..n: number the model's points in order, then name them back
    number = {p: i + 1 for i, p in enumerate(points)}
    local = tuple(f"{number[p]}{d}" if p in number else str(lab)
                  for (p, d), lab in zip(found, labels, strict=True))  # fmt: skip
    ref_v, ref_h = best_reference_points(shapes, local, n_points=len(points))

    def name(label):
        return f"{points[int(label[:-1]) - 1]}{label[-1]}"

    pairs = [(name(a), name(b)) for a, b in seed_layout(len(points), ref_v, ref_h)]
    return pairs, points[ref_v - 1], points[ref_h - 1]
