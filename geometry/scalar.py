"""Bracketed scalar root and minimum, in plain Python.

Why not scipy.optimize.brentq / minimize_scalar: importing scipy.optimize costs about
0.2 s, and the geometry of every case needs one root (the fillet's end) and two polished
extrema (the undercut limit, the largest chamber volume). Both searches keep a bracket
at every step, so they cannot leave it, and stop on an absolute x tolerance as the scipy
calls they replace did. Checked against closed forms and scipy in tests/test_scalar.py.
"""

from __future__ import annotations

import math
from collections.abc import Callable

#: Golden-section ratio: the bracket shrinks by this factor per evaluation.
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
#: Enough steps for any bracket of doubles to shrink to one ulp (2^-1074 .. 2^1024).
MAX_STEPS = 2200


def root(f: Callable[[float], float], a: float, b: float, xtol: float = 1e-14) -> float:
    """A zero of ``f`` in [a, b], where f(a) and f(b) differ in sign.

    Regula falsi with the Illinois modification (the retained end's value is halved
    when the same end is kept twice, which restores superlinear convergence), falling
    back to bisection whenever the secant step would shrink the bracket too little.
    """
    fa, fb = f(a), f(b)
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if (fa > 0.0) == (fb > 0.0):
        raise ValueError(f"root not bracketed: f({a}) = {fa}, f({b}) = {fb}")
    side = 0
    best = (abs(fa), a) if abs(fa) < abs(fb) else (abs(fb), b)  # by the true values
    for _ in range(MAX_STEPS):
        width = abs(b - a)
        if width <= xtol or 0.5 * (a + b) in (a, b):  # (adjacent doubles: nothing between)
            break
        x = (a * fb - b * fa) / (fb - fa)
        if not (min(a, b) < x < max(a, b)):
            x = 0.5 * (a + b)
        fx = f(x)
        if fx == 0.0:
            return x
        best = min(best, (abs(fx), x))
        if (fx > 0.0) == (fb > 0.0):
            b, fb = x, fx
            if side == -1:
                fa *= 0.5
            side = -1
        else:
            a, fa = x, fx
            if side == 1:
                fb *= 0.5
            side = 1
        if abs(b - a) > 0.5 * width:
            # The secant crept along one end: bisect once to guarantee the bracket halves.
            m = 0.5 * (a + b)
            fm = f(m)
            if fm == 0.0:
                return m
            best = min(best, (abs(fm), m))
            if (fm > 0.0) == (fb > 0.0):
                b, fb = m, fm
            else:
                a, fa = m, fm
            side = 0
    return best[1]  # (the Illinois halving scales the kept end's value: not comparable)


def edge(holds: Callable[[float], bool], inside: float, outside: float,
         steps: int) -> tuple[float, float]:
    """(inside, outside): the bracket of where ``holds`` stops holding, halved ``steps``
    times from ``inside`` (where it holds) and ``outside`` (where it does not).  For a
    predicate with no value to interpolate (a section that holds fluid, a rack that
    generates no undercut)."""
    for _ in range(steps):
        mid = 0.5 * (inside + outside)
        if holds(mid):
            inside = mid
        else:
            outside = mid
    return inside, outside


def minimum(f: Callable[[float], float], lo: float, hi: float,
            xtol: float = 1e-10) -> tuple[float, float]:
    """(x, f(x)) at a local minimum of ``f`` inside [lo, hi], by golden-section search.

    For a function unimodal on the bracket this is its minimum; the caller brackets it
    from a sampled scan, as scipy's bounded method was used here.
    """
    a, b = (lo, hi) if lo <= hi else (hi, lo)
    x1 = b - _GOLDEN * (b - a)
    x2 = a + _GOLDEN * (b - a)
    f1, f2 = f(x1), f(x2)
    for _ in range(MAX_STEPS):
        if b - a <= xtol:
            break
        if f1 <= f2:
            b, x2, f2 = x2, x1, f1
            x1 = b - _GOLDEN * (b - a)
            f1 = f(x1)
        else:
            a, x1, f1 = x1, x2, f2
            x2 = a + _GOLDEN * (b - a)
            f2 = f(x2)
    return (x1, f1) if f1 <= f2 else (x2, f2)


def periodic_peak(values) -> tuple[float, float]:
    """(position in samples, value) of the largest value of a periodic curve sampled
    uniformly, located by the parabola through the largest sample and its two
    neighbours (wrapping round the period).

    On a smooth peak this errs by O(h^3) in the value where the largest sample errs by
    O(h^2).  Where the curve has a kink inside those three samples no parabola fits it;
    the vertex then still lies within half a step of the largest sample and adds at
    most a quarter of the larger fall to a neighbour (the neighbours are no higher), so
    the located value is off by no more than the sampled one can be.  A flat or convex
    triple keeps the largest sample.
    """
    import numpy as np

    y = np.asarray(values, dtype=float)
    k = int(np.argmax(y))
    a, b, c = float(y[k - 1]), float(y[k]), float(y[(k + 1) % len(y)])
    curvature = a - 2.0 * b + c
    if not curvature < 0.0:
        return float(k), b
    t = 0.5 * (a - c) / curvature
    return k + t, b - 0.25 * (a - c) * t


def hermite_coefficients(x0: float, x1: float, y0: float, y1: float, d0: float, d1: float):
    """(a, b, c, e) of the cubic Hermite through (x0, y0) with slope d0 and (x1, y1) with
    slope d1, as a + b t + c t^2 + e t^3 in t = (x - x0) / (x1 - x0)."""
    h = x1 - x0
    return (y0, h * d0, 3.0 * (y1 - y0) - h * (2.0 * d0 + d1), 2.0 * (y0 - y1) + h * (d0 + d1))


def hermite_peak(x, y, dy) -> tuple[float, float]:
    """(x, value) of the largest value of the piecewise cubic Hermite through (x, y) with
    slopes dy, near its largest sample: where its slope turns from rising to falling in
    the intervals on either side (the sample itself where it does not)."""
    import numpy as np

    x, y, dy = (np.asarray(v, dtype=float) for v in (x, y, dy))
    k = int(np.argmax(y))
    best = (float(x[k]), float(y[k]))
    for i in (k - 1, k):
        if i < 0 or i + 1 >= len(x):
            continue
        a, b, c, e = hermite_coefficients(x[i], x[i + 1], y[i], y[i + 1], dy[i], dy[i + 1])
        # p'(t) = b + 2 c t + 3 e t^2: its roots in [0, 1] where it turns downwards.
        roots = np.roots([3.0 * e, 2.0 * c, b]) if abs(e) + abs(c) > 0.0 else np.array([])
        for t in roots:
            if abs(t.imag) > 1e-12 or not 0.0 <= t.real <= 1.0:
                continue
            t = float(t.real)
            if 2.0 * c + 6.0 * e * t <= 0.0:
                val = a + b * t + c * t * t + e * t ** 3
                if val > best[1]:
                    best = (float(x[i] + t * (x[i + 1] - x[i])), float(val))
    return best


def hermite_fall(x, y, dy, level: float, start: int) -> float:
    """The first x after sample ``start`` where the piecewise cubic Hermite through (x, y)
    with slopes dy falls to ``level``, located between the samples that bracket it.
    Raises ValueError if it never does."""
    import numpy as np

    y = np.asarray(y, dtype=float)
    below = np.nonzero(y[start:] <= level)[0]
    if not len(below):
        raise ValueError(f"the samples never fall to {level}")
    k = start + int(below[0])
    if y[k] == level or k == 0:
        return float(x[k])
    a, b, c, e = hermite_coefficients(x[k - 1], x[k], y[k - 1], y[k], dy[k - 1], dy[k])
    t = root(lambda t: a + b * t + c * t * t + e * t ** 3 - level, 0.0, 1.0, xtol=1e-15)
    return float(x[k - 1] + t * (x[k] - x[k - 1]))
