"""Section properties against closed forms."""

import numpy as np
import pytest

from bayesupdate.errors import BayesUpdateError
from bayesupdate.fe import circular_tube, oval_tube, solid_round


def test_circular_tube_exact_annulus():
    D, t = 0.045, 1.5e-3
    p = circular_tube(D, t).properties()
    ro, ri = D / 2, D / 2 - t
    assert p["A"] == pytest.approx(np.pi * (ro**2 - ri**2), rel=1e-14)
    assert p["Iy"] == pytest.approx(np.pi / 4 * (ro**4 - ri**4), rel=1e-14)
    assert p["J"] == pytest.approx(2 * p["Iy"], rel=1e-14)
    # Cowper's hollow-circle shear coefficient tends to 0.5 for thin walls (here m = 0.933)
    assert 0.5 < p["Asy"] / p["A"] < 0.54


def test_oval_tube_circle_limit_matches_thin_wall_circle():
    # an oval with equal axes is a thin-walled circle on its mid-line radius r = (D - t)/2
    D, t = 0.2, 1e-3
    p = oval_tube(D, D, t).properties()
    r = (D - t) / 2
    assert p["A"] == pytest.approx(2 * np.pi * r * t, rel=1e-12)
    assert p["Iy"] == pytest.approx(np.pi * r**3 * t, rel=1e-12)
    assert p["J"] == pytest.approx(
        2 * np.pi * r**3 * t, rel=1e-12
    )  # Bredt: 4 (pi r^2)^2 t / 2 pi r
    assert p["Asy"] == pytest.approx(p["A"] / 2, rel=1e-12)


def test_oval_tube_ellipse_second_moments():
    # thin-walled ellipse, a = 0.15, b = 0.05 (mid-line): I about the major axis from the exact
    # perimeter integral t * int z^2 ds, checked here by brute-force quadrature
    W, H, t = 0.301, 0.101, 1e-3
    p = oval_tube(W, H, t).properties()
    a, b = (W - t) / 2, (H - t) / 2
    phi = np.linspace(0, 2 * np.pi, 200001)
    y, z = a * np.cos(phi), b * np.sin(phi)
    ds = np.hypot(np.gradient(y, phi), np.gradient(z, phi)) * (phi[1] - phi[0])
    assert p["A"] == pytest.approx(t * ds[:-1].sum(), rel=1e-6)
    assert p["Iy"] == pytest.approx(t * (z**2 * ds)[:-1].sum(), rel=1e-6)
    assert p["Iz"] == pytest.approx(t * (y**2 * ds)[:-1].sum(), rel=1e-6)
    assert p["Iz"] > 5 * p["Iy"]


def test_solid_round():
    p = solid_round(0.012).properties()
    assert p["A"] == pytest.approx(np.pi * 0.006**2, rel=1e-14)
    assert p["Iy"] == pytest.approx(np.pi * 0.006**4 / 4, rel=1e-14)
    assert p["Asy"] / p["A"] == pytest.approx(6 * 1.3 / (7 + 1.8), rel=1e-12)


@pytest.mark.parametrize(
    "make",
    [
        lambda: circular_tube(0.045, 0.0),
        lambda: circular_tube(0.045, 0.03),
        lambda: oval_tube(0.2, -0.1, 1e-3),
        lambda: solid_round(float("nan")),
    ],
)
def test_bad_sections_raise(make):
    with pytest.raises(BayesUpdateError):
        make()


def test_areas_alone_equal_the_full_properties_bit_for_bit():
    """The total mass's area path (``section_areas``) gives ``section_properties``' A exactly, for
    tubes, ovals and bars mixed, so a mass is the same number whichever path computed it."""
    from bayesupdate.fe.sections import section_areas, section_properties

    rng = np.random.default_rng(7)
    code = rng.integers(0, 3, 500)
    width = rng.uniform(0.03, 0.3, 500)
    height = width * rng.uniform(0.3, 1.0, 500)
    wall = rng.uniform(1e-4, 1e-2, 500)
    areas = section_areas(code, width, height, wall)
    np.testing.assert_array_equal(areas, section_properties(code, width, height, wall, 0.3)["A"])
    tube = code == 0  # and the annulus itself: pi (ro^2 - ri^2)
    ro = width[tube] / 2
    np.testing.assert_allclose(areas[tube], np.pi * (ro**2 - (ro - wall[tube]) ** 2), rtol=1e-14)
