"""geometry/scalar.py: bracketed root and minimum against closed forms."""

import math

import pytest

from rotorflow.geometry.scalar import minimum, root


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
