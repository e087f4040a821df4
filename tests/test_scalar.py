"""geometry/scalar.py: bracketed root and minimum against closed forms; the located
peak of a sampled periodic curve against the analytic maximum."""

import math

import numpy as np
import pytest

from rotorflow.geometry.scalar import edge, minimum, periodic_peak, root


@pytest.mark.parametrize("f, a, b, exact", [
    (math.cos, 0.0, 3.0, math.pi / 2),
    (lambda x: x**3 - 2.0, 0.0, 2.0, 2.0 ** (1 / 3)),
    (lambda x: math.exp(x) - 1e6, 0.0, 20.0, math.log(1e6)),  # convex: plain regula falsi stalls
    (lambda x: math.tanh(50 * (x - 0.3)), -1.0, 1.0, 0.3),
    (lambda x: (x - 1e-3) ** 9, -1.0, 1.0, 1e-3),  # flat zero
])
def test_root_closed_forms(f, a, b, exact):
    calls = []

    def counted(x):
        calls.append(x)
        return f(x)

    x = root(counted, a, b, xtol=1e-14)
    assert abs(x - exact) <= 2e-14 + 1e-12 * abs(exact) or abs(f(x)) == 0.0
    assert all(min(a, b) <= c <= max(a, b) for c in calls)  # never leaves the bracket
    assert len(calls) < 200


def test_root_refuses_no_bracket():
    with pytest.raises(ValueError, match="bracketed"):
        root(lambda x: x * x + 1.0, -1.0, 1.0)


@pytest.mark.parametrize("f, lo, hi, exact", [
    (lambda x: (x - 0.7) ** 2 + 3.0, 0.0, 1.0, 0.7),
    (lambda x: -math.sin(x), 1.0, 2.0, math.pi / 2),
    (lambda x: math.cosh(x - 0.123), 0.1, 0.2, 0.123),
])
def test_minimum_closed_forms(f, lo, hi, exact):
    x, fx = minimum(f, lo, hi, xtol=1e-12)
    # A smooth minimum is flat: x is fixed only to about sqrt(eps) by the values.
    assert abs(x - exact) < 3e-8
    assert fx == f(x)


def _smooth(x):
    # an asymmetric periodic peak (no symmetry to make a parabola exact)
    return np.cos(x - 0.4) + 0.3 * np.cos(2.0 * x + 1.1)


def test_periodic_peak_converges_at_third_order_on_a_smooth_peak():
    # The true maximum by golden section on a bracket found densely.
    dense = np.linspace(0.0, 2.0 * math.pi, 20001)
    k = int(np.argmax(_smooth(dense)))
    x_true, neg = minimum(lambda x: -float(_smooth(x)), dense[k - 1], dense[k + 1], 1e-13)
    true = -neg
    errors, sampled = [], []
    for n in (48, 96, 192, 384):  # (from 24 to 48 it is pre-asymptotic, 2.2)
        x = 0.123 + 2.0 * math.pi * np.arange(n) / n  # samples off the peak
        pos, value = periodic_peak(_smooth(x))
        errors.append(abs(value - true))
        sampled.append(abs(_smooth(x).max() - true))
        # the vertex lies within half a step of the true maximum
        assert abs(math.remainder(0.123 + 2.0 * math.pi * pos / n - x_true, 2.0 * math.pi)) \
            < math.pi / n
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    # the sampled maximum is second order at best; the parabola's vertex third order
    assert orders.min() > 2.8, orders
    assert all(e < 0.1 * s for e, s in zip(errors[1:], sampled[1:], strict=True))


@pytest.mark.parametrize("offset", [0.0, 0.1, 0.37, 0.5, 0.81])
def test_periodic_peak_at_a_kink_is_no_worse_than_the_sample(offset):
    # A V-shaped peak (a load whose slope jumps): no parabola fits it, and the located
    # value must not overshoot it nor fall further from it than the largest sample.
    n = 48
    h = 2.0 * math.pi / n
    x0 = 1.0 + offset * h
    x = 1.0 + h * np.arange(n)
    y = -np.abs(np.sin(0.5 * (x - x0)))
    _, value = periodic_peak(y)
    assert value <= 1e-15
    assert abs(value) <= abs(y.max()) + 1e-15


def test_periodic_peak_wraps_round_the_period():
    n = 32
    x = 2.0 * math.pi * np.arange(n) / n
    y = np.cos(x - 0.05)  # the peak between the last sample and the first
    pos, value = periodic_peak(y)
    assert value == pytest.approx(1.0, abs=1e-4)
    assert 0.0 <= pos < 1.0 or pos > n - 1


def test_hermite_peak_and_fall_converge_on_a_smooth_curve():
    """The cubic Hermite through samples of cos(x - 0.3) and its derivative finds the
    peak (x = 0.3, value 1) and the fall to 0.5 (x = 0.3 + pi/3) between the samples,
    where the largest sample is off by up to half a step.  From 16 to 128 intervals
    the errors fall at about third order or better (measured 3.3 for the peak's place,
    3.6 for its value, 4.8 for the fall; from step to step they scatter, 2 to 6.7, with
    where the samples fall)."""
    import math

    import numpy as np

    from rotorflow.geometry.scalar import hermite_fall, hermite_peak

    errors = []
    for n in (16, 128):
        x = np.linspace(-2.0, 2.0, n + 1)
        y, dy = np.cos(x - 0.3), -np.sin(x - 0.3)
        xp, vp = hermite_peak(x, y, dy)
        fall = hermite_fall(x, y, dy, 0.5, int(np.argmax(y)))
        errors.append((abs(xp - 0.3), abs(vp - 1.0), abs(fall - 0.3 - math.pi / 3)))
    errors = np.array(errors)
    assert errors[-1].max() < 1e-6  # the largest sample: 0.0125 off
    orders = np.log2(errors[0] / errors[1]) / 3.0
    assert np.all(orders > 3.0), orders


def test_edge_brackets_where_a_predicate_stops_holding():
    """x * x < 2 holds up to sqrt 2: 40 halvings of [0, 3] bracket it within 3 / 2^40,
    from either side (inside above or below outside)."""
    lo, hi = edge(lambda x: x * x < 2.0, 0.0, 3.0, 40)
    assert lo < math.sqrt(2.0) <= hi and hi - lo == pytest.approx(3.0 / 2 ** 40)
    hi, lo = edge(lambda x: x * x > 2.0, 3.0, 0.0, 40)
    assert lo <= math.sqrt(2.0) < hi and hi - lo == pytest.approx(3.0 / 2 ** 40)
