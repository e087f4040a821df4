"""geometry/spline.py against scipy's CubicSpline (an independent implementation: LAPACK
banded solve and piecewise-polynomial evaluation) and against the polynomials a cubic
spline must reproduce exactly."""

import numpy as np
import pytest
from scipy.interpolate import CubicSpline as Reference

from rotorflow.geometry.spline import CubicSpline

# Round-off of both constructions on O(1) data with knot ratios up to ~10.
AGREE = 1e-9


def _knots(n, rng, uniform):
    if uniform:
        return np.linspace(-1.0, 2.0, n)
    return np.sort(np.concatenate([[-1.0, 2.0], rng.uniform(-1.0, 2.0, n - 2)]))


@pytest.mark.parametrize("n", [2, 3, 4, 5, 6, 9, 50, 1001])
@pytest.mark.parametrize("uniform", [True, False])
def test_not_a_knot_matches_scipy(n, uniform):
    rng = np.random.default_rng(n)
    x = _knots(n, rng, uniform)
    y = rng.normal(size=(n, 2, 3))
    xq = rng.uniform(-1.2, 2.2, size=(7, 11))
    for extrapolate in (True, False):
        ours = CubicSpline(x, y, extrapolate=extrapolate)
        ref = Reference(x, y, bc_type="not-a-knot", extrapolate=extrapolate)
        for nu in range(4):
            a, b = ours(xq, nu), ref(xq, nu)
            assert a.shape == b.shape == (7, 11, 2, 3)
            np.testing.assert_array_equal(np.isnan(a), np.isnan(b))
            scale = 1.0 + np.nanmax(np.abs(b))
            assert np.nanmax(np.abs(a - b)) <= AGREE * scale, (n, nu, extrapolate)


@pytest.mark.parametrize("n", [2, 3, 4, 5, 8, 64, 4097])
@pytest.mark.parametrize("uniform", [True, False])
def test_periodic_matches_scipy(n, uniform):
    rng = np.random.default_rng(100 + n)
    x = _knots(n, rng, uniform)
    y = rng.normal(size=n)
    y[-1] = y[0]
    xq = rng.uniform(-4.0, 5.0, size=301)
    ours, ref = CubicSpline(x, y, bc_type="periodic"), Reference(x, y, bc_type="periodic")
    for nu in range(4):
        assert np.max(np.abs(ours(xq, nu) - ref(xq, nu))) <= AGREE * (1 + np.abs(ref(xq, nu)).max())


def test_reproduces_a_cubic_exactly():
    # Not-a-knot ends make the spline exact for any cubic: a check that needs no reference.
    x = np.array([0.0, 0.3, 0.35, 1.0, 1.7, 2.0, 3.1])
    f = lambda t: 2.0 - t + 0.5 * t**2 - 0.25 * t**3  # noqa: E731
    s = CubicSpline(x, f(x))
    t = np.linspace(-0.5, 3.5, 41)
    np.testing.assert_allclose(s(t), f(t), atol=1e-12)
    np.testing.assert_allclose(s(t, 1), -1.0 + t - 0.75 * t**2, atol=1e-11)
    np.testing.assert_allclose(s(t, 3), -1.5, atol=1e-10)


def test_periodic_trigonometric_converges_at_fourth_order():
    errors = []
    for n in (16, 32, 64):
        x = np.linspace(0.0, 2 * np.pi, n + 1)
        s = CubicSpline(x, np.sin(x), bc_type="periodic")
        t = np.linspace(0.0, 2 * np.pi, 997)
        errors.append(np.abs(s(t) - np.sin(t)).max())
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 3.8), orders


def test_bad_input_named():
    with pytest.raises(ValueError, match="increase"):
        CubicSpline([0.0, 1.0, 1.0], [0.0, 1.0, 2.0])
    with pytest.raises(ValueError, match="periodic"):
        CubicSpline([0.0, 1.0, 2.0], [0.0, 1.0, 2.0], bc_type="periodic")


@pytest.mark.parametrize("bc", ["not-a-knot", "periodic"])
def test_integral_matches_scipy(bc):
    rng = np.random.default_rng(7)
    x = _knots(40, rng, False)
    y = rng.normal(size=40)
    y[-1] = y[0]
    ours, ref = CubicSpline(x, y, bc_type=bc), Reference(x, y, bc_type=bc)
    for a, b in ((-1.0, 2.0), (-0.3, 1.7), (1.2, 0.1)):
        assert ours.integrate(a, b) == pytest.approx(ref.integrate(a, b), abs=1e-12)
